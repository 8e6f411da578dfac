"""The six axes' noise as one state space: correlations across axes recovered from a record."""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.filter.joint_noise import _nearest_correlation, joint_noise
from fosmodel.noise.axes import resolve_axes
from fosmodel.noise.imu_noise import imu_noise

RATE = 100.0
NAMES = ["gx_dps", "gy_dps", "gz_dps", "ax_mps2", "ay_mps2", "az_mps2"]
N = np.array([0.01, 0.012, 0.009, 1e-3, 1.2e-3, 1.5e-3])  # white, units*sqrt(s)
K = np.array([4e-4, 4e-4, 3e-4, 4e-5, 4e-5, 5e-5])  # random walk, units/sqrt(s)


def _correlation(pairs):
    c = np.eye(6)
    for (i, j), rho in pairs.items():
        c[i, j] = c[j, i] = rho
    return c


WHITE = _correlation({(0, 1): 0.5, (3, 4): -0.4, (0, 3): 0.3, (2, 5): 0.6})
BIAS = _correlation({(0, 1): 0.8, (3, 4): 0.7})


@pytest.fixture(scope="module")
def record():
    """400,000 samples of six axes: correlated white noise and correlated random walks."""
    rng = np.random.default_rng(4)
    n = 400_000
    white = (rng.standard_normal((n, 6)) @ np.linalg.cholesky(WHITE).T) * N * math.sqrt(RATE)
    walk = np.cumsum((rng.standard_normal((n, 6)) @ np.linalg.cholesky(BIAS).T) * K
                     / math.sqrt(RATE), axis=0)
    x = white + walk
    return {c: x[:, i] for i, c in enumerate(NAMES)}


@pytest.fixture(scope="module")
def joint(record):
    return joint_noise(record, imu_noise(record, resolve_axes(NAMES), RATE, "sim.csv"))


def test_the_white_and_bias_correlations_across_axes_are_recovered(joint):
    assert np.abs(joint.white_correlation - WHITE).max() < 0.01
    assert joint.bias_correlation[0, 1] == pytest.approx(0.8, abs=0.15)
    assert joint.bias_correlation[3, 4] == pytest.approx(0.7, abs=0.15)
    uncorrelated = (BIAS == 0)  # off the diagonal: pairs whose biases are independent
    assert np.abs(joint.bias_correlation[uncorrelated]).max() < 0.1


def test_the_state_space_carries_them_in_its_driving_noise(joint):
    q, independent = joint.model.Q, joint.independent.Q
    names = joint.model.state_names
    white = [names.index(f"{c}: white") for c in NAMES]
    for a, i in enumerate(white):
        for b, j in enumerate(white):
            expected = joint.white_correlation[a, b] * math.sqrt(independent[i, i]
                                                                  * independent[j, j])
            assert q[i, j] == pytest.approx(expected, rel=1e-12)
    assert np.array_equal(np.diag(q), np.diag(independent))
    assert np.count_nonzero(independent - np.diag(np.diag(independent))) == 0
    # the white state's variance per sample is N^2 rate, as the per-axis model's
    assert q[white[3], white[3]] == pytest.approx(N[3] ** 2 * RATE, rel=0.05)
    # the recovered covariance of the white parts, axes 0 and 1
    assert q[white[0], white[1]] == pytest.approx(0.5 * N[0] * N[1] * RATE, rel=0.06)
    assert np.linalg.eigvalsh(q).min() > -1e-12 * np.abs(q).max()
    p0 = joint.initial_covariance()
    assert p0.shape == q.shape and np.allclose(p0, p0.T)


def test_a_pieced_correlation_matrix_is_brought_to_the_nearest_valid_one():
    c = _correlation({(0, 1): 0.9, (1, 2): 0.9, (0, 2): -0.9})[:3, :3]
    assert np.linalg.eigvalsh(c).min() < 0
    fixed = _nearest_correlation(c)
    assert np.linalg.eigvalsh(fixed).min() > -1e-12
    assert np.allclose(np.diag(fixed), 1.0) and np.allclose(fixed, fixed.T)


def test_one_axis_is_refused(record):
    noise = imu_noise({"gx_dps": record["gx_dps"][:20_000]}, resolve_axes(["gx_dps"]), RATE)
    with pytest.raises(InputError) as err:
        joint_noise(record, noise)
    assert str(err.value) == "a joint noise model needs at least two axes"


@pytest.mark.slow
def test_the_allan_command_writes_the_joint_model(record, tmp_path, capsys):
    path = tmp_path / "imu.csv"
    pd.DataFrame({c: v[:100_000] for c, v in record.items()}).to_csv(path, index=False,
                                                                      float_format="%.9g")
    out = tmp_path / "noise"
    code = cli.main(["allan", str(path), "--rate", "100", "--columns", ",".join(NAMES), "--out",
                     str(out)])
    assert code == 0, capsys.readouterr().err
    data = json.loads((out / "joint_model.json").read_text())
    assert data["axes"] == NAMES
    white = np.array(data["white_correlation"])
    assert white[0, 1] == pytest.approx(0.5, abs=0.02)
    q = np.array(data["Q"])
    assert q.shape == (18, 18) and np.allclose(q, q.T)

"""The filter JSON: written by fosmodel, read back, and run by a client with numpy alone."""

import json
import math
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel, InputError
from fosmodel.filter import (
    KalmanFilter,
    initial_covariance,
    position_velocity_error_model,
    read_filter_file,
    run_filter,
    to_nonlinear_state_space,
    to_state_space,
    write_filter_file,
)

RATE = 10.0
DT = 1.0 / RATE
SIGMA_M = 0.1
CYCLE_S = 30

#: A client's Kalman filter: json and numpy only, the 1-D aided position filter on one axis.
CLIENT = textwrap.dedent("""
    import json, sys
    import numpy as np

    spec = json.load(open(sys.argv[1]))
    data = np.load(sys.argv[2])
    assert spec["schema"] == "fosmodel.filter" and spec["kind"] == "linear"
    A = lambda k: np.array(spec[k], dtype=float)
    phi_e, g_e, q, h_e, b_e, p0_e = A("Phi"), A("G"), A("Q"), A("H"), A("B"), A("P0")
    dt, p, m = spec["dt_s"], len(phi_e), spec["n_inputs"]
    # u: every input is the constant here; the file says so
    assert [i["definition"].startswith("the constant 1") for i in spec["inputs"]] == [True] * m
    u = np.ones(m)
    phi = np.zeros((p + 2, p + 2))
    phi[:2, :2] = [[1.0, dt], [0.0, 1.0]]
    phi[1, 2:] = dt * h_e[0]
    phi[2:, 2:] = phi_e
    g = np.vstack([np.zeros((2, g_e.shape[1])), g_e])
    gqg = g @ q @ g.T
    b = np.vstack([np.zeros((2, m)), b_e]) @ u
    h = np.eye(1, p + 2)
    x = np.r_[0.0, 0.0, A("x0")]
    P = np.zeros((p + 2, p + 2))
    P[2:, 2:] = p0_e
    r = data["r"]
    est, var = [], []
    for zk in data["z"]:
        x = phi @ x + b
        P = phi @ P @ phi.T + gqg
        if np.isfinite(zk):
            s = h @ P @ h.T + r
            k = P @ h.T / s[0, 0]
            x = x + k[:, 0] * (zk - x[0])
            a = np.eye(p + 2) - k @ h
            P = a @ P @ a.T + k @ (r * np.eye(1)) @ k.T
        est.append(x[0])
        var.append(P[0, 0])
    assert "fosmodel" not in sys.modules
    np.save(sys.argv[3], np.array([est, var]))
""")


def _record(n=24_000, seed=21):
    """An accelerometer axis in m/s^2: AR noise about a wandering bias, offset 0.02."""
    rng = np.random.default_rng(seed)
    return (0.02 + lfilter([1.0], [1.0, -0.7], rng.standard_normal(n)) * 2e-3
            + np.cumsum(rng.standard_normal(n)) * 2e-5)


def _truth(error):
    """Position error of the integrated error (the recursion of position_velocity_error_model)."""
    p = v = 0.0
    out = np.empty(len(error))
    for k in range(len(error)):
        prev = error[k - 1] if k else 0.0
        p, v = p + DT * v, v + DT * prev
        out[k] = p
    return out


def _measurements(true, seed=3):
    rng = np.random.default_rng(seed)
    z = true + SIGMA_M * rng.standard_normal(len(true))
    period = round(CYCLE_S / DT)
    z[(np.arange(len(true)) // period) % 2 == 1] = np.nan  # prediction-only half cycles
    return z


def test_a_client_with_numpy_alone_reproduces_run_filter(tmp_path):
    y = _record()
    half = len(y) // 2
    model = FOSModel(max_lag=4, levels=[60.0], rate=RATE).fit(y[:half])
    model = model.refit_weights(y[:half], hold=True)  # a unit root inside the AR
    ss = to_state_space(model)
    path = tmp_path / "ax.json"
    written = write_filter_file(path, ss, n_samples=half, units={"ax": "m/s^2"},
                                meta={"column": "ax"})
    assert written["output_unit"] == "m/s^2" and written["rate_hz"] == RATE
    true = _truth(y[half:] - model.offsets_["y"])
    z = _measurements(true)
    np.savez(tmp_path / "data.npz", z=z, r=SIGMA_M**2)
    subprocess.run([sys.executable, "-I", "-c", CLIENT, str(path), str(tmp_path / "data.npz"),
                    str(tmp_path / "out.npy")], check=True, cwd=tmp_path)
    est, var = np.load(tmp_path / "out.npy")
    # fosmodel's own filter of the same system
    system = position_velocity_error_model(ss, DT)
    p0 = np.zeros((system.n_states,) * 2)
    p0[2:, 2:] = initial_covariance(ss, half)
    kf = KalmanFilter.from_state_space(system, [[SIGMA_M**2]], np.zeros(system.n_states), p0)
    run = run_filter(kf, z, np.ones((len(z), 1)))
    np.testing.assert_allclose(est, run.x[:, 0], rtol=0, atol=1e-9)
    np.testing.assert_allclose(var, run.variance[:, 0], rtol=1e-9)
    rms = math.sqrt(np.mean((est - true) ** 2))
    assert rms < 1.0  # the filter holds the position to metres over 30 s outages


def test_read_back_gives_the_same_system_and_start(tmp_path):
    y = _record(8000)
    model = FOSModel(max_lag=3, levels=[30.0], rate=RATE).fit(y)
    ss = to_state_space(model)
    write_filter_file(tmp_path / "f.json", ss, n_samples=8000)
    back = read_filter_file(tmp_path / "f.json")
    for name in ("Phi", "B", "G", "H", "Q", "D", "level_gains"):
        np.testing.assert_array_equal(getattr(back.system, name), getattr(ss, name))
    assert back.system.rate == RATE and back.system.input_names == ss.input_names
    np.testing.assert_array_equal(back.P0, initial_covariance(ss, 8000))
    assert back.R.shape == (1, 1) and back.inputs[0]["unit"] == "1"
    nonlinear = FOSModel(max_lag=2, degree=2, rate=RATE, max_terms=4,
                         stop="max_terms").fit(y)
    ekf = to_nonlinear_state_space(nonlinear)
    data = write_filter_file(tmp_path / "n.json", ekf, P0=np.eye(ekf.n_states))
    assert data["kind"] == "nonlinear" and "Phi" not in data
    again = read_filter_file(tmp_path / "n.json").system
    x = np.array([0.3, -0.1])
    np.testing.assert_allclose(again.f(x, [1.0]), ekf.f(x, [1.0]), rtol=1e-12)


def test_bad_files_are_refused_by_name(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps({"schema": "fosmodel.filter", "schema_version": 99}))
    with pytest.raises(InputError, match=r"schema_version 99; this fosmodel reads 1$"):
        read_filter_file(path)
    y = _record(4000)
    ss = to_state_space(FOSModel(max_lag=2, rate=RATE).fit(y))
    data = write_filter_file(path, ss, n_samples=4000)
    del data["Q"]
    path.write_text(json.dumps(data))
    with pytest.raises(InputError, match=r"the filter JSON has no 'Q'$"):
        read_filter_file(path)
    no_rate = to_state_space(FOSModel(max_lag=2).fit(y))
    with pytest.raises(InputError, match=r"^the filter JSON needs the model's sample rate"):
        write_filter_file(path, no_rate, n_samples=10)

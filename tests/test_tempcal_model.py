"""An axis's bias against temperature: degree, lag and coefficients recovered with intervals."""

import numpy as np
import pytest
from numpy.polynomial import Polynomial

from fosmodel.core.derived import first_order_lag, parse
from fosmodel.loop.record import LoopRecord
from fosmodel.workflows.tempcal_model import ThermalModel, firmware_projection, fit_thermal

AXES = ("gx_dps", "gy_dps", "gz_dps", "ax_mps2", "ay_mps2", "az_mps2")


def _record(group, column):
    starts = np.cumsum([0] + [len(s.temperature) for s in group.sessions])
    sessions = tuple(slice(a, b) for a, b in zip(starts[:-1], starts[1:]))
    return LoopRecord(np.concatenate([s.columns[column] for s in group.sessions]),
                      {"temp_c": np.concatenate([s.temperature for s in group.sessions])},
                      group.sessions[0].rate, sessions)


def _fit(group, column):
    rec = _record(group, column)
    return fit_thermal(rec, rec.sessions, "temp_c", 25.0, 3, 30, 0.01), rec


def _true(truth, column):
    """The true coefficients of powers 1..3 about 25 C (the fits' centre)."""
    coef = Polynomial(truth["coefs"][column])(Polynomial([25.0 - truth["t_ref_c"], 1.0])).coef
    return {k: float(coef[k]) if k < len(coef) else 0.0 for k in (1, 2, 3)}


def _covered(model, truth, column):
    """Every true coefficient within its interval (one not fitted must be 0)."""
    true, intervals = _true(truth, column), model.intervals(0.95)
    fitted = {int(parse(n)[2]): iv for n, iv in zip(model.forms, intervals)}
    return all(fitted[k][0] <= v <= fitted[k][1] if k in fitted else v == 0
               for k, v in true.items())


def test_each_axis_s_degree_and_coefficients_are_recovered(thermal_group):
    group, truth = thermal_group(0)
    for column in AXES:
        model, _ = _fit(group, column)
        assert model.degree == len(truth["coefs"][column]) - 1, column
        assert model.lag_s is None and model.firmware_form, column
        assert _covered(model, truth, column), column


@pytest.mark.slow
def test_the_coefficients_lie_within_their_intervals_in_nine_seeds_of_ten(thermal_group):
    hits = dict.fromkeys(AXES, 0)
    for seed in range(10):
        group, truth = thermal_group(seed)
        for column in AXES:
            hits[column] += _covered(_fit(group, column)[0], truth, column)
    assert min(hits.values()) >= 9, hits


def test_a_thermal_lag_is_found_and_its_time_constant_refined(thermal_group):
    group, truth = thermal_group(0, lag_s=300.0, columns=["gx_dps", "ay_mps2"])
    for column in ("gx_dps", "ay_mps2"):
        model, _ = _fit(group, column)
        assert model.lag_s == pytest.approx(300.0, rel=0.05), column
        assert not model.firmware_form
        assert _covered(model, truth, column), column


def test_no_temperature_effect_gives_no_forms(thermal_group):
    group, _ = thermal_group(0, coefs={"gx_dps": (0.0,)}, columns=["gx_dps"])
    model, _ = _fit(group, "gx_dps")
    assert model.forms == () and model.degree == 0 and model.p_value >= 0.01
    assert model.describe() == "no temperature effect"
    assert not np.any(model.bias(np.linspace(0, 50, 10), 1.0))


def test_the_firmware_projection_is_the_least_squares_polynomial_of_the_model(thermal_group):
    group, _ = thermal_group(0, lag_s=300.0, columns=["gx_dps"])
    model, rec = _fit(group, "gx_dps")
    firmware = firmware_projection(model, rec, rec.sessions)
    assert firmware.firmware_form and firmware.degree == model.degree
    # the reference: the model's bias on the powers of T beside a constant per session
    temps = [rec.channels["temp_c"][s] for s in rec.sessions]
    bias = np.concatenate([model.bias(t, rec.rate) for t in temps])
    powers = np.concatenate([(t[:, None] - 25.0) ** np.arange(1, model.degree + 1) for t in temps])
    dummies = np.zeros((len(bias), len(temps)))
    for k, s in enumerate(rec.sessions):
        dummies[s, k] = 1
    expected = np.linalg.lstsq(np.column_stack([powers, dummies]), bias, rcond=None)[0]
    np.testing.assert_allclose(firmware.weights, expected[: model.degree], rtol=1e-6)


def test_a_model_is_clipped_to_its_range_and_its_lag_runs_from_the_session_s_start():
    model = ThermalModel("temp_c", 20.0, ("pow(lowpass(temp_c,60s),1,20)",
                                           "pow(lowpass(temp_c,60s),2,20)"), (0.5, 0.01),
                         np.zeros((2, 2)), base_range=(10.0, 30.0))
    temp = np.r_[np.full(100, 0.0), np.linspace(0, 50, 400)]
    base = np.clip(first_order_lag(temp, 60.0, 2.0), 10, 30)
    np.testing.assert_allclose(model.bias(temp, 2.0), 0.5 * (base - 20) + 0.01 * (base - 20) ** 2)
    assert model.lag_s == 60.0 and model.powers == {1: 0.5, 2: 0.01} and model.degree == 2

"""A driver's slow part: its forms recovered, with the level beside it, said when it cannot."""

import numpy as np
import pytest

from fosmodel.core.derived import parse
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.driver_forms import DriverForms, block_samples, form_names, slow_driver
from fosmodel.loop.record import LoopRecord

CONFIG = LoopConfig(rate=1.0, sensor="gyro", units="deg/s")


def _finding(y, temp):
    record = LoopRecord.single(y, {"temp_c": temp}, 1.0)
    return slow_driver(y, "temp_c", DriverForms(record, (slice(0, len(y) // 2),), 20.0), 1e-3)


def test_the_forms_offered_are_powers_of_the_driver_and_its_lags_and_its_rate():
    names = form_names("temp_c", 12.5, 10_800.0, 54.0, 1.0)
    assert names[:2] == ["pow(temp_c,1,12.5)", "pow(temp_c,2,12.5)"]
    lags = sorted({float(parse(parse(n)[1])[2]) for n in names[2:-1]})
    assert lags == [160.0, 240.0, 350.0, 510.0, 740.0, 1100.0]  # 3 blocks .. a tenth of the data
    assert names[-1] == "rate(temp_c,160s)" and len(names) == 2 + 2 * 6 + 1
    assert block_samples([slice(0, 10_800)], 1.0, 20.0) == 54


def test_a_driver_with_its_lagged_form_is_recovered(sweep_record):
    y, temp = sweep_record(0, lag_s=600.0)
    finding = _finding(y, temp)
    assert finding.fired and finding.evidence["level_blocks"] is None
    ((name, weight),) = finding.evidence["forms"]
    kind, base, power, _ = parse(name)
    assert (kind, power, parse(base)[0]) == ("power", "1", "lowpass")
    assert float(parse(base)[2]) == pytest.approx(600.0, rel=0.35)  # the grid's nearest
    assert weight == pytest.approx(0.02, rel=0.15)
    res = close_loop(y, {"temp_c": temp}, CONFIG)
    assert res.steps[0].effect.kind == "driver" and res.steps[0].effect.part == "slow"
    assert res.final_model.model.compensation == dict(finding.evidence["forms"])
    assert not res.worse()


def test_a_known_temperature_sensitivity_is_recovered_with_the_level_in_the_model(
        sweep_record):
    """A bias random walk beside the temperature: the level follows what the driver leaves."""
    y, temp = sweep_record(0, walk=0.0002, noise=0.01)
    res = close_loop(y, {"temp_c": temp}, CONFIG)
    model = res.final_model.model
    ((name, weight),) = model.compensation.items()
    assert parse(name)[:3] == ("power", "temp_c", "1") and weight == pytest.approx(0.02, rel=0.15)
    assert any(t.startswith("level@") for t in model.terms_)
    slow = next(s for s in res.steps if s.effect.kind == "driver")
    assert slow.effect.level_taus or any(s.effect.kind == "level" for s in res.steps)
    assert res.after.bias_rms[300] < 0.5 * res.before.bias_rms[300]
    assert not res.worse()


def test_a_driver_that_does_not_vary_in_the_fitting_segment_is_said_so(sweep_record):
    y, temp = sweep_record(1, still_until=0.6, walk=0.0002)
    assert _finding(y, temp).p_value > 1e-3
    res = close_loop(y, {"temp_c": temp}, CONFIG)
    assert not any(s.effect.kind == "driver" for s in res.steps)
    (note,) = [n for n in res.notes if n.startswith("temp_c")]
    assert note.startswith("temp_c follows the slow residual but does not vary in the fitting "
                           "segment: give a record or sessions where it does (its block means "
                           "correlate with the output's at 0.")


@pytest.mark.parametrize("seed", [0, 1])
def test_a_temperature_that_drives_nothing_is_not_named(seed):
    """The control of the day-long sweep: the same draws, no temperature effect."""
    from data_synth import make_scenario

    rec = make_scenario("temperature_sweep_control", seed=seed)
    y = rec.columns["gx_dps"]
    res = close_loop(y, {k: v for k, v in rec.columns.items() if k != "gx_dps"}, CONFIG)
    assert not any(s.effect.kind == "driver" for s in res.steps), [
        s.effect.describe() for s in res.steps]
    assert not res.worse()


def test_an_accelerometer_drives_a_gyro_in_its_fast_part_only():
    from fosmodel.loop.effects import CandidateFamily
    from fosmodel.loop.findings import Diagnostics
    from fosmodel.loop.fitting import Fitter
    from fosmodel.loop.roles import channel_roles

    rng = np.random.default_rng(0)
    n = 4000
    channels = {"temp_c": np.linspace(5, 20, n), "ax_g": rng.standard_normal(n),
                "gy_dps": rng.standard_normal(n)}
    roles = channel_roles(channels, "gyro")
    assert roles.motion == ("ax_g",) and roles.slow == ("temp_c",)
    record = LoopRecord.single(rng.standard_normal(n), channels, 1.0)
    config = LoopConfig(rate=1.0)
    family = CandidateFamily(config.max_lag)
    model = Fitter(record, slice(0, 2000), config).fit(family)
    findings = Diagnostics(record, (slice(0, 2000),), roles, config)(model, family)
    assert [f.evidence["channel"] for f in findings if f.test == "driver"] == ["temp_c"]
    assert [f.evidence["channel"] for f in findings if f.test == "aux"] == [
        "temp_c", "ax_g", "gy_dps"]  # the companion's correlation is cross-axis noise


def test_a_sweep_under_a_flat_bias_instability_is_found_at_the_longer_scale():
    """An accelerometer's 5e-4 m/s^2/C over a day's sweep, under a bias instability whose
    Allan deviation is flat: at 200 blocks its increments are lost in the flicker's, at a
    quarter as many the sweep has moved further than the flicker can."""
    from data_synth import make_sessions

    rec = make_sessions("temperature_sweep", seed=0)[0]
    y, temp = rec.columns["ax_mps2"], rec.columns["temp_c"]
    finding = _finding(y, temp)
    assert finding.fired and finding.p_value < 1e-6
    assert finding.evidence["block_s"] == 4 * block_samples([slice(0, len(y) // 2)], 1.0, 20.0)
    weights = dict(finding.evidence["forms"])
    assert weights[next(iter(weights))] == pytest.approx(5e-4, rel=0.2)


def _ramp_then_hold(seed, n=40_000):
    """A driver that ramps steadily over the first half and holds over the second, and an
    output that follows it (5e-3 per degree) beside a bias random walk."""
    rng = np.random.default_rng(seed)
    temp = np.minimum(np.linspace(5.0, 35.0, n), 20.0)
    y = 5e-3 * temp + np.cumsum(rng.normal(0, 5e-5, n)) + rng.normal(0, 0.01, n)
    return y, {"pow(temp_c,1,20)": temp - 20.0}


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_a_steady_ramp_beside_a_trend_does_not_tell_a_sensitivity_from_none(seed):
    """Over the ramp alone the driver is one line with the trend fitted beside it; once it
    has held still a while its sensitivity shows."""
    from fosmodel.loop.driver_forms import TREND, forms_p, refit_forms

    y, forms = _ramp_then_hold(seed)
    block = 100
    assert forms_p(y, forms, [slice(0, 18_000)], block, TREND) > 1e-3
    assert forms_p(y, forms, [slice(0, 30_000)], block, TREND) < 1e-6
    (weight,) = refit_forms(y, forms, [slice(0, 30_000)], block, TREND).values()
    assert weight == pytest.approx(5e-3, rel=0.3)
    (over_ramp,) = refit_forms(y, forms, [slice(0, 18_000)], block, TREND).values()
    assert abs(over_ramp) > 100 * 5e-3  # what the noise makes it
    # beside itself a form adds nothing
    assert forms_p(y, forms, [slice(0, 30_000)], block, TREND,
                   beside={"same": forms["pow(temp_c,1,20)"]}) == pytest.approx(1.0, abs=1e-6)


def test_an_origin_whose_past_is_a_steady_ramp_does_not_judge_the_driver():
    """The day's accelerometer sweep (5e-4 m/s^2/C): its temperature climbs steadily until a
    third of the day, so the origins at a quarter and a third of it cannot estimate the
    sensitivity beside a trend; judged from them its free runs lost hundreds of times the
    level's 30 min bias and the temperature went unnamed.  Judged from the origins that can,
    it goes in, once."""
    from data_synth import make_sessions

    rec = make_sessions("temperature_sweep", seed=2)[0]
    y = rec.columns["ax_mps2"]
    channels = {k: v for k, v in rec.columns.items() if k != "ax_mps2"}
    res = close_loop(y, channels, LoopConfig(rate=1.0, sensor="accel", units="m/s^2"))
    (slow,) = [s for s in res.steps if s.effect.kind == "driver"]
    assert slow.effect.channel == "temp_c" and slow.effect.part == "slow"
    assert slow.judgement.gains(slow.judgement.kept_on)[:2] == [None, None]
    assert res.after.bias_rms[1800] < 0.8 * res.before.bias_rms[1800]
    assert not res.worse()

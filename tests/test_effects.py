import numpy as np
import pytest

from fosmodel.core.levels import level_series
from fosmodel.loop.diagnose import Finding
from fosmodel.loop.effects import CandidateFamily, Effect, effects_from

RATE = 10.0
N = 200
TIME = np.arange(N) / RATE
TRAIN = slice(0, 100)


def test_each_kind_adds_its_candidates():
    temp = np.linspace(20, 30, N)
    fam = CandidateFamily(5)
    aux = fam.add(Effect("aux", channel="temp", max_lag=3), {"temp": temp}, N, RATE, TRAIN)
    assert aux.exog_lags == {"temp": 3} and aux.inputs["temp"] is temp
    np.testing.assert_allclose(aux.columns["sq(temp)"], (temp - temp[:100].mean()) ** 2)
    fast = fam.add(Effect("aux", channel="temp", max_lag=2, form="fast", tau_s=20.0),
                   {"temp": temp}, N, RATE, TRAIN)
    assert fast.exog_lags == {"temp_fast20s": 2} and not fast.columns
    np.testing.assert_allclose(fast.inputs["temp_fast20s"], temp - level_series(temp, 20, RATE))
    per = fam.add(Effect("periodic", freq_hz=1.25), {}, N, RATE, TRAIN)
    np.testing.assert_allclose(per.columns["cos@1.25Hz"], np.cos(2 * np.pi * 1.25 * TIME))
    np.testing.assert_allclose(per.columns["sin@1.25Hz"], np.sin(2 * np.pi * 1.25 * TIME))
    nonlinear = fam.add(Effect("nonlinear", max_lag=4), {}, N, RATE, TRAIN)
    assert nonlinear.degree == 2 and nonlinear.product_lags == 4
    level = fam.add(Effect("level", taus=(2.0, 8.0)), {}, N, RATE, TRAIN)
    assert level.levels == (2.0, 8.0) and not level.columns
    drift = fam.add(Effect("drift", form="linear", tau_s=4.0), {}, N, RATE, TRAIN)
    np.testing.assert_allclose(drift.columns["t@s"], TIME)
    np.testing.assert_allclose(drift.columns["exp(-t/4s)"], np.exp(-TIME / 4.0))
    step = fam.add(Effect("step", time_s=7.5), {}, N, RATE, TRAIN)
    np.testing.assert_array_equal(step.columns["step@7.5s"], (TIME >= 7.5).astype(float))
    assert fam.columns == {} and fam.degree == 1  # the family itself is unchanged


def test_candidate_names_are_valid_fos_column_names():
    from fosmodel.core.candidates import CandidateSpec

    fam = CandidateFamily(2)
    for e in (Effect("aux", channel="temp_c", max_lag=1),
              Effect("aux", channel="temp_c", max_lag=1, form="fast", tau_s=20.0),
              Effect("periodic", freq_hz=7.3137), Effect("level", taus=(1.0, 3.5)),
              Effect("drift", form="exponential", tau_s=62.33), Effect("step", time_s=104.9)):
        fam = fam.add(e, {"temp_c": TIME}, N, RATE, TRAIN)
    CandidateSpec(2, 1, fam.exog_lags, list(fam.columns), levels=fam.levels)  # raises if bad


def _finding(test, fired, **evidence):
    return Finding(test, 1.0, 0.0 if fired else 1.0, 0.01, evidence)


def test_findings_map_to_effects():
    findings = [
        _finding("whiteness", True), _finding("allan", True),
        _finding("periodic", True, freq_hz=7.3), _finding("aux", True, channel="t", lag=4),
        _finding("aux", False, channel="u", lag=0), _finding("nonlinear", True, max_lag=4),
        _finding("trend", True, form="linear", tau_s=50.0), _finding("step", True, time_s=9.0)]
    effects = effects_from(findings, aux_max_lag=2, level_taus=(1.0, 5.0), fast_tau_s=20.0)
    assert [(e.kind, e.form) for e in effects] == [
        ("level", None), ("periodic", None), ("aux", None), ("aux", "fast"),
        ("nonlinear", None), ("drift", "linear"), ("step", None)]
    level, _, aux, fast, nonlinear, _, step = effects
    assert level.taus == (1.0, 5.0) and level.evidence["slow_tests"] == ["allan", "trend", "step"]
    assert aux.channel == fast.channel == "t" and aux.max_lag == fast.max_lag == 4
    assert fast.tau_s == 20.0 and nonlinear.max_lag == 4
    assert effects[1].freq_hz == 7.3 and step.time_s == 9.0
    # no slow test fired, or no grid: no level
    assert all(e.kind != "level" for e in effects_from(findings[2:6], 2, (1.0,)))
    assert all(e.kind != "level" for e in effects_from(findings, 2, ()))


def test_slow_relations_and_sameness():
    assert Effect("drift", tau_s=5.0).is_slow and Effect("step", time_s=1.0).is_slow
    assert Effect("aux", channel="t").is_slow
    assert not Effect("aux", channel="t", form="fast", tau_s=20.0).is_slow
    assert not Effect("level", taus=(1.0,)).is_slow and not Effect("periodic").is_slow
    assert not Effect("aux", channel="t").same_as(Effect("aux", channel="t", form="fast"))
    assert Effect("level", taus=(1.0,)).same_as(Effect("level", taus=(2.0,)))


def test_describe_and_bad_kind():
    assert Effect("periodic", freq_hz=7.31374).describe() == "periodic 7.3137 Hz"
    assert "step at 105 s" == Effect("step", time_s=105.0).describe()
    assert Effect("level", taus=(1.5, 30.0)).describe() == "local level (tau 1.5-30 s)"
    assert Effect("aux", channel="ay", max_lag=10, form="fast", tau_s=20.0).describe() == (
        "aux ay, fast part (lags 0-10)")
    assert Effect("nonlinear", max_lag=4).describe() == (
        "nonlinear (cross-products of degree 2 of y[n-1]..y[n-4])")
    with pytest.raises(ValueError):
        Effect("magic")

import numpy as np
import pytest

from fosmodel.diagnose import Finding
from fosmodel.effects import CandidateFamily, Effect, effects_from

RATE = 10.0
TIME = np.arange(200) / RATE
TRAIN = slice(0, 100)


def test_each_kind_adds_its_candidates():
    temp = np.linspace(20, 30, 200)
    fam = CandidateFamily(5)
    aux = fam.add(Effect("aux", channel="temp", max_lag=3), {"temp": temp}, TIME, TRAIN)
    assert aux.exog_lags == {"temp": 3}
    np.testing.assert_allclose(aux.columns["sq(temp)"], (temp - temp[:100].mean()) ** 2)
    per = fam.add(Effect("periodic", freq_hz=1.25), {}, TIME, TRAIN)
    np.testing.assert_allclose(per.columns["cos@1.2500Hz"], np.cos(2 * np.pi * 1.25 * TIME))
    np.testing.assert_allclose(per.columns["sin@1.2500Hz"], np.sin(2 * np.pi * 1.25 * TIME))
    assert fam.add(Effect("nonlinear"), {}, TIME, TRAIN).degree == 2
    drift = fam.add(Effect("drift", form="linear", tau_s=4.0), {}, TIME, TRAIN)
    np.testing.assert_allclose(drift.columns["t"], TIME)
    np.testing.assert_allclose(drift.columns["exp(-t/4s)"], np.exp(-TIME / 4.0))
    step = fam.add(Effect("step", time_s=7.5), {}, TIME, TRAIN)
    np.testing.assert_array_equal(step.columns["step@7.5s"], (TIME >= 7.5).astype(float))
    assert fam.columns == {} and fam.degree == 1  # the family itself is unchanged


def test_candidate_names_are_valid_fos_column_names():
    from fosmodel.candidates import CandidateSpec

    fam = CandidateFamily(2)
    for e in (Effect("aux", channel="temp_c", max_lag=1), Effect("periodic", freq_hz=7.3137),
              Effect("drift", form="exponential", tau_s=62.33), Effect("step", time_s=104.9)):
        fam = fam.add(e, {"temp_c": TIME}, TIME, TRAIN)
    CandidateSpec(2, 1, fam.exog_lags, list(fam.columns))  # raises on a bad name


def _finding(test, fired, **evidence):
    return Finding(test, 1.0, 0.0 if fired else 1.0, 0.01, evidence)


def test_findings_map_to_effects():
    findings = [
        _finding("whiteness", True), _finding("allan", True),
        _finding("periodic", True, freq_hz=7.3), _finding("aux", True, channel="t", lag=4),
        _finding("aux", False, channel="u", lag=0), _finding("nonlinear", True),
        _finding("trend", True, form="linear", tau_s=50.0), _finding("step", True, time_s=9.0)]
    effects = effects_from(findings, aux_max_lag=2)
    assert [e.kind for e in effects] == ["periodic", "aux", "nonlinear", "drift", "step"]
    aux = effects[1]
    assert aux.channel == "t" and aux.max_lag == 4  # at least the lag found
    assert effects[0].freq_hz == 7.3 and effects[4].time_s == 9.0


def test_describe_and_bad_kind():
    assert Effect("periodic", freq_hz=7.31374).describe() == "periodic 7.3137 Hz"
    assert "step at 105 s" == Effect("step", time_s=105.0).describe()
    with pytest.raises(ValueError):
        Effect("magic")

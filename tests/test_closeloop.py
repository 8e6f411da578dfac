"""The residual loop on data_synth records whose effect nobody declared (issues 5 and 15)."""

import numpy as np
import pytest
from scipy.signal import lfilter

from data_synth import make_scenario
from data_synth.true_effects import true_effects
from fosmodel.core.exceptions import InputError
from fosmodel.loop.closeloop import LoopConfig, close_loop, score_family
from fosmodel.loop.effects import CandidateFamily
from fosmodel.loop.judge import MIN_HALF_WINDOWS, compare, forecasts, outage_windows


def _run(name, seed, **kw):
    rec = make_scenario(name, seed=seed, **kw)
    y = rec.columns[rec.target]
    channels = {k: v for k, v in rec.columns.items() if k != rec.target}
    config = LoopConfig(rate=rec.rate, sensor="gyro", units=rec.truth["units"])
    return rec, y, channels, config, close_loop(y, channels, config)


def _found(res, true):
    """The kept step that is the true effect (kind, and channel for an input), or None."""
    return next((s for s in res.steps if s.effect.kind == true.kind
                 and (true.kind != "aux" or s.effect.channel == true.channel)), None)


@pytest.mark.parametrize("seed", [0, 1])
@pytest.mark.parametrize("name", [
    "undeclared_temperature", "undeclared_vibration", "undeclared_nonlinear",
    "undeclared_drift", "undeclared_aux_lag", "undeclared_step"])
@pytest.mark.slow
def test_loop_finds_the_effect_and_recovers_half_of_what_the_truth_gives(name, seed):
    rec, y, channels, config, res = _run(name, seed)
    ((true, slow),) = true_effects(rec.truth)
    step = _found(res, true)
    assert step is not None, [s.effect.describe() for s in res.steps]
    # besides the effect, at most the local level (a slow error's stochastic form)
    assert {s.effect.kind for s in res.steps} <= {true.kind, "level"}
    if name == "undeclared_aux_lag":
        assert step.lag == 3
    if true.kind == "periodic":
        assert abs(step.effect.freq_hz - true.freq_hz) < 0.05
    metric = "outage_mse" if slow else "mse"
    family = CandidateFamily(config.max_lag).add(true, channels, len(y), rec.rate,
                                                 res.segments.train)
    truth = score_family(y, channels, config, family)
    before, after = res.before[metric], res.after[metric]
    assert before - after >= 0.5 * (before - truth[metric]) > 0


@pytest.mark.parametrize("name", ["clean", "unrelated_temperature"])
@pytest.mark.slow
def test_controls_add_nothing_and_never_worsen(name):
    added = 0
    for seed in range(20):
        _, _, _, _, res = _run(name, seed)
        added += bool(res.steps)
        assert res.after["mse"] <= 1.01 * res.before["mse"]
    assert added <= 1


def test_two_effects_at_once_are_both_found():
    _, _, _, _, res = _run("temperature_and_vibration", 0)
    found = {(s.effect.kind, s.effect.channel) for s in res.steps}
    assert ("aux", "temp_c") in found and any(k == "periodic" for k, _ in found)
    freq = next(s.effect.freq_hz for s in res.steps if s.effect.kind == "periodic")
    assert abs(freq - 7.3137) < 0.05


def test_a_random_walk_bias_is_taken_as_a_level_not_a_function_of_time():
    rng = np.random.default_rng(4)
    n, rate = 60_000, 100.0
    noise = lfilter([1.0], [1.0, -0.6, 0.1], rng.standard_normal(n)) * 0.3
    y = noise + np.cumsum(rng.standard_normal(n)) * 0.004
    config = LoopConfig(rate=rate, sensor="gyro", units="deg/s")
    res = close_loop(y, {}, config)
    kinds = [s.effect.kind for s in res.steps]
    assert kinds[:1] == ["level"] and "drift" not in kinds
    assert res.steps[0].tau_s in res.level_taus
    assert res.after["bias_rms"]["30"] < res.before["bias_rms"]["30"]
    assert not res.worse()


def test_a_level_is_rejected_where_there_is_no_slow_error():
    rng = np.random.default_rng(5)
    y = lfilter([1.0], [1.0, -0.6, 0.1], rng.standard_normal(60_000)) * 0.3
    config = LoopConfig(rate=100.0, level_taus=(0.5, 2.0, 8.0))
    # the slow tests are what offer a level: force the offer by judging it directly
    from fosmodel.loop.closeloop import _Fitter, _Judge, loop_split
    from fosmodel.loop.effects import Effect

    segments = loop_split(len(y), config)
    fitter = _Fitter(y, {}, segments, config)
    family = CandidateFamily(config.max_lag)
    current = fitter.fit(family)
    effect = Effect("level", taus=config.level_taus)
    trial = fitter.fit(family.add(effect, {}, len(y), 100.0, segments.train))
    verdict = _Judge(fitter, current, y, segments, config)(trial, effect)
    assert not verdict["accepted"]
    assert close_loop(y, {}, config).steps == []


def test_the_prediction_segment_never_decides():
    rec, y, channels, config, res = _run("undeclared_vibration", 0)
    z = y.copy()
    predict = res.segments.predict
    z[predict] += 5 * np.sin(np.arange(predict.stop - predict.start) * 0.37)  # a new effect
    other = close_loop(z, channels, config)
    assert [s.effect for s in other.steps] == [s.effect for s in res.steps]
    assert [s.comparison for s in other.steps] == [s.comparison for s in res.steps]


def test_json_has_the_documented_layout():
    _, _, _, _, res = _run("undeclared_aux_lag", 0)
    data = res.to_json_dict()
    keys = {"mse", "position_error_m", "outage_mse", "bias_rms", "outage_position_error_m",
            "terms"}
    assert keys <= set(data["before"]) and keys <= set(data["after"])
    effect = data["effects"][0]
    assert {"kind", "channel", "lag", "freq_hz", "tau_s", "evidence", "mse_before",
            "mse_after"} <= set(effect)
    assert effect["kind"] == "aux" and effect["channel"] == "accel_x" and effect["lag"] == 3
    assert effect["freq_hz"] is None and effect["mse_after"] < effect["mse_before"]
    evaluation = effect["evidence"]["evaluation"]
    assert len(evaluation["origins_s"]) == 4 and evaluation["kept_on"] in ("one_step", "outage")
    assert {"worse_on_prediction", "level_taus_offered", "rejected"} <= set(data)


class _LastPlus:
    """Predicts the last sample plus ``step[n]``; its free runs hold the last sample."""

    def __init__(self, step):
        self.step = step

    def predict(self, y):
        return np.r_[np.nan, y[:-1]] + self.step[: len(y)]

    def simulate(self, y_init, n_steps):
        return np.full(n_steps, np.asarray(y_init)[-1])


def _compare(a, b, y, segment, config):
    horizon = round(config.eval_horizon_s * config.rate)
    starts = outage_windows(segment, horizon)
    return compare(forecasts(a, y, segment, starts, horizon),
                   forecasts(b, y, segment, starts, horizon), config.accept_alpha)


def test_a_change_that_helps_only_in_the_first_half_of_the_evaluation_does_not_pass():
    rng = np.random.default_rng(0)
    n, segment = 6000, slice(2000, 6000)
    jump = rng.standard_normal(n)
    y = np.cumsum(jump) + rng.standard_normal(n)
    config = LoopConfig(rate=10.0)
    base = _LastPlus(np.zeros(n))
    share = np.where(np.arange(n) < 4000, 1.0, -0.2)  # knows the jumps, then errs the other way
    fading = _compare(base, _LastPlus(share * jump), y, segment, config)
    # significant over the whole segment, and lower errors there
    assert fading["one_step_p"] < config.accept_alpha / 2 and fading["one_step_gain"] > 0.05
    first, second = fading["one_step_gain_halves"]
    assert fading["halves_judged"] and first > 0 > second
    assert "one_step" in fading["passes_whole"] and "one_step" not in fading["passes"]
    steady = _compare(base, _LastPlus(0.4 * jump), y, segment, config)
    assert min(steady["one_step_gain_halves"]) > 0 and "one_step" in steady["passes"]
    # too few outage windows to judge halves: the whole segment decides
    short = _compare(base, _LastPlus(share * jump), y, slice(3500, 4500), config)
    assert 2 * MIN_HALF_WINDOWS > 20 and not short["halves_judged"]
    assert short["one_step_gain_halves"][1] < 0 and "one_step" in short["passes"]


def test_too_short_a_record_is_refused():
    rec = make_scenario("clean", duration=60.0, seed=0)
    with pytest.raises(InputError, match="too short for the split"):
        close_loop(rec.columns["gyro_x"], {}, LoopConfig(rate=rec.rate))


@pytest.mark.slow
def test_a_rejected_candidate_keeps_no_columns_into_the_next_diagnosis(monkeypatch):
    # memory of long records: at each diagnosis the only effect columns alive are the model's
    import gc
    import weakref

    from fosmodel.loop import closeloop

    made: list = []
    checked: list[int] = []
    add, diagnose = CandidateFamily.add, closeloop._Diagnostics.__call__

    def recording_add(self, effect, *args, **kwargs):
        family = add(self, effect, *args, **kwargs)
        made.extend(weakref.ref(v) for k, v in family.columns.items() if k not in self.columns)
        return family

    def checking_diagnose(self, model):
        gc.collect()
        alive = [ref() for ref in made if ref() is not None]
        assert all(any(a is v for v in model.inputs.values()) for a in alive)
        checked.append(len(made))
        return diagnose(self, model)

    monkeypatch.setattr(CandidateFamily, "add", recording_add)
    monkeypatch.setattr(closeloop._Diagnostics, "__call__", checking_diagnose)
    res = _run("slow_steps", 0)[-1]
    assert len(checked) >= 2 and checked[-1] > 0  # a diagnosis after columns were tried
    assert any(r["kind"] in ("drift", "step") for r in res.rejected)

"""The effect catalogue: each kind through the registry, its candidates, JSON and offers."""

from dataclasses import dataclass

import numpy as np
import pytest

from fosmodel.core.candidates import CandidateSpec
from fosmodel.core.derived import cosine_name, lowpass_name, power_name, sine_name
from fosmodel.core.levels import level_series
from fosmodel.loop.config import LoopConfig
from fosmodel.loop.diagnose import Finding
from fosmodel.loop.driver_forms import follows_time
from fosmodel.loop.effects import (
    CandidateFamily,
    Effect,
    Offer,
    effect_class,
    effect_from_dict,
    effects_from,
    kinds,
    make_effect,
    register,
    unregister,
)
from fosmodel.loop.effects.drift import Drift, trend_note
from fosmodel.loop.record import LoopRecord
from fosmodel.loop.roles import channel_roles

RATE = 10.0
N = 2000
TIME = np.arange(N) / RATE
TEMP = np.linspace(20, 30, N)
RECORD = LoopRecord.single(np.sin(TIME), {"temp_c": TEMP, "Accel X (g)": np.cos(TIME),
                                          "gz_dps": np.cos(2 * TIME)}, RATE)


def test_every_kind_is_registered_in_rank_order():
    assert kinds() == ("level", "driver", "companion", "periodic", "nonlinear", "drift", "step")
    assert all(effect_class(k).kind == k for k in kinds())
    with pytest.raises(ValueError, match="unknown effect kind 'magic'; known: level, driver"):
        make_effect("magic")


def test_each_kind_adds_its_candidates():
    fam = CandidateFamily(5)
    lag = power_name("temp_c", 1, 25.0, tau_s=60)
    slow = fam.add(make_effect("driver", channel="temp_c", part="slow", forms=[[lag, 0.02]],
                        level_taus=[2.0, 8.0], block=10, level_blocks=6.0), RECORD)
    assert slow.compensation == {lag: 0.02} and slow.levels == (2.0, 8.0)
    assert slow.comp_fit == (10, 1 / 6.0) and not slow.exog_lags
    np.testing.assert_allclose(slow.compensation_series(),
                               0.02 * (RECORD.derive(lowpass_name("temp_c", 60)) - 25.0))
    fast = fam.add(make_effect("driver", channel="Accel X (g)", part="fast", max_lag=2, tau_s=20.0),
                   RECORD)
    token = "u__Accel_20_X_20__28_g_29__fast20s"
    assert fast.exog_lags == {token: 2} and not fast.columns
    x = RECORD.channels["Accel X (g)"]
    start = x[:200].mean()  # the fast part's level starts at the mean of its first 20 s
    np.testing.assert_allclose(fast.inputs[token], x - level_series(np.r_[start, x], 20, RATE)[1:])
    companion = fam.add(make_effect("companion", channel="gz_dps", max_lag=3, tau_s=20.0), RECORD)
    assert companion.exog_lags == {"gz_dps_fast20s": 3}
    per = fam.add(make_effect("periodic", freq_hz=1.25), RECORD)
    np.testing.assert_allclose(per.columns["cos@1.25Hz"], np.cos(2 * np.pi * 1.25 * TIME))
    np.testing.assert_allclose(per.columns["sin@1.25Hz"], np.sin(2 * np.pi * 1.25 * TIME))
    nonlinear = fam.add(make_effect("nonlinear", max_lag=4), RECORD)
    assert nonlinear.degree == 2 and nonlinear.product_lags == 4
    level = fam.add(make_effect("level", taus=(2.0, 8.0)), RECORD)
    assert level.levels == (2.0, 8.0) and not level.columns
    drift = fam.add(make_effect("drift", form="linear", tau_s=4.0), RECORD)
    np.testing.assert_allclose(drift.columns["t@s"], TIME)
    np.testing.assert_allclose(drift.columns["exp(-t/4s)"], np.exp(-TIME / 4.0))
    step = fam.add(make_effect("step", time_s=7.5), RECORD)
    np.testing.assert_array_equal(step.columns["step@7.5s"], (TIME >= 7.5).astype(float))
    assert fam.columns == {} and fam.degree == 1  # the family itself is unchanged
    spec = CandidateSpec(2, 1, {**fast.exog_lags, **companion.exog_lags},
                         [*per.columns, *drift.columns, *step.columns], levels=level.levels)
    assert len(spec.exog_lags) == 2  # raises if a name were not a valid candidate name


@pytest.mark.parametrize("effect", [
    make_effect("level", taus=(1.5, 30.0)),
    make_effect("driver", channel="temp_c", part="slow", forms=[["pow(temp_c,2,25)", 0.001]],
         level_taus=[3.0], block=20, level_blocks=None),
    make_effect("driver", channel="ay", part="fast", max_lag=10, tau_s=20.0),
    make_effect("companion", channel="gz_dps", max_lag=10, tau_s=20.0),
    make_effect("periodic", freq_hz=7.31374), make_effect("nonlinear", max_lag=4),
    make_effect("drift", form="exponential", tau_s=62.33), make_effect("step", time_s=104.9)])
def test_each_kind_round_trips_through_its_json(effect):
    import json

    back = effect_from_dict(json.loads(json.dumps(effect.to_dict())))
    assert back == effect and back.describe() == effect.describe()
    assert back.same_as(effect)


def test_descriptions():
    assert make_effect("periodic", freq_hz=7.31374).describe() == "periodic 7.3137 Hz"
    assert make_effect("step", time_s=105.0).describe() == "step at 105 s"
    assert make_effect("level", taus=(1.5, 30.0)).describe() == "local level (tau 1.5-30 s)"
    assert make_effect("driver", channel="ay", part="fast", max_lag=10, tau_s=20.0).describe() == (
        "driver ay, fast part (lags 0-10)")
    forms = [[power_name("temp_c", 1, 25), 0.02], [power_name("temp_c", 2, 25), 0.001],
             [power_name("temp_c", 1, 25, tau_s=600), 0.01]]
    assert make_effect("driver", channel="temp_c", part="slow", forms=forms,
                level_taus=[5.0]).describe() == (
        "driver temp_c, slow part (as read, powers 1, 2; lag 600 s, power 1) with the level")
    assert make_effect("companion", channel="gz_dps", max_lag=10).describe() == (
        "companion gz_dps as an input, as asked (fast part, lags 0-10)")
    assert make_effect("nonlinear", max_lag=4).describe() == (
        "nonlinear (cross-products of degree 2 of y[n-1]..y[n-4])")
    # the synthetic records' truth still spells a channel input "aux": a driver's fast part
    assert make_effect("aux", channel="accel_x", max_lag=5).describe() == (
        "driver accel_x, fast part (lags 0-5)")


def _finding(test, fired, **evidence):
    return Finding(test, 1.0, 0.0 if fired else 1.0, 0.01, evidence)


def _offer(findings, aux=(), family=None):
    config = LoopConfig(rate=RATE, sensor="gyro", units="deg/s", aux=aux)
    roles = channel_roles(["temp_c", "ax_g", "gz_dps"], "gyro", aux=aux)
    return Offer(findings, RECORD, (slice(0, 1000),), roles, config,
                 family or CandidateFamily(5), (1.0, 5.0))


FINDINGS = [
    _finding("whiteness", True), _finding("allan", True),
    _finding("periodic", True, freq_hz=7.3), _finding("aux", True, channel="ax_g", lag=4),
    _finding("aux", True, channel="gz_dps", lag=1), _finding("aux", False, channel="temp_c",
                                                             lag=0),
    _finding("nonlinear", True, max_lag=4), _finding("trend", True, form="linear", tau_s=50.0),
    _finding("step", True, time_s=9.0),
    _finding("driver", True, channel="temp_c", forms=[["pow(temp_c,1,25)", 0.02]],
             block_s=1.0, level_blocks=6.0, share=0.5)]


def test_findings_offer_effects_by_role():
    effects = effects_from(_offer(FINDINGS))
    assert [(e.kind, getattr(e, "part", None)) for e in effects] == [
        ("level", None), ("driver", "slow"), ("driver", "fast"), ("periodic", None),
        ("nonlinear", None), ("drift", None), ("step", None)]
    level, slow, fast, *_ = effects
    assert level.taus == (1.0, 5.0) and level.evidence["slow_tests"] == ["allan", "trend", "step"]
    assert slow.channel == "temp_c" and slow.forms == (("pow(temp_c,1,25)", 0.02),)
    assert slow.level_taus and slow.block == 10 and slow.level_blocks == 6.0
    assert fast.channel == "ax_g" and fast.max_lag == 10  # an accelerometer drives a gyro
    # the companion gz_dps correlates, but is no input unless asked for
    assert not any(getattr(e, "channel", None) == "gz_dps" for e in effects)
    asked = effects_from(_offer(FINDINGS, aux=("gz_dps",)))
    (companion,) = [e for e in asked if e.kind == "companion"]
    assert companion.channel == "gz_dps" and companion.max_lag == 10
    # no slow test fired and no level in the model: no level, and the driver comes alone
    quiet = effects_from(_offer([f for f in FINDINGS if f.test not in ("allan", "trend",
                                                                       "step")]))
    assert "level" not in [e.kind for e in quiet]
    assert next(e for e in quiet if e.kind == "driver").level_taus is None


def test_slow_relations_and_sameness():
    assert make_effect("drift", tau_s=5.0).strict and make_effect("step", time_s=1.0).strict
    assert not make_effect("level", taus=(1.0,)).strict
    assert not make_effect("driver", channel="t", part="slow").strict
    assert make_effect("driver", channel="t", part="fast", max_lag=1, tau_s=20.0).strict
    assert not make_effect("driver", channel="t", part="fast").same_as(
        make_effect("driver", channel="t"))
    assert make_effect("level", taus=(1.0,)).same_as(make_effect("level", taus=(2.0,)))
    # a slow part's forms with the level or without are one cause, added once; other forms
    # (a lag the residual still follows) are another
    lagged = [["pow(lowpass(t,600s),1,10)", 2.0]]
    alone = make_effect("driver", channel="t", forms=[["pow(t,1,10)", 1.0]])
    assert make_effect("driver", channel="t", forms=[["pow(t,1,10)", 0.5]],
                level_taus=[10.0]).same_as(alone)
    assert not make_effect("driver", channel="t", forms=lagged).same_as(alone)
    assert make_effect("periodic", freq_hz=7.30).same_as(make_effect("periodic", freq_hz=7.33))
    assert make_effect("drift").waits_for == ("level", "driver") == make_effect("step").waits_for
    assert not make_effect("periodic").pooled and not make_effect("step").pooled
    assert make_effect("driver", channel="t").pooled and make_effect("drift").pooled


@dataclass(frozen=True)
class _SlowLine(Effect):
    """A toy kind: a line too slow for the periodic test, offered whenever the residual is
    not white."""

    kind = "toy_slow_line"
    rank = 5
    freq_hz: float = 0.02

    @classmethod
    def offered(cls, offer):
        return [cls()] if offer.fired("whiteness") else []

    def add_to(self, family, record):
        return family.with_columns([cosine_name(self.freq_hz), sine_name(self.freq_hz)],
                                   record)

    def describe(self):
        return f"toy line {self.freq_hz:g} Hz"


@pytest.fixture
def toy_kind():
    register(_SlowLine)
    yield _SlowLine
    unregister(_SlowLine.kind)


def test_a_new_kind_is_one_registered_class_and_runs_through_the_loop(toy_kind, tmp_path):
    from scipy.signal import lfilter

    from fosmodel.loop.closeloop import close_loop
    from fosmodel.loop.loop_report import write_loop_report

    assert "toy_slow_line" in kinds()
    rng = np.random.default_rng(1)
    n, rate = 30_000, 100.0
    t = np.arange(n) / rate
    y = (lfilter([1.0], [1.0, -0.5], rng.standard_normal(n)) * 0.1
         + 0.2 * np.sin(2 * np.pi * 0.02 * t + 0.4))
    res = close_loop(y, {}, LoopConfig(rate=rate))
    assert res.steps[0].effect.kind == "toy_slow_line", [s.effect.describe() for s in res.steps]
    assert {"cos@0.02Hz", "sin@0.02Hz"} & set(res.steps[0].terms_added)
    assert res.to_json_dict()["effects"][0]["kind"] == "toy_slow_line"
    assert "toy line 0.02 Hz" in (write_loop_report(res, tmp_path, "toy")[-1]).read_text()
    with pytest.raises(ValueError, match="registered already"):
        register(type("Other", (_SlowLine,), {"kind": "toy_slow_line"}))


def _sweep_offer(temp, form):
    """An offer on a 20,000 s record at 10 Hz whose trend test fired with ``form``."""
    n = 200_000
    record = LoopRecord.single(np.zeros(n), {"temp_c": temp, "gz_dps": np.zeros(n)}, RATE)
    config = LoopConfig(rate=RATE, sensor="gyro", units="deg/s")
    roles = channel_roles(["temp_c", "gz_dps"], "gyro")
    return Offer([_finding("trend", True, form=form, tau_s=50.0)], record,
                 (slice(0, n // 2),), roles, config, CandidateFamily(5), (1.0,))


def test_a_driver_that_follows_time_leaves_the_trend_out():
    t = np.arange(200_000) / RATE
    ramp = 5 + 1e-3 * t + 0.01 * np.random.default_rng(0).standard_normal(t.size)
    wave = np.sin(2 * np.pi * t / 2000.0)  # slow, but no line in time
    record = LoopRecord.single(np.zeros(t.size), {"ramp": ramp, "wave": wave}, RATE)
    fit = (slice(0, 100_000),)
    assert follows_time(record, fit, "ramp", 200) == pytest.approx(1, abs=1e-3)
    assert follows_time(record, fit, "wave", 200) is None
    # too few blocks to tell a line from chance: a short record's driver never follows time
    assert follows_time(record, (slice(0, 10_000),), "ramp", 200) is None
    # the warm-up alone where the temperature follows time; nothing for a line in time
    (drift,) = Drift.offered(_sweep_offer(ramp, "linear+exponential"))
    assert not drift.trend and drift.follower == "temp_c"
    assert drift.describe() == ("drift (warm-up, tau 50 s; no trend: temp_c follows time in "
                                "the fitting data)")
    assert list(CandidateFamily(5).add(drift, record).columns) == ["exp(-t/50s)"]
    assert Drift.offered(_sweep_offer(ramp, "linear")) == []
    (free,) = Drift.offered(_sweep_offer(wave, "linear"))
    assert free.trend and free.describe() == "drift (trend and warm-up, tau 50 s)"
    notes = trend_note(record, fit, channel_roles(["ramp", "wave"], "gyro"),
                       LoopConfig(rate=RATE))
    assert notes == ["ramp follows time in the fitting data (r = +1.00): a trend in time is "
                     "not offered, since fitted there it could not be told from ramp and "
                     "would run on where ramp holds still"]

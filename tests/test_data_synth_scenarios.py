"""Named scenarios (data_synth.scenarios): presets, truth and undeclared effects."""

import json
import math
import re

import allantools
import numpy as np
import pytest
from scipy.signal import lfilter

from data_synth import list_scenarios, make_scenario, make_sessions
from data_synth.scenarios import SCENARIOS, session_seed
from data_synth.terms import evaluate
from fosmodel.core.exceptions import InputError

Z = 4.5
REQUIRED = {
    "paper_accel_y",
    "paper_gyro_y",
    "gyro_array_8",
    "temp_chamber_gyro",
    "temp_chamber_accel",
    "undeclared_temperature",
    "undeclared_vibration",
    "undeclared_nonlinear",
    "undeclared_drift",
    "undeclared_aux_lag",
    "undeclared_step",
    "clean",
    "unrelated_temperature",
    "temperature_and_vibration",
    "temperature_sweep",
    "temperature_sweep_lag",
    "temperature_sweep_control",
    "temperature_sessions",
    "temperature_sessions_control",
    "companion_noise",
}
IDENT = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")
# scenario -> (names of its undeclared sources, extra columns after the target)
LOOP = {
    "clean": ((), ()),
    "unrelated_temperature": ((), ("temp_c",)),
    "undeclared_temperature": (("temperature_bias",), ("temp_c",)),
    "undeclared_vibration": (("vibration",), ()),
    "undeclared_nonlinear": (("nonlinear",), ()),
    "undeclared_drift": (("drift",), ()),
    "undeclared_aux_lag": (("g_sensitivity",), ("accel_x",)),
    "undeclared_step": (("bias_step",), ()),
    "temperature_and_vibration": (("temperature_bias", "vibration"), ("temp_c",)),
}


def sources(rec):
    return {s["name"]: s for s in rec.truth["sources"]}


def test_list_scenarios_names_and_descriptions():
    listed = list_scenarios()
    assert REQUIRED <= set(listed)
    assert all(isinstance(d, str) and d and "\n" not in d for d in listed.values())


@pytest.mark.parametrize("name", sorted(SCENARIOS))
def test_every_scenario_builds_with_a_complete_truth(name):
    records = make_sessions(name, duration=20.0, seed=1)
    assert len(records) == SCENARIOS[name].sessions
    for k, rec in enumerate(records):
        t = json.loads(json.dumps(rec.truth, allow_nan=False))
        seed = 1 if len(records) == 1 else session_seed(1, k)
        assert t["scenario"] == name and t["seed"] == seed and t["duration_s"] == 20.0
        assert t["rate_hz"] == SCENARIOS[name].rate and t["n_samples"] == rec.n_samples
        assert list(rec.columns)[0] == rec.target == t["target"]
        for col, values in rec.columns.items():
            assert IDENT.match(col) and col not in ("y", "time")
            assert values.dtype == np.float64 and np.all(np.isfinite(values))
            assert t["columns"][col]["units"]
        for s in t["sources"]:
            assert isinstance(s["declared"], bool) and s["kind"] and "units" in s["params"]
            assert s["terms"] is None or all(set(d) == {"term", "coef"} for d in s["terms"])


def test_defaults_of_the_paper_records():
    for name, target, units in (
        ("paper_gyro_y", "gyro_y", "deg/s"),
        ("paper_accel_y", "accel_y", "m/s^2"),
    ):
        rec = make_scenario(name)
        assert rec.n_samples == 720_000 and rec.rate == 200.0 and rec.truth["duration_s"] == 3600.0
        assert list(rec.columns) == [target] and rec.truth["units"] == units
        kinds = [s["kind"] for s in rec.truth["sources"]]
        assert kinds == [
            "constant_bias",
            "white_noise",
            "gauss_markov",
            "bias_instability",
            "quantization",
        ]
        gm = sources(rec)["gm"]
        assert gm["params"]["order"] == 2 and [d["term"] for d in gm["terms"]] == [
            "y[n-1]",
            "y[n-2]",
        ]


def test_paper_gyro_units_override_scales_everything():
    a = make_scenario("paper_gyro_y", duration=30.0, seed=4)
    b = make_scenario("paper_gyro_y", duration=30.0, seed=4, units="deg/h")
    assert b.truth["units"] == "deg/h"
    np.testing.assert_allclose(b.columns["gyro_y"], 3600 * a.columns["gyro_y"], rtol=1e-9)
    assert sources(b)["white"]["params"]["arw"] == pytest.approx(
        sources(a)["white"]["params"]["arw"]
    )


def test_gyro_array_recovers_table_5_1_arw_per_gyro():
    rec = make_scenario("gyro_array_8", seed=2)
    assert rec.rate == 102.4 and list(rec.columns) == [f"gyro_{i}" for i in range(1, 9)]
    arw = sources(rec)["arw"]["params"]["densities"]  # deg/s/sqrt(Hz) = deg/sqrt(s)
    assert arw[0] == pytest.approx(0.07118)
    tol = Z / math.sqrt(2 * (3600 - 1))
    for j, col in enumerate(rec.columns.values()):
        _, ad, _, _ = allantools.oadev(col, rate=rec.rate, data_type="freq", taus=np.array([1.0]))
        assert abs(ad[0] / arw[j] - 1) < tol


def test_gyro_array_equicorrelation_and_typical_values():
    n_s = 600.0
    rec = make_scenario("gyro_array_8", duration=n_s, seed=3, rho_arw=-0.1, typical=True)
    x = np.column_stack(list(rec.columns.values()))
    r = np.corrcoef(x.T)[np.triu_indices(8, 1)]
    n = rec.n_samples
    # random-walk part is negligible over 10 min: allow its share on top of the sampling error
    assert np.all(np.abs(r + 0.1) < Z * 0.99 / math.sqrt(n) + 0.01)
    assert sources(rec)["rrw"]["params"]["rrw"] == [0.00029] * 8
    assert rec.truth["columns"]["gyro_2"]["role"] == "auxiliary"


def test_temperature_chamber_steps_and_bias():
    rec = make_scenario("temp_chamber_gyro", seed=0)
    temp, gyro = rec.columns["temp_c"], rec.columns["gyro_y"]
    assert rec.rate == 100.0 and list(rec.columns) == ["gyro_y", "temp_c"]
    assert temp.min() == pytest.approx(-30, abs=0.1) and temp.max() == pytest.approx(60, abs=0.5)
    bias = sources(rec)["temperature_bias"]
    assert [d["term"] for d in bias["terms"]] == ["1", "temp_c[n-0]", "temp_c[n-0]^2"]
    assert rec.truth["columns"]["temp_c"]["declared_use"] is True
    dwell = int(360 * rec.rate)
    for level in range(10):
        sl = slice((level + 1) * dwell - 6000, (level + 1) * dwell)  # the settled last minute
        expected = evaluate(bias["terms"], {"gyro_y": gyro[sl], "temp_c": temp[sl]}, "gyro_y")
        noise = 3.1 / 60 * 10  # worst ARW of El-Diasty et al. (2007) Table 1, per sample at 100 Hz
        assert abs(np.mean(gyro[sl] - expected)) < Z * noise / math.sqrt(6000)
    accel = make_scenario("temp_chamber_accel", duration=100.0)
    assert accel.truth["units"] == "m/s^2" and accel.target == "accel_y"


@pytest.mark.parametrize("name", sorted(LOOP))
def test_loop_scenarios_declare_exactly_their_effects(name):
    undeclared, extra = LOOP[name]
    rec = make_scenario(name, seed=0)
    assert rec.rate == 100.0 and rec.n_samples == 30_000
    assert list(rec.columns) == ["gyro_x", *extra]
    assert tuple(s["name"] for s in rec.truth["sources"] if not s["declared"]) == undeclared
    if extra:  # auxiliary columns are plain columns, present whether or not they act
        assert rec.truth["columns"][extra[0]]["role"] == ("input" if undeclared else "auxiliary")


@pytest.mark.parametrize(
    "name, kind",
    [
        ("undeclared_temperature", "temperature_bias"),
        ("undeclared_vibration", "vibration"),
        ("undeclared_drift", "drift"),
        ("undeclared_aux_lag", "aux_input"),
        ("undeclared_step", "bias_step"),
    ],
)
def test_effect_equals_its_truth_and_is_clear_but_not_trivial(name, kind):
    seed = 6
    clean, rec = make_scenario("clean", seed=seed), make_scenario(name, seed=seed)
    effect = rec.columns["gyro_x"] - clean.columns["gyro_x"]  # same base draw (keyed streams)
    (src,) = [s for s in rec.truth["sources"] if not s["declared"]]
    assert src["kind"] == kind
    t, p = rec.time(), src["params"]
    if src["terms"] is not None:
        expected = evaluate(src["terms"], rec.columns, "gyro_x")
    elif kind == "vibration":
        (h,) = p["harmonics"]
        expected = h["amplitude"] * np.sin(2 * np.pi * h["freq_hz"] * t + h["phase_rad"])
        assert abs(h["fft_bin"] - round(h["fft_bin"])) > 0.05
    elif kind == "drift":
        expected = p["slope_per_h"] * t / 3600 + p["warmup_amplitude"] * (
            1 - np.exp(-t / p["warmup_tau_s"])
        )
    else:
        (step,) = p["steps"]
        expected = step["amplitude"] * (np.arange(rec.n_samples) >= step["sample"])
    ok = ~np.isnan(expected)
    np.testing.assert_allclose(effect[ok], expected[ok], atol=1e-12)
    # Seen through the base AR(2) model, the effect must stand far above the estimation
    # noise (N * fraction >> 1, a chi-square(1) statistic) while staying a small share.
    base = sources(rec)["base"]
    a1, a2 = base["params"]["ar_coefs"]
    whitened = lfilter([1.0, -a1, -a2], [1.0], effect)[10:]
    frac = whitened.var() / base["innovation_std"] ** 2
    assert 50 < frac * len(whitened) and frac < 0.05


def test_nonlinear_cross_term_is_clear_but_not_trivial():
    rec = make_scenario("undeclared_nonlinear", seed=0)
    src = sources(rec)["nonlinear"]
    assert {d["term"] for d in src["terms"]} == {"y[n-1]", "y[n-2]", "y[n-1]*y[n-2]"}
    cross = [d for d in src["terms"] if "*" in d["term"]]
    part = evaluate(cross, rec.columns, "gyro_x")[2:]
    frac = part.var() / src["innovation_std"] ** 2
    assert 50 < frac * len(part) and frac < 0.05


@pytest.mark.parametrize(
    "name",
    [
        "clean",
        "unrelated_temperature",
        "undeclared_temperature",
        "undeclared_nonlinear",
        "undeclared_aux_lag",
        "rate_table_gyro",
    ],
)
def test_exact_model_of_the_target_leaves_white_innovations(name):
    rec = make_scenario(name, seed=11)
    model = rec.truth["model"]
    pred = evaluate(model["terms"], rec.columns, rec.target)
    resid = (rec.columns[rec.target] - pred)[~np.isnan(pred)]
    n = len(resid)
    assert abs(resid.std() / model["innovation_std"] - 1) < Z / math.sqrt(2 * n)
    for lag in (1, 2, 3):
        assert abs(np.corrcoef(resid[lag:], resid[:-lag])[0, 1]) < Z / math.sqrt(n)


def test_models_absent_where_no_finite_representation():
    for name in (
        "undeclared_vibration",
        "undeclared_drift",
        "undeclared_step",
        "temperature_and_vibration",
        "paper_gyro_y",
    ):
        assert make_scenario(name, duration=10.0).truth["model"] is None


def test_rate_table_scale_factor():
    rec = make_scenario("rate_table_gyro")
    assert rec.n_samples == 66_000 and list(rec.columns) == ["gyro_z", "rate_ref"]
    terms = {d["term"]: d["coef"] for d in rec.truth["model"]["terms"]}
    assert terms == {"rate_ref[n-0]": pytest.approx(1 - 0.003984), "1": 0.2813}
    assert rec.columns["rate_ref"].max() == pytest.approx(80, abs=0.01)
    assert rec.columns["rate_ref"].min() == pytest.approx(-80, abs=0.01)


def test_step_time_override():
    rec = make_scenario("undeclared_step", duration=100.0, step_time_s=10.0)
    assert sources(rec)["bias_step"]["params"]["steps"][0]["sample"] == 1000


def test_bad_scenarios_and_overrides_raise_input_error():
    with pytest.raises(InputError, match="unknown scenario"):
        make_scenario("nope")
    with pytest.raises(InputError, match="no parameter"):
        make_scenario("clean", units="deg/h")
    with pytest.raises(InputError, match="rho"):
        make_scenario("gyro_array_8", duration=1.0, rho_arw=-0.5)
    with pytest.raises(InputError):
        make_scenario("clean", duration=-1.0)


# -- slow-error loop records (15 minutes) -------------------------------------------------------

SLOW = {
    "slow_clean": ((), ()),
    "slow_unrelated_temperature": ((), ("temp_c",)),
    "slow_random_walk": (("bias_walk",), ()),
    "slow_warmup": (("drift",), ()),
    "slow_warmup_drift": (("drift",), ()),
    "slow_steps": (("bias_step",), ()),
    "slow_random_walk_temperature": (("bias_walk", "temperature_bias"), ("temp_c",)),
    "slow_warmup_drift_temperature": (("drift", "temperature_bias"), ("temp_c",)),
}


@pytest.mark.parametrize("name", sorted(SLOW))
def test_slow_scenarios_declare_exactly_their_effects(name):
    undeclared, extra = SLOW[name]
    rec = make_scenario(name, seed=0)
    assert rec.rate == 100.0 and rec.n_samples == 90_000
    assert list(rec.columns) == ["gyro_x", *extra]
    assert tuple(s["name"] for s in rec.truth["sources"] if not s["declared"]) == undeclared
    # the same base draw in every one of them (keyed random streams)
    base = make_scenario("slow_clean", seed=0).columns["gyro_x"]
    effect = rec.columns["gyro_x"] - base
    if not undeclared:
        np.testing.assert_array_equal(effect, 0.0)


def _slow_effect(name, seed=0, **kw):
    rec = make_scenario(name, seed=seed, **kw)
    return rec, rec.columns["gyro_x"] - make_scenario("slow_clean", seed=seed).columns["gyro_x"]


def test_the_random_walk_wanders_on_a_half_slope_above_the_noise():
    long = make_scenario("slow_random_walk", seed=3, duration=9000.0)
    params = sources(long)["bias_walk"]["params"]
    walk = long.columns["gyro_x"] - make_scenario("slow_clean", seed=3,
                                                  duration=9000.0).columns["gyro_x"]
    taus, adev = allantools.oadev(walk, rate=100.0, data_type="freq",
                                  taus=np.array([10.0, 30.0, 100.0, 300.0]))[:2]
    slope = np.polyfit(np.log(taus), np.log(adev), 1)[0]
    assert slope == pytest.approx(0.5, abs=0.1)
    assert adev[1] == pytest.approx(params["density"] * math.sqrt(30 / 3), rel=0.25)
    # over the 15 minutes its 30 s means wander well beyond the base noise's
    rec, walk = _slow_effect("slow_random_walk", seed=3)
    base = make_scenario("slow_clean", seed=3).columns["gyro_x"]
    means = [x.reshape(-1, 3000).mean(axis=1).std() for x in (walk, base)]
    assert means[0] > 3 * means[1]


@pytest.mark.parametrize("tau", [20.0, 60.0, 180.0])
def test_warm_ups_of_several_time_constants(tau):
    rec, effect = _slow_effect("slow_warmup", tau_s=tau)
    p = sources(rec)["drift"]["params"]
    assert p["warmup_tau_s"] == tau and p["slope_per_h"] == 0.0
    np.testing.assert_allclose(effect, 0.2 * -np.expm1(-rec.time() / tau), atol=1e-12)


def test_warm_up_and_linear_drift():
    rec, effect = _slow_effect("slow_warmup_drift")
    p = sources(rec)["drift"]["params"]
    assert (p["slope_per_h"], p["warmup_amplitude"], p["warmup_tau_s"]) == (1.2, 0.2, 300.0)
    t = rec.time()
    np.testing.assert_allclose(effect, 1.2 * t / 3600 + 0.2 * -np.expm1(-t / 300), atol=1e-12)


def test_steps_sit_in_the_fitting_segment():
    rec, effect = _slow_effect("slow_steps")
    steps = sources(rec)["bias_step"]["params"]["steps"]
    assert [(s["time_s"], s["amplitude"]) for s in steps] == [(150.0, 0.15), (350.0, -0.12)]
    t = rec.time()
    np.testing.assert_allclose(effect, 0.15 * (t >= 150) - 0.12 * (t >= 350), atol=1e-12)


@pytest.mark.parametrize("name", ["slow_random_walk_temperature",
                                  "slow_warmup_drift_temperature"])
def test_the_temperature_really_drives_the_bias(name):
    rec, effect = _slow_effect(name)
    src = sources(rec)
    temp = rec.columns["temp_c"]
    bias = 0.03 * (temp - 25) + 0.002 * (temp - 25) ** 2
    slow_name = "bias_walk" if "random_walk" in name else "drift"
    others = effect - bias
    rng_free = make_scenario(name.replace("_temperature", ""), seed=0).columns["gyro_x"]
    np.testing.assert_allclose(others, rng_free - make_scenario("slow_clean", seed=0)
                               .columns["gyro_x"], atol=1e-12)
    assert src["temperature_bias"]["params"]["coefs"] == [0.0, 0.03, 0.002]
    assert slow_name in src
    # the heater moves through 23-29 C with no trend in time
    means = temp.reshape(12, -1).mean(axis=1)
    assert 22.9 < temp.min() and temp.max() < 29.1
    assert abs(np.corrcoef(np.arange(12), means)[0, 1]) < 0.3


# -- scenarios of several sessions ------------------------------------------------------------


def test_sessions_draw_independently_and_a_control_draws_the_same():
    a = make_sessions("temperature_sessions", seed=4, duration=600.0)
    b = make_sessions("temperature_sessions", seed=4, duration=600.0)
    ctl = make_sessions("temperature_sessions_control", seed=4, duration=600.0)
    assert [r.truth for r in a] == [r.truth for r in b]
    seeds = [r.truth["seed"] for r in a]
    assert len(set(seeds)) == 3 and seeds == [session_seed(4, k) for k in range(3)]
    assert [r.truth["seed"] for r in ctl] == seeds
    for r, c in zip(a, ctl):  # gy_dps is not driven: the very same values
        np.testing.assert_array_equal(r.columns["gy_dps"], c.columns["gy_dps"])
    white = [r.columns["gy_dps"] - r.columns["gy_dps"].mean() for r in a]
    assert abs(np.corrcoef(white[0], white[1])[0, 1]) < Z / math.sqrt(600)
    other = make_sessions("temperature_sessions", seed=5, duration=600.0)
    assert not np.array_equal(other[0].columns["gy_dps"], a[0].columns["gy_dps"])


def test_session_scenarios_refuse_make_scenario_and_fixed_parameters():
    with pytest.raises(InputError, match="has 3 sessions: make them with make_sessions"):
        make_scenario("temperature_sessions")
    with pytest.raises(InputError, match=r"no parameter \['sensitivity'\]"):
        make_sessions("temperature_sessions_control", sensitivity={"gx_dps": [0, 1]})
    with pytest.raises(InputError, match=r"no parameter \['lag_s'\]"):
        make_scenario("temperature_sweep_lag", lag_s=10.0)
    with pytest.raises(InputError, match="one orientation per sweep"):
        make_sessions("temperature_sessions", orientations=["+z/+x"])
    with pytest.raises(InputError, match="perpendicular"):
        make_sessions("temperature_sessions", duration=10.0,
                      orientations=["+z/+x", "+x/+x", "+y/+x"])
    with pytest.raises(InputError, match="sensitivity names"):
        make_scenario("temperature_sweep", sensitivity={"gw_dps": [0, 1]})
    with pytest.raises(InputError, match="seed"):
        make_sessions("temperature_sessions", seed=-1)


def test_one_session_scenarios_through_make_sessions():
    (rec,) = make_sessions("clean", seed=3, duration=10.0)
    np.testing.assert_array_equal(rec.columns["gyro_x"],
                                  make_scenario("clean", seed=3, duration=10.0).columns["gyro_x"])
    assert "session" not in rec.truth


def test_session_overrides_reach_every_session():
    records = make_sessions("temperature_sessions", seed=0, duration=3600.0, lag_s=600.0,
                            sweeps=[[[0, 10], [1, 12]], [[0, 10], [1, 14]]],
                            orientations=["+z/+x", "-z/+y"])
    assert len(records) == 2 and records[1].truth["orientation"]["up"] == "-z"
    assert records[0].truth["shared"]["temperature_bias"]["gx_dps"]["lag_s"] == 600.0
    assert records[1].columns["temp_c"][-1] == pytest.approx(14.0, abs=0.3)

"""SynthRecord and compose (data_synth.record)."""

import json

import numpy as np
import pytest

from data_synth.arrays import CorrelatedGaussMarkov, CorrelatedWhiteNoise
from data_synth.effects import (
    AuxInput,
    ConstantBias,
    Quantizer,
    TemperatureBias,
    TurnOnBias,
    Vibration,
)
from data_synth.profiles import Sweep, WarmUp
from data_synth.record import SynthRecord, compose, sample_count, source_rng
from data_synth.sources import GaussMarkov, WhiteNoise
from data_synth.terms import evaluate


def temperature_record(seed=0, extra=()):
    sources = [
        GaussMarkov(0.5, 0.02, order=2, name="base"),
        WarmUp(22.0, 12.0, 90.0, channel="temp_c"),
        TemperatureBias((0.0, 0.02, 0.001), declared=False),
        *extra,
    ]
    return compose(
        sources,
        duration=60.0,
        rate=100.0,
        seed=seed,
        target="gyro_x",
        column_units={"temp_c": "degC"},
    )


def test_columns_target_first_float64_and_frame():
    rec = temperature_record()
    assert isinstance(rec, SynthRecord)
    assert list(rec.columns) == ["gyro_x", "temp_c"] and rec.target == "gyro_x"
    assert all(v.dtype == np.float64 and v.shape == (6000,) for v in rec.columns.values())
    assert rec.rate == 100.0 and rec.n_samples == 6000
    frame = rec.to_frame()
    assert list(frame.columns) == ["time", "gyro_x", "temp_c"]
    np.testing.assert_array_equal(frame["time"], np.arange(6000) / 100.0)
    assert list(rec.to_frame(time=False).columns) == ["gyro_x", "temp_c"]


def test_truth_layout_and_json_serialisable():
    rec = temperature_record(seed=5)
    t = json.loads(json.dumps(rec.truth, allow_nan=False))
    for key in (
        "scenario",
        "seed",
        "rate_hz",
        "duration_s",
        "n_samples",
        "target",
        "units",
        "sources",
        "columns",
        "model",
    ):
        assert key in t
    assert (t["seed"], t["rate_hz"], t["duration_s"], t["n_samples"]) == (5, 100.0, 60.0, 6000)
    assert t["target"] == "gyro_x" and t["units"] == "deg/s"
    kinds = [s["kind"] for s in t["sources"]]
    assert kinds == ["gauss_markov", "warm_up", "temperature_bias"]
    bias = t["sources"][2]
    assert bias["declared"] is False and bias["channel"] == "gyro_x"
    assert t["columns"]["temp_c"] == {
        "units": "degC",
        "role": "input",
        "writers": ["warm_up"],
        "used_by": ["temperature_bias"],
        "declared_use": False,
    }


def test_exact_model_reproduces_the_innovations():
    rec = temperature_record(seed=2)
    model = rec.truth["model"]
    pred = evaluate(model["terms"], rec.columns, rec.target)
    resid = (rec.columns["gyro_x"] - pred)[2:]
    n = len(resid)
    assert abs(resid.std() / model["innovation_std"] - 1) < 4.5 / np.sqrt(2 * n)
    assert abs(np.corrcoef(resid[1:], resid[:-1])[0, 1]) < 4.5 / np.sqrt(n)


def test_same_seed_same_record_and_sources_have_independent_streams():
    a, b = temperature_record(seed=3), temperature_record(seed=3)
    np.testing.assert_array_equal(a.columns["gyro_x"], b.columns["gyro_x"])
    assert a.truth == b.truth
    c = temperature_record(seed=4)
    assert not np.array_equal(a.columns["gyro_x"], c.columns["gyro_x"])
    # adding a source leaves the draw of the others unchanged
    d = temperature_record(seed=3, extra=[Vibration(5.0, (0.1,), declared=False)])
    vib = Vibration(5.0, (0.1,)).generate(6000, 100.0, None)
    np.testing.assert_allclose(d.columns["gyro_x"] - vib, a.columns["gyro_x"], atol=1e-15)


def test_source_rng_is_keyed_by_seed_and_label():
    x = source_rng(1, "white").standard_normal(4)
    np.testing.assert_array_equal(x, source_rng(1, "white").standard_normal(4))
    assert not np.array_equal(x, source_rng(1, "gm").standard_normal(4))
    assert not np.array_equal(x, source_rng(2, "white").standard_normal(4))


def test_quantized_target_has_no_exact_model():
    rec = compose(
        [WhiteNoise(0.05), ConstantBias(0.3)], duration=10.0, rate=100.0, quantizer=Quantizer(0.025)
    )
    q = rec.columns["gyro_y"] / 0.025
    np.testing.assert_allclose(q, np.round(q), atol=1e-9)
    assert rec.truth["model"] is None
    assert rec.truth["sources"][-1]["kind"] == "quantization"
    assert compose([WhiteNoise(0.05), ConstantBias(0.3)], duration=10.0, rate=100.0).truth[
        "model"
    ] == {
        "terms": [{"term": "1", "coef": 0.3}],
        "innovation_std": 0.5,
        "units": {"innovation_std": "deg/s"},
    }


def test_columns_are_quantized_after_their_users_read_them():
    rec = compose(
        [Sweep((0.0, 100.0), (5.0, 20.0), channel="temp_c"),
         TemperatureBias((0.0, 0.004, 1.5e-4), t_ref_c=15.0)],
        duration=100.0, rate=1.0, target="gx_dps", column_units={"temp_c": "degC"},
        quantizers={"temp_c": Quantizer(0.5), "gx_dps": Quantizer(0.001)},
    )
    temp = np.interp(np.arange(100.0), [0, 100], [5, 20])  # the temperature itself
    np.testing.assert_array_equal(rec.columns["temp_c"], 0.5 * np.round(temp / 0.5))
    bias = 0.004 * (temp - 15) + 1.5e-4 * (temp - 15) ** 2  # read before the quantization
    np.testing.assert_allclose(rec.columns["gx_dps"], 0.001 * np.round(bias / 0.001), atol=1e-15)
    q = {s["name"]: s for s in rec.truth["sources"] if s["kind"] == "quantization"}
    assert q["quantization"]["channel"] == "gx_dps" and q["quantization"]["params"]["lsb"] == 0.001
    assert q["temp_c_quantization"]["channel"] == "temp_c"
    assert rec.truth["columns"]["temp_c"]["lsb"] == 0.5 and rec.truth["model"] is None
    with pytest.raises(ValueError, match="does not have"):
        compose([ConstantBias(1.0)], duration=2.0, rate=1.0, quantizers={"temp_c": Quantizer(1)})
    with pytest.raises(ValueError, match="a quantizer and an entry"):
        compose([ConstantBias(1.0)], duration=2.0, rate=1.0, quantizer=Quantizer(1),
                quantizers={"gyro_y": Quantizer(1)})


def test_constants_cross_covariance_and_extra_truth():
    axes = ("gx_dps", "gy_dps")
    rec = compose(
        [ConstantBias(0.3, name="bias"), TurnOnBias(0.1, name="turn_on"),
         TurnOnBias(0.1, channel="gy_dps", name="gy_turn_on"),
         CorrelatedWhiteNoise(axes, (0.01, 0.02), 0.5, name="white"),
         CorrelatedGaussMarkov(axes, (0.1, 0.1), 2.0, -0.2, name="fast")],
        duration=10.0, rate=4.0, target="gx_dps", column_units={"gy_dps": "deg/s"},
        extra_truth={"orientation": {"up": "+z"}},
    )
    constants = rec.truth["constants"]
    turn_on = [s for s in rec.truth["sources"] if s["name"] == "turn_on"][0]["params"]["value"]
    assert constants["gx_dps"] == {"value": pytest.approx(0.3 + turn_on),
                                   "sources": ["bias", "turn_on"]}
    assert constants["gy_dps"]["sources"] == ["gy_turn_on"]
    (cross,) = rec.truth["cross_covariance"]
    sigma = np.array([0.01, 0.02]) * 2.0  # density * sqrt(4 Hz)
    expected = np.array([[1, 0.5], [0.5, 1]]) * np.outer(sigma, sigma) + np.array(
        [[1, -0.2], [-0.2, 1]]) * 0.01
    np.testing.assert_allclose(cross["covariance"], expected, rtol=1e-12)
    assert cross["channels"] == list(axes) and cross["sources"] == ["white", "fast"]
    assert cross["units"] == "(deg/s)^2" and rec.truth["orientation"] == {"up": "+z"}
    assert "constants" not in compose([WhiteNoise(0.1)], duration=1.0, rate=10.0).truth
    with pytest.raises(ValueError, match="may not replace"):
        compose([WhiteNoise(0.1)], duration=1.0, rate=10.0, extra_truth={"seed": 3})


def test_inputs_are_generated_before_their_users_whatever_the_order():
    rec = compose(
        [AuxInput("accel_x", {2: 0.5}), WhiteNoise(1.0, channel="accel_x")],
        duration=1.0,
        rate=50.0,
        target="gyro_x",
        column_units={"accel_x": "m/s^2"},
    )
    u, g = rec.columns["accel_x"], rec.columns["gyro_x"]
    np.testing.assert_allclose(g[2:], 0.5 * u[:-2])
    assert list(rec.columns) == ["gyro_x", "accel_x"]


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"sources": [WhiteNoise(0.1), WhiteNoise(0.2)]}, "unique"),
        ({"sources": [WhiteNoise(0.1, channel="temp_c")]}, "units"),
        ({"sources": [AuxInput("temp_c", {0: 1.0})], "column_units": {"temp_c": "degC"}}, "needs"),
        ({"sources": [AuxInput("gyro_y", {1: 0.5})]}, "circular"),
        ({"sources": [WhiteNoise(0.1)], "target": "y"}, "column name"),
        ({"sources": [WhiteNoise(0.1)], "duration": 0.001}, "at least 2"),
        ({"sources": [WhiteNoise(0.1)], "rate": -1.0}, "positive"),
        ({"sources": [WhiteNoise(0.1)], "seed": -1}, "seed"),
    ],
)
def test_compose_rejects_bad_input(kwargs, match):
    args = {"duration": 1.0, "rate": 100.0, **kwargs}
    with pytest.raises(ValueError, match=match):
        compose(**args)


def test_sample_count_rounds():
    assert sample_count(3600.0, 102.4) == 368640
    assert sample_count(0.1, 200.0) == 20

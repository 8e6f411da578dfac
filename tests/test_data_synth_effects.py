"""Deterministic and input-driven effects, quantization (data_synth.effects)."""

import math

import numpy as np
import pytest

from data_synth.effects import (
    AuxInput,
    BiasStep,
    ConstantBias,
    Drift,
    Quantizer,
    ScaleFactorError,
    TemperatureBias,
    TurnOnBias,
    Vibration,
)
from data_synth.record import source_rng
from data_synth.terms import evaluate

Z = 4.5
RNG = source_rng(0, "effects")


def test_constant_and_turn_on_bias_terms_are_the_realised_values():
    x = ConstantBias(0.2813).generate(10, 100.0, RNG)
    assert np.all(x == 0.2813)
    assert ConstantBias(0.2813).truth(100.0, "deg/s", x)["terms"] == [{"term": "1", "coef": 0.2813}]
    src = TurnOnBias(0.05)
    values = np.array([src.generate(3, 100.0, source_rng(s, "t"))[0] for s in range(2000)])
    assert abs(values.std() / 0.05 - 1) < Z / math.sqrt(2 * len(values))
    x = src.generate(5, 100.0, source_rng(7, "t"))
    assert np.all(x == x[0])
    t = src.truth(100.0, "deg/s", x)
    assert t["params"]["value"] == x[0] and t["terms"] == [{"term": "1", "coef": x[0]}]


def test_scale_factor_error_under_true_rate():
    rate_ref = np.linspace(-80, 80, 50)
    src = ScaleFactorError(-0.003984, "rate_ref")
    x = src.generate(50, 100.0, RNG, {"rate_ref": rate_ref})
    np.testing.assert_allclose(x, -0.003984 * rate_ref)
    t = src.truth(100.0, "deg/s", x)
    assert t["params"]["scale_percent"] == pytest.approx(-0.3984)
    assert t["terms"] == [{"term": "rate_ref[n-0]", "coef": -0.003984}]


def test_aux_input_enters_with_exact_lags():
    u = source_rng(1, "u").standard_normal(1000)
    src = AuxInput("accel_x", {3: 0.03, 0: -0.01})
    x = src.generate(1000, 100.0, RNG, {"accel_x": u})
    np.testing.assert_allclose(x[3:], 0.03 * u[:-3] - 0.01 * u[3:])
    np.testing.assert_allclose(x[:3], 0.03 * u[0] - 0.01 * u[:3])  # u[0] held before the start
    t = src.truth(100.0, "deg/s", x)
    assert t["terms"] == [
        {"term": "accel_x[n-0]", "coef": -0.01},
        {"term": "accel_x[n-3]", "coef": 0.03},
    ]
    assert t["params"]["delays_s"] == [0.0, 0.03]
    pred = evaluate(t["terms"], {"g": x, "accel_x": u}, "g")
    np.testing.assert_allclose(pred[3:], x[3:])
    with pytest.raises(ValueError):
        AuxInput("accel_x", {-1: 0.1})


def test_temperature_bias_terms_equal_the_polynomial():
    temp = np.linspace(-30, 60, 500)
    src = TemperatureBias((0.2813, 0.006, 1e-4), t_ref_c=25.0)
    x = src.generate(500, 100.0, RNG, {"temp_c": temp})
    np.testing.assert_allclose(x, 0.2813 + 0.006 * (temp - 25) + 1e-4 * (temp - 25) ** 2)
    t = src.truth(100.0, "deg/s", x)
    assert [d["term"] for d in t["terms"]] == ["1", "temp_c[n-0]", "temp_c[n-0]^2"]
    np.testing.assert_allclose(evaluate(t["terms"], {"g": x, "temp_c": temp}, "g"), x, rtol=1e-12)
    assert t["params"]["raw_coefs"] == pytest.approx([0.2813 - 0.15 + 0.0625, 0.001, 1e-4])


def test_temperature_bias_through_a_thermal_lag():
    rate, lag, slope = 1.0, 1800.0, 1.0 / 3600  # a 1 C/h ramp after a flat hour
    temp = 5.0 + slope * np.maximum(np.arange(36_000) - 3600.0, 0.0)
    src = TemperatureBias((0.0, 0.004, 1.5e-4), t_ref_c=15.0, lag_s=lag)
    sensor = src.sensor_temperature(temp, rate)
    assert np.all(sensor[:3601] == 5.0)  # settled at the first sample: flat while it is flat
    phi = math.exp(-1 / (rate * lag))
    offset = slope * phi / (1 - phi)  # the exact steady lag of a first-order filter on a ramp
    assert offset == pytest.approx(slope * lag, rel=1e-3)
    assert temp[-1] - sensor[-1] == pytest.approx(offset, rel=1e-6)
    x = src.generate(len(temp), rate, RNG, {"temp_c": temp})
    np.testing.assert_allclose(x, 0.004 * (sensor - 15) + 1.5e-4 * (sensor - 15) ** 2)
    t = src.truth(rate, "deg/s", x)
    assert t["terms"] is None and t["params"]["lag_s"] == lag
    assert TemperatureBias((0.0, 0.01)).truth(rate, "deg/s", x)["params"]["lag_s"] == 0.0
    with pytest.raises(ValueError, match="lag_s"):
        TemperatureBias((0.0, 0.01), lag_s=-1.0)


def test_vibration_frequency_amplitude_phase_and_grid_position():
    rate, n = 100.0, 30_000
    src = Vibration(7.3137, (0.1, 0.02), (0.7, -1.0))
    x = src.generate(n, rate, RNG)
    t = np.arange(n) / rate
    design = np.column_stack(
        [
            np.sin(2 * np.pi * 7.3137 * t),
            np.cos(2 * np.pi * 7.3137 * t),
            np.sin(2 * np.pi * 14.6274 * t),
            np.cos(2 * np.pi * 14.6274 * t),
        ]
    )
    a, b, c, d = np.linalg.lstsq(design, x, rcond=None)[0]
    assert math.hypot(a, b) == pytest.approx(0.1) and math.atan2(b, a) == pytest.approx(0.7)
    assert math.hypot(c, d) == pytest.approx(0.02) and math.atan2(d, c) == pytest.approx(-1.0)
    truth = src.truth(rate, "deg/s", x)
    assert truth["terms"] is None
    h1 = truth["params"]["harmonics"][0]
    assert h1["fft_bin"] == pytest.approx(2194.11)
    assert abs(h1["fft_bin"] - round(h1["fft_bin"])) > 0.05  # off the FFT grid


def test_bias_step_and_drift():
    x = BiasStep((1.234,), (0.15,)).generate(300, 100.0, RNG)
    assert np.all(x[:124] == 0) and np.all(x[124:] == 0.15)
    t = BiasStep((1.234,), (0.15,)).truth(100.0, "deg/s", x)
    assert t["params"]["steps"] == [{"time_s": 1.234, "sample": 124, "amplitude": 0.15}]
    assert t["terms"] is None
    d = Drift(slope_per_h=1.2, warmup_amplitude=0.2, warmup_tau_s=60.0)
    y = d.generate(30_001, 100.0, RNG)
    assert y[0] == 0.0
    assert y[-1] == pytest.approx(1.2 * 300 / 3600 + 0.2 * (1 - math.exp(-5)))
    assert d.truth(100.0, "deg/s", y)["params"]["units"]["slope_per_h"] == "deg/s/h"


def test_quantization_error_has_lsb_squared_over_12_variance():
    lsb, n = 0.025, 200_000
    x = 10 * lsb * source_rng(2, "q").standard_normal(n) + 0.2813
    q = Quantizer(lsb).apply(x)
    err = q - x
    assert np.allclose(q / lsb, np.round(q / lsb))
    assert np.abs(err).max() <= lsb / 2 + 1e-12
    # var(U^2) = lsb^4/180 for U uniform on [-lsb/2, lsb/2]
    assert abs(np.mean(err**2) - lsb**2 / 12) < Z * lsb**2 / math.sqrt(180 * n)
    assert abs(err.mean()) < Z * lsb / math.sqrt(12 * n)
    assert Quantizer(lsb).params("deg/s")["error_variance"] == pytest.approx(lsb**2 / 12)
    with pytest.raises(ValueError):
        Quantizer(0.0)

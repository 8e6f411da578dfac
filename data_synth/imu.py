"""Six-axis static IMU records: day-long temperature sweeps, and axes with shared noise.

Two families of records, both in the column names ``fosmodel imu`` recognises
(``gx_dps``..``gz_dps`` in deg/s, ``ax_mps2``..``az_mps2`` in m/s^2, ``temp_c``):

* :func:`sweep_spec` -- one session of a sensor at 1 Hz whose temperature
  follows a slow piecewise-linear sweep (flat stretches included) with a small
  wander; every axis has a turn-on bias, what its orientation puts on it
  (gravity, earth rate), white noise, bias instability and a rate random walk;
  the driven axes add an undeclared bias polynomial in the temperature, through
  an optional thermal lag; every column is quantized at a coarse LSB.  The
  sessions of one sensor share everything but their turn-on biases (drawn per
  session), orientations, sweeps and random draws.
* :func:`companion_spec` -- axes whose white noise (and a fast Gauss-Markov
  error) is correlated across the gyros, and across the accelerometers, with a
  known covariance, and where no axis enters another's error.

Noise levels (design choices, stated here): the 1 Hz sweep records are modelled
on a day-long record of a consumer IMU held back for testing (three sessions,
coarse quantization, one gyro axis whose slow bias follows the temperature with
correlation 0.996); the sizes below give, on the driven gyro, 10-minute means
that follow the temperature about as closely.  The companion records use the
ADIS16405-like levels of the ``static_imu`` scenario.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from data_synth.arrays import CorrelatedGaussMarkov, CorrelatedWhiteNoise
from data_synth.base import Source
from data_synth.effects import ConstantBias, Quantizer, TemperatureBias, TurnOnBias
from data_synth.orientation import Orientation
from data_synth.profiles import Sweep
from data_synth.sources import BiasInstability, GaussMarkov, RandomWalk, WhiteNoise
from data_synth.units import ACCEL_UNIT, arw_to_density, mg_to_mps2, vrw_to_density

GYROS = ("gx_dps", "gy_dps", "gz_dps")
ACCELS = ("ax_mps2", "ay_mps2", "az_mps2")
UNITS = {**{c: "deg/s" for c in GYROS}, **{c: ACCEL_UNIT for c in ACCELS}}

#: Per sensor at 1 Hz: white noise as ARW deg/sqrt(h) or VRW m/s/sqrt(h), bias instability B
#: and rate random walk K (deg/s and deg/s/sqrt(s), or m/s^2 and m/s^2/sqrt(s)), turn-on bias
#: sigma (deg/s, m/s^2).
SWEEP_NOISE = {
    "gyro": {"white": 0.5, "bias_instability": 0.001, "rrw": 3e-6, "turn_on": 0.1},
    "accel": {"white": 0.06, "bias_instability": 3e-4, "rrw": 2e-6, "turn_on": 0.02},
}
#: Correlation times of the bias instability's Gauss-Markov terms at 1 Hz.
SWEEP_BI_BAND_S = (10.0, 10_000.0)
#: The temperature's own wander about the sweep (followed by the bias, too small to teach it).
TEMP_WANDER_C, TEMP_WANDER_TAU_S = 0.05, 1800.0
#: Coarse LSBs of the sweep records.
GYRO_LSB, ACCEL_LSB, TEMP_LSB = 0.01, 0.002, 0.1
#: The driven axes and their bias polynomials about T_REF_C (degC): coefs[k] per degC^k.
SENSITIVITY = {"gx_dps": (0.0, 0.005, 1e-4), "ax_mps2": (0.0, 5e-4)}
T_REF_C = 15.0
#: The thermal lag of the lagged sweep: half an hour.
LAG_S = 1800.0

#: Sweeps as (fraction of the session, degC): one day warming from 5 C, held, cooled.
DAY_SWEEP = ((0.0, 5.0), (1 / 3, 20.0), (1 / 2, 20.0), (5 / 6, 8.0), (1.0, 8.0))
#: Three sessions from 5 C up to 16-24 C; the first flat for its first half.
SESSION_SWEEPS = (
    ((0.0, 5.0), (0.5, 5.0), (1.0, 16.0)),
    ((0.0, 5.0), (0.75, 24.0), (1.0, 24.0)),
    ((0.0, 5.0), (0.1, 5.0), (0.6, 20.0), (1.0, 20.0)),
)
#: Each session another axis up: gravity on z, then x, then -y.
SESSION_ORIENTATIONS = ("+z/+x", "+x/+y", "-y/+z")

#: Per axis: gyro ARW (deg/sqrt(h)) and accelerometer VRW (m/s/sqrt(h)) around the ADIS16405
#: datasheet's 2 and 0.2, a little apart so that the axes differ (design choice).
IMU_GYRO_ARW = {"gx_dps": 2.0, "gy_dps": 2.2, "gz_dps": 1.9}
IMU_ACCEL_VRW = {"ax_mps2": 0.20, "ay_mps2": 0.22, "az_mps2": 0.25}
#: Bias instability B: the datasheet's in-run stability (0.007 deg/s, 0.2 mg) is the Allan
#: floor, 0.664 B.  Rate random walk K: about what the ADIS16405 sessions show (150 deg/h/sqrt(h)
#: = 7e-4 deg/s/sqrt(s); 90 m/s/h/sqrt(h) = 4.2e-4 m/s^2/sqrt(s)).
IMU_GYRO_B, IMU_GYRO_K = 0.007 / 0.664, 7e-4
IMU_ACCEL_B, IMU_ACCEL_K = mg_to_mps2(0.2) / 0.664, 4.2e-4
#: Shared parts: equal-time correlations of the gyros' and of the accelerometers' noise.
GYRO_CORR = ((1.0, 0.3, -0.15), (0.3, 1.0, 0.2), (-0.15, 0.2, 1.0))
ACCEL_CORR = ((1.0, 0.25, 0.1), (0.25, 1.0, -0.2), (0.1, -0.2, 1.0))
#: The fast shared error: a Gauss-Markov of 0.2 s, 0.1 deg/s on the gyros, 0.01 m/s^2 on
#: the accelerometers (a third of their white noise per sample at 100 Hz).
FAST_TAU_S, FAST_SIGMA = 0.2, {"gyro": 0.1, "accel": 0.01}


def sweep_spec(
    duration: float,
    *,
    sweep: Sequence[Sequence[float]] = DAY_SWEEP,
    orientation: str = "+z/+x",
    sensitivity: Mapping[str, Sequence[float]] | None = None,
    t_ref_c: float = T_REF_C,
    lag_s: float = 0.0,
    gyro_lsb: float = GYRO_LSB,
    accel_lsb: float = ACCEL_LSB,
    temp_lsb: float = TEMP_LSB,
    latitude_deg: float = 51.05,
) -> dict[str, Any]:
    """The :func:`~data_synth.record.compose` arguments of one temperature-sweep session.

    Parameters
    ----------
    duration : float
        Seconds; the sweep's knots are fractions of it.
    sweep : sequence of (fraction, degC)
        The temperature path (:class:`~data_synth.profiles.Sweep`), fractions increasing
        from 0 to 1.
    orientation : str
        ``"UP/NORTH"`` body axes (:class:`~data_synth.orientation.Orientation`).
    sensitivity : mapping of column to coefficients, optional
        The driven columns and their bias polynomials about ``t_ref_c``
        (:data:`SENSITIVITY` if None; ``{}`` for a control).
    t_ref_c, lag_s : float
        The polynomials' reference temperature and the thermal lag (s) between the
        temperature column and the sensor's bias.
    gyro_lsb, accel_lsb, temp_lsb : float
        Quantization steps; 0 leaves the column unquantized.
    latitude_deg : float
        Latitude of the site (earth rate).
    """
    sensitivity = SENSITIVITY if sensitivity is None else sensitivity
    unknown = sorted(set(sensitivity) - set(UNITS))
    if unknown:
        raise ValueError(f"sensitivity names {unknown}; the axes are {list(UNITS)}")
    attitude = Orientation.parse(orientation, latitude_deg)
    sources: list[Source] = []
    for column, at_rest in _at_rest(attitude).items():
        sources += _axis_sources(column, at_rest)
        if column in sensitivity:
            sources.append(TemperatureBias(tuple(sensitivity[column]), t_ref_c=t_ref_c,
                                           lag_s=lag_s, channel=column, declared=False,
                                           name=f"{column}_temperature_bias"))
    knots = [(float(f) * duration, float(t)) for f, t in sweep]
    sources += [
        Sweep(tuple(t for t, _ in knots), tuple(v for _, v in knots), channel="temp_c",
              name="temp_sweep"),
        GaussMarkov(TEMP_WANDER_C, TEMP_WANDER_TAU_S, channel="temp_c", name="temp_wander"),
    ]
    lsb = {**dict.fromkeys(GYROS, gyro_lsb), **dict.fromkeys(ACCELS, accel_lsb),
           "temp_c": temp_lsb}
    return dict(
        sources=sources, target=GYROS[0], units="deg/s",
        column_units={**UNITS, "temp_c": "degC"},
        quantizers={c: Quantizer(q) for c, q in lsb.items() if q > 0},
        extra_truth={"orientation": attitude.to_dict()},
    )


def sessions_spec(
    duration: float,
    *,
    sweeps: Sequence[Sequence[Sequence[float]]] = SESSION_SWEEPS,
    orientations: Sequence[str] = SESSION_ORIENTATIONS,
    **shared: Any,
) -> list[dict[str, Any]]:
    """The compose arguments of each session of one sensor: a sweep and an orientation each,
    everything in ``shared`` (the arguments of :func:`sweep_spec`) common."""
    if len(sweeps) != len(orientations) or len(sweeps) < 2:
        raise ValueError(f"need one orientation per sweep and two sessions or more; got "
                         f"{len(sweeps)} sweeps and {len(orientations)} orientations")
    return [sweep_spec(duration, sweep=s, orientation=o, **shared)
            for s, o in zip(sweeps, orientations)]


def _at_rest(attitude: Orientation) -> dict[str, float]:
    """What each axis reads at rest in that attitude: the earth rate, gravity."""
    return {**dict(zip(GYROS, attitude.earth_rate().tolist())),
            **dict(zip(ACCELS, attitude.specific_force().tolist()))}


def _at_rest_name(column: str) -> str:
    return f"{column}_{'earth_rate' if column in GYROS else 'gravity'}"


def _axis_sources(column: str, at_rest: float) -> list[Source]:
    """Turn-on bias, what the orientation puts on the axis, white noise, bias instability
    and rate random walk of one axis of a sweep record."""
    sensor = "gyro" if column in GYROS else "accel"
    noise = SWEEP_NOISE[sensor]
    density = (arw_to_density if sensor == "gyro" else vrw_to_density)(noise["white"])
    return [
        TurnOnBias(noise["turn_on"], channel=column, name=f"{column}_turn_on"),
        ConstantBias(at_rest, channel=column, name=_at_rest_name(column)),
        WhiteNoise(density, channel=column, name=f"{column}_white"),
        BiasInstability(noise["bias_instability"], *SWEEP_BI_BAND_S, channel=column,
                        name=f"{column}_bias_instability"),
        RandomWalk(noise["rrw"], channel=column, name=f"{column}_random_walk"),
    ]


def companion_spec(
    *,
    gyro_corr: Any = GYRO_CORR,
    accel_corr: Any = ACCEL_CORR,
    fast: bool = True,
    orientation: str = "+z/+x",
) -> dict[str, Any]:
    """The compose arguments of a six-axis record whose axes share part of their noise.

    Parameters
    ----------
    gyro_corr, accel_corr : float or array_like
        Equal-time correlation of the gyros' (accelerometers') white noise and fast error:
        a scalar for all pairs or a 3 x 3 matrix; 0 makes the axes independent.
    fast : bool
        Add the shared fast Gauss-Markov error.
    orientation : str
        ``"UP/NORTH"`` body axes.
    """
    attitude = Orientation.parse(orientation)
    sources: list[Source] = []
    groups = (("gyro", GYROS, gyro_corr, IMU_GYRO_ARW, arw_to_density),
              ("accel", ACCELS, accel_corr, IMU_ACCEL_VRW, vrw_to_density))
    for sensor, axes, corr, levels, to_density in groups:
        sources.append(CorrelatedWhiteNoise(axes, tuple(to_density(levels[c]) for c in axes),
                                            corr, name=f"{sensor}_white"))
        if fast:
            sources.append(CorrelatedGaussMarkov(axes, (FAST_SIGMA[sensor],), FAST_TAU_S, corr,
                                                 name=f"{sensor}_fast"))
    for column, at_rest in _at_rest(attitude).items():
        b, k = (IMU_GYRO_B, IMU_GYRO_K) if column in GYROS else (IMU_ACCEL_B, IMU_ACCEL_K)
        sources += [
            ConstantBias(at_rest, channel=column, name=_at_rest_name(column)),
            BiasInstability(b, 0.1, 3000.0, channel=column, name=f"{column}_bias_instability"),
            RandomWalk(k, channel=column, name=f"{column}_random_walk"),
        ]
    return dict(sources=sources, target=GYROS[0], units="deg/s", column_units=UNITS,
                extra_truth={"orientation": attitude.to_dict()})

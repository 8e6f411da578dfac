"""Named scenario presets.

Parameter provenance (seeds in /work/shared/seeds):

* Crossbow CC-300-class (AHRS300CC) noise: El-Diasty et al. (2007) Table 1, mean over the four
  chamber temperatures: gyro-Y ARW 2.8946 deg/sqrt(h), accelerometer-Y VRW
  0.2797 m/s/sqrt(h); per-temperature values for the chamber records.
* Biases and scale factors: Park (2004) Tables 4.1/4.2 (RGA300CA, Crossbow):
  accelerometer-Y bias 2.4233 mg, yaw-gyro bias 0.2813 deg/s and scale-factor
  error -0.3984 %; resolutions (quantization LSB) 1 mg and 0.025 deg/s and the
  rate-table sequence 0 -> 80 -> -80 -> 0 deg/s in 10 deg/s steps from Park (2004)
  Table 5.4 and section 4.3.
* Gyro array: Koldbæk and Totu (2011) Table 5.1 (ADIS16265 board at 102.4 Hz), per-gyro ARW in
  deg/sqrt(s) and RRW in deg/sqrt(s^3); typical values 0.068 / 0.00029 (eq. 5.4);
  equicorrelation as in eq. 6.36 (uncorrelated by default, the thesis' working
  assumption for separately packaged sensors).
* Chamber: El-Diasty et al. (2007), -30 to +60 C every 10 C, 100 Hz.

Values not given by the seeds are design choices, stated where they are set:
the higher-order Gauss-Markov component of the paper records (Tamazin et al. 2013, Fig. 2
shows its shape, not its size), bias instabilities, temperature coefficients,
and the effect sizes of the residual-loop scenarios (chosen so that 5 minutes
at 100 Hz show each effect well above the estimation noise while it stays a
few per cent of the signal variance).
"""

from __future__ import annotations

import inspect
import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from data_synth.arrays import CorrelatedRandomWalk, CorrelatedWhiteNoise
from data_synth.effects import (
    AuxInput,
    BiasStep,
    ConstantBias,
    Drift,
    Knocks,
    Quantizer,
    ScaleFactorError,
    TemperatureBias,
    Vibration,
)
from data_synth.imu import (
    ACCEL_CORR,
    ACCEL_LSB,
    DAY_SWEEP,
    GYRO_CORR,
    GYRO_LSB,
    IMU_ACCEL_B,
    IMU_ACCEL_K,
    IMU_ACCEL_VRW,
    IMU_GYRO_ARW,
    IMU_GYRO_B,
    IMU_GYRO_K,
    LAG_S,
    SESSION_ORIENTATIONS,
    SESSION_SWEEPS,
    T_REF_C,
    TEMP_LSB,
    companion_spec,
    sessions_spec,
    sweep_spec,
)
from data_synth.profiles import CHAMBER_LEVELS_C, StepProfile, WarmUp
from data_synth.record import SynthRecord, compose
from data_synth.sources import (
    ARProcess,
    BiasInstability,
    GaussMarkov,
    NonlinearAR,
    RandomWalk,
    TemperatureWhiteNoise,
    WhiteNoise,
)
from data_synth.units import (
    ACCEL_UNIT,
    arw_to_density,
    mg_to_mps2,
    rate_factor,
    rrw_to_density,
    vrw_to_density,
)
from fosmodel.core.exceptions import InputError

#: El-Diasty et al. (2007) Table 1, AHRS300CC: chamber temperatures and Y-axis noise coefficients.
CC300_TEMPS_C = (-30.0, 0.0, 30.0, 60.0)
CC300_GYRO_ARW = (3.0994, 2.6285, 2.8262, 3.0243)  # deg/sqrt(h)
CC300_ACCEL_VRW = (0.3397, 0.2696, 0.2283, 0.2811)  # m/s/sqrt(h)

#: Koldbæk and Totu (2011) Table 5.1 (15-18 April): per-gyro ARW deg/sqrt(s) and RRW deg/sqrt(s^3).
ARRAY_ARW = (0.07118, 0.06882, 0.06434, 0.07874, 0.06654, 0.08422, 0.06221, 0.06654)
ARRAY_RRW = (0.00032, 0.00018, 0.00027, 0.00039, 0.00028, 0.00015, 0.00033, 0.00029)
#: Koldbæk and Totu (2011) eq. 5.4: typical ARW and RRW.
ARRAY_TYPICAL = (0.068, 0.00029)

#: Rate-table sequence of Park (2004) section 4.3 (33 levels, deg/s).
RATE_TABLE_LEVELS = tuple(range(0, 81, 10)) + tuple(range(70, -81, -10)) + tuple(range(-70, 1, 10))

LOOP_RATE, LOOP_DURATION = 100.0, 300.0
#: The slow-error loop records: 15 minutes, so that 30 % of the record (the prediction
#: segment, 270 s) holds nine 30 s bias windows.
SLOW_DURATION = 900.0
#: Off the FFT grid for the default 300 s (7.3137 * 300 = 2194.11 bins).
VIBRATION_HZ = 7.3137


@dataclass(frozen=True)
class Scenario:
    """A registered preset.

    ``build(**params)`` returns the keyword arguments of
    :func:`~data_synth.record.compose` other than duration, rate, seed and
    names (``sources``, ``target``, ``units``...), or for a scenario of several
    sessions a list of them, one per session; a builder that declares a
    ``duration`` parameter receives the record length.  ``fixed`` holds the
    builder parameters this preset sets for good (a control's absent effect).
    """

    name: str
    description: str
    duration: float
    rate: float
    build: Callable[..., Any]
    sessions: int = 1
    fixed: Mapping[str, Any] = field(default_factory=dict)

    def parameters(self) -> list[str]:
        """Names of the parameters a caller may override."""
        return [p for p in inspect.signature(self.build).parameters
                if p != "duration" and p not in self.fixed]


SCENARIOS: dict[str, Scenario] = {}


def _register(name: str, duration: float, rate: float, description: str, *, sessions: int = 1,
              fixed: Mapping[str, Any] | None = None):
    def deco(fn):
        SCENARIOS[name] = Scenario(name, description, duration, rate, fn, sessions,
                                   dict(fixed or {}))
        return fn

    return deco


def list_scenarios() -> dict[str, str]:
    """Scenario names with their one-line descriptions."""
    return {name: s.description for name, s in SCENARIOS.items()}


def session_seed(seed: int, index: int) -> int:
    """The compose seed of session ``index`` (0-based) of a multi-session record drawn with
    ``seed``: ``SeedSequence([seed, index])``'s first word, so sessions draw independently and
    a control drawn with the same seed draws the same noise."""
    return int(np.random.SeedSequence([seed, index]).generate_state(1)[0])


def make_scenario(
    name: str,
    *,
    duration: float | None = None,
    rate: float | None = None,
    seed: int = 0,
    **overrides: Any,
) -> SynthRecord:
    """Generate the record of a named scenario.

    Parameters
    ----------
    name : str
        A key of :func:`list_scenarios` with one session (see :func:`make_sessions`).
    duration, rate : float, optional
        Seconds and Hz; None keeps the scenario's default.
    seed : int
        Non-negative seed; the same seed gives the same record.
    **overrides
        Scenario parameters (e.g. ``units="deg/h"``, ``rho_arw=-0.1``); see
        :meth:`Scenario.parameters`.

    Raises
    ------
    fosmodel.core.exceptions.InputError
        Unknown scenario or parameter, a scenario of several sessions, or values that
        cannot be used.
    """
    sc = _scenario(name, overrides)
    if sc.sessions > 1:
        raise InputError(f"scenario {name!r} has {sc.sessions} sessions: make them with "
                         "make_sessions (fosmodel synth writes one file per session)")
    duration = sc.duration if duration is None else duration
    rate = sc.rate if rate is None else rate
    try:
        spec = sc.build(**_arguments(sc, duration, overrides))
        return compose(duration=duration, rate=rate, seed=seed, scenario=name,
                       description=sc.description, **spec)
    except ValueError as exc:
        raise InputError(f"scenario {name!r}: {exc}") from exc


def make_sessions(
    name: str,
    *,
    duration: float | None = None,
    rate: float | None = None,
    seed: int = 0,
    **overrides: Any,
) -> list[SynthRecord]:
    """Generate every session of a named scenario: records of one sensor.

    Each session is drawn with its own seed (:func:`session_seed`), so the sessions'
    noises and turn-on biases are independent, and the same ``seed`` gives a control
    the same draws.  Each record's truth adds ``session`` (``index`` from 1,
    ``count``, ``label`` ``s1``..., the ``group_seed``) and ``shared``: what every
    session has in common, the temperature bias of each driven column
    (``{column: {"coefs", "t_ref_c", "raw_coefs", "lag_s", "input"}}``, empty for a
    control).  A one-session scenario gives ``[make_scenario(...)]``.

    Parameters
    ----------
    name : str
        A key of :func:`list_scenarios`.
    duration, rate : float, optional
        Seconds and Hz of each session; None keeps the scenario's default.
    seed : int
        Non-negative seed.
    **overrides
        Scenario parameters; see :meth:`Scenario.parameters`.

    Returns
    -------
    list of SynthRecord
        The sessions in order.

    Raises
    ------
    fosmodel.core.exceptions.InputError
        Unknown scenario or parameter, or values that cannot be used.
    """
    sc = _scenario(name, overrides)
    if sc.sessions == 1:
        return [make_scenario(name, duration=duration, rate=rate, seed=seed, **overrides)]
    if not isinstance(seed, (int, np.integer)) or seed < 0:
        raise InputError(f"seed must be a non-negative integer, got {seed!r}")
    duration = sc.duration if duration is None else duration
    rate = sc.rate if rate is None else rate
    try:
        specs = sc.build(**_arguments(sc, duration, overrides))
        records = []
        for index, spec in enumerate(specs):
            session = {"index": index + 1, "count": len(specs), "label": f"s{index + 1}",
                       "group_seed": int(seed)}
            extra = {**spec.pop("extra_truth", {}), "session": session}
            records.append(compose(duration=duration, rate=rate, seed=session_seed(seed, index),
                                   scenario=name, description=sc.description, extra_truth=extra,
                                   **spec))
    except ValueError as exc:
        raise InputError(f"scenario {name!r}: {exc}") from exc
    shared = {"temperature_bias": _temperature_biases(records[0].truth)}
    for rec in records:
        rec.truth["shared"] = shared
    return records


def _scenario(name: str, overrides: Mapping[str, Any]) -> Scenario:
    if name not in SCENARIOS:
        raise InputError(f"unknown scenario {name!r}; choose from {', '.join(SCENARIOS)}")
    sc = SCENARIOS[name]
    unknown = sorted(set(overrides) - set(sc.parameters()))
    if unknown:
        raise InputError(
            f"scenario {name!r} has no parameter {unknown}; it takes {sc.parameters()}"
        )
    return sc


def _arguments(sc: Scenario, duration: float, overrides: Mapping[str, Any]) -> dict[str, Any]:
    """The builder's arguments: the overrides, the fixed values and, if it asks, the duration."""
    args = {**overrides, **sc.fixed}
    if "duration" in inspect.signature(sc.build).parameters:
        args["duration"] = duration
    return args


def _temperature_biases(truth: Mapping[str, Any]) -> dict[str, dict[str, Any]]:
    """The temperature bias of each column, as the truth of its source gives it."""
    keys = ("input", "t_ref_c", "coefs", "raw_coefs", "lag_s")
    return {s["channel"]: {k: s["params"][k] for k in keys}
            for s in truth["sources"] if s["kind"] == "temperature_bias"}


# --- paper-like records (Tamazin et al. 2013) -------------------------------------------


@_register(
    "paper_accel_y",
    3600.0,
    200.0,
    "FOS-paper-like CC-300 accelerometer-Y: VRW + 2nd-order GM + bias instability + bias, 1 mg LSB",
)
def _paper_accel_y(gm_order=2):
    sources = [
        ConstantBias(mg_to_mps2(2.4233), name="bias"),
        WhiteNoise(vrw_to_density(sum(CC300_ACCEL_VRW) / 4), name="white"),
        # Design choice: ~5 mg correlated component with 1 s stages
        # (Tamazin et al. 2013, Fig. 2 shape).
        GaussMarkov(0.05, 1.0, order=gm_order, name="gm"),
        # Design choice: 0.5 mg bias instability, flicker band 0.1 s to 1000 s.
        BiasInstability(mg_to_mps2(0.5), 0.1, 1000.0, name="bias_instability"),
    ]
    return dict(
        sources=sources, target="accel_y", units=ACCEL_UNIT, quantizer=Quantizer(mg_to_mps2(1.0))
    )


@_register(
    "paper_gyro_y",
    3600.0,
    200.0,
    "FOS-paper-like CC-300 gyro-Y: ARW + 2nd-order GM + "
    "bias instability + bias, 0.025 deg/s LSB (units deg/s or deg/h)",
)
def _paper_gyro_y(units="deg/s", gm_order=2):
    k = rate_factor(units)
    sources = [
        ConstantBias(0.2813 * k, name="bias"),
        WhiteNoise(arw_to_density(sum(CC300_GYRO_ARW) / 4, units), name="white"),
        # Design choice: 0.5 deg/s correlated component, 0.5 s stages
        # (Tamazin et al. 2013, Fig. 2 shape).
        GaussMarkov(0.5 * k, 0.5, order=gm_order, name="gm"),
        # Design choice: 0.01 deg/s bias instability (the better gyro of Koldbæk and Totu
        # 2011: 0.006 deg/s).
        BiasInstability(0.01 * k, 0.1, 1000.0, name="bias_instability"),
    ]
    return dict(sources=sources, target="gyro_y", units=units, quantizer=Quantizer(0.025 * k))


# --- gyro array (Koldbæk and Totu 2011) ------------------------------------------------


@_register(
    "gyro_array_8",
    3600.0,
    102.4,
    "8 gyros (gyro_1..gyro_8) with Koldbæk and Totu (2011) Table 5.1 "
    "ARW/RRW; optional equicorrelation rho_arw / rho_rrw",
)
def _gyro_array_8(units="deg/s", rho_arw=0.0, rho_rrw=0.0, typical=False):
    names = tuple(f"gyro_{i}" for i in range(1, 9))
    arw = (ARRAY_TYPICAL[0],) * 8 if typical else ARRAY_ARW
    rrw = (ARRAY_TYPICAL[1],) * 8 if typical else ARRAY_RRW
    sources = [
        CorrelatedWhiteNoise(
            names, tuple(arw_to_density(a, units, per="sqrt(s)") for a in arw), rho_arw,
            name="arw",
        ),
        CorrelatedRandomWalk(names, tuple(rrw_to_density(r, units) for r in rrw), rho_rrw,
                             name="rrw"),
    ]
    return dict(
        sources=sources, target="gyro_1", units=units, column_units={n: units for n in names}
    )


# --- a static six-axis IMU ------------------------------------------------------------------

# The ADIS16405-like levels (IMU_GYRO_ARW...) are in data_synth.imu, shared with companion_noise.


@_register(
    "static_imu",
    3600.0,
    100.0,
    "Static six-axis IMU (gx_dps..gz_dps in deg/s, ax_mps2..az_mps2 in m/s^2), ADIS16405-like: "
    "white noise, bias instability and rate random walk per axis",
)
def _static_imu():
    sources = []
    for column, arw in IMU_GYRO_ARW.items():
        sources += [WhiteNoise(arw_to_density(arw), channel=column, name=f"{column}_white"),
                    BiasInstability(IMU_GYRO_B, 0.1, 3000.0, channel=column,
                                    name=f"{column}_bias_instability"),
                    RandomWalk(IMU_GYRO_K, channel=column, name=f"{column}_random_walk")]
    for column, vrw in IMU_ACCEL_VRW.items():
        sources += [WhiteNoise(vrw_to_density(vrw), channel=column, name=f"{column}_white"),
                    BiasInstability(IMU_ACCEL_B, 0.1, 3000.0, channel=column,
                                    name=f"{column}_bias_instability"),
                    RandomWalk(IMU_ACCEL_K, channel=column, name=f"{column}_random_walk")]
    units = {**{c: "deg/s" for c in IMU_GYRO_ARW}, **{c: ACCEL_UNIT for c in IMU_ACCEL_VRW}}
    return dict(sources=sources, target="gx_dps", units="deg/s", column_units=units)


# --- temperature chamber (El-Diasty et al. 2007) and rate table (Park 2004) ------------


def _chamber(target, units, bias_coefs, densities):
    sources = [
        # Sensor temperature follows the chamber set points with a 60 s thermal lag (choice).
        StepProfile(CHAMBER_LEVELS_C, lag_s=60.0, channel="temp_c", name="chamber"),
        # Temperature read-out noise 0.02 C per sample at 100 Hz (choice).
        WhiteNoise(0.002, channel="temp_c", name="temp_noise"),
        TemperatureBias(bias_coefs, t_ref_c=25.0, name="temperature_bias"),
        TemperatureWhiteNoise(CC300_TEMPS_C, densities, name="white"),
    ]
    return dict(sources=sources, target=target, units=units, column_units={"temp_c": "degC"})


@_register(
    "temp_chamber_gyro",
    3600.0,
    100.0,
    "CC-300 gyro-Y in a thermal chamber, -30..+60 C "
    "steps: temp_c column, quadratic temperature bias, temperature-dependent ARW",
)
def _temp_chamber_gyro(units="deg/s"):
    k = rate_factor(units)
    # Bias 0.2813 deg/s at 25 C (Park 2004); 0.006 deg/s/C and 1e-4 deg/s/C^2 are choices.
    return _chamber(
        "gyro_y",
        units,
        (0.2813 * k, 0.006 * k, 1e-4 * k),
        [arw_to_density(a, units) for a in CC300_GYRO_ARW],
    )


@_register(
    "temp_chamber_accel",
    3600.0,
    100.0,
    "CC-300 accelerometer-Y in a thermal chamber, "
    "-30..+60 C steps: temp_c column, quadratic temperature bias, temperature-dependent VRW",
)
def _temp_chamber_accel():
    # Bias 2.4233 mg at 25 C (Park 2004); 0.05 mg/C and 0.002 mg/C^2 are choices.
    return _chamber(
        "accel_y",
        ACCEL_UNIT,
        tuple(mg_to_mps2(c) for c in (2.4233, 0.05, 0.002)),
        [vrw_to_density(v) for v in CC300_ACCEL_VRW],
    )


@_register(
    "rate_table_gyro",
    660.0,
    100.0,
    "Yaw gyro on a rate table, 0->80->-80->0 deg/s in "
    "10 deg/s steps (Park 2004): rate_ref column, scale-factor error -0.3984 %, bias, ARW",
)
def _rate_table_gyro():
    sources = [
        StepProfile(RATE_TABLE_LEVELS, lag_s=0.5, channel="rate_ref", name="table"),
        AuxInput("rate_ref", {0: 1.0}, name="true_rate"),
        ScaleFactorError(-0.003984, "rate_ref", name="scale_factor"),
        ConstantBias(0.2813, name="bias"),
        WhiteNoise(arw_to_density(2.25), name="white"),  # RGA300CA spec < 2.25 deg/sqrt(h)
    ]
    return dict(sources=sources, target="gyro_z", units="deg/s", column_units={"rate_ref": "deg/s"})


# --- residual-loop records: one undeclared effect each --------------------------------------


def _base() -> GaussMarkov:
    """CC-300-class gyro noise (0.5 deg/s, cf. ARW 2.9 deg/sqrt(h) = 0.48 deg/s at 100 Hz)
    coloured by a two-pole response: 2nd-order GM with 0.02 s stages, an exact AR(2)."""
    return GaussMarkov(0.5, 0.02, order=2, name="base")


def _warmup_temperature() -> list:
    """temp_c column: 22 C warming by 12 C with a 90 s time constant, 0.02 C read-out noise."""
    return [
        WarmUp(22.0, 12.0, 90.0, channel="temp_c", name="temp_warmup"),
        WhiteNoise(0.002, channel="temp_c", name="temp_noise"),
    ]


def _temperature_bias() -> TemperatureBias:
    """0.02 deg/s/C and 0.001 deg/s/C^2 about 25 C: about 0.3 deg/s over the warm-up."""
    return TemperatureBias(
        (0.0, 0.02, 0.001), t_ref_c=25.0, declared=False, name="temperature_bias"
    )


def _vibration() -> Vibration:
    """0.1 deg/s sinusoid at 7.3137 Hz (off the FFT grid of the default record)."""
    return Vibration(VIBRATION_HZ, (0.1,), (0.7,), declared=False, name="vibration")


def _loop(*sources, **units):
    return dict(sources=list(sources), target="gyro_x", units="deg/s", column_units=units)


@_register(
    "clean",
    LOOP_DURATION,
    LOOP_RATE,
    "Control: gyro_x with only the AR(2) (2nd-order GM) base noise",
)
def _clean():
    return _loop(_base())


@_register(
    "unrelated_temperature",
    LOOP_DURATION,
    LOOP_RATE,
    "Control: base noise plus a warming temp_c column that does not affect gyro_x",
)
def _unrelated_temperature():
    return _loop(_base(), *_warmup_temperature(), temp_c="degC")


@_register(
    "undeclared_temperature",
    LOOP_DURATION,
    LOOP_RATE,
    "Base noise plus an undeclared quadratic bias in the warming temp_c column",
)
def _undeclared_temperature():
    return _loop(_base(), *_warmup_temperature(), _temperature_bias(), temp_c="degC")


@_register(
    "undeclared_vibration",
    LOOP_DURATION,
    LOOP_RATE,
    "Base noise plus an undeclared 0.1 deg/s vibration at 7.3137 Hz (off the FFT grid)",
)
def _undeclared_vibration():
    return _loop(_base(), _vibration())


@_register(
    "undeclared_nonlinear",
    LOOP_DURATION,
    LOOP_RATE,
    "Undeclared bounded cross-product "
    "dynamics: y[n] = 0.5 y[n-1] - 0.2 y[n-2] + 0.2 y[n-1] y[n-2] + e[n]",
)
def _undeclared_nonlinear():
    # Cross term ~1 % of the innovation variance; escape radius 3.5 deg/s = 8.9 std.
    return _loop(NonlinearAR((0.5, -0.2), ((1, 2, 0.2),), 0.35, declared=False, name="nonlinear"))


@_register(
    "undeclared_drift",
    LOOP_DURATION,
    LOOP_RATE,
    "Base noise plus an undeclared drift: 1.2 deg/s/h linear and 0.2 deg/s warm-up (60 s)",
)
def _undeclared_drift():
    drift = Drift(1.2, 0.2, 60.0, declared=False, name="drift")
    return _loop(_base(), drift)


@_register(
    "undeclared_aux_lag",
    LOOP_DURATION,
    LOOP_RATE,
    "Base noise plus undeclared "
    "g-sensitivity: the accel_x column enters gyro_x 3 samples late (0.03 deg/s per m/s^2)",
)
def _undeclared_aux_lag():
    return _loop(
        _base(),
        # accel_x: 2 m/s^2 vehicle motion (GM, 0.05 s) plus CC-300 accelerometer noise.
        GaussMarkov(2.0, 0.05, channel="accel_x", name="accel_motion"),
        WhiteNoise(vrw_to_density(sum(CC300_ACCEL_VRW) / 4), channel="accel_x", name="accel_noise"),
        AuxInput("accel_x", {3: 0.03}, declared=False, name="g_sensitivity"),
        accel_x=ACCEL_UNIT,
    )


@_register(
    "undeclared_step",
    LOOP_DURATION,
    LOOP_RATE,
    "Base noise plus an undeclared 0.15 deg/s bias step at 35 % of the record (or at step_time_s)",
)
def _undeclared_step(duration, step_time_s=None):
    # 35 %: inside the first half, the part of a record a model is fitted on.
    time_s = 0.35 * duration if step_time_s is None else step_time_s
    return _loop(_base(), BiasStep((time_s,), (0.15,), declared=False, name="bias_step"))


@_register(
    "temperature_and_vibration",
    LOOP_DURATION,
    LOOP_RATE,
    "Base noise plus two undeclared effects: the temp_c quadratic bias and the 7.3137 Hz vibration",
)
def _temperature_and_vibration():
    return _loop(_base(), *_warmup_temperature(), _temperature_bias(), _vibration(), temp_c="degC")


# --- residual-loop records with slow errors (15 minutes) -------------------------------------


def _slow_base() -> list:
    """AR(3) + white noise: the fast part of a gyro error.

    AR(3) ``0.5, -0.2, 0.1`` (stable, a short-memory colouring) driven by 0.2 deg/s,
    0.24 deg/s stationary; white noise of the CC-300 class, ARW 2.9 deg/sqrt(h)
    (0.48 deg/s per sample at 100 Hz).  Their 30 s means scatter by about 0.01 deg/s:
    the slow effects below are several times that.
    """
    return [ARProcess((0.5, -0.2, 0.1), 0.2, name="ar3"),
            WhiteNoise(arw_to_density(2.9), name="white")]


def _random_walk() -> RandomWalk:
    """Bias random walk, K = 0.0063 deg/sqrt(s^3): its Allan deviation, K sqrt(tau/3),
    reaches 0.02 deg/s at 30 s, twice the noise's 30 s scatter, and it wanders about
    0.19 deg/s over the record."""
    return RandomWalk(0.0063, declared=False, name="bias_walk")


def _switched_temperature() -> list:
    """temp_c that keeps moving through the record: a heater switched every 75 s between
    set points 23-29 C in no order of time (the bias it drives is not a trend), followed
    with a 15 s thermal lag, and 0.02 C read-out noise; it drives the bias by 0.03 deg/s/C
    and 0.002 deg/s/C^2.  A level follows such a bias only tens of seconds late; the
    temperature says at once."""
    set_points = (25.0, 28.0, 23.0, 27.0, 24.0, 29.0, 26.0, 23.0, 28.0, 25.0, 27.0, 24.0)
    return [StepProfile(set_points, dwell_s=75.0, lag_s=15.0, channel="temp_c",
                        name="temp_heater"),
            WhiteNoise(0.002, channel="temp_c", name="temp_noise"),
            TemperatureBias((0.0, 0.03, 0.002), t_ref_c=25.0, declared=False,
                            name="temperature_bias")]


def _slow(*sources, **units):
    return _loop(*_slow_base(), *sources, **units)


@_register("slow_clean", SLOW_DURATION, LOOP_RATE,
           "Control (15 min): gyro_x with only the AR(3) + white base noise")
def _slow_clean():
    return _slow()


@_register("slow_unrelated_temperature", SLOW_DURATION, LOOP_RATE,
           "Control (15 min): AR(3) + white noise and a switching temp_c that affects nothing")
def _slow_unrelated_temperature():
    return _slow(*_switched_temperature()[:2], temp_c="degC")


@_register("slow_random_walk", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared bias random walk (K 0.0063 deg/s/sqrt(s))")
def _slow_random_walk():
    return _slow(_random_walk())


@_register("slow_warmup", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared 0.2 deg/s exponential warm-up "
           "(time constant tau_s, default 60 s)")
def _slow_warmup(tau_s: float = 60.0):
    return _slow(Drift(0.0, 0.2, tau_s, declared=False, name="drift"))


@_register("slow_warmup_drift", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared 300 s, 0.2 deg/s warm-up and a "
           "1.2 deg/s/h linear drift")
def _slow_warmup_drift():
    return _slow(Drift(1.2, 0.2, 300.0, declared=False, name="drift"))


@_register("slow_steps", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus undeclared bias steps of +0.15 deg/s at 150 s and "
           "-0.12 deg/s at 350 s")
def _slow_steps():
    return _slow(BiasStep((150.0, 350.0), (0.15, -0.12), declared=False, name="bias_step"))


@_register("slow_random_walk_temperature", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared bias random walk and an undeclared "
           "quadratic bias in a switching temp_c")
def _slow_random_walk_temperature():
    return _slow(_random_walk(), *_switched_temperature(), temp_c="degC")


@_register("slow_warmup_drift_temperature", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared warm-up and linear drift and an "
           "undeclared quadratic bias in a cycling temp_c")
def _slow_warmup_drift_temperature():
    return _slow(Drift(1.2, 0.2, 300.0, declared=False, name="drift"), *_switched_temperature(),
                 temp_c="degC")


# --- effects that begin inside the record, a driver on a short record -----------------------


@_register("slow_step_third", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared bias step (+0.15 deg/s, or amplitude) a "
           "third of the way in: after the earliest origins of the judge")
def _slow_step_third(duration, amplitude: float = 0.15):
    return _slow(BiasStep((duration / 3,), (amplitude,), declared=False, name="bias_step"))


@_register("slow_late_warmup", SLOW_DURATION, LOOP_RATE,
           "AR(3) + white noise plus an undeclared 0.2 deg/s warm-up (tau_s, default 60 s) "
           "that starts a third of the way in (or at start_s)")
def _slow_late_warmup(duration, tau_s: float = 60.0, start_s: float | None = None):
    start = duration / 3 if start_s is None else start_s
    return _slow(Drift(0.0, 0.2, tau_s, start_s=start, declared=False, name="drift"))


#: The short record with a measured driver: ten minutes, as a bench record of a MEMS IMU
#: with its die temperature.
SHORT_DURATION = 600.0


def _cooling_temperature() -> list:
    """temp_c of a die settling after turn-on: 27 C cooling by 2 C with a 200 s time constant,
    read in steps of 1/340 C (an MPU-6050's) with 0.002 C noise per sample.  Over ten minutes it
    follows time: a trend fitted there could not be told from it."""
    return [WarmUp(27.0, -2.0, 200.0, channel="temp_c", name="temp_cooling"),
            WhiteNoise(0.0002, channel="temp_c", name="temp_noise")]


@_register("short_driver", SHORT_DURATION, LOOP_RATE,
           "Ten minutes: AR(3) + white noise plus an undeclared 0.1 deg/s/C bias (or "
           "sensitivity) in a cooling temp_c, and a bias random walk of walk_k (default none)")
def _short_driver(sensitivity: float = 0.1, walk_k: float = 0.0):
    walk = [RandomWalk(walk_k, declared=False, name="bias_walk")] if walk_k else []
    bias = [TemperatureBias((0.0, sensitivity), t_ref_c=25.0, declared=False,
                            name="temperature_bias")] if sensitivity else []
    spec = _slow(*walk, *_cooling_temperature(), *bias, temp_c="degC")
    spec["quantizers"] = {"temp_c": Quantizer(1.0 / 340.0)}
    return spec


_register("short_driver_control", SHORT_DURATION, LOOP_RATE,
          "Control: short_driver without the temperature effect (same draws per seed)",
          fixed={"sensitivity": 0.0})(_short_driver)


@_register("companion_knocks", 1800.0, 100.0,
           "Static six-axis IMU (as static_imu) whose companion column (az_mps2) carries "
           "count knocks (39 of 0.05 s, 5 m/s^2): spikes on a column the gyro's loop does "
           "not analyse")
def _companion_knocks(column: str = "az_mps2", count: int = 39, knock_s: float = 0.05,
                      amplitude: float = 5.0):
    spec = _static_imu()
    spec["sources"].append(Knocks(count, amplitude, knock_s, channel=column, name="knocks"))
    return spec


#: A phone's gyro as a user logs it: 10 Hz for six hours, in rad/s, a 16-bit read-out at
#: +-2000 deg/s (LSB 0.061 deg/s, above the 0.022 deg/s of white noise per sample), white
#: noise of 0.007 deg/s/sqrt(Hz) (0.42 deg/sqrt(h)), a bias instability of 20 deg/h and a
#: random walk that moves the bias by about 0.01 deg/s over the record (choices in the range
#: of consumer MEMS data sheets).
PHONE_DURATION, PHONE_RATE = 6 * 3600.0, 10.0
PHONE_LSB = math.radians(4000.0 / 2**16)
PHONE_WHITE = math.radians(0.007)
PHONE_B, PHONE_K = math.radians(20.0 / 3600.0) / 0.664, math.radians(6.8e-5)
PHONE_GYROS = ("gx_rads", "gy_rads", "gz_rads")


@_register("phone_gyro", PHONE_DURATION, PHONE_RATE,
           "A phone's three gyros at 10 Hz for 6 h in rad/s: white noise, a 20 deg/h bias "
           "instability, a bias random walk and a 0.061 deg/s read-out step; no effect "
           "beyond the stochastic ones")
def _phone_gyro():
    sources = []
    for column in PHONE_GYROS:
        sources += [WhiteNoise(PHONE_WHITE, channel=column, name=f"{column}_white"),
                    BiasInstability(PHONE_B, 1.0, 3000.0, channel=column,
                                    name=f"{column}_bias_instability"),
                    RandomWalk(PHONE_K, channel=column, name=f"{column}_random_walk")]
    return dict(sources=sources, target="gx_rads", units="rad/s",
                column_units={c: "rad/s" for c in PHONE_GYROS},
                quantizers={c: Quantizer(PHONE_LSB) for c in PHONE_GYROS})


# --- six-axis records of one sensor: temperature sweeps, sessions, shared noise ---------------

DAY, SWEEP_RATE = 86_400.0, 1.0


@_register("temperature_sweep", DAY, SWEEP_RATE,
           "Six-axis IMU + temp_c, 1 Hz, one day: 5->20 C, held, ->8 C; undeclared bias "
           "polynomial in temp_c on gx_dps and ax_mps2; coarse LSBs")
def _temperature_sweep(duration, sweep=DAY_SWEEP, orientation="+z/+x", sensitivity=None,
                       t_ref_c=T_REF_C, lag_s=0.0, gyro_lsb=GYRO_LSB, accel_lsb=ACCEL_LSB,
                       temp_lsb=TEMP_LSB):
    return sweep_spec(duration, sweep=sweep, orientation=orientation, sensitivity=sensitivity,
                      t_ref_c=t_ref_c, lag_s=lag_s, gyro_lsb=gyro_lsb, accel_lsb=accel_lsb,
                      temp_lsb=temp_lsb)


_register("temperature_sweep_lag", DAY, SWEEP_RATE,
          "temperature_sweep with a 30 min thermal lag between temp_c and the driven biases",
          fixed={"lag_s": LAG_S})(_temperature_sweep)
_register("temperature_sweep_control", DAY, SWEEP_RATE,
          "Control: temperature_sweep without the temperature effect (same draws per seed)",
          fixed={"sensitivity": {}})(_temperature_sweep)


@_register("temperature_sessions", DAY, SWEEP_RATE,
           "3 sessions of one six-axis IMU, 1 Hz, a day each, another axis up each: sweeps from "
           "5 C to 16-24 C (the first flat for half), shared temp_c bias on gx_dps, ax_mps2",
           sessions=3)
def _temperature_sessions(duration, sweeps=SESSION_SWEEPS, orientations=SESSION_ORIENTATIONS,
                          sensitivity=None, t_ref_c=T_REF_C, lag_s=0.0, gyro_lsb=GYRO_LSB,
                          accel_lsb=ACCEL_LSB, temp_lsb=TEMP_LSB):
    return sessions_spec(duration, sweeps=sweeps, orientations=orientations,
                         sensitivity=sensitivity, t_ref_c=t_ref_c, lag_s=lag_s,
                         gyro_lsb=gyro_lsb, accel_lsb=accel_lsb, temp_lsb=temp_lsb)


_register("temperature_sessions_control", DAY, SWEEP_RATE,
          "Control: temperature_sessions without the temperature effect (same draws per seed)",
          sessions=3, fixed={"sensitivity": {}})(_temperature_sessions)


@_register("companion_noise", 3600.0, 100.0,
           "Six-axis IMU whose gyros share part of their white noise and a fast 0.2 s error, "
           "and so do its accelerometers (known covariance); no axis enters another")
def _companion_noise(gyro_corr=GYRO_CORR, accel_corr=ACCEL_CORR, fast=True):
    return companion_spec(gyro_corr=gyro_corr, accel_corr=accel_corr, fast=fast)

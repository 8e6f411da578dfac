"""An IMU's Allan noise in the files VIO systems and autopilots read, each as its source uses it.

Every target takes the same two terms per sensor: the white-noise coefficient ``N``
(units*sqrt(s), which *is* the continuous-time density in units/sqrt(Hz)) and the rate random
walk ``K`` (units/sqrt(s): the density of the bias's driving noise in units/s/sqrt(Hz)), as one
number per sensor, the largest over its axes (:meth:`fosmodel.noise.imu_noise.ImuNoise.export`
gathers them into a :class:`NoiseExport`).
What changes from one target to the next is how its filter discretises them, read from its
own code (cited beside each conversion below):

============================  =====================================  ======================
target                        white noise                            bias random walk
============================  =====================================  ======================
Kalibr ``imu.yaml``           ``N``                                  ``K``
OpenVINS (Kalibr-style)       ``N``                                  ``K``
ORB-SLAM3                     ``N``                                  ``K``
VINS-Mono / VINS-Fusion       ``N sqrt(2 rate)``                     ``K sqrt(rate)``
PX4 EKF2                      ``N / sqrt(dt)``, dt = 0.01 s          ``K / sqrt(dt)``
ArduPilot EKF3                ``N / sqrt(dt)``, dt = 0.012 s         ``K / sqrt(dt)``
============================  =====================================  ======================

``rate`` is the IMU's sample rate, ``dt`` the EKF's prediction step (PX4's
``EKF2_PREDICT_US``, ArduPilot's ``EKF_TARGET_DT``).  A term the fit does not resolve is
exported as its upper limit (never 0) and the file says so.

``inflate`` multiplies every exported value: a static record shows the sensor's noise alone,
while on a moving platform vibration, scale-factor and misalignment errors and the motion's
own unmodelled effects add to it; practitioners inflate the Allan values (OpenVINS's
calibration guide: "maybe 10-20x"; its RealSense D455 configuration: white noise 2x, bias
random walk 10x).  Every file records the factor.

References
----------
Kalibr wiki, "IMU Noise Model" (github.com/ethz-asl/kalibr/wiki/IMU-Noise-Model).
OpenVINS: ``ov_msckf/src/state/Propagator.cpp`` (``Qc = sigma_w^2/dt``, ``sigma_wb^2 dt``),
``config/*/kalibr_imu_chain.yaml``, ``docs/gs-calibration.dox`` (github.com/rpng/open_vins).
ORB-SLAM3: ``src/Tracking.cc`` (``IMU::Calib(Tbc, Ng*sf, Na*sf, Ngw/sf, Naw/sf)``,
``sf = sqrt(IMU.Frequency)``), ``src/ImuTypes.cc`` (``Preintegrated::IntegrateNewMeasurement``)
(github.com/UZ-SLAMLab/ORB_SLAM3).
VINS-Fusion: ``vins_estimator/src/factor/integration_base.h`` (``midPointIntegration``: the
noise matrix ``V`` and ``noise = diag(ACC_N^2, GYR_N^2, ACC_N^2, GYR_N^2, ACC_W^2,
GYR_W^2)``), ``config/euroc/euroc_mono_imu_config.yaml`` (github.com/HKUST-Aerial-Robotics/
VINS-Fusion; VINS-Mono's ``integration_base.h`` is the same).
PX4: ``src/modules/ekf2/EKF/covariance.cpp`` (``Ekf::predictCovariance``),
``src/modules/ekf2/module.yaml``, ``params_gyro_bias.yaml``, ``params_accel_bias.yaml``
(github.com/PX4/PX4-Autopilot).
ArduPilot: ``libraries/AP_NavEKF3/AP_NavEKF3_core.cpp`` (``NavEKF3_core::CovariancePrediction``),
``AP_NavEKF3_core.h`` (``EKF_TARGET_DT``), ``AP_NavEKF3.cpp`` (the ``EK3_*_NSE`` parameters)
(github.com/ArduPilot/ardupilot).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any, NamedTuple

from .._version import __version__

#: PX4 EKF2's prediction step: ``EKF2_PREDICT_US`` 10000 (src/modules/ekf2/module.yaml).
PX4_PREDICT_S = 0.01
#: ArduPilot EKF3's prediction step: ``EKF_TARGET_DT`` 0.012 (AP_NavEKF3_core.h).
ARDUPILOT_DT_S = 0.012
#: The continuous-time densities in SI.
SI_UNITS = {("gyro", "N"): "rad/s/sqrt(Hz)", ("gyro", "K"): "rad/s^2/sqrt(Hz)",
            ("accel", "N"): "m/s^2/sqrt(Hz)", ("accel", "K"): "m/s^3/sqrt(Hz)"}


class Density(NamedTuple):
    """One sensor's value of a term: continuous-time density in SI, its axis, and what it is."""

    value: float
    axis: str
    kind: str  # "fitted" or "upper limit"


@dataclass(frozen=True)
class NoiseExport:
    """What every export is made from: per sensor ``N`` and ``K`` in SI, the rate, the factor.

    Attributes
    ----------
    densities : mapping of (sensor, term) to Density
        ``("gyro", "N")``, ``("gyro", "K")``, ``("accel", "N")``, ``("accel", "K")``, as
        measured (before ``inflate``).
    rate : float
        The IMU's sample rate in Hz.
    source : str
        The record's file name.
    columns : tuple of str
        The axes the values come from.
    inflate : float
        Factor on every exported value (1: the static record's values).
    """

    densities: Mapping[tuple[str, str], Density]
    rate: float
    source: str
    columns: tuple[str, ...]
    inflate: float = 1.0

    def value(self, sensor: str, term: str) -> float:
        """Return the exported (inflated) continuous-time density of a sensor's term, in SI."""
        return self.inflate * self.densities[sensor, term].value

    def header(self, comment: str, target: str) -> list[str]:
        """Return the lines every file starts with: what it is, from what, and the inflation."""
        inflation = (f"inflated {self.inflate:g}x for a moving platform: every value "
                     f"below is {self.inflate:g} times the static record's"
                     if self.inflate != 1.0 else
                     "not inflated: the static record's values; a moving "
                     "platform usually needs more (vibration, scale and misalignment errors)")
        return [f"{comment} IMU noise for {target}, from the Allan deviation of {self.source} "
                f"({', '.join(self.columns)}) by fosmodel {__version__}.",
                f"{comment} {inflation}.",
                f"{comment} One number per sensor: the largest over its axes; 'upper limit' marks "
                "a term the fit does not resolve."]

    def note(self, sensor: str, term: str) -> str:
        """Say which axis a value comes from, and whether it is an upper limit."""
        d = self.densities[sensor, term]
        return d.axis + ("" if d.kind == "fitted" else ", upper limit: the fit does not resolve it")


class Parameter(NamedTuple):
    """One exported parameter: its name in the target, sensor, term, value and units."""

    name: str
    sensor: str
    term: str
    value: float
    units: str


def _kalibr_parameters(e: NoiseExport) -> list[Parameter]:
    """Kalibr, OpenVINS: the continuous-time densities themselves.

    OpenVINS's Propagator.cpp discretises them as ``Qc = sigma_w^2 / dt`` (white) and
    ``sigma_wb^2 * dt`` (bias walk), Kalibr's ``sigma_d = sigma / sqrt(dt)``.
    """
    names = {"gyro": "gyroscope", "accel": "accelerometer"}
    fields = {"N": "noise_density", "K": "random_walk"}
    return [Parameter(f"{names[s]}_{fields[t]}", s, t, e.value(s, t), SI_UNITS[s, t])
            for s in ("accel", "gyro") for t in ("N", "K")]


def _orbslam3_parameters(e: NoiseExport) -> list[Parameter]:
    """ORB-SLAM3: continuous-time densities, discretised by the code itself.

    Tracking.cc builds ``IMU::Calib(Tbc, Ng*sf, Na*sf, Ngw/sf, Naw/sf)`` with ``sf =
    sqrt(IMU.Frequency)``; ImuTypes.cc then adds ``B Cov B'`` (``B`` proportional to the sample
    interval ``dt``: ``(N sqrt(f) dt)^2 = N^2 dt`` per sample) and ``CovWalk = (K/sqrt(f))^2 =
    K^2 dt`` per sample: exactly the continuous model, so the parameters are ``N`` and ``K``.
    """
    names = {("gyro", "N"): "IMU.NoiseGyro", ("accel", "N"): "IMU.NoiseAcc",
             ("gyro", "K"): "IMU.GyroWalk", ("accel", "K"): "IMU.AccWalk"}
    return [Parameter(names[s, t], s, t, e.value(s, t), SI_UNITS[s, t])
            for s, t in names]


def _vins_parameters(e: NoiseExport) -> list[Parameter]:
    """VINS-Mono / VINS-Fusion: per-sample standard deviations, as integration_base.h uses them.

    ``midPointIntegration`` adds ``V noise V'`` per IMU step ``dt = 1/rate``, with ``noise =
    diag(ACC_N^2, GYR_N^2, ACC_N^2, GYR_N^2, ACC_W^2, GYR_W^2)``: the angle takes
    ``0.5 dt`` of each of the step's two gyro noises (``V(3,3)``, ``V(3,9)``), a variance of
    ``gyr_n^2 dt^2 / 2``, which equals the continuous model's ``N^2 dt`` when ``gyr_n = N
    sqrt(2 rate)`` (the velocity likewise for ``acc_n``); the bias takes ``dt`` of its walk
    noise (``V(9,12)``, ``V(12,15)``), ``acc_w^2 dt^2 = K^2 dt`` when ``acc_w = K sqrt(rate)``.
    The configs call them "measurement noise standard deviation" and "bias random work noise
    standard deviation".
    """
    n_scale, k_scale = math.sqrt(2.0 * e.rate), math.sqrt(e.rate)
    units = {("accel", "N"): "m/s^2", ("gyro", "N"): "rad/s", ("accel", "K"): "m/s^3",
             ("gyro", "K"): "rad/s^2"}
    names = {("accel", "N"): "acc_n", ("gyro", "N"): "gyr_n", ("accel", "K"): "acc_w",
             ("gyro", "K"): "gyr_w"}
    return [Parameter(names[s, t], s, t, e.value(s, t) * (n_scale if t == "N" else k_scale),
                      units[s, t]) for s, t in names]


def _ekf_parameters(e: NoiseExport, names: Mapping[tuple[str, str], str],
                    dt: float) -> list[Parameter]:
    """PX4 EKF2, ArduPilot EKF3: standard deviations per prediction step ``dt``.

    Both add ``(dt * GYR_NOISE)^2`` to the delta angle's variance per step (``N^2 dt`` when
    ``GYR_NOISE = N / sqrt(dt)``) and ``(dt * GYR_B_NOISE)^2`` to the rate bias's (``K^2 dt``
    when ``GYR_B_NOISE = K / sqrt(dt)``); the accelerometer alike.
    """
    units = {("gyro", "N"): "rad/s", ("accel", "N"): "m/s^2", ("gyro", "K"): "rad/s^2",
             ("accel", "K"): "m/s^3"}
    return [Parameter(names[s, t], s, t, e.value(s, t) / math.sqrt(dt), units[s, t])
            for s, t in names]


_PX4_NAMES = {("gyro", "N"): "EKF2_GYR_NOISE", ("accel", "N"): "EKF2_ACC_NOISE",
              ("gyro", "K"): "EKF2_GYR_B_NOISE", ("accel", "K"): "EKF2_ACC_B_NOISE"}
_ARDUPILOT_NAMES = {("gyro", "N"): "EK3_GYRO_P_NSE", ("accel", "N"): "EK3_ACC_P_NSE",
                    ("gyro", "K"): "EK3_GBIAS_P_NSE", ("accel", "K"): "EK3_ABIAS_P_NSE"}
#: Each parameter's documented range (module.yaml, params_*_bias.yaml; AP_NavEKF3.cpp): a value
#: outside it may be refused by a ground station (the firmware clips to [0, 1] in the code).
RANGES = {"EKF2_GYR_NOISE": (0.0001, 0.1), "EKF2_ACC_NOISE": (0.01, 1.0),
          "EKF2_GYR_B_NOISE": (0.0, 0.01), "EKF2_ACC_B_NOISE": (0.0, 0.01),
          "EK3_GYRO_P_NSE": (0.0001, 0.1), "EK3_ACC_P_NSE": (0.01, 1.0),
          "EK3_GBIAS_P_NSE": (0.00001, 0.001), "EK3_ABIAS_P_NSE": (0.00001, 0.02)}


def px4_parameters(e: NoiseExport, predict_s: float = PX4_PREDICT_S) -> list[Parameter]:
    """PX4 EKF2's four IMU noise parameters (``predict_s``: ``EKF2_PREDICT_US`` in s).

    covariance.cpp, ``Ekf::predictCovariance``: ``d_ang_var = sq(delta_ang_dt * gyro_noise)``,
    ``gyro_bias_process_noise = sq(dt * gyro_bias_p_noise)`` with ``dt = _dt_ekf_avg``.
    """
    return _ekf_parameters(e, _PX4_NAMES, predict_s)


def ardupilot_parameters(e: NoiseExport, dt_s: float = ARDUPILOT_DT_S) -> list[Parameter]:
    """ArduPilot EKF3's four IMU noise parameters (``dt_s``: the EKF step, ``EKF_TARGET_DT``).

    AP_NavEKF3_core.cpp, ``CovariancePrediction``: ``daxVar = sq(dt*_gyrNoise)``, ``dvxVar =
    sq(dt*_accNoise)``, and the bias states' process noise ``sq(dt * _gyroBiasProcessNoise)``
    per step for the rate bias (older versions: ``sq(sq(dt) * ...)`` on the delta-angle bias,
    ``dt`` times the rate bias: the same).
    """
    return _ekf_parameters(e, _ARDUPILOT_NAMES, dt_s)


def _number(value: float) -> str:
    return f"{value:.6e}"


def _real(value: float) -> str:
    """``value`` as OpenCV reads a real number (``100.0``, not the integer ``100``)."""
    text = f"{value:.6g}"
    return text if any(c in text for c in ".en") else f"{text}.0"


def _opencv_yaml(e: NoiseExport, target: str, why: list[str], parameters: list[Parameter],
                 tail: list[str]) -> str:
    """Write a fragment of an OpenCV ``FileStorage`` YAML file (``%YAML:1.0`` first, as needed)."""
    lines = ["%YAML:1.0", *e.header("#", target), *why, ""]
    lines += [f"{p.name}: {_number(p.value)}  # {p.units}, {e.note(p.sensor, p.term)}"
              for p in parameters]
    return "\n".join([*lines, *tail]) + "\n"


def kalibr_yaml(e: NoiseExport, rostopic: str = "/imu0") -> str:
    """Kalibr's ``imu.yaml``: per sensor ``N`` and ``K``, continuous time, in SI."""
    lines = [*e.header("#", "Kalibr"),
             "# Continuous-time densities (Kalibr discretises them with update_rate): noise "
             "density = Allan N,", "# random walk = Allan rate random walk K.", ""]
    params = {p.name: p for p in _kalibr_parameters(e)}
    for sensor, title in (("accel", "Accelerometers"), ("gyro", "Gyroscopes")):
        lines.append(f"# {title}")
        lines += [f"{p.name}: {_number(p.value)}  # {p.units}, {e.note(p.sensor, p.term)}"
                  for p in params.values() if p.sensor == sensor]
        lines.append("")
    lines += [f"rostopic: {rostopic}  # set to the IMU's topic",
              f"update_rate: {e.rate:.6g}  # Hz"]
    return "\n".join(lines) + "\n"


def openvins_yaml(e: NoiseExport) -> str:
    """OpenVINS's ``kalibr_imu_chain.yaml``: Kalibr's densities, identity intrinsics.

    The intrinsics (``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg``) are OpenVINS's
    "calibrated" defaults, as in its ``config/euroc_mav/kalibr_imu_chain.yaml``.
    """
    eye3 = ["    - [1.0, 0.0, 0.0]", "    - [0.0, 1.0, 0.0]", "    - [0.0, 0.0, 1.0]"]
    zero3 = ["    - [0.0, 0.0, 0.0]"] * 3
    lines = ["%YAML:1.0", *e.header("#", "OpenVINS (kalibr_imu_chain.yaml)"),
             "# Continuous-time densities: OpenVINS's Propagator.cpp discretises them as "
             "sigma_w^2/dt and sigma_wb^2*dt.", "", "imu0:", "  T_i_b:",
             "    - [1.0, 0.0, 0.0, 0.0]", "    - [0.0, 1.0, 0.0, 0.0]",
             "    - [0.0, 0.0, 1.0, 0.0]", "    - [0.0, 0.0, 0.0, 1.0]"]
    lines += [f"  {p.name}: {_number(p.value)}  # {p.units}, {e.note(p.sensor, p.term)}"
              for p in _kalibr_parameters(e)]
    lines += ["  rostopic: /imu0  # set to the IMU's topic", "  time_offset: 0.0",
              f"  update_rate: {_real(e.rate)}", "  model: \"kalibr\"",
              "  Tw:", *eye3, "  R_IMUtoGYRO:", *eye3, "  Ta:", *eye3, "  R_IMUtoACC:", *eye3,
              "  Tg:", *zero3]
    return "\n".join(lines) + "\n"


def orbslam3_yaml(e: NoiseExport) -> str:
    """ORB-SLAM3's IMU settings (paste into the settings file beside the camera's)."""
    why = ["# Continuous-time densities (rad/s/sqrt(Hz)...): Tracking.cc multiplies the noise by "
           "sqrt(IMU.Frequency)", "# and divides the walk by it, so these are Allan N and K.",
           "# Paste into the ORB-SLAM3 settings file (it starts with %YAML:1.0, as here)."]
    return _opencv_yaml(e, "ORB-SLAM3", why, _orbslam3_parameters(e),
                        [f"IMU.Frequency: {_real(e.rate)}  # Hz (ORB-SLAM3 reads a real number)"])


def vins_yaml(e: NoiseExport) -> str:
    """VINS-Mono / VINS-Fusion's four IMU noise parameters (paste into the config)."""
    why = [f"# Per-sample standard deviations at the IMU rate ({e.rate:.6g} Hz), as "
           "integration_base.h propagates them:",
           "# acc_n, gyr_n = N sqrt(2 rate) (its mid-point step takes half of each of two "
           "samples' noise),",
           "# acc_w, gyr_w = K sqrt(rate) (the bias takes dt of its walk noise per step).",
           "# Paste into the VINS config (it starts with %YAML:1.0, as here); keep its g_norm."]
    return _opencv_yaml(e, "VINS-Mono / VINS-Fusion", why, _vins_parameters(e), [])


def _ekf_text(e: NoiseExport, target: str, parameters: list[Parameter], dt: float,
              line: Callable[[Parameter], str], step: str) -> str:
    lines = [*e.header("#", target),
             f"# Standard deviations per EKF prediction step dt = {dt:g} s ({step}): the EKF "
             "adds (dt*NOISE)^2 per step,",
             "# so NOISE = Allan N / sqrt(dt) and B_NOISE = Allan K / sqrt(dt); for another dt "
             f"multiply them by sqrt({dt:g}/dt).", ""]
    for p in parameters:
        lo, hi = RANGES[p.name]
        out = "" if lo <= p.value <= hi else (f"; outside the documented range {lo:g}-{hi:g}: "
                                               "a ground station may refuse it")
        lines += [f"# {p.name}: {p.units}, {e.note(p.sensor, p.term)}{out}", line(p)]
    return "\n".join(lines) + "\n"


def px4_params(e: NoiseExport, predict_s: float = PX4_PREDICT_S) -> str:
    """PX4 EKF2's parameters as ``param set`` commands (the MAVLink console, or a startup file)."""
    return _ekf_text(e, "PX4 EKF2", px4_parameters(e, predict_s), predict_s,
                     lambda p: f"param set {p.name} {p.value:.6g}",
                     f"EKF2_PREDICT_US = {predict_s * 1e6:.0f}")


def ardupilot_params(e: NoiseExport, dt_s: float = ARDUPILOT_DT_S) -> str:
    """ArduPilot EKF3's parameters as a ``.parm`` file (``NAME VALUE`` lines)."""
    return _ekf_text(e, "ArduPilot EKF3", ardupilot_parameters(e, dt_s), dt_s,
                     lambda p: f"{p.name} {p.value:.6g}", "EKF_TARGET_DT")


#: Each export's file name and how it is written.
FILES: dict[str, Callable[[NoiseExport], str]] = {
    "imu.yaml": kalibr_yaml,
    "openvins_kalibr_imu_chain.yaml": openvins_yaml,
    "vins_imu.yaml": vins_yaml,
    "orbslam3_imu.yaml": orbslam3_yaml,
    "px4_ekf2.params": px4_params,
    "ardupilot_ek3.parm": ardupilot_params,
}


def export_files(e: NoiseExport) -> dict[str, str]:
    """Return every export's text by file name."""
    return {name: write(e) for name, write in FILES.items()}


def exports_dict(e: NoiseExport) -> dict[str, Any]:
    """Return every export's parameters as JSON-ready values (with their units), and the factor."""
    targets = {"kalibr": _kalibr_parameters(e), "openvins": _kalibr_parameters(e),
               "orbslam3": _orbslam3_parameters(e), "vins": _vins_parameters(e),
               "px4_ekf2": px4_parameters(e), "ardupilot_ek3": ardupilot_parameters(e)}
    return {"inflate": e.inflate, "rate_hz": e.rate,
            "px4_predict_s": PX4_PREDICT_S, "ardupilot_dt_s": ARDUPILOT_DT_S,
            "measured": {f"{s}_{t}": {"value": d.value, "units": SI_UNITS[s, t], "axis": d.axis,
                                      "is": d.kind} for (s, t), d in e.densities.items()},
            **{name: {p.name: {"value": p.value, "units": p.units} for p in params}
               for name, params in targets.items()}}

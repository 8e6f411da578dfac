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
exported as its upper limit (never 0) and the file says so.  The white noise is ``N`` together
with the white-like part of a short Gauss-Markov term (``sqrt(N^2 + 2 G^2 Tc)``, Tc at most
:data:`GM_WHITE_MAX_TC_S`; :meth:`fosmodel.noise.imu_noise.AxisNoise.gm_white_si`).  A value
beyond an autopilot parameter's documented range (:data:`RANGES`) is clamped to it, and the file
(and :func:`clamp_notes`, for the console) says so.

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
#: Standard gravity in m/s^2: VINS's ``g_norm`` when the record cannot tell its own.
STANDARD_GRAVITY = 9.80665
#: Longest correlation time of a Gauss-Markov term whose white-like part joins the exported
#: white noise: the shortest bias window the reports judge (30 s); a longer one is a slow
#: bias to a filter (bias states, random walk), not noise.
GM_WHITE_MAX_TC_S = 30.0
#: The continuous-time densities in SI.
SI_UNITS = {("gyro", "N"): "rad/s/sqrt(Hz)", ("gyro", "K"): "rad/s^2/sqrt(Hz)",
            ("accel", "N"): "m/s^2/sqrt(Hz)", ("accel", "K"): "m/s^3/sqrt(Hz)"}


class Density(NamedTuple):
    """One sensor's value of a term: continuous-time density in SI, its axis, and what it is.

    For the white noise, ``gm_white`` is the part of ``value`` that comes from a short
    Gauss-Markov term (``G sqrt(2 Tc)``, its correlation time ``gm_tc``), 0 if none.
    """

    value: float
    axis: str
    kind: str  # "fitted" or "upper limit"
    gm_white: float = 0.0
    gm_tc: float | None = None


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
    gravity : float
        Magnitude of gravity in m/s^2 for the targets that take it (VINS's ``g_norm``).
    gravity_from : str
        Where ``gravity`` comes from: the record's accelerometers at rest, or standard gravity.
    """

    densities: Mapping[tuple[str, str], Density]
    rate: float
    source: str
    columns: tuple[str, ...]
    inflate: float = 1.0
    gravity: float = STANDARD_GRAVITY
    gravity_from: str = "standard gravity"

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
        lines = [f"{comment} IMU noise for {target}, from the Allan deviation of {self.source} "
                 f"({', '.join(self.columns)}) by fosmodel {__version__}.",
                 f"{comment} {inflation}.",
                 f"{comment} One number per sensor: the largest over its axes; 'upper limit' "
                 "marks a term the fit does not resolve."]
        if any(self.densities[s, "N"].gm_white > 0 for s in ("gyro", "accel")):
            lines.append(f"{comment} White noise = sqrt(N^2 + 2 G^2 Tc): Allan N with the "
                         "white-like part of a short Gauss-Markov term (sigma G, correlation "
                         f"time Tc <= {GM_WHITE_MAX_TC_S:g} s),")
            lines.append(f"{comment} its spectrum's level below 1/(2 pi Tc): a filter with no "
                         "state for that term sees it as white noise.")
        return lines

    def note(self, sensor: str, term: str) -> str:
        """Say which axis a value comes from, whether it is an upper limit, and any GM part."""
        d = self.densities[sensor, term]
        text = d.axis + ("" if d.kind == "fitted" else
                         ", upper limit: the fit does not resolve it")
        if d.gm_white > 0 and d.gm_tc is not None:
            text += (f", with a Gauss-Markov term's white-like {d.gm_white:.3e} "
                     f"(Tc {d.gm_tc:.3g} s)")
        return text


class Parameter(NamedTuple):
    """One exported parameter: its name in the target, sensor, term, value and units.

    ``clamped_from`` is the value before it was clamped to the target's documented range
    (:data:`RANGES`), None when it was within it.
    """

    name: str
    sensor: str
    term: str
    value: float
    units: str
    clamped_from: float | None = None


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
    out = []
    for (s, t), name in names.items():
        value = e.value(s, t) / math.sqrt(dt)
        lo, hi = RANGES[name]
        written = min(max(value, lo), hi)
        out.append(Parameter(name, s, t, written, units[s, t],
                             None if written == value else value))
    return out


_PX4_NAMES = {("gyro", "N"): "EKF2_GYR_NOISE", ("accel", "N"): "EKF2_ACC_NOISE",
              ("gyro", "K"): "EKF2_GYR_B_NOISE", ("accel", "K"): "EKF2_ACC_B_NOISE"}
_ARDUPILOT_NAMES = {("gyro", "N"): "EK3_GYRO_P_NSE", ("accel", "N"): "EK3_ACC_P_NSE",
                    ("gyro", "K"): "EK3_GBIAS_P_NSE", ("accel", "K"): "EK3_ABIAS_P_NSE"}
#: Each parameter's documented range (module.yaml, params_*_bias.yaml; AP_NavEKF3.cpp): a ground
#: station refuses a value outside it, so the exports clamp to it and say so.
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


def _topic(rostopic: str) -> str:
    """Quote a ROS topic for YAML: OpenCV keeps an unquoted value's trailing comment."""
    if '"' in rostopic or "\\" in rostopic:
        raise ValueError(f"a ROS topic holds no quote or backslash, got {rostopic!r}")
    return f'"{rostopic}"'


def _lines(e: NoiseExport, parameters: list[Parameter], indent: str = "") -> list[str]:
    return [f"{indent}{p.name}: {_number(p.value)}  # {p.units}, {e.note(p.sensor, p.term)}"
            for p in parameters]


def kalibr_yaml(e: NoiseExport, rostopic: str = "/imu0") -> str:
    """Kalibr's ``imu.yaml``: per sensor ``N`` and ``K``, continuous time, in SI."""
    lines = [*e.header("#", "Kalibr"),
             "# Continuous-time densities (Kalibr discretises them with update_rate): noise "
             "density = Allan N,", "# random walk = Allan rate random walk K.", ""]
    params = _kalibr_parameters(e)
    for sensor, title in (("accel", "Accelerometers"), ("gyro", "Gyroscopes")):
        lines.append(f"# {title}")
        lines += _lines(e, [p for p in params if p.sensor == sensor])
        lines.append("")
    lines += [f"rostopic: {_topic(rostopic)}  # set to the IMU's topic",
              f"update_rate: {_real(e.rate)}  # Hz"]
    return "\n".join(lines) + "\n"


def openvins_yaml(e: NoiseExport, rostopic: str = "/imu0") -> str:
    """OpenVINS's ``kalibr_imu_chain.yaml``: Kalibr's densities, identity intrinsics.

    ov_msckf reads the file its ``estimator_config.yaml`` names (``relative_config_imu:
    "kalibr_imu_chain.yaml"``) and, under ``imu0``, the four densities, ``rostopic`` and the
    intrinsics (``model``, ``Tw``, ``R_IMUtoGYRO``, ``Ta``, ``R_IMUtoACC``, ``Tg``), here
    OpenVINS's "calibrated" defaults, as in its ``config/euroc_mav/kalibr_imu_chain.yaml``.
    """
    eye3 = ["    - [1.0, 0.0, 0.0]", "    - [0.0, 1.0, 0.0]", "    - [0.0, 0.0, 1.0]"]
    zero3 = ["    - [0.0, 0.0, 0.0]"] * 3
    lines = ["%YAML:1.0", *e.header("#", "OpenVINS (kalibr_imu_chain.yaml)"),
             "# Continuous-time densities: OpenVINS's Propagator.cpp discretises them as "
             "sigma_w^2/dt and sigma_wb^2*dt.",
             "# OpenVINS's calibration guide advises inflating Allan values \"maybe 10-20x\" "
             "for a moving platform",
             "# (the exports' inflation factor); keep this file's name: "
             "estimator_config.yaml's relative_config_imu names it.", "", "imu0:", "  T_i_b:",
             "    - [1.0, 0.0, 0.0, 0.0]", "    - [0.0, 1.0, 0.0, 0.0]",
             "    - [0.0, 0.0, 1.0, 0.0]", "    - [0.0, 0.0, 0.0, 1.0]"]
    lines += _lines(e, _kalibr_parameters(e), "  ")
    lines += [f"  rostopic: {_topic(rostopic)}  # set to the IMU's topic", "  time_offset: 0.0",
              f"  update_rate: {_real(e.rate)}", "  model: \"kalibr\"",
              "  Tw:", *eye3, "  R_IMUtoGYRO:", *eye3, "  Ta:", *eye3, "  R_IMUtoACC:", *eye3,
              "  Tg:", *zero3]
    return "\n".join(lines) + "\n"


def orbslam3_yaml(e: NoiseExport) -> str:
    """ORB-SLAM3's IMU settings (paste into the settings file beside the camera's).

    ``File.version: "1.0"`` selects ORB-SLAM3's ``Settings`` parser (System.cc), whose
    ``readParameter<float>`` refuses anything but a real number: ``IMU.Frequency`` is written
    ``100.0``.  (The older parser, used without ``File.version``, wants an integer frequency
    and ``Tbc``; the two cannot share one file.)  ``IMU.T_b_c1``, the camera-to-body transform,
    is the identity here: replace it with the camera's calibration.
    """
    eye4 = ", ".join("1.0" if i % 5 == 0 else "0.0" for i in range(16))
    lines = ["%YAML:1.0", *e.header("#", "ORB-SLAM3"),
             "# Continuous-time densities (rad/s/sqrt(Hz)...): Tracking.cc multiplies the noise "
             "by sqrt(IMU.Frequency)", "# and divides the walk by it, so these are Allan N and K.",
             "# Paste into the ORB-SLAM3 settings file (it starts with %YAML:1.0, as here); "
             "File.version \"1.0\"", "# selects the parser that reads IMU.Frequency as a real "
             "number.", "", 'File.version: "1.0"', "",
             *_lines(e, _orbslam3_parameters(e)),
             f"IMU.Frequency: {_real(e.rate)}  # Hz",
             "# The camera-to-body transform: the identity here, replace it with the camera's "
             "calibration.",
             "IMU.T_b_c1: !!opencv-matrix", "   rows: 4", "   cols: 4", "   dt: f",
             f"   data: [{eye4}]"]
    return "\n".join(lines) + "\n"


def vins_yaml(e: NoiseExport, rostopic: str = "/imu0") -> str:
    """VINS-Mono / VINS-Fusion's IMU settings: the four noise parameters, ``imu``, ``g_norm``."""
    lines = ["%YAML:1.0", *e.header("#", "VINS-Mono / VINS-Fusion"),
             f"# Per-sample standard deviations at the IMU rate ({e.rate:.6g} Hz), as "
             "integration_base.h propagates them:",
             "# acc_n, gyr_n = N sqrt(2 rate) (its mid-point step takes half of each of two "
             "samples' noise),",
             "# acc_w, gyr_w = K sqrt(rate) (the bias takes dt of its walk noise per step).",
             "# Paste into the VINS config (it starts with %YAML:1.0, as here).", "",
             "imu: 1  # VINS-Fusion: use the IMU",
             f"imu_topic: {_topic(rostopic)}  # set to the IMU's topic",
             *_lines(e, _vins_parameters(e)),
             f"g_norm: {_real(round(e.gravity, 6))}  # m/s^2, {e.gravity_from}"]
    return "\n".join(lines) + "\n"


def clamp_notes(e: NoiseExport) -> list[str]:
    """Say, one line each, which autopilot parameters were clamped to their documented range.

    A value above the range is written as its maximum: the filter then trusts that sensor more
    than the record says, which the note tells.
    """
    out = []
    for target, params in (("PX4", px4_parameters(e)), ("ArduPilot", ardupilot_parameters(e))):
        for p in params:
            if p.clamped_from is None:
                continue
            lo, hi = RANGES[p.name]
            side, what = (("above", "its maximum") if p.clamped_from > hi else
                          ("below", "its minimum"))
            out.append(f"{target} {p.name} {p.clamped_from:.6g} {p.units} is {side} its "
                       f"documented range {lo:g}-{hi:g}: written as {what} {p.value:g}"
                       + (", so the filter trusts this sensor more than the record says"
                          if p.clamped_from > hi else ""))
    return out


def _ekf_header(e: NoiseExport, target: str, dt: float, step: str) -> list[str]:
    return [*e.header("#", target),
            f"# Standard deviations per EKF prediction step dt = {dt:g} s ({step}): the EKF "
            "adds (dt*NOISE)^2 per step,",
            "# so NOISE = Allan N / sqrt(dt) and B_NOISE = Allan K / sqrt(dt); for another dt "
            f"multiply them by sqrt({dt:g}/dt).",
            "# A value beyond the parameter's documented range is clamped to it (a ground "
            "station refuses it), as said beside it."]


def _ekf_note(e: NoiseExport, p: Parameter) -> str:
    lo, hi = RANGES[p.name]
    clamped = "" if p.clamped_from is None else (
        f"; CLAMPED: {p.clamped_from:.6g} is outside the documented range {lo:g}-{hi:g}, "
        f"written as {p.value:g}")
    return f"# {p.name}: {p.units}, {e.note(p.sensor, p.term)}{clamped}"


#: QGroundControl's parameter-file fields: vehicle id 1, component id 1 (the autopilot,
#: MAV_COMP_ID_AUTOPILOT1), and the type MAV_PARAM_TYPE_REAL32 (9) of every EKF2 noise.
QGC_VEHICLE, QGC_COMPONENT, QGC_REAL32 = 1, 1, 9


def px4_params(e: NoiseExport, predict_s: float = PX4_PREDICT_S) -> str:
    """PX4 EKF2's parameters as QGroundControl's parameter file (Parameters > Load from file).

    QGroundControl's ``ParameterManager`` reads tab-separated lines of five fields (vehicle id,
    component id, name, value, MAVLink type) and skips ``#`` lines; a line of any other shape
    is skipped without a word, so nothing else is written in it.  The same values as console
    commands are in :func:`px4_console`.
    """
    lines = ["# Onboard parameters for Vehicle 1",
             *_ekf_header(e, "PX4 EKF2", predict_s, f"EKF2_PREDICT_US = {predict_s * 1e6:.0f}"),
             "# QGroundControl: Vehicle Setup > Parameters > Tools > Load from file; the console "
             "commands are in px4_ekf2_console.txt.", "#",
             "# Vehicle-Id\tComponent-Id\tName\tValue\tType"]
    for p in px4_parameters(e, predict_s):
        lines += [_ekf_note(e, p),
                  f"{QGC_VEHICLE}\t{QGC_COMPONENT}\t{p.name}\t{p.value:.6g}\t{QGC_REAL32}"]
    return "\n".join(lines) + "\n"


def px4_console(e: NoiseExport, predict_s: float = PX4_PREDICT_S) -> str:
    """PX4 EKF2's parameters as ``param set`` commands (the MAVLink shell, or a startup file)."""
    lines = _ekf_header(e, "PX4 EKF2 (param set commands)", predict_s,
                        f"EKF2_PREDICT_US = {predict_s * 1e6:.0f}")
    for p in px4_parameters(e, predict_s):
        lines += [_ekf_note(e, p), f"param set {p.name} {p.value:.6g}"]
    return "\n".join(lines) + "\n"


def ardupilot_params(e: NoiseExport, dt_s: float = ARDUPILOT_DT_S) -> str:
    """ArduPilot EKF3's parameters as a ``.parm`` file (``NAME VALUE`` lines, ``#`` comments)."""
    lines = _ekf_header(e, "ArduPilot EKF3", dt_s, "EKF_TARGET_DT")
    for p in ardupilot_parameters(e, dt_s):
        lines += [_ekf_note(e, p), f"{p.name} {p.value:.6g}"]
    return "\n".join(lines) + "\n"


@dataclass(frozen=True)
class ExportTarget:
    """One file a filter or VIO system reads: who reads it, its name, its writer, its values.

    ``key`` names the target's parameters in the JSON (two files of one consumer share it),
    ``short`` names the consumer in the command line's help, ``consumer`` and ``use`` in the
    report (``"PX4 EKF2"``, ``"for the console"``).
    """

    key: str
    short: str
    consumer: str
    file: str
    write: Callable[[NoiseExport], str]
    parameters: Callable[[NoiseExport], list[Parameter]]
    use: str = ""


#: Every export, in the order the report names them: adding a target is one entry here.
TARGETS: tuple[ExportTarget, ...] = (
    ExportTarget("kalibr", "Kalibr", "Kalibr", "imu.yaml", kalibr_yaml, _kalibr_parameters),
    ExportTarget("openvins", "OpenVINS", "OpenVINS", "kalibr_imu_chain.yaml", openvins_yaml,
                 _kalibr_parameters),
    ExportTarget("vins", "VINS", "VINS-Mono/Fusion", "vins_imu.yaml", vins_yaml,
                 _vins_parameters),
    ExportTarget("orbslam3", "ORB-SLAM3", "ORB-SLAM3", "orbslam3_imu.yaml", orbslam3_yaml,
                 _orbslam3_parameters),
    ExportTarget("px4_ekf2", "PX4", "PX4 EKF2", "px4_ekf2.params", px4_params, px4_parameters,
                 "for QGroundControl"),
    ExportTarget("px4_ekf2", "PX4", "PX4 EKF2", "px4_ekf2_console.txt", px4_console,
                 px4_parameters, "for the console"),
    ExportTarget("ardupilot_ek3", "ArduPilot", "ArduPilot EKF3", "ardupilot_ek3.parm",
                 ardupilot_params, ardupilot_parameters),
)
#: Each export's file name and how it is written.
FILES: dict[str, Callable[[NoiseExport], str]] = {t.file: t.write for t in TARGETS}


def consumers() -> str:
    """Return the consumers of the exports by their short names: ``"Kalibr, OpenVINS, ..."``."""
    return ", ".join(dict.fromkeys(t.short for t in TARGETS))


def export_listing(folder: str = "") -> str:
    """Return the exports as the report lists them: each consumer, its files in ``folder``."""
    by_consumer: dict[str, list[ExportTarget]] = {}
    for t in TARGETS:
        by_consumer.setdefault(t.consumer, []).append(t)
    return ", ".join(
        f"{consumer} ("
        + ", ".join(f"`{folder}{t.file}`" + (f" {t.use}" if t.use else "") for t in targets)
        + ")" for consumer, targets in by_consumer.items())


def export_files(e: NoiseExport) -> dict[str, str]:
    """Return every export's text by file name."""
    return {name: write(e) for name, write in FILES.items()}


def _json_parameter(p: Parameter) -> dict[str, Any]:
    out: dict[str, Any] = {"value": p.value, "units": p.units}
    if p.clamped_from is not None:
        out["clamped_from"] = p.clamped_from
    return out


def exports_dict(e: NoiseExport) -> dict[str, Any]:
    """Return every export's parameters as JSON-ready values (with their units), and the factor."""
    targets = {t.key: t.parameters(e) for t in TARGETS}
    return {"inflate": e.inflate, "rate_hz": e.rate,
            "px4_predict_s": PX4_PREDICT_S, "ardupilot_dt_s": ARDUPILOT_DT_S,
            "gravity_m_s2": e.gravity, "gravity_from": e.gravity_from,
            "gm_white_max_tc_s": GM_WHITE_MAX_TC_S,
            "measured": {f"{s}_{t}": {"value": d.value, "units": SI_UNITS[s, t], "axis": d.axis,
                                      "is": d.kind, "gauss_markov_white": d.gm_white,
                                      "gauss_markov_tc_s": d.gm_tc}
                         for (s, t), d in e.densities.items()},
            **{name: {p.name: _json_parameter(p) for p in params}
               for name, params in targets.items()}}

"""Thermal calibration: every axis's bias against temperature, judged out of sample.

From static records of one IMU with a temperature column (each record a *session*: a cold
start, a warm-up, a cool-down), every gyro and accelerometer axis gets a model of its slow
bias against temperature (:mod:`fosmodel.workflows.tempcal_model`: powers chosen by the
data up to the firmware's degree, a first-order thermal lag where the data call for one,
a level per session for its turn-on bias), the best polynomial PX4's and ArduPilot's
firmware can evaluate, and PX4's own procedure on the same records
(:mod:`fosmodel.workflows.tempcal_px4`).  Each is judged on data it was not fitted on
(:mod:`fosmodel.workflows.tempcal_heldout`): leaving one session out where there are
several, else the later part of the sweep.

Before any fit the temperature's range is checked: a record without a temperature column,
or whose temperature spans less than :data:`MIN_SPAN_C`, is refused, and so is a degree
the span cannot support (as much again for each power; PX4's on-board
calibration asks a rise of 24 C for its cubic, ArduPilot's 10 C).  Without a degree asked,
the firmware's cubic is offered as far as the span supports it, and a narrower one is said.

The records are first averaged over :attr:`TempcalConfig.resolution_s` (a second): a bias
that follows the temperature is slow, and the fits read means over blocks of
:attr:`TempcalConfig.block_s` anyway.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..core.exceptions import InputError
from ..core.validation import check_int, check_positive
from ..loop.record import LoopRecord
from ..noise.axes import Axis
from ..noise.metrics import to_si_scale
from .tempcal_heldout import HeldOut, Hysteresis, held_out, hysteresis
from .tempcal_model import ThermalModel, firmware_projection, fit_thermal
from .tempcal_px4 import Px4Fit, px4_fit

Progress = Callable[[str], None]
#: The highest power of temperature PX4's (``TC_*_X3_*``) and ArduPilot's (``INS_TCALn_*3``)
#: firmware evaluate.
FIRMWARE_DEGREE = 3
#: The least temperature span (degC) a calibration is fitted over: each power of the
#: polynomial needs as much.
MIN_SPAN_C = 5.0


@dataclass(frozen=True)
class TempcalConfig:
    """Settings of a thermal calibration.

    Parameters
    ----------
    degree : int, optional
        The highest power of temperature offered, at most :data:`FIRMWARE_DEGREE` (default:
        that, as far as the temperature's span supports it).
    min_span_c : float
        The least temperature span (degC) fitted over, and the span each power needs.
    block_s : float
        Blocks (s) of the slow part the fits and the held-out residual read.
    head_s : float
        A held-out session's constant (its turn-on bias) comes from its first ``head_s``
        seconds, which are then left out of what is judged: what a navigation filter
        learns at alignment.
    train : float
        With a single session, the fraction of it fitted on; the rest is judged.
    resolution_s : float
        The records are averaged over this many seconds first.
    alpha : float
        Level of the tests that keep a lag or a rate of change.
    confidence : float
        Of the coefficients' and the ratios' intervals.
    """

    degree: int | None = None
    min_span_c: float = MIN_SPAN_C
    block_s: float = 30.0
    head_s: float = 60.0
    train: float = 0.7
    resolution_s: float = 1.0
    alpha: float = 0.01
    confidence: float = 0.95

    def __post_init__(self) -> None:
        """Check every setting.

        Raises
        ------
        InputError
            A setting out of its range.
        """
        if self.degree is not None:
            check_int(self.degree, "degree", 1)
            if self.degree > FIRMWARE_DEGREE:
                raise InputError(f"degree={self.degree}: PX4's and ArduPilot's firmware evaluate "
                                 f"a polynomial of degree {FIRMWARE_DEGREE} at most")
        for name in ("min_span_c", "block_s", "head_s", "resolution_s"):
            check_positive(getattr(self, name), name)
        for name in ("train", "alpha", "confidence"):
            value = getattr(self, name)
            if not 0 < value < 1:
                raise InputError(f"{name} must lie between 0 and 1, got {value!r}")

    def degree_for(self, span: float, where: str) -> tuple[int, str | None]:
        """Return the degree fitted over a temperature ``span`` (degC), and a note if capped.

        Raises
        ------
        InputError
            A span below :attr:`min_span_c`, or a degree asked that it cannot support.
        """
        supported = min(FIRMWARE_DEGREE, int(span / self.min_span_c + 1e-9))
        if supported < 1:
            raise InputError(f"{where} spans only {span:.3g} C; a thermal calibration needs at "
                             f"least {self.min_span_c:g} C (min_span_c=...)")
        if self.degree is not None and self.degree > supported:
            raise InputError(f"{where} spans {span:.3g} C, too narrow for degree={self.degree} "
                             f"({self.min_span_c:g} C per power); it supports degree="
                             f"{supported}")
        if self.degree is None and supported < FIRMWARE_DEGREE:
            return supported, (f"{where} spans {span:.3g} C: powers up to {supported} offered "
                               f"({self.min_span_c:g} C per power), not the firmware's "
                               f"{FIRMWARE_DEGREE}")
        return self.degree or supported, None


@dataclass(frozen=True)
class TempSession:
    """One record of a sensor's axes: its columns, its temperature, its rate (Hz)."""

    name: str
    columns: Mapping[str, np.ndarray]
    temperature: np.ndarray
    rate: float


@dataclass(frozen=True)
class AxisGroup:
    """Axes that share a temperature and a time base, over every session.

    A CSV's gyros and accelerometers are one group; a PX4 ULog's ``sensor_gyro`` and
    ``sensor_accel`` two, each with its ``device_id``.
    """

    name: str
    axes: tuple[Axis, ...]
    temperature: str
    sessions: tuple[TempSession, ...]
    device_id: int | None = None


@dataclass
class AxisCal:
    """One axis's calibration: its models, PX4's, and how each does out of sample."""

    axis: Axis
    group: str
    tref: float
    tmin: float
    tmax: float
    model: ThermalModel
    firmware: ThermalModel
    px4: Px4Fit
    constants: dict[str, list[float]]
    held: HeldOut
    hysteresis: dict[str, Hysteresis | None]
    points: list[tuple[np.ndarray, np.ndarray]] = field(repr=False, default_factory=list)
    block: int = 1
    rate: float = 1.0

    @property
    def si_scale(self) -> float:
        """Factor from the axis's units to the firmware's (rad/s, m/s^2)."""
        return to_si_scale(self.axis.sensor, self.axis.units)

    def to_dict(self, confidence: float) -> dict[str, Any]:
        """Return the axis's calibration as JSON."""
        return {"column": self.axis.column, "sensor": self.axis.sensor, "units": self.axis.units,
                "group": self.group, "range_c": {"tmin": self.tmin, "tmax": self.tmax,
                                                 "tref": self.tref},
                "model": self.model.to_dict(confidence),
                "firmware_model": self.firmware.to_dict(confidence),
                "px4_procedure": {"coefficients": list(self.px4.coefficients),
                                  "tref": self.px4.tref, "tmin": self.px4.tmin,
                                  "tmax": self.px4.tmax},
                "session_constants": self.constants,
                "held_out": self.held.to_dict(),
                "hysteresis": {k: h.to_dict() if h else None for k, h in self.hysteresis.items()}}


@dataclass
class TempcalResult:
    """Every axis's calibration, the groups they came in, and what was noted on the way."""

    axes: list[AxisCal]
    groups: list[AxisGroup]
    config: TempcalConfig
    notes: list[str] = field(default_factory=list)

    def to_dict(self) -> dict[str, Any]:
        """Return the calibration as JSON: every axis's models and their validation."""
        cfg = self.config
        return {"sessions": [s.name for s in self.groups[0].sessions],
                "groups": [{"name": g.name, "temperature": g.temperature,
                            "device_id": g.device_id, "axes": [a.column for a in g.axes]}
                           for g in self.groups],
                "settings": {"degree": cfg.degree, "min_span_c": cfg.min_span_c,
                             "block_s": cfg.block_s, "head_s": cfg.head_s, "train": cfg.train,
                             "resolution_s": cfg.resolution_s, "alpha": cfg.alpha,
                             "confidence": cfg.confidence},
                "axes": [a.to_dict(cfg.confidence) for a in self.axes], "notes": self.notes}


def run_tempcal(groups: Sequence[AxisGroup], config: TempcalConfig | None = None,
              progress: Progress | None = None) -> TempcalResult:
    """Calibrate every axis of ``groups`` against its temperature (the module docstring).

    Raises
    ------
    InputError
        No axis, sessions of different rates within a group, a temperature span too narrow
        for a calibration or for the degree asked, or a session too short to judge.
    """
    config = config or TempcalConfig()
    say = progress or (lambda line: None)
    if not any(g.axes for g in groups):
        raise InputError("no gyro or accelerometer axis to calibrate")
    notes: list[str] = []
    plans = []
    for group in groups:  # every range is checked before any fit
        temps = np.concatenate([s.temperature for s in group.sessions])
        where = f"{_sources(group)}: {group.temperature}"
        degree, note = config.degree_for(float(temps.max() - temps.min()), where)
        notes += [note] if note else []
        plans.append((group, degree, _reduced(group, config)))
    out = []
    for group, degree, (rate, temps, columns, sessions) in plans:
        for axis in group.axes:
            say(f"{axis.column}: fitting its bias against {group.temperature}")
            rec = LoopRecord(columns[axis.column], {group.temperature: temps}, rate, sessions,
                             tuple(s.name for s in group.sessions))
            out.append(_calibrate_axis(rec, group, axis, degree, config))
            say(f"{axis.column}: {out[-1].model.describe()}")
    return TempcalResult(out, list(groups), config, notes)


def _sources(group: AxisGroup) -> str:
    names = [s.name for s in group.sessions]
    return names[0] if len(names) == 1 else f"{names[0]} and {len(names) - 1} more"


def _reduced(group: AxisGroup, config: TempcalConfig
             ) -> tuple[float, np.ndarray, dict[str, np.ndarray], tuple[slice, ...]]:
    """Return the group's sessions end to end as means over ``resolution_s``.

    Raises
    ------
    InputError
        Sessions whose rates differ by more than 1 %, or one shorter than a block beyond
        its head.
    """
    rates = [s.rate for s in group.sessions]
    if max(rates) > 1.01 * min(rates):
        raise InputError("the sessions' rates differ: " + ", ".join(
            f"{s.name} {s.rate:g} Hz" for s in group.sessions))
    per = max(1, round(min(rates) * config.resolution_s))
    rate = float(np.mean(rates)) / per
    need = (config.head_s + 2 * config.block_s) * rate
    temps, sessions, start = [], [], 0
    columns: dict[str, list[np.ndarray]] = {a.column: [] for a in group.axes}
    for s in group.sessions:
        n = len(s.temperature) // per
        if n < need:
            raise InputError(f"{s.name}: {n / rate:.4g} s is too short for a thermal "
                             f"calibration (head_s={config.head_s:g} and two blocks of "
                             f"block_s={config.block_s:g})")
        temps.append(_means(s.temperature, per, n))
        for a in group.axes:
            columns[a.column].append(_means(s.columns[a.column], per, n))
        sessions.append(slice(start, start + n))
        start += n
    return (rate, np.concatenate(temps), {k: np.concatenate(v) for k, v in columns.items()},
            tuple(sessions))


def _means(x: np.ndarray, per: int, n: int) -> np.ndarray:
    return np.asarray(x[: n * per], dtype=float).reshape(n, per).mean(axis=1)


def _calibrate_axis(rec: LoopRecord, group: AxisGroup, axis: Axis, degree: int,
                    config: TempcalConfig) -> AxisCal:
    """Fit one axis on every session, judge its fits out of sample, fit PX4's procedure."""
    temps = rec.channels[group.temperature]
    tmin, tmax = float(temps.min()), float(temps.max())
    tref = float(f"{0.5 * (tmin + tmax):.4g}")
    block = max(1, round(config.block_s * rec.rate))

    def fit(parts: Sequence[slice]) -> tuple[ThermalModel, ThermalModel]:
        model = fit_thermal(rec, parts, group.temperature, tref, degree, block, config.alpha)
        return model, firmware_projection(model, rec, parts)

    model, firmware = fit(rec.sessions)
    raw = [(s.temperature, s.columns[axis.column]) for s in group.sessions]
    accel = axis.sensor == "accel"
    held = held_out(rec, fit, raw, accel, block, config.head_s, config.train,
                    config.confidence)
    px4 = px4_fit([t for t, _ in raw], [v for _, v in raw], accel)
    residuals: dict[str, list[np.ndarray]] = {}
    constants: dict[str, list[float]] = {}
    for name, m in (("model", model), ("firmware", firmware)):
        rs = [rec.y[s] - m.bias(temps[s], rec.rate) for s in rec.sessions]
        constants[name] = [float(r.mean()) for r in rs]
        residuals[name] = [r - r.mean() for r in rs]
    points = []
    for s, c in zip(rec.sessions, constants["model"]):
        n = (s.stop - s.start) // block
        cut = slice(s.start, s.start + n * block)
        points.append((temps[cut].reshape(n, block).mean(axis=1),
                       (rec.y[cut] - c).reshape(n, block).mean(axis=1)))
    loops = {name: hysteresis(parts, [temps[s] for s in rec.sessions], block, rec.rate,
                              config.confidence) for name, parts in residuals.items()}
    return AxisCal(axis, group.name, tref, tmin, tmax, model, firmware, px4, constants, held,
                   loops, points, block, rec.rate)


def firmware_offset(cal: AxisCal) -> tuple[float, ...]:
    """Return the firmware polynomial's coefficients of powers 0..3 about ``tref``, in SI.

    The constant is the mean session's bias at ``tref`` for a gyro; 0 for an accelerometer,
    whose bias a static record cannot tell from gravity (PX4's accelerometer calibration,
    run after the thermal one, sets its offset).
    """
    powers = cal.firmware.powers
    constant = float(np.mean(cal.constants["firmware"])) if cal.axis.sensor == "gyro" else 0.0
    return tuple(cal.si_scale * (constant if k == 0 else powers.get(k, 0.0))
                 for k in range(FIRMWARE_DEGREE + 1))

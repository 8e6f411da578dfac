"""Records checked before they are trusted: at rest, in the units they claim, every column named.

An Allan deviation describes a sensor at rest: on a record that moves it reads the motion as
noise (a turn as rate random walk, a tilt as a bias step), and a factor of 57 or 9.8 in the
units moves every coefficient by as much.  Before the analysis:

- :func:`check_units` holds the accelerometers' mean against gravity in the units given: a
  triad at rest reads a specific force of 1 g (0.7-1.3 g for a low-cost sensor's scale and
  offset errors), or about 0 when gravity has been removed from the record; fewer axes read at
  most 1 g.  A mean that would be 1 g in other units names those units.  (A name's units
  against those given, ``gx_dps`` with ``rad/s``, are checked when the axes are resolved:
  :func:`fosmodel.noise.axes.resolve_axes`.)
- :func:`stillness` finds where the record is at rest, one window (1 s) at a time: a window
  moves when a gyro's median is off its neighbours' (the median of the minute around it, so
  that a slow bias drift is not motion) or the accelerometers' median vector is off the
  record's, by more than :data:`NOISE_SIGMAS` times the noise of a window's median (the
  sample noise from the record's own first differences) and more than a floor
  (:data:`GYRO_FLOOR`, :data:`ACCEL_FLOOR`: the drift of a static low-cost sensor stays below
  them).  Medians, not means: a lone spike is an outlier, not motion.  A window holds at
  least :data:`MIN_WINDOW` samples (10 s at 1 Hz); at such a low rate the minute around a
  window is at least :data:`MIN_NEIGHBOURS` windows, and the noise of a gyro window's median
  is also read off the medians themselves (neighbouring samples wander together).  A record
  shorter than two windows is left to the analyses' own length checks.
  :func:`static_part` refuses a record that moves, or with ``static_only`` keeps its longest
  static stretch.
- :func:`unused_columns` names every column of a record that is not analysed, and why.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy.ndimage import median_filter

from ..core.exceptions import InputError
from ..io.record import Record
from .allan import MIN_SAMPLES
from .axes import Axis, infer_axis
from .metrics import STANDARD_GRAVITY, to_si_scale

#: A static accelerometer triad's mean magnitude: within this of 1 g (scale and offset errors of
#: a low-cost sensor), or below :data:`GRAVITY_REMOVED` (a record with gravity taken out).
GRAVITY_TOLERANCE = 0.3
GRAVITY_REMOVED = 0.05
#: Accelerometer units tried when the mean does not fit gravity.
_ACCEL_UNITS = ("m/s^2", "g", "mg")
#: Length of a window of the stillness test (s), and fewest samples in one.
WINDOW_S = 1.0
MIN_WINDOW = 10
#: Fewest windows in a static stretch worth analysing (besides the Allan deviation's
#: :data:`~fosmodel.noise.allan.MIN_SAMPLES`).
MIN_STRETCH_WINDOWS = 10
#: A gyro window is held against the median of the windows in the minute around it, and of
#: no fewer than :data:`MIN_NEIGHBOURS` windows (at a low rate a window is longer than 1 s).
NEIGHBOURS_S = 60.0
MIN_NEIGHBOURS = 7
#: At a rate where a window holds more than 1 s (under :data:`MIN_WINDOW` Hz), and from this
#: many windows, the noise of a gyro window's median is also read off the medians themselves:
#: there neighbouring samples are correlated (a wander of the bias spans several), and the
#: sample noise alone would make a static record's medians look like motion.
MIN_SPREAD_WINDOWS = 20
#: A window moves beyond this many standard deviations of its median's noise...
NOISE_SIGMAS = 8.0
#: ...and beyond these floors: 0.5 deg/s of rotation, 0.03 g of specific force (a tilt of 1.7
#: degrees), both above the drift of the static ADIS16405 and MPU-6050 records in ../shared.
GYRO_FLOOR = math.radians(0.5)
ACCEL_FLOOR = 0.03 * STANDARD_GRAVITY
#: Standard deviation of the median of n normal samples, over that of one sample / sqrt(n).
_MEDIAN_EFFICIENCY = math.sqrt(math.pi / 2.0)


def check_units(columns: Mapping[str, np.ndarray], axes: Sequence[Axis], source: str) -> None:
    """Refuse accelerometer units that gravity contradicts.

    Parameters
    ----------
    columns : mapping of str to ndarray
        The signals by column name.
    axes : sequence of Axis
        The columns with their sensors and units.
    source : str
        The record's file, for the message.

    Raises
    ------
    InputError
        Three accelerometer axes whose mean magnitude is neither within
        :data:`GRAVITY_TOLERANCE` of 1 g nor below :data:`GRAVITY_REMOVED`, or fewer whose
        mean exceeds 1 g by more than the tolerance; the message names the columns, the
        units given, and the units that would make it 1 g.
    """
    accels = [a for a in axes if a.sensor == "accel"]
    if not accels:
        return
    mean = np.array([np.mean(columns[a.column]) * to_si_scale("accel", a.units)
                     for a in accels])
    g = float(np.linalg.norm(mean)) / STANDARD_GRAVITY
    triad = len(accels) == 3
    plausible = (abs(g - 1.0) <= GRAVITY_TOLERANCE or g < GRAVITY_REMOVED) if triad \
        else g <= 1.0 + GRAVITY_TOLERANCE
    if plausible:
        return
    names = ", ".join(a.column for a in accels)
    units = {a.units for a in accels}
    told = f"{next(iter(units))}" if len(units) == 1 else "the units given"
    what = (f"the mean specific force of {names} is {g:.3g} g in {told}, where an "
            "accelerometer triad at rest reads 1 g (or about 0 with gravity removed)" if triad
            else f"the mean of {names} is {g:.3g} g in {told}, more than the 1 g an "
                 "accelerometer at rest can read")
    raise InputError(f"{source}: {what}{_other_units(g, units)}; check the units of "
                     f"{'the column' if len(accels) == 1 else 'these columns'}")


def _other_units(g: float, units: set[str]) -> str:
    """Say which accelerometer units would put a mean of ``g`` (in ``units``) nearest 1 g."""
    if len(units) != 1:
        return ""
    given = to_si_scale("accel", next(iter(units)))
    fits = {u: g * to_si_scale("accel", u) / given for u in _ACCEL_UNITS if u not in units}
    near = {u: v for u, v in fits.items() if abs(v - 1.0) <= GRAVITY_TOLERANCE}
    if not near:
        return ""
    best = min(near, key=lambda u: abs(near[u] - 1.0))
    return f"; in {best} it would be {near[best]:.3g} g"


@dataclass(frozen=True)
class Stillness:
    """Where a record is at rest, window by window.

    Attributes
    ----------
    still : ndarray of bool
        One value per window: at rest.
    window : int
        Samples per window (the last window takes the samples left over).
    n_samples : int
        Samples in the record.
    rate : float
        Sample rate in Hz.
    rotation : float
        Largest departure of a gyro's window median from its neighbours' (rad/s; NaN without
        gyros).
    force : float
        Largest departure of the accelerometers' median vector from the record's (m/s^2; NaN
        without accelerometers).
    """

    still: np.ndarray
    window: int
    n_samples: int
    rate: float
    rotation: float
    force: float

    def stretches(self) -> list[tuple[int, int]]:
        """Return the static stretches as (first sample, end sample), in order."""
        edges = np.flatnonzero(np.diff(np.concatenate([[0], self.still.astype(int), [0]])))
        return [(self._sample(a), self._sample(b)) for a, b in zip(edges[::2], edges[1::2])]

    def _sample(self, window: int) -> int:
        return self.n_samples if window >= len(self.still) else window * self.window

    def longest(self) -> tuple[int, int] | None:
        """Return the longest static stretch (first sample, end sample), or None."""
        stretches = self.stretches()
        return max(stretches, key=lambda s: s[1] - s[0]) if stretches else None

    @property
    def moving_s(self) -> float:
        """Return the time the record moves, in seconds."""
        moving = self.n_samples - sum(b - a for a, b in self.stretches())
        return moving / self.rate

    def describe_motion(self) -> str:
        """Say for how long and by how much the record moves (for the messages)."""
        parts = []
        if math.isfinite(self.rotation):
            parts.append(f"its rate departs from rest by up to {math.degrees(self.rotation):.3g} "
                         "deg/s")
        if math.isfinite(self.force):
            parts.append(f"its specific force by up to {self.force / STANDARD_GRAVITY:.3g} g")
        first = int(np.argmin(self.still)) * self.window / self.rate
        return (f"it moves for {self.moving_s:.3g} s of its {self.n_samples / self.rate:.4g} s "
                f"(first at {first:.3g} s), where {' and '.join(parts)} "
                f"({self.window / self.rate:.3g} s medians)")


def stillness(columns: Mapping[str, np.ndarray], axes: Sequence[Axis], rate: float) -> Stillness:
    """Find where a record is at rest, one window of :data:`WINDOW_S` at a time.

    Parameters
    ----------
    columns : mapping of str to ndarray
        The signals by column name, of equal length.
    axes : sequence of Axis
        The columns with their sensors and units (gyros and accelerometers are tested).
    rate : float
        Sample rate in Hz.

    Returns
    -------
    Stillness
    """
    n = len(columns[axes[0].column])
    window = max(int(round(WINDOW_S * rate)), MIN_WINDOW)
    found = {"gyro": math.nan, "accel": math.nan}
    if n < 2 * window:  # no window to hold against another: the length checks speak
        return Stillness(np.ones(1, dtype=bool), max(n, 1), n, float(rate), math.nan,
                         math.nan)
    count = n // window
    neighbours = max(2 * int(round(NEIGHBOURS_S / (window / rate) / 2)) + 1, MIN_NEIGHBOURS)
    still = np.ones(count, dtype=bool)
    for sensor in ("gyro", "accel"):
        mine = [a for a in axes if a.sensor == sensor]
        if not mine:
            continue
        x = np.column_stack([columns[a.column] * to_si_scale(sensor, a.units) for a in mine])
        medians, noise = _window_medians(x, window, count)
        if sensor == "gyro" and window > WINDOW_S * rate and count >= MIN_SPREAD_WINDOWS:
            noise = np.maximum(noise, _median_spread(medians))  # a low rate's correlated samples
        if sensor == "gyro":  # against the minute around it: a drifting bias is not a turn
            off = np.abs(medians - median_filter(medians, size=(neighbours, 1),
                                                          mode="nearest"))
            limit = np.maximum(NOISE_SIGMAS * noise, GYRO_FLOOR)
            moving = np.any(off > limit, axis=1)
            found[sensor] = float(off.max())
        else:  # against the record's: a tilt, once made, stays
            off_norm = np.linalg.norm(medians - np.median(medians, axis=0), axis=1)
            limit_norm = max(NOISE_SIGMAS * float(np.linalg.norm(noise)), ACCEL_FLOOR)
            moving = off_norm > limit_norm
            found[sensor] = float(off_norm.max())
        still &= ~moving
    return Stillness(still, window, n, float(rate), found["gyro"], found["accel"])


def _window_medians(x: np.ndarray, window: int, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Each window's median per column (the last window takes the rest), and their noise.

    The noise of one window's median: the sample noise (1.4826 MAD of the first differences,
    over sqrt(2), which a slow drift does not inflate) times ``sqrt(pi/2) / sqrt(window)``.
    """
    medians = np.median(x[: count * window].reshape(count, window, -1), axis=1)
    if len(x) > count * window and count > 1:
        medians[-1] = np.median(x[(count - 1) * window:], axis=0)
    d = np.diff(x, axis=0)
    sample = 1.4826 * np.median(np.abs(d - np.median(d, axis=0)), axis=0) / math.sqrt(2.0)
    return medians, _MEDIAN_EFFICIENCY * sample / math.sqrt(window)


def _median_spread(medians: np.ndarray) -> np.ndarray:
    """Return the noise of a window's median read off the medians (1.4826 MAD of their steps)."""
    dm = np.diff(medians, axis=0)
    return 1.4826 * np.median(np.abs(dm - np.median(dm, axis=0)), axis=0) / math.sqrt(2.0)


def static_part(columns: Mapping[str, np.ndarray], axes: Sequence[Axis], rate: float,
                source: str, static_only: bool = False) -> tuple[slice, str] | None:
    """Refuse a record that moves, or with ``static_only`` find its longest static stretch.

    Parameters
    ----------
    columns : mapping of str to ndarray
        The signals by column name, of equal length.
    axes : sequence of Axis
        The columns with their sensors and units.
    rate : float
        Sample rate in Hz.
    source : str
        The record's file, for the messages.
    static_only : bool
        Keep the longest static stretch of a record that moves, instead of refusing it.

    Returns
    -------
    (slice, str) or None
        None when the record is at rest throughout; else the samples of its longest static
        stretch and a sentence saying which.

    Raises
    ------
    InputError
        The record moves (and not ``static_only``: the message says where it is at rest), or
        its longest static stretch has fewer than :data:`fosmodel.noise.allan.MIN_SAMPLES`
        samples or :data:`MIN_STRETCH_WINDOWS` windows.
    """
    found = stillness(columns, axes, rate)
    if found.still.all():
        return None
    longest = found.longest()
    span = "it is never at rest for a whole second" if longest is None else (
        f"its longest static stretch is {longest[0] / rate:.4g}-{longest[1] / rate:.4g} s "
        f"({longest[1] - longest[0]} samples)")
    fewest = max(MIN_SAMPLES, MIN_STRETCH_WINDOWS * found.window)
    if longest is None or longest[1] - longest[0] < fewest:
        raise InputError(f"{source}: the record is not static: {found.describe_motion()}; "
                         f"{span}, too short for an Allan analysis (at least {fewest} samples, "
                         f"{fewest / rate:.3g} s)")
    if not static_only:
        raise InputError(f"{source}: the record is not static: {found.describe_motion()}; an "
                         f"Allan analysis needs the sensor at rest: pass static_only=True to "
                         f"analyse its longest static stretch ({longest[0] / rate:.4g}-"
                         f"{longest[1] / rate:.4g} s)")
    first, end = longest
    return slice(int(first), int(end)), (f"{source}: analysing its longest static stretch, "
                                         f"{first / rate:.4g}-{end / rate:.4g} s from its start "
                                         f"({end - first} of {found.n_samples} samples): "
                                         f"{found.describe_motion()}")


def check_record(rec: Record, axes: Sequence[Axis],
                 static_only: bool = False) -> tuple[Record, str | None]:
    """Check a record's units and stillness before an analysis; keep its static stretch.

    :func:`check_units`, then :func:`static_part` on the axes' columns.

    Parameters
    ----------
    rec : Record
        The record as loaded.
    axes : sequence of Axis
        Its columns to analyse, with their sensors and units.
    static_only : bool
        Keep the longest static stretch of a record that moves, instead of refusing it.

    Returns
    -------
    (Record, str or None)
        The record, or its longest static stretch (the other columns and the time cut alike)
        with a sentence saying which.

    Raises
    ------
    InputError
        From :func:`check_units` and :func:`static_part`.
    """
    if not axes:
        return rec, None
    columns = {a.column: rec.column(a.column) for a in axes}
    check_units(columns, axes, rec.source)
    found = static_part(columns, axes, rec.require_rate(), rec.source, static_only)
    if found is None:
        return rec, None
    part, note = found
    return Record(rec.source, {k: v[part] for k, v in rec.data.items()}, rec.rate,
                  None if rec.time is None else rec.time[part], list(rec.notes),
                  dict(rec.metadata), units=dict(rec.units)), note


def unused_columns(names: Sequence[str], used: Sequence[str],
                   named: bool) -> list[tuple[str, str]]:
    """Name every column that is not analysed, and why.

    Parameters
    ----------
    names : sequence of str
        The record's columns (its time column is not among them: it gives the time).
    used : sequence of str
        The columns analysed or used beside them (a temperature).
    named : bool
        The axes were named (``--columns``): the others are skipped for that.

    Returns
    -------
    list of (str, str)
        Each skipped column and why, in the record's order.
    """
    out = []
    for column in names:
        if column in used:
            continue
        if named:
            out.append((column, "not among columns="))
            continue
        out.append((column, "its name tells neither a gyro nor an accelerometer"
                    + _swapped(column) + f"; give its units (units={{'{column}': UNITS}}) or name "
                    "it in columns= to use it"))
    return out


def _swapped(column: str) -> str:
    """Suggest the name with its first two letters swapped when that name tells an axis."""
    turned = column[1::-1] + column[2:]
    return f" (is it {turned}?)" if len(column) > 2 and infer_axis(turned)[0] else ""

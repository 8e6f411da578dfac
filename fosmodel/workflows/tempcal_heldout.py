"""A thermal calibration judged on data it was not fitted on, and its warming against cooling.

:func:`held_out` refits everything a calibration chooses (its forms, degree, lag, level) on
part of the data and judges the residual bias where nothing was fitted:

* with several sessions, each is held out in turn: fitted on the others, judged on it.  Its
  own constant (the turn-on bias) comes from its first ``head_s`` seconds, which are then
  left out of what is judged: what a navigation filter learns at alignment;
* with one session, the first ``train`` of it is fitted on, its constant from there, and the
  later part of the sweep is judged (where the temperature went on, the fit is clipped at
  the edge of its range, as the firmware clips it).

The residual bias is the residual's means over blocks of ``block_s``: the before (no
compensation), the chosen model's, the firmware polynomial's and PX4's procedure's (fitted
on the same data, :mod:`fosmodel.workflows.tempcal_px4`), every held-out part pooled.  Their
ratios of RMS have intervals from the blocks' long-run variance
(:func:`fosmodel.loop.intervals.ratio`).

:func:`hysteresis` sets the residual while warming against the residual while cooling, at
the temperatures both cover, session by session: a bias that follows the die late reads
apart on the way up and on the way down, and a polynomial in the temperature cannot follow
both.  The sessions' spread gives its interval: within one session, warming and cooling are
hours apart, and the wander of the bias between them would read as hysteresis.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy import stats

from ..loop.intervals import Ratio, ratio
from ..loop.record import LoopRecord
from .tempcal_model import ThermalModel
from .tempcal_px4 import px4_fit

Fitter = Callable[[Sequence[slice]], tuple[ThermalModel, ThermalModel]]
#: The residuals judged: none (before), the chosen model, the firmware's form, PX4's procedure.
NAMES = ("before", "model", "firmware", "px4")
#: The ratios reported: ``(after, before)`` of the names above.
RATIOS = (("model", "before"), ("firmware", "before"), ("px4", "before"), ("model", "px4"),
          ("firmware", "px4"), ("firmware", "model"))
#: Warming or cooling: the temperature moving faster than this (degC per minute).
MOVING_C_PER_MIN = 0.05
#: Fewest blocks of each way a session's hysteresis is measured on.
MIN_BLOCKS = 10


@dataclass
class HeldOut:
    """The residual bias where nothing was fitted: its blocks, their RMS and ratios.

    ``blocks`` holds, for each of :data:`NAMES`, the residual's block means over every
    held-out part pooled; ``times`` each block's centre (s from its session's start) and
    ``session`` its session; ``outside`` whether its temperature lies beyond the range its
    fits were fitted over (where they are clipped); ``folds`` what each fit chose.
    """

    how: str
    blocks: dict[str, np.ndarray]
    times: np.ndarray
    session: np.ndarray
    outside: np.ndarray
    ratios: dict[str, Ratio]
    folds: list[dict[str, Any]] = field(default_factory=list)

    @property
    def rms(self) -> dict[str, float]:
        """Each residual's RMS over the held-out blocks."""
        return {k: float(np.sqrt(np.mean(v**2))) if len(v) else float("nan")
                for k, v in self.blocks.items()}

    def to_dict(self) -> dict[str, Any]:
        """Return the held-out judgement as JSON."""
        return {"how": self.how, "blocks": len(self.times),
                "blocks_outside_the_fitted_range": int(self.outside.sum()), "rms": self.rms,
                "ratios": {k: r.to_dict() for k, r in self.ratios.items()}, "folds": self.folds}


def held_out(rec: LoopRecord, fit: Fitter, raw: Sequence[tuple[np.ndarray, np.ndarray]],
             accel: bool, block: int, head_s: float, train: float,
             confidence: float) -> HeldOut:
    """Judge an axis's fits out of sample (the module docstring).

    ``rec`` is the axis over its sessions (averaged), ``fit(parts)`` returns the chosen and
    the firmware-form models fitted on ``parts``, ``raw`` each session's temperature and
    readings as recorded (for PX4's procedure, which filters samples).  ``head_s``, ``train``
    and ``confidence`` are those of :class:`fosmodel.workflows.tempcal.TempcalConfig`.
    """
    temp = next(iter(rec.channels.values()))
    folds = []  # (fitted parts, judged session, first sample judged, constant's window)
    if len(rec.sessions) > 1:
        head = max(1, round(head_s * rec.rate))
        how = "leave one session out"
        for k in range(len(rec.sessions)):
            others = tuple(p for j, p in enumerate(rec.sessions) if j != k)
            folds.append((others, k, head, slice(0, head)))
    else:
        s = rec.sessions[0]
        cut = round(train * (s.stop - s.start))
        how = f"the later part of the sweep (fitted on its first {train:.0%})"
        folds.append(((slice(s.start, s.start + cut),), 0, cut, slice(0, cut)))
    pooled: dict[str, list[np.ndarray]] = {n: [] for n in NAMES}
    times, session, outside, chosen = [], [], [], []
    for parts, k, first, window in folds:
        model, firmware = fit(parts)
        px4 = px4_fit(*_raw_parts(rec, parts, raw), accel)
        s = rec.sessions[k]
        t, y = temp[s], rec.y[s]
        offsets = {"before": np.zeros(len(y)), "model": model.bias(t, rec.rate),
                   "firmware": firmware.bias(t, rec.rate), "px4": px4.offset(t)}
        n = (len(y) - first) // block
        for name, offset in offsets.items():
            r = y - offset
            r = r[first : first + n * block] - r[window].mean()
            pooled[name].append(r.reshape(n, block).mean(axis=1))
        times.append((first + (np.arange(n) + 0.5) * block) / rec.rate)
        session.append(np.full(n, k))
        fitted = np.concatenate([temp[p] for p in parts])
        means = t[first : first + n * block].reshape(n, block).mean(axis=1)
        outside.append((means < fitted.min()) | (means > fitted.max()))
        chosen.append({"held_out": rec.names[k] if rec.names else str(k),
                       "model": model.describe(), "firmware": firmware.describe(),
                       "blocks": n})
    blocks = {name: np.concatenate(v) for name, v in pooled.items()}
    ratios = {f"{a}/{b}": ratio(f"{a} / {b} RMS", f"{a}_{b}", blocks[b], blocks[a],
                                confidence, power=0.5) for a, b in RATIOS}
    return HeldOut(how, blocks, np.concatenate(times), np.concatenate(session),
                   np.concatenate(outside), ratios, chosen)


def _raw_parts(rec: LoopRecord, parts: Sequence[slice],
               raw: Sequence[tuple[np.ndarray, np.ndarray]]
               ) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Return the recorded samples (temperature, readings) the averaged ``parts`` cover."""
    temps, values = [], []
    for part in parts:
        k = next(j for j, s in enumerate(rec.sessions) if s.start <= part.start < s.stop)
        s, (t, v) = rec.sessions[k], raw[k]
        scale = len(t) / (s.stop - s.start)
        cut = slice(round((part.start - s.start) * scale), round((part.stop - s.start) * scale))
        temps.append(t[cut])
        values.append(v[cut])
    return temps, values


@dataclass(frozen=True)
class Hysteresis:
    """The residual while warming less the residual while cooling, at the same temperatures.

    ``difference`` is the mean over the ``sessions`` (each session's at the temperatures it
    covers both ways, ``each``), with its interval (``low``, ``high``) from their spread: NaN
    with fewer than :data:`MIN_SESSIONS`.
    """

    difference: float
    low: float
    high: float
    each: tuple[float, ...]

    @property
    def sessions(self) -> int:
        """How many sessions warm and cool over a common range."""
        return len(self.each)

    @property
    def found(self) -> bool:
        """Whether the interval leaves out 0: warming and cooling read apart."""
        return bool(self.low > 0 or self.high < 0)

    def to_dict(self) -> dict[str, Any]:
        """Return it as JSON."""
        return {"warming_minus_cooling": self.difference, "interval": [self.low, self.high],
                "found": self.found, "each_session": list(self.each)}


#: Fewest sessions an interval of the hysteresis is drawn from: within one session, warming
#: and cooling are hours apart, and the bias's wander between them reads as hysteresis.
MIN_SESSIONS = 3


def hysteresis(residuals: Sequence[np.ndarray], temps: Sequence[np.ndarray], block: int,
               rate: float, confidence: float) -> Hysteresis | None:
    """Compare the residual while warming with the residual while cooling (module docstring).

    ``residuals`` and ``temps`` are per session; a block warms or cools when its temperature
    moves faster than :data:`MOVING_C_PER_MIN`.  Each session that holds at least
    :data:`MIN_BLOCKS` blocks of each way at temperatures the other covers gives its
    difference of means; their mean has a Student interval from their spread.  None where no
    session does.
    """
    each = []
    for r, t in zip(residuals, temps):
        n = len(r) // block
        if n < 3:
            continue
        tb = t[: n * block].reshape(n, block).mean(axis=1)
        rb = r[: n * block].reshape(n, block).mean(axis=1)
        slope = np.gradient(tb) * rate / block * 60.0
        warming, cooling = slope > MOVING_C_PER_MIN, slope < -MOVING_C_PER_MIN
        if not warming.any() or not cooling.any():
            continue
        low = max(tb[warming].min(), tb[cooling].min())
        high = min(tb[warming].max(), tb[cooling].max())
        inside = (tb >= low) & (tb <= high)
        if (warming & inside).sum() >= MIN_BLOCKS and (cooling & inside).sum() >= MIN_BLOCKS:
            each.append(float(rb[warming & inside].mean() - rb[cooling & inside].mean()))
    if not each:
        return None
    mean, k = float(np.mean(each)), len(each)
    if k < MIN_SESSIONS:
        return Hysteresis(mean, float("nan"), float("nan"), tuple(each))
    half = float(stats.t.ppf((1 + confidence) / 2, k - 1) * np.std(each, ddof=1) / np.sqrt(k))
    return Hysteresis(mean, mean - half, mean + half, tuple(each))

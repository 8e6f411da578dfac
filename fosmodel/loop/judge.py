"""How the residual loop judges a candidate: out of sample, at several outage lengths.

A candidate model ``b`` (the current model ``a`` with one effect added) is
judged on the evaluation segment, which neither was fitted on; the
prediction segment is never looked at.  The errors compared are the one-step
errors over the segment, and for each outage length (horizon) the free-run
errors over consecutive windows of it: their mean over each window, the bias a
navigation filter integrates (per sample they are mostly white noise).

*Forecast encompassing* (:func:`compare`): does the change ``b`` makes to
``a``'s forecasts explain ``a``'s errors?  And does ``b`` make them worse (the
Diebold-Mariano test of the loss differences)?  ``beta = sum(e_a d) / sum(d^2)``
with ``d`` the change, its t statistic from the spread over groups (ten
batches of one-step errors; the outage windows).  With no effect ``beta`` is
centred on 0.  Each error kind at each horizon is one typed
:class:`Comparison`.

*Rolling origins* (forward chaining): a deterministic function of time fitted
on one stretch helps next to it and runs on beyond.  So both models are also
refitted (their weights, :meth:`fosmodel.models.model.FOSModel.refit_weights`) on
shorter pasts ending at earlier origins, and judged on the same evaluation
segment, now further from their fitting data.

An origin that cannot have seen an effect does not judge it: an effect with an onset
(a step's time, :meth:`fosmodel.loop.effects.Effect.onset_s`) is judged only from the
origins with :data:`ONSET_REFIT_SLOWS` times ``slow_s`` of data after it, where its
weight can be refitted (from an origin before a step any model of the step looks wrong).

The verdict (:func:`verdict`): an effect is kept if it gains beyond noise on
some error kind at some horizon, loses beyond noise on none, and loses no more than
:data:`MAX_POINT_LOSS` of any horizon's outage bias however few the windows: a quarter
more bias at 300 s is no noise to a navigation filter, whatever its p-value.

References
----------
D. I. Harvey, S. J. Leybourne and P. Newbold, "Tests for forecast
encompassing", *Journal of Business & Economic Statistics* 16(2), 1998.
F. X. Diebold and R. S. Mariano, "Comparing predictive accuracy", *Journal of
Business & Economic Statistics* 13(3), 1995.
R. J. Hyndman and G. Athanasopoulos, *Forecasting: Principles and Practice*,
3rd ed., 2021, section 5.10 (time series cross-validation).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np
from scipy import stats

from ..models.bound import BoundModel
from ..noise.metrics import OneStepModel, free_run_errors

#: Fewest outage windows the evaluation segment must hold for a horizon to be judged there:
#: the encompassing t test then has 7 degrees of freedom, and a day-long record's 20 % still
#: judges its 30 min outages.
MIN_WINDOWS = 8
#: Fewest windows a before/after ratio's interval needs (:mod:`fosmodel.loop.intervals`).
MIN_INTERVAL_WINDOWS = 10
MIN_HALF_WINDOWS = 20  # outage windows in each half of the evaluation segment to judge it
GAIN_TOL = 1e-9  # an earlier origin's gain above -GAIN_TOL counts as no loss (rounding)
#: Smallest share of the errors' sum of squares an effect must remove to be kept: with
#: hundreds of thousands of samples a 0.03 % gain is "significant", and not worth a term
#: that may cost more where it extrapolates.
MIN_GAIN = 1e-3
#: The same for the outage biases: a 1 % lower sum of squares is a 0.5 % lower bias RMS,
#: finer than a report's intervals resolve and than a filter's bias model would notice (an
#: accelerometer's fast part gained 0.2-0.5 % on a static gyro's 30 min outages).
MIN_OUTAGE_GAIN = 1e-2
#: Largest share of an outage bias's sum of squares an effect may add at any horizon and still
#: be kept on its gains elsewhere (its point estimate, however few the windows).
MAX_POINT_LOSS = 0.1
#: Data an origin needs after an effect's onset to judge it, in units of ``slow_s``: the
#: effect's weight is then a mean over that much at least, where the fast noise has averaged
#: out.
ONSET_REFIT_SLOWS = 1.0
ONE_STEP, OUTAGE = "one_step", "outage"
BATCHES = 10  # groups of one-step errors of the encompassing test


def windows(segment: slice, horizon: int, most: int) -> np.ndarray:
    """Return the starts of consecutive windows of ``horizon`` samples in ``segment``.

    At most ``most`` of them, evenly spread when the segment holds more.
    """
    starts = np.arange(segment.start, segment.stop - horizon + 1, horizon)
    if len(starts) > most:
        starts = starts[np.linspace(0, len(starts) - 1, most).round().astype(int)]
    return starts


@dataclass(frozen=True)
class Forecasts:
    """A model's errors on a segment: one-step, and each window's mean free-run error.

    ``biases`` maps each horizon (s) to the mean error over each of its windows.
    """

    one_step: np.ndarray
    biases: dict[float, np.ndarray]


def forecasts(model: OneStepModel, y: np.ndarray, segment: slice,
              plan: dict[float, tuple[np.ndarray, int]]) -> Forecasts:
    """Return the errors of ``model`` on ``segment`` of the record ``y``.

    ``plan`` maps each horizon (s) to its window starts and length in samples.
    """
    stop = segment.stop
    one_step = y[segment] - _prediction(model, y[:stop], segment.start)[segment]
    # the prediction, as long as the record, is gone before the free runs begin
    return Forecasts(one_step, {h: free_run_errors(model, y[:stop], starts, n).mean(axis=1)
                                for h, (starts, n) in plan.items()})


def _prediction(model: OneStepModel, y: np.ndarray, start: int) -> np.ndarray:
    """``model``'s one-step prediction of ``y`` (from ``start`` on where it can)."""
    pred = model.predict(y, start=start) if isinstance(model, BoundModel) else model.predict(y)
    return np.asarray(pred, dtype=float)


@dataclass(frozen=True)
class Comparison:
    """A trial against the current model on one error kind at one horizon.

    ``kind`` is ``"one_step"`` or ``"outage"`` (the window means at ``horizon_s``);
    ``groups`` the batches or windows compared; ``gain`` the share of the errors' sum of
    squares the trial removes, ``halves`` the same over each half of the segment (None
    where too few windows judge them); ``beta``, ``t``, ``p`` the encompassing test and
    ``p_worse`` the p-value of the trial making the errors worse.
    """

    kind: str
    horizon_s: float | None
    groups: int
    gain: float
    halves: tuple[float, float] | None
    beta: float
    t: float
    p: float
    p_worse: float

    @property
    def key(self) -> str:
        """``one_step`` or ``outage_30s``: the comparison's name in JSON."""
        return ONE_STEP if self.kind == ONE_STEP else f"{OUTAGE}_{self.horizon_s:g}s"

    @property
    def label(self) -> str:
        """``one-step`` or ``30 s outage bias``: the comparison in words."""
        return "one-step" if self.kind == ONE_STEP else f"{self.horizon_s:g} s outage bias"

    def passes(self, alpha: float, halves: bool = True) -> bool:
        """Whether the trial gains here beyond noise.

        Significant at ``alpha / 2``, at least :data:`MIN_GAIN` over the segment
        (:data:`MIN_OUTAGE_GAIN` for the outage biases) and, with ``halves`` and where judged,
        over each half.
        """
        judged = (self.halves or ()) if halves else ()
        least = MIN_GAIN if self.kind == ONE_STEP else MIN_OUTAGE_GAIN
        return self.p < alpha / 2 and self.gain >= least and all(g > 0 for g in judged)

    def loses(self, alpha: float) -> bool:
        """Whether the trial makes these errors worse beyond noise (at ``alpha / 2``)."""
        return self.p_worse < alpha / 2

    def loses_much(self) -> bool:
        """Whether it adds more than :data:`MAX_POINT_LOSS` to an outage bias's sum of squares.

        The point estimate, whatever the windows: a navigation filter suffers the loss the
        windows measured, significant or not.
        """
        return self.kind == OUTAGE and self.gain < -MAX_POINT_LOSS

    def to_dict(self) -> dict[str, Any]:
        """Return the comparison as JSON."""
        return {**asdict(self), "halves": list(self.halves) if self.halves else None}


def compare(a: Forecasts, b: Forecasts) -> tuple[Comparison, ...]:
    """Compare ``b`` with ``a``: the one-step errors, then the window means at each horizon.

    The halves of the segment are judged at a horizon whose windows number at least
    ``2 * MIN_HALF_WINDOWS``, and for the one-step errors when the shortest horizon's do:
    on a shorter segment the halves' errors are too few to tell a fading effect from noise.
    """
    shortest = len(a.biases[min(a.biases)]) if a.biases else 0
    out = [_comparison(ONE_STEP, None, list(zip(np.array_split(a.one_step, BATCHES),
                                                np.array_split(a.one_step - b.one_step,
                                                               BATCHES))), shortest)]
    for h, bias_a in a.biases.items():
        change = bias_a - b.biases[h]
        out.append(_comparison(OUTAGE, h, [(np.array([e]), np.array([d]))
                                           for e, d in zip(bias_a, change)], len(bias_a)))
    return tuple(out)


def _comparison(kind: str, horizon_s: float | None,
                pairs: list[tuple[np.ndarray, np.ndarray]], windows: int) -> Comparison:
    """Return the encompassing test and gains over ``(errors, change)`` groups."""
    beta, t, p = _encompassing(pairs)
    half = len(pairs) // 2
    judged = windows >= 2 * MIN_HALF_WINDOWS
    halves = (_gain(pairs[:half]), _gain(pairs[half:])) if judged else None
    return Comparison(kind, horizon_s, len(pairs), _gain(pairs), halves, beta, t, p,
                      _p_worse(pairs))


def _p_worse(groups: list[tuple[np.ndarray, np.ndarray]]) -> float:
    """Return the one-sided p-value of the change making the errors' sum of squares larger.

    The Diebold-Mariano test of the groups' loss differences ``|e - d|^2 - |e|^2``, against
    Student's t with one degree of freedom fewer than the groups.  (The encompassing
    ``beta`` cannot say it: a change that overshoots, ``d = 3 e``, has ``beta`` 1/3 and
    makes every error twice as large.)
    """
    loss = np.array([float((e - d) @ (e - d) - e @ e) for e, d in groups])
    if len(loss) < 2:
        return 1.0
    spread = float(loss.std(ddof=1))
    if spread == 0:
        return 0.0 if loss.mean() > 0 else 1.0
    return float(stats.t.sf(loss.mean() / (spread / np.sqrt(len(loss))), len(loss) - 1))


def _gain(groups: list[tuple[np.ndarray, np.ndarray]]) -> float:
    """Share of the errors' sum of squares that the change removes: 1 - |e - d|^2 / |e|^2."""
    before = sum(float(e @ e) for e, _ in groups)
    after = sum(float((e - d) @ (e - d)) for e, d in groups)
    return 1.0 - after / before if before > 0 else 0.0


def _encompassing(groups: list[tuple[np.ndarray, np.ndarray]]) -> tuple[float, float, float]:
    """``beta`` of the errors on the change, its one-sided t statistic and p-value.

    ``groups`` are (errors, change) pairs; the standard error comes from the
    spread of the groups' contributions (len(groups) - 1 degrees of freedom).
    """
    num = np.array([float(e @ d) for e, d in groups])
    den = np.array([float(d @ d) for _, d in groups])
    if den.sum() <= 0 or len(groups) < 2:
        return math.nan, math.nan, 1.0
    beta = float(num.sum() / den.sum())
    spread = num - beta * den
    se = math.sqrt(float(spread @ spread) * len(groups) / (len(groups) - 1)) / den.sum()
    if se == 0:
        return beta, (math.inf if beta > 0 else 0.0), (0.0 if beta > 0 else 1.0)
    t = beta / se
    return beta, t, float(stats.t.sf(t, len(groups) - 1))


@dataclass(frozen=True)
class Judgement:
    """A trial judged against the current model.

    ``last`` are the comparisons from the fitting segment's end, ``earlier`` those from
    each earlier origin (None where the trial's new terms cannot be estimated there; the
    whole None when they were not looked at: the trial failed at the end); ``kept_on`` is
    the key of the comparison it is kept on (None: rejected), ``reason`` why not when the
    loop held an accepted trial back.  ``beyond`` are the comparisons at horizons the
    evaluation segment holds too few windows of, from the earliest origin on (where that
    stretch holds enough; :class:`fosmodel.loop.fitting.Judge`).  Over several sessions
    ``last`` pools every held-out session's comparisons and ``sessions`` holds each one's.
    ``note`` says how it was judged where that differs from the rest: an onset that left it
    to fewer origins, or none, and the horizons it is unjudged at.
    """

    last: tuple[Comparison, ...]
    origins_s: tuple[float, ...]
    earlier: tuple[tuple[Comparison, ...] | None, ...] | None
    kept_on: str | None
    reason: str | None = None
    sessions: tuple[tuple[Comparison, ...], ...] | None = None
    beyond: tuple[Comparison, ...] = ()
    note: str | None = None

    @property
    def accepted(self) -> bool:
        """Whether the trial is kept (on ``kept_on``)."""
        return self.kept_on is not None

    def at(self, key: str) -> Comparison:
        """Return the comparison at the end named ``key``."""
        return next(c for c in self.last if c.key == key)

    def gains(self, key: str) -> list[float | None]:
        """Return the gains on ``key`` from each origin, the earliest first, the end last."""
        earlier = [None if cs is None else next((c.gain for c in cs if c.key == key), None)
                   for cs in (self.earlier or ())]
        return [*earlier, self.at(key).gain]

    def score(self, origins: Iterable[int] | None = None) -> tuple[float, float]:
        """Return the gain it is kept on, averaged over the origins, and its t: what ranks it.

        ``origins`` are the origins to average over, counted back from the end (0, the
        fitting segment's end; 1, the origin before it...); by default every origin that
        judged it.
        """
        found = self._gains_back()
        chosen = range(len(found)) if origins is None else origins
        gains = [g for i in chosen if i < len(found) for g in [found[i]] if g is not None]
        return float(np.mean(gains)), self.at(self.kept_on or ONE_STEP).t

    def judged_from(self) -> set[int]:
        """Return the origins that judged it, counted back from the end (0, always)."""
        return {i for i, g in enumerate(self._gains_back()) if g is not None} | {0}

    def _gains_back(self) -> list[float | None]:
        """Return the gains on what it is kept on, from the end back to the earliest origin."""
        return self.gains(self.kept_on or ONE_STEP)[::-1]

    def held_back(self, reason: str) -> Judgement:
        """Return this judgement, not accepted, for ``reason``."""
        return replace(self, kept_on=None, reason=reason)

    def to_dict(self) -> dict[str, Any]:
        """Return the judgement as JSON: each comparison at the end, the gains from every origin."""
        return {"comparisons": {c.key: c.to_dict() for c in self.last},
                "origins_s": list(self.origins_s),
                "gains_from_origins": None if self.earlier is None else
                {c.key: self.gains(c.key) for c in self.last},
                "kept_on": self.kept_on, "accepted": self.accepted, "reason": self.reason,
                "note": self.note,
                "beyond_evaluation": {c.key: c.to_dict() for c in self.beyond},
                **({} if self.sessions is None else {"sessions": [
                    {c.key: c.to_dict() for c in each} for each in self.sessions]})}


def verdict(last: tuple[Comparison, ...], earlier: list[tuple[Comparison, ...]] | None,
            alpha: float, strict: bool = True) -> str | None:
    """Return the key of the comparison a candidate is kept on, or None.

    It must pass (:meth:`Comparison.passes`) at the fitting segment's end on some error
    kind at some horizon, lose beyond noise (:meth:`Comparison.loses`) on none and no more
    than :data:`MAX_POINT_LOSS` of any outage bias (:meth:`Comparison.loses_much`).  A
    ``strict`` candidate (one that could run on beyond its data: a function of time, and
    fast effects, which are cheap to judge) must also gain on each half of the segment and
    lose nothing on the comparison it passes from any earlier origin (gain above
    ``-GAIN_TOL``); the others (a level, which holds still beyond its data; a driver's slow
    part, which runs as its measured cause does) need only a positive gain on average over
    the origins.  Of several comparisons passed, the one with the largest such gain.

    A strict candidate is not kept on a comparison judged only next to its fitting data: one
    whose halves are not judged (too few windows) and that no earlier origin judged (a step
    after every earlier origin).  ``earlier`` None: the earlier origins are not looked at
    yet, and nothing is asked of them.
    """
    if any(c.loses(alpha) or c.loses_much() for c in last):
        return None
    kept = []
    for c in last:
        if not c.passes(alpha, strict):
            continue
        gains = [e.gain for cs in earlier or [] for e in cs if e.key == c.key]
        if strict and any(g < -GAIN_TOL for g in gains):
            continue
        if strict and earlier is not None and c.halves is None and not gains:
            continue  # judged only right after its data, as a stale constant would be
        mean = float(np.mean([*gains, c.gain]))
        if mean > 0:
            kept.append((mean, c.key))
    return max(kept)[1] if kept else None


def losses_text(comparisons: Iterable[Comparison], alpha: float) -> str | None:
    """Say what a trial loses, beyond noise or more than :data:`MAX_POINT_LOSS`; None: nothing."""
    noisy = [c.label for c in comparisons if c.loses(alpha)]
    large = [f"{c.label} ({-c.gain:.1%} more sum of squares)" for c in comparisons
             if c.loses_much() and not c.loses(alpha)]
    parts = ([f"loses beyond noise on the {', '.join(noisy)}"] if noisy else []) + (
        [f"loses more than {MAX_POINT_LOSS:.0%} on the {', '.join(large)}, not kept on "
         "gains elsewhere however few its windows"] if large else [])
    return "; ".join(parts) or None

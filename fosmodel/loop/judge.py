"""How the residual loop judges a candidate: out of sample, from several origins.

A candidate model ``b`` (the current model ``a`` with one effect added) is
judged on the evaluation segment, which neither was fitted on; the
prediction segment is never looked at.  Two kinds of errors are compared:
the one-step errors over the segment and the free-run (outage) errors over
consecutive windows of ``eval_horizon_s``.

*Forecast encompassing* (:func:`compare`): does the change ``b`` makes to
``a``'s forecasts explain ``a``'s errors?  ``beta = sum(e_a d) / sum(d^2)``
with ``d`` the change, its t statistic from the spread over groups (ten
batches of one-step errors; the outage windows).  With no effect ``beta`` is
centred on 0.

*Rolling origins* (forward chaining): a deterministic function of time fitted
on one stretch helps next to it and runs on beyond.  So both models are also
refitted (their weights, :meth:`fosmodel.models.model.FOSModel.refit_weights`) on
shorter pasts ending at earlier origins, and judged on the same evaluation
segment, now further from their fitting data: the distance from the earliest
origin to the end of the segment is like the distance from the fitting
segment to the end of the record.  An effect that only helps next to its
fitting data fails there.

References
----------
D. I. Harvey, S. J. Leybourne and P. Newbold, "Tests for forecast
encompassing", *Journal of Business & Economic Statistics* 16(2), 1998.
R. J. Hyndman and G. Athanasopoulos, *Forecasting: Principles and Practice*,
3rd ed., 2021, section 5.10 (time series cross-validation).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy import stats

from ..models.bound import BoundModel
from ..noise.metrics import OneStepModel, free_run_errors

MAX_WINDOWS = 100  # most outage windows of the evaluation test
MIN_HALF_WINDOWS = 20  # outage windows in each half of the evaluation segment to judge it
GAIN_TOL = 1e-9  # an earlier origin's gain above -GAIN_TOL counts as no loss (rounding)
#: Smallest share of the errors' sum of squares an effect must remove to be kept: with
#: hundreds of thousands of samples a 0.03 % gain is "significant", and not worth a term
#: that may cost more where it extrapolates.
MIN_GAIN = 1e-3


@dataclass(frozen=True)
class Forecasts:
    """A model's errors on the evaluation segment: one-step and per outage window."""

    one_step: np.ndarray
    outage: np.ndarray  # (windows, samples)


def outage_windows(segment: slice, horizon: int) -> np.ndarray:
    """Return the starts of consecutive outage windows of ``horizon`` samples in ``segment``.

    At most :data:`MAX_WINDOWS` of them, evenly spread (enough for the t test).
    """
    starts = np.arange(segment.start, segment.stop - horizon + 1, horizon)
    if len(starts) > MAX_WINDOWS:
        starts = starts[np.linspace(0, len(starts) - 1, MAX_WINDOWS).round().astype(int)]
    return starts


def forecasts(model: OneStepModel, y: np.ndarray, segment: slice, starts: np.ndarray,
              horizon: int) -> Forecasts:
    """Return the one-step and outage errors of ``model`` on ``segment`` of the record ``y``."""
    stop = segment.stop
    one_step = y[segment] - _prediction(model, y[:stop], segment.start)[segment]
    # the prediction, as long as the record, is gone before the free runs begin
    return Forecasts(one_step, free_run_errors(model, y[:stop], starts, horizon))


def _prediction(model: OneStepModel, y: np.ndarray, start: int) -> np.ndarray:
    """``model``'s one-step prediction of ``y`` (from ``start`` on where it can)."""
    pred = model.predict(y, start=start) if isinstance(model, BoundModel) else model.predict(y)
    return np.asarray(pred, dtype=float)


def compare(a: Forecasts, b: Forecasts, alpha: float) -> dict:
    """Test whether ``b`` beats ``a`` by more than noise would, and all along the segment.

    For each of the one-step and the outage errors: the encompassing
    ``beta``, its one-sided t statistic and p-value, the share of the
    errors' sum of squares the change removes (``gain``) over the segment and
    over each half, and ``p_worse``, the p-value of the change making the
    errors worse.  ``b`` passes on an error kind (``"passes"``) if its test
    is significant at ``alpha / 2`` and the gain is positive over the segment
    and, when each half holds at least :data:`MIN_HALF_WINDOWS` outage
    windows, over each half; on a shorter segment the halves' errors are too
    few to tell a fading effect from noise.  ``"passes_whole"`` leaves the
    halves out.

    The outage errors are compared by their mean over each window (the bias a
    navigation filter integrates); per sample they are mostly white noise.
    """
    bias_a, bias_b = a.outage.mean(axis=1, keepdims=True), b.outage.mean(axis=1, keepdims=True)
    groups = {"one_step": list(zip(np.array_split(a.one_step, 10),
                                   np.array_split(a.one_step - b.one_step, 10))),
              "outage": list(zip(bias_a, bias_a - bias_b))}
    judge_halves = len(a.outage) >= 2 * MIN_HALF_WINDOWS
    out: dict = {"halves_judged": judge_halves, "passes": [], "passes_whole": []}
    for name, pairs in groups.items():
        beta, t, p = _encompassing(pairs)
        half = len(pairs) // 2
        gain, halves = _gain(pairs), [_gain(pairs[:half]), _gain(pairs[half:])]
        out.update({f"{name}_gain": gain, f"{name}_gain_halves": halves, f"{name}_beta": beta,
                    f"{name}_t": t, f"{name}_p": p,
                    f"{name}_p_worse": float(stats.t.cdf(t, len(pairs) - 1)) if t == t else 1.0})
        judged = [gain, *halves] if judge_halves else [gain]
        if p < alpha / 2 and gain > 0:
            out["passes_whole"].append(name)
            if min(judged) > 0:
                out["passes"].append(name)
    return out


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


def passes(at_origin: dict, halves: bool = True) -> list[str]:
    """Return the error kinds on which a candidate passes at the fitting segment's end.

    Each with a gain of at least :data:`MIN_GAIN` (over each half of the segment too, with
    ``halves``).
    """
    found = at_origin["passes" if halves else "passes_whole"]
    return [name for name in found if at_origin[f"{name}_gain"] >= MIN_GAIN]


def verdict(at_origin: dict, earlier: list[dict], alpha: float,
            strict: bool = True) -> str | None:
    """Return the error kind on which a candidate is kept, or None.

    It must pass :func:`compare` at the fitting segment's end on that kind
    with a gain of at least :data:`MIN_GAIN` and not make the other kind's
    errors significantly worse.  A ``strict`` candidate (one that could run
    on beyond its data: a function of time, a channel's slow part, and fast
    effects, which are cheap to judge) must also gain on each half of the
    segment and lose nothing on it from any earlier origin (gain above
    ``-GAIN_TOL``); the level, which holds still beyond its data as the
    model without it does, needs only a positive gain on average over the
    origins: refitted on half the fitting segment its weights are rough.
    """
    for name, other in (("outage", "one_step"), ("one_step", "outage")):
        if name not in passes(at_origin, strict):
            continue
        gains = [e[f"{name}_gain"] for e in earlier]
        if strict and any(g < -GAIN_TOL for g in gains):
            continue
        if not strict and np.mean([*gains, at_origin[f"{name}_gain"]]) <= 0:
            continue
        if at_origin[f"{other}_p_worse"] < alpha / 2:
            continue
        return name
    return None

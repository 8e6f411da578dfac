"""One sensor's sessions: a FOS model whose terms and weights they share, a constant each.

Recordings of one sensor made on different days share its dynamics and its
sensitivities (to temperature, to specific force) but not its turn-on bias: each
session starts with a constant of its own.  Fitting every session's samples as
one record would take the differences between those constants for an effect of
whatever differs between the sessions too (a mean temperature, an orientation).
So the fit is the *within* estimator of panel data (Wooldridge 2010, sec. 10.5):
every session's output and inputs lose their own means over its fitting part, and
one least-squares fit (FOS) over all parts, each with its own lag window
(:meth:`FOSModel.fit` with ``segments``), gives the shared weights.  Each
session's constant is then the shift of the shared model's one-step prediction that
puts it at the session's mean output over its own fitting part (every lag and level
held at that mean; :func:`session_constant`), which a free run carries to the
session's own level (:meth:`FOSModel.shifted`).  A new
session's constant comes the same way from its first minutes, as a navigation
filter learns a turn-on bias at alignment.

References
----------
J. M. Wooldridge, *Econometric Analysis of Cross Section and Panel Data*, 2nd ed.,
MIT Press, 2010, section 10.5.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np

from ..core.exceptions import InputError
from .compensation import compensation_series
from .model import FOSModel


def within(values: np.ndarray, parts: Sequence[slice], total: slice | None = None) -> np.ndarray:
    """Return ``values`` with each part less its own mean (a copy; outside the parts as is).

    ``total`` is where the parts lie in ``values`` (all of it by default).
    """
    out = np.array(values, dtype=float, copy=True)
    for part in parts:
        out[part] -= out[part].mean()
    return out if total is None else out[total]


def fit_sessions(model: FOSModel, ys: Sequence[np.ndarray],
                 exogs: Sequence[Mapping[str, np.ndarray] | None],
                 parts: Sequence[slice] | None = None,
                 hold: bool = False) -> tuple[FOSModel, list[float]]:
    """Fit ``model`` on several sessions: shared weights, and each session's constant.

    Parameters
    ----------
    model : FOSModel
        The unfitted model (its candidates); fitted in place and returned.
    ys, exogs : sequences
        Each session's output and its channels and columns (each as long as its output).
    parts : sequence of slice, optional
        The part of each session fitted on (by default all of it).
    hold : bool
        Refit the output's lags and levels to sum to one
        (:meth:`FOSModel.refit_weights`).

    Returns
    -------
    model, constants
        The fitted model (its own constant that of the mean session's) and each session's
        constant, the shift (:meth:`FOSModel.shifted`) that fits it.

    Raises
    ------
    InputError
        No session, or sessions with other channels.
    """
    if not ys:
        raise InputError("a fit over sessions needs at least one")
    names = [sorted(e or {}) for e in exogs]
    if any(n != names[0] for n in names):
        raise InputError(f"the sessions' channels differ: {', '.join(names[0]) or 'none'} "
                         f"against {', '.join(next(n for n in names if n != names[0]))}")
    parts = list(parts or [slice(0, len(y)) for y in ys])
    starts = np.cumsum([0, *(len(y) for y in ys)])
    spans = [slice(int(a + p.start), int(a + p.stop)) for a, p in zip(starts, parts)]
    y = within(np.concatenate(ys), spans)
    exog = {k: within(np.concatenate([np.asarray(e[k], dtype=float) for e in exogs if e]),
                      spans) for k in names[0]}
    model.fit(y, exog or None, segments=spans)
    if hold:
        model = model.refit_weights(y, exog or None, segments=spans, hold=True)
    constants = [session_constant(model, np.asarray(sy, dtype=float), e, p)
                 for sy, e, p in zip(ys, exogs, parts)]
    return model.shifted(float(np.mean(constants))), [c - float(np.mean(constants))
                                                      for c in constants]


def session_constant(model: FOSModel, y: np.ndarray, exog: Mapping[str, np.ndarray] | None,
                     window: slice) -> float:
    """Return the shift that gives ``model`` a session's constant, from ``window`` of its record.

    The turn-on bias is an offset of the session's output: the shift (:meth:`FOSModel.shifted`)
    that puts the model's one-step prediction at the session's mean output over ``window``
    when every lag and level of the output is there too (its mean one-step residual with the
    output held at that mean, the inputs and any compensation as measured).  For a stationary
    model it is the offset times one minus the sum of the output's own weights; for a model
    whose level follows the output (weights summing to one) it is only what undoes a drift
    of the constant, since the level carries the session's bias itself.  The plain mean
    one-step residual over a few minutes would be mostly their white noise, and a free run
    of such a model turns any constant left in it into a ramp.  Only the samples up to the
    window's end are read.
    """
    stop = window.stop
    levels = set(model.candidate_spec().level_names)
    head = {k: np.asarray(v)[:stop] for k, v in exog.items() if k not in levels} \
        if exog else None
    y = np.asarray(y[:stop], dtype=float)
    comp = (compensation_series(model.compensation, head, stop, model.rate)
            if model.compensation else np.zeros(stop))
    target = (y - comp)[window]
    target = target[np.isfinite(target)]
    if not target.size:
        raise InputError(f"the window {window.start}-{window.stop} holds no sample")
    held = comp + target.mean()  # the levels are then computed from it: flat too
    residual = (held - np.asarray(model.predict(held, head or None), dtype=float))[window]
    residual = residual[np.isfinite(residual)]
    if not residual.size:
        raise InputError(f"the window {window.start}-{window.stop} holds no prediction past "
                         f"the model's lag window of {model.lag_window_} samples")
    return float(residual.mean())

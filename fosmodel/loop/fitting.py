"""How the loop fits a candidate family on one record, and judges a trial out of sample."""

from __future__ import annotations

import copy

import numpy as np

from ..core.levels import level_name, level_series
from ..models.bound import BoundModel
from ..models.model import FOSModel
from .config import LoopConfig
from .driver_forms import forms_p, refit_forms
from .effects import CandidateFamily, Effect
from .judge import Forecasts, Judgement, compare, forecasts, verdict
from .record import LoopRecord
from .scores import Plan, plan


class FamilyArrays:
    """What a candidate family's model reads besides the record: its target and its levels.

    The target is the output minus the family's compensation; the levels are those of the
    target, restarted at each session's start as its derived columns are
    (:class:`LoopRecord`).  Both are computed once per compensation and passed with the
    inputs (a model would recompute the levels at every prediction and free run).
    """

    def __init__(self, record: LoopRecord, config: LoopConfig) -> None:
        self.record, self.config = record, config
        self._targets: dict[tuple, np.ndarray] = {}
        self._levels: dict[tuple, np.ndarray] = {}

    def target(self, family: CandidateFamily) -> np.ndarray:
        """Return the output minus the family's compensation: what its terms model."""
        key = tuple(sorted(family.compensation.items()))
        if key not in self._targets:
            comp = family.compensation_series()
            self._targets[key] = self.record.y if comp is None else self.record.y - comp
        return self._targets[key]

    def inputs(self, family: CandidateFamily) -> dict[str, np.ndarray]:
        """Every array the family's model reads: its columns and the levels of its target."""
        key, target = tuple(sorted(family.compensation.items())), self.target(family)
        for tau in family.levels:
            if (tau, key) not in self._levels:
                self._levels[tau, key] = self._level(target, tau)
        return {**family.arrays(),
                **{level_name(tau): self._levels[tau, key] for tau in family.levels}}

    def _level(self, target: np.ndarray, tau: float) -> np.ndarray:
        sessions, rate = self.record.sessions, self.config.rate
        if len(sessions) == 1:
            return level_series(target, tau, rate)
        return np.concatenate([level_series(target[s], tau, rate) for s in sessions])

    def forget(self, keep: CandidateFamily) -> None:
        """Drop what only other families read: their targets, levels and columns."""
        key = tuple(sorted(keep.compensation.items()))
        self._targets = {k: v for k, v in self._targets.items() if k in ((), key)}
        self._levels = {k: v for k, v in self._levels.items() if k[1] in ((), key)}
        self.record.forget(set(keep.arrays()))


class Fitter(FamilyArrays):
    """Fits the FOS model of a candidate family on the fitting segment of one record.

    It also refits the weights of such a model on shorter pasts.
    """

    def __init__(self, record: LoopRecord, train: slice, config: LoopConfig) -> None:
        super().__init__(record, config)
        self.train = train

    def fit(self, family: CandidateFamily) -> BoundModel:
        """Fit the family's FOS model on the fitting segment."""
        inputs = self.inputs(family)
        model = FOSModel(max_lag=family.max_lag, degree=family.degree,
                         exog_lags=dict(family.exog_lags), columns=list(family.columns),
                         levels=list(family.levels), rate=self.config.rate,
                         product_lags=family.product_lags, stop=self.config.fos_stop,
                         compensation=dict(family.compensation) or None)
        train = self.train
        past = {k: v[train] for k, v in inputs.items()}
        model.fit(self.record.y[train], past)
        if _holds(family):
            model = model.refit_weights(self.record.y[train], past, hold=True)
        return BoundModel(model, inputs)

    def refit(self, bound: BoundModel, family: CandidateFamily, stop: int) -> BoundModel:
        """``bound`` (of ``family``) with its weights fitted on the samples before ``stop``.

        A compensation's weights are fitted anew there too (its forms stay), and the levels
        follow the output it leaves: from an earlier origin a driver's sensitivity is what
        the data before it say.
        """
        model, inputs = bound.model, bound.inputs
        if family.compensation:
            block, gain = family.comp_fit
            weights = refit_forms(self.record.y, family.comp_columns, [slice(0, stop)], block,
                                  gain)
            family = family.changed(compensation=weights)
            model = copy.copy(model)
            model.compensation = weights
            inputs = self.inputs(family)
        past = {k: v[:stop] for k, v in inputs.items()}
        return BoundModel(model.refit_weights(self.record.y[:stop], past, hold=_holds(family)),
                          inputs)

def _holds(family: CandidateFamily) -> bool:
    """Whether the family's levels are held (:meth:`FOSModel.refit_weights` with ``hold``).

    With a compensation: its output has lost the driver's slow swing, so on the fitting
    data its level wanders too little against the noise for least squares to weigh it
    fully, and a free run would drift back to a training mean the bias has left.  Without
    one the slow swing itself holds the weights near one, and a drift or a step beside the
    level is fitted against a level that follows them only as least squares lets it.
    """
    return bool(family.levels and family.compensation)


class Judge:
    """Judges trial models against the current one out of sample (:mod:`fosmodel.loop.judge`).

    The current model's refits and forecasts from every origin are computed once
    per round.  An origin from which a trial's new terms cannot be estimated (a
    step after it: the refit drops them; a driver's forms its past does not tell from
    none) cannot judge it, and is left out.
    """

    def __init__(self, fitter: Fitter, current: BoundModel, family: CandidateFamily,
                 where: Plan) -> None:
        self.fitter, self.where, self.family = fitter, where, family
        self.y, config = fitter.record.y, fitter.config
        end = fitter.train.stop
        self.origins = np.unique(np.linspace(end / 2, end, config.origins).round().astype(int))
        if len(self.origins) > 1 and self.origins[0] <= max(4 * config.max_lag, 100):
            self.origins = self.origins[-1:]  # too short a past to refit on
        self.refits = [self._refit(current, family, o) for o in self.origins]
        self.current = [self._forecasts(m) for m in self.refits]
        self.beyond = self._beyond_plan(where)
        self.beyond_current = self._beyond(self.refits[0]) if self.beyond else None

    def _beyond_plan(self, where: Plan) -> Plan | None:
        """Return where the earliest origin judges what the evaluation segment holds too few of.

        Unseen by the refits at that origin, the stretch from it to the evaluation segment's
        end may hold enough of them to judge: a horizon is not passed unjudged where it can
        be judged there.
        """
        if len(self.origins) < 2 or not where.skipped:
            return None
        beyond = plan(slice(int(self.origins[0]), where.segment.stop), tuple(where.skipped),
                      self.fitter.config.rate, self.fitter.config.n_starts,
                      "earliest origin's unseen")
        return beyond if beyond.horizons else None

    def _beyond(self, model: BoundModel) -> Forecasts:
        assert self.beyond is not None
        return forecasts(model, self.y, self.beyond.segment, self.beyond.horizons)

    @property
    def origins_s(self) -> tuple[float, ...]:
        """The fit origins in seconds, the fitting segment's end last."""
        return tuple(float(o / self.fitter.config.rate) for o in self.origins)

    def _refit(self, model: BoundModel, family: CandidateFamily, origin: int) -> BoundModel:
        if origin == self.origins[-1]:
            return model
        return self.fitter.refit(model, family, int(origin))

    def _forecasts(self, model: BoundModel) -> Forecasts:
        return forecasts(model, self.y, self.where.segment, self.where.horizons)

    def _earlier(self, trial: BoundModel, family: CandidateFamily, origin: int,
                 current: BoundModel, base: Forecasts) -> tuple | None:
        if not self._shows_driver(family, origin):
            return None  # its past cannot tell the driver's sensitivity from none
        refit = self._refit(trial, family, origin)
        if set(refit.model.terms_) <= set(current.model.terms_) \
                and refit.model.compensation == current.model.compensation:
            return None  # nothing new estimable
        return compare(base, self._forecasts(refit))

    def _shows_driver(self, family: CandidateFamily, origin: int) -> bool:
        """Whether the past before ``origin`` tells the trial's new driver forms from none.

        Their F test there (:func:`fosmodel.loop.driver_forms.forms_p`, beside the forms
        already in) at the level a driver is offered at.  Over a steady ramp of the driver
        the refitted sensitivity is what the noise makes it (an accelerometer's
        5e-4 m/s^2/C read -4.6e-3 with the ramp alone before the origin, and from there its
        30 min outage biases' sum of squares was 926 times the level's): such an origin
        judges the estimation noise of a short past, not the driver, as an origin before
        a step cannot judge the step.
        """
        old = self.family.compensation
        new = [n for n, w in family.compensation.items() if old.get(n) != w]
        if not new:
            return True
        block, gain = family.comp_fit
        columns = family.comp_columns
        p = forms_p(self.y, {n: columns[n] for n in new}, [slice(0, origin)], block, gain,
                    {n: columns[n] for n in columns if n not in new})
        return p < self.fitter.config.alpha

    def __call__(self, trial: BoundModel, family: CandidateFamily,
                 effect: Effect) -> Judgement:
        """Judge ``trial``: at the fitting segment's end, then from the earlier origins.

        The earlier origins are looked at only for a trial that passes at the end.
        """
        alpha = self.fitter.config.accept_alpha
        last = compare(self.current[-1], self._forecasts(trial))
        if verdict(last, None, alpha, effect.strict) is None:
            return Judgement(last, self.origins_s, None, None)
        found = [self._earlier(trial, family, o, m, f) for o, m, f in
                 zip(self.origins[:-1], self.refits[:-1], self.current[:-1])]
        kept = verdict(last, [f for f in found if f is not None], alpha, effect.strict)
        if kept is None or self.beyond is None or self.beyond_current is None:
            return Judgement(last, self.origins_s, tuple(found), kept)
        refit = self._refit(trial, family, int(self.origins[0]))
        beyond = compare(self.beyond_current, self._beyond(refit))[1:]  # the one-step is judged
        lost = [c.label for c in beyond if c.loses(alpha)]
        judgement = Judgement(last, self.origins_s, tuple(found), kept, beyond=beyond)
        if lost:
            return judgement.held_back(
                f"loses beyond noise on the {', '.join(lost)}, which the evaluation segment "
                f"holds too few windows of, judged from the earliest origin "
                f"({self.origins_s[0]:g} s) on")
        return judgement

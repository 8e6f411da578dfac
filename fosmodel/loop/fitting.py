"""How the loop fits a candidate family on one record, and judges a trial out of sample."""

from __future__ import annotations

import copy
from collections.abc import Sequence

import numpy as np

from ..core.levels import level_name, level_series
from ..models.bound import BoundModel
from ..models.model import FOSModel
from .config import LoopConfig
from .driver_forms import forms_p, refit_forms
from .effects import CandidateFamily, Effect
from .judge import (
    ONSET_REFIT_SLOWS,
    Forecasts,
    Judgement,
    compare,
    forecasts,
    losses_text,
    verdict,
)
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
    per round.  An origin that cannot judge a trial is left out: one before its effect's
    onset or too soon after it (:data:`fosmodel.loop.judge.ONSET_REFIT_SLOWS`), one from
    which its new terms cannot be estimated (the refit drops them), one whose past does not
    tell a driver's forms from none.
    """

    def __init__(self, fitter: Fitter, current: BoundModel, family: CandidateFamily,
                 where: Plan, added: Sequence[Effect] = ()) -> None:
        self.fitter, self.where, self.family = fitter, where, family
        self.added = tuple(added)  # the current model's effects: their onsets count too
        self.y, config = fitter.record.y, fitter.config
        end = fitter.train.stop
        self.origins = np.unique(np.linspace(end / 2, end, config.origins).round().astype(int))
        if len(self.origins) > 1 and self.origins[0] <= max(4 * config.max_lag, 100):
            self.origins = self.origins[-1:]  # too short a past to refit on
        self.refits = [self._refit(current, family, o) for o in self.origins]
        self.current = [self._forecasts(m) for m in self.refits]
        self._beyond_plans: dict[int, tuple[Plan, Forecasts] | None] = {}

    def _beyond_at(self, index: int) -> tuple[Plan, Forecasts] | None:
        """Return where the origin ``index`` judges what the evaluation segment holds too few of.

        Unseen by the refits at that origin, the stretch from it to the evaluation segment's
        end may hold enough of them to judge: a horizon is not passed unjudged where it can
        be judged there.  With the current model's forecasts there; None if it holds none.
        """
        if index not in self._beyond_plans:
            where, config = self.where, self.fitter.config
            found = None
            if where.skipped and index < len(self.origins) - 1:
                beyond = plan(slice(int(self.origins[index]), where.segment.stop),
                              tuple(where.skipped), config.rate, config.n_starts,
                              "earliest origin's unseen")
                if beyond.horizons:
                    found = beyond, self._beyond(self.refits[index], beyond)
            self._beyond_plans[index] = found
        return self._beyond_plans[index]

    def _beyond(self, model: BoundModel, where: Plan) -> Forecasts:
        return forecasts(model, self.y, where.segment, where.horizons)

    @property
    def origins_s(self) -> tuple[float, ...]:
        """The fit origins in seconds, the fitting segment's end last."""
        return tuple(float(o / self.fitter.config.rate) for o in self.origins)

    def onset_s(self, effect: Effect) -> float | None:
        """Return the latest onset of ``effect`` and of the current model's effects, or None.

        From an origin before a step already in, the current model's refit has lost it as
        the trial's has: the two compare models of a record neither has seen.
        """
        onsets = [o for e in (*self.added, effect) for o in [e.onset_s()] if o is not None]
        return max(onsets) if onsets else None

    def can_judge(self, origin: int, effect: Effect) -> bool:
        """Whether ``origin`` (a sample) lies far enough after the onsets to judge ``effect``.

        :data:`fosmodel.loop.judge.ONSET_REFIT_SLOWS` times ``slow_s`` after its onset and
        the current model's effects' (:meth:`onset_s`) at least; with no onset, from every
        origin.
        """
        onset = self.onset_s(effect)
        config = self.fitter.config
        return onset is None or origin / config.rate >= onset + ONSET_REFIT_SLOWS * config.slow_s

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

        The earlier origins are looked at only for a trial that passes at the end, and only
        those that can judge its effect (:meth:`can_judge`); the horizons the evaluation
        segment holds too few windows of, from the earliest of them on.
        """
        alpha = self.fitter.config.accept_alpha
        last = compare(self.current[-1], self._forecasts(trial))
        if verdict(last, None, alpha, effect.strict) is None:
            return Judgement(last, self.origins_s, None, None, reason=losses_text(last, alpha))
        able = [i for i, o in enumerate(self.origins[:-1]) if self.can_judge(int(o), effect)]
        found = [self._earlier(trial, family, int(self.origins[i]), self.refits[i],
                               self.current[i]) if i in able else None
                 for i in range(len(self.origins) - 1)]
        note = self._onset_note(effect, able)
        kept = verdict(last, [f for f in found if f is not None], alpha, effect.strict)
        beyond_at = self._beyond_at(able[0]) if able else None
        if kept is None or beyond_at is None:
            unjudged = self._unjudged(beyond_at)
            return Judgement(last, self.origins_s, tuple(found), kept, note=_join(note, unjudged))
        where, base = beyond_at
        refit = self._refit(trial, family, int(self.origins[able[0]]))
        beyond = compare(base, self._beyond(refit, where))[1:]  # the one-step is judged
        judgement = Judgement(last, self.origins_s, tuple(found), kept, beyond=beyond,
                              note=_join(note, self._unjudged(beyond_at)))
        lost = losses_text(beyond, alpha)
        if lost:
            return judgement.held_back(
                f"{lost}, which the evaluation segment holds too few windows of, judged from "
                f"the origin at {self.origins_s[able[0]]:g} s on")
        return judgement

    def _onset_note(self, effect: Effect, able: list[int]) -> str | None:
        """Say so when an onset left the effect to fewer origins, or to none."""
        earlier, onset = len(self.origins) - 1, self.onset_s(effect)
        if onset is None or not earlier or len(able) == earlier:
            return None
        whose = "its onset" if onset == effect.onset_s() else "the onset of an effect in the model"
        if not able:
            return (f"judged on the evaluation segment alone, by the strict rule: no earlier "
                    f"origin has {ONSET_REFIT_SLOWS * self.fitter.config.slow_s:g} s after "
                    f"{whose} ({onset:.4g} s) to refit on")
        return (f"judged from the origins at {self.origins_s[able[0]]:g} s on: the earlier "
                f"ones precede {whose} ({onset:.4g} s) or follow it too closely")

    def _unjudged(self, beyond_at: tuple[Plan, Forecasts] | None) -> str | None:
        """Name the horizons the earliest origin judges but none that can judge the effect does.

        Those no origin holds enough windows of are unjudged for every effect: the notes
        say so once.
        """
        judged = set(beyond_at[0].horizons) if beyond_at else set()
        earliest = self._beyond_at(0)
        missing = [h for h in (earliest[0].horizons if earliest else ()) if h not in judged]
        if not missing:
            return None
        return ("unjudged at the " + ", ".join(f"{h:g} s" for h in missing)
                + " outage bias: too few windows from the origins that can judge it")


def _join(*parts: str | None) -> str | None:
    found = [p for p in parts if p]
    return "; ".join(found) or None

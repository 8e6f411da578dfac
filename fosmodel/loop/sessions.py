"""The residual loop over several sessions of one sensor, judged session by session.

Each session (a record of the same sensor, another day) is split in time: the
first ``train + evaluate`` of it *decides* (it is fitted on and judged on), the
rest is *predicted* and decides nothing.  The model's dynamics and driver
sensitivities are shared, each session keeps a constant of its own (its turn-on
bias; :mod:`fosmodel.models.sessions`).

The judge is leave-one-session-out: a candidate and the current model are
fitted on the other sessions (their structure chosen there, a driver's weights
too) and judged on the held-out one, which neither saw.  The held-out
session's own constant comes from its first ``head_s`` seconds, which are then
left out of what is judged: it is what a navigation filter learns of a turn-on
bias at alignment, before the run it is to carry, and it looks at nothing that
is judged.  The comparisons of every held-out session are pooled (their batches
and outage windows together) into one verdict, and each held-out session plays
the part an earlier origin plays on a single record (:func:`fosmodel.loop.judge.
verdict`): a strict effect must lose nothing on any of them, the others must gain
on average.

Held out across sessions is not held out in time: a function of time since each
session's start (a drift), fitted on the others' deciding hours, is judged on the
held-out session's same hours, where it interpolates; on the predicted hours it
runs on beyond them.  So a strict effect is also judged *ahead*: both models are
fitted on the others up to the fitting fraction (``train``) of each and judged on
the held-out session from there to the end of its deciding part, further in time
than either saw.  There too it must lose nothing on what it passes, and nothing
beyond noise pooled.  A line's
phase and a step's time belong to one record: only the kinds several sessions
may share are offered (``pooled``).
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from ..core.derived import channels_read
from ..core.exceptions import InputError
from ..core.levels import levels_for
from ..core.validation import as_channels, as_signal
from ..models.bound import BoundModel
from ..models.model import FOSModel
from ..models.sessions import fit_sessions, session_constant
from .config import LoopConfig
from .diagnose import Finding
from .driver_forms import refit_forms, still
from .effects import CandidateFamily, Effect
from .effects.drift import trend_note
from .findings import Diagnostics
from .fitting import FamilyArrays, _holds
from .intervals import Ratio, ratios
from .judge import MIN_WINDOWS, Forecasts, Judgement, compare, forecasts, verdict
from .outcome import LoopOutcome
from .record import LoopRecord
from .roles import Roles, channel_roles
from .rounds import REPORT_WINDOWS, Progress, Rejected, Step, run_rounds
from .scores import Outages, Plan, Scores, plan, scores


@dataclass(frozen=True)
class Session:
    """One recording of the sensor: the modelled column, the other channels, a name."""

    y: Any
    channels: Any = None
    name: str = ""


class SessionFitter(FamilyArrays):
    """Fits a candidate family on the deciding parts of some sessions: shared weights.

    The levels of the (compensated) output restart at each session's start, as its
    derived columns do (:class:`LoopRecord`).
    """

    def __init__(self, record: LoopRecord, decide: tuple[slice, ...], config: LoopConfig) -> None:
        super().__init__(record, config)
        self.decide = decide

    def fit(self, family: CandidateFamily, which: Sequence[int] | None = None) -> BoundModel:
        """Fit the family on the deciding parts of the sessions ``which`` (all by default).

        The model's constant is that of their mean session; the compensation's weights are
        the family's (see :meth:`refitted` for the weights of other sessions).
        """
        which = list(range(len(self.decide))) if which is None else list(which)
        cfg, rec = self.config, self.record
        target, inputs = self.target(family), self.inputs(family)
        model = FOSModel(max_lag=family.max_lag, degree=family.degree,
                         exog_lags=dict(family.exog_lags), columns=list(family.columns),
                         levels=list(family.levels), rate=cfg.rate,
                         product_lags=family.product_lags, stop=cfg.fos_stop)
        arrays = {k: v for k, v in inputs.items() if not k.startswith("level@")}
        # each session up to its deciding part's end: the fit, its centring included, reads
        # nothing of what it is to predict
        parts = [slice(rec.sessions[k].start, self.decide[k].stop) for k in which]
        model, _ = fit_sessions(model, [target[s] for s in parts],
                                [{k: v[s] for k, v in arrays.items()} for s in parts],
                                [_relative(self.decide[k], rec.sessions[k]) for k in which],
                                hold=_holds(family))
        model.compensation = dict(family.compensation) or None
        return BoundModel(model, inputs)

    def refitted(self, family: CandidateFamily, which: Sequence[int]) -> CandidateFamily:
        """Return the family with its compensation's weights fitted on the sessions ``which``."""
        if not family.compensation:
            return family
        block, gain = family.comp_fit
        weights = refit_forms(self.record.y, family.comp_columns,
                              [self.decide[k] for k in which], block, gain)
        return family.changed(compensation=weights)

    def session(self, model: BoundModel, k: int, window: slice | None = None) -> BoundModel:
        """Return ``model`` bound to session ``k`` with the constant fitting ``window`` of it.

        ``window`` is in the session's own samples (default: its deciding part).
        """
        s = self.record.sessions[k]
        inputs = {name: v[s] for name, v in model.inputs.items()}
        y = self.record.y[s]
        window = _relative(self.decide[k], s) if window is None else window
        constant = session_constant(model.model, y, inputs, window)
        return BoundModel(model.model.shifted(constant), inputs)

def _relative(part: slice, session: slice) -> slice:
    return slice(part.start - session.start, part.stop - session.start)


@dataclass(frozen=True)
class Ahead:
    """Where a strict effect is judged ahead in time.

    ``fitter`` fits on each session's first ``train`` of it, ``plans`` judge each session
    from there to its deciding part's end.
    """

    fitter: SessionFitter
    plans: list[Plan]

    @property
    def origins_s(self) -> tuple[float, ...]:
        """Each session's origin, in seconds from its start."""
        rec = self.fitter.record
        return tuple((d.stop - s.start) / self.fitter.config.rate
                     for d, s in zip(self.fitter.decide, rec.sessions))


class SessionJudge:
    """Judges a trial leave-one-session-out against the current family (module docstring)."""

    def __init__(self, fitter: SessionFitter, family: CandidateFamily, plans: list[Plan],
                 head: int, ahead: Ahead | None = None) -> None:
        self.fitter, self.plans, self.head, self.ahead = fitter, plans, head, ahead
        self.family = family
        self.current = [self._forecasts(fitter, plans, family, k) for k in range(len(plans))]
        self._current_ahead: list[Forecasts] | None = None

    def _forecasts(self, fitter: SessionFitter, plans: list[Plan], family: CandidateFamily,
                   k: int) -> Forecasts:
        others = [j for j in range(len(plans)) if j != k]
        fitted = fitter.fit(fitter.refitted(family, others), others)
        bound = fitter.session(fitted, k, slice(0, self.head))
        y = fitter.record.y[fitter.record.sessions[k]]
        return forecasts(bound, y, plans[k].segment, plans[k].horizons)

    def _ahead(self, family: CandidateFamily) -> list[Forecasts]:
        assert self.ahead is not None
        return [self._forecasts(self.ahead.fitter, self.ahead.plans, family, k)
                for k in range(len(self.ahead.plans))]

    def __call__(self, trial: BoundModel, family: CandidateFamily, effect: Effect) -> Judgement:
        """Judge the trial's family on each held-out session, and on them all pooled.

        A strict effect that passes is then judged ahead in time (the module docstring).
        """
        alpha = self.fitter.config.accept_alpha
        found = [self._forecasts(self.fitter, self.plans, family, k)
                 for k in range(len(self.plans))]
        each = tuple(compare(a, b) for a, b in zip(self.current, found))
        pooled = compare(_pool(self.current), _pool(found))
        kept = verdict(pooled, list(each), alpha, effect.strict)
        if kept is None or not effect.strict or self.ahead is None:
            return Judgement(pooled, (), None, kept, sessions=each)
        if self._current_ahead is None:
            self._current_ahead = self._ahead(self.family)
        later = self._ahead(family)
        ahead = tuple(compare(a, b) for a, b in zip(self._current_ahead, later))
        kept = verdict(pooled, [*each, *ahead], alpha, effect.strict)
        if any(c.loses(alpha) for c in compare(_pool(self._current_ahead), _pool(later))):
            kept = None
        return Judgement(pooled, self.ahead.origins_s, ahead, kept, sessions=each)


def _pool(parts: list[Forecasts]) -> Forecasts:
    """Return every held-out session's forecasts end to end, each horizon's windows together."""
    horizons = sorted({h for f in parts for h in f.biases})
    return Forecasts(np.concatenate([f.one_step for f in parts]),
                     {h: np.concatenate([f.biases[h] for f in parts if h in f.biases])
                      for h in horizons})


@dataclass
class SessionsResult(LoopOutcome):
    """Everything the loop did over several sessions.

    ``before``/``after`` are the starting and final model's predicted errors, pooled over
    the sessions and per session (``before_sessions``...); ``constants`` each session's own
    constant of the final model, relative to its written constant.
    """

    config: LoopConfig
    names: tuple[str, ...]
    roles: Roles
    before_scores: Scores
    after_scores: Scores
    before_sessions: list[Scores]
    after_sessions: list[Scores]
    steps: list[Step]
    rejected: list[Rejected]
    findings_before: list[Finding]
    findings_after: list[Finding]
    base_model: BoundModel
    final_model: BoundModel
    constants: list[float]
    judged: list[Plan]
    reported: list[Plan]
    level_taus: tuple[float, ...] = ()
    notes: list[str] = field(default_factory=list)

    def ratios(self, session: int | None = None) -> list[Ratio]:
        """Return the final model's ratios to the starting one, pooled or of one session."""
        if session is None:
            return ratios(self.before_scores, self.after_scores, self.config.confidence)
        return ratios(self.before_sessions[session], self.after_sessions[session],
                      self.config.confidence)

    def worse_in(self, session: int) -> list[str]:
        """Return what the final model made worse beyond its interval in one session."""
        return [r.text() for r in self.ratios(session) if r.verdict == "worse"]

    def to_json_dict(self) -> dict[str, Any]:
        """Return the pooled before/after, each session's, the effects, the constants as JSON."""
        return {"sessions": [{"name": name, "constant": c, "before": b.to_dict(),
                              "after": a.to_dict(), "worse": self.worse_in(k),
                              "ratios": {r.key: r.to_dict() for r in self.ratios(k)}}
                             for k, (name, c, b, a) in enumerate(zip(
                                 self.names, self.constants, self.before_sessions,
                                 self.after_sessions))],
                "before": self.before.to_dict(), "after": self.after.to_dict(),
                "ratios": {r.key: r.to_dict() for r in self.ratios()},
                "worse_on_prediction": self.worse(),
                "effects": [{**s.effect.to_dict(), **s.chosen, "terms_added": s.terms_added,
                             "evaluation": s.judgement.to_dict()} for s in self.steps],
                "rejected": [r.to_dict() for r in self.rejected],
                "roles": {"drivers": list(self.roles.drivers),
                          "companions": list(self.roles.companions),
                          "companions_as_inputs": list(self.roles.opted_in)},
                "level_taus_offered": list(self.level_taus), "notes": self.notes}


def close_sessions(sessions: Sequence[Session], config: LoopConfig,
                   progress: Progress | None = None) -> SessionsResult:
    """Run the residual loop over several sessions of one sensor (the module docstring).

    Parameters
    ----------
    sessions : sequence of Session
        Two or more records of the sensor, each with the same channels.
    config : LoopConfig
        ``train + evaluate`` of each session decides; ``head_s`` gives a held-out session
        its constant.
    progress : callable, optional
        Called with a line of text as each model is fitted and each effect tried.

    Returns
    -------
    SessionsResult

    Raises
    ------
    InputError
        Fewer than two sessions, sessions with other channels, or one too short.
    """
    say = progress or (lambda _: None)
    record, names = _record(sessions, config)
    roles = channel_roles(record.channels, config.sensor, config.companions, config.aux)
    head = round(config.head_s * config.rate)
    decide, predict, judged, reported = _parts(record, config, head)
    fitter = SessionFitter(record, decide, config)
    ahead = _ahead(record, config, judged, head)
    taus = config.level_taus if config.level_taus is not None else levels_for(
        np.concatenate([record.y[p] for p in decide]), config.rate)
    family = CandidateFamily(config.max_lag)
    clock = time.perf_counter()
    base = fitter.fit(family)
    say(f"starting model: {len(base.model.terms_)} terms, shared by {len(names)} sessions "
        f"({time.perf_counter() - clock:.1f} s)")
    layout = ManySessions(fitter, Diagnostics(record, decide, roles, config), judged,
                          reported, head, ahead)
    done = run_rounds(layout, record, roles, config, tuple(taus), base, family, say)
    current = done.final_model
    before = _scores(fitter, base, reported, config)
    after = done.steps[-1].sessions if done.steps else before
    constants = [session_constant(current.model, record.y[s], {k: v[s] for k, v in
                                                                current.inputs.items()},
                                  _relative(p, s))
                 for s, p in zip(record.sessions, decide)]
    return SessionsResult(config, names, roles, _pool_scores(before), _pool_scores(after),
                          before, after, done.steps, done.rejected, done.findings_before,
                          done.findings_after, base, current, constants, judged, reported,
                          tuple(taus), _notes(record, layout.diagnose, fitter, done.family,
                                              roles, judged, names))


class ManySessions:
    """Several sessions' part in the round driver (:class:`fosmodel.loop.rounds.Layout`).

    Effects are fitted and offered on each session's deciding part (the kinds several
    sessions may share only), judged leave-one-session-out (:class:`SessionJudge`), scored
    on each session's predicted part and pooled.
    """

    def __init__(self, fitter: SessionFitter, diagnose: Diagnostics, judged: list[Plan],
                 reported: list[Plan], head: int, ahead: Ahead) -> None:
        self.fitter, self.diagnose, self.judged, self.reported = fitter, diagnose, judged, reported
        self.head, self.ahead = head, ahead
        self.fit = fitter.decide

    def offered(self, cls: type[Effect]) -> bool:
        """Only the kinds several sessions may share (``pooled``)."""
        return cls.pooled

    def round_line(self, number: int, count: int) -> str:
        """Say the round's number, how many effects it tries, and how each is judged."""
        return (f"round {number}: {count} effect(s) to try, each judged on every session "
                f"held out")

    def judge(self, current: BoundModel, family: CandidateFamily,
              added: Sequence[Effect]) -> SessionJudge:
        """Return the round's leave-one-session-out judge against ``family``."""
        return SessionJudge(self.fitter, family, self.judged, self.head, self.ahead)

    def scores(self, model: BoundModel) -> tuple[Scores, list[Scores]]:
        """Return the model's predicted errors, pooled and each session's."""
        each = _scores(self.fitter, model, self.reported, self.fitter.config)
        return _pool_scores(each), each

    def findings(self, model: BoundModel, family: CandidateFamily) -> list[Finding]:
        """Return the diagnostics of the sessions' residuals over their deciding parts."""
        record, residuals = self.fitter.record, []
        for k, part in enumerate(self.fit):
            bound, rel = self.fitter.session(model, k), _relative(part, record.sessions[k])
            y = record.y[record.sessions[k]][: rel.stop]
            residuals.append((y - bound.predict(y))[rel][model.lag_window_:])
        return self.diagnose.of(residuals, model.lag_window_, family)

    def forget(self, family: CandidateFamily) -> None:
        """Drop what only other families read, here and in the fitter ahead."""
        self.fitter.forget(family)
        self.ahead.fitter.forget(family)


def score_sessions(sessions: Sequence[Session], config: LoopConfig,
                   effects: Sequence[Effect]) -> Scores:
    """Return the pooled predicted numbers of the starting model with ``effects`` added.

    Fitted as :func:`close_sessions` fits (shared weights, a constant each, the same parts):
    with the effects a user knows to be there, or a rival set of them, the yardstick of
    what the loop kept.
    """
    record, _ = _record(sessions, config)
    decide, _, _, reported = _parts(record, config, round(config.head_s * config.rate))
    family = CandidateFamily(config.max_lag)
    for effect in effects:
        family = family.add(effect, record)
    fitter = SessionFitter(record, decide, config)
    return _pool_scores(_scores(fitter, fitter.fit(family), reported, config))


def _record(sessions: Sequence[Session], config: LoopConfig) -> tuple[LoopRecord, tuple]:
    """Return the sessions end to end, their channels checked alike."""
    if len(sessions) < 2:
        raise InputError(f"a loop over sessions needs two or more, got {len(sessions)}")
    names = tuple(s.name or f"session {k + 1}" for k, s in enumerate(sessions))
    ys = [as_signal(s.y, f"{name}: the record") for s, name in zip(sessions, names)]
    channels = [as_channels(s.channels, list(s.channels or {}), len(y))
                for s, y in zip(sessions, ys)]
    for name, ch in zip(names[1:], channels[1:]):
        if sorted(ch) != sorted(channels[0]):
            first = ", ".join(sorted(channels[0])) or "none"
            raise InputError(f"{name}: its channels ({', '.join(sorted(ch)) or 'none'}) are "
                             f"not those of {names[0]} ({first})")
    bounds = np.cumsum([0, *(len(y) for y in ys)])
    spans = tuple(slice(int(a), int(b)) for a, b in zip(bounds[:-1], bounds[1:]))
    record = LoopRecord(np.concatenate(ys), {k: np.concatenate([c[k] for c in channels])
                                             for k in channels[0]}, config.rate, spans, names)
    return record, names


def _parts(record: LoopRecord, config: LoopConfig, head: int) -> tuple:
    """Each session's deciding and predicted parts, where it is judged and reported."""
    decide, predict, judged, reported = [], [], [], []
    horizons = (config.eval_horizon_s, *config.horizons_s)
    for s, name in zip(record.sessions, record.names):
        n = s.stop - s.start
        cut = round((config.train + config.evaluate) * n)
        judged_part = slice(head, cut)
        if head <= config.max_lag + 10 or cut - head < 3 * round(config.eval_horizon_s
                                                                 * config.rate):
            raise InputError(f"{name} ({n} samples, {n / config.rate:.6g} s) is too short: its "
                             f"first {config.head_s:g} s give its constant, and the "
                             f"{config.train + config.evaluate:g} of it that decides must hold "
                             f"three {config.eval_horizon_s:g} s outages after them")
        decide.append(slice(s.start, s.start + cut))
        predict.append(slice(s.start + cut, s.stop))
        judged.append(plan(judged_part, horizons, config.rate, config.n_starts, name, 1))
        reported.append(plan(slice(cut, n), config.horizons_s, config.rate, config.n_starts,
                             f"{name} predicted", REPORT_WINDOWS))
    pooled = {h: sum(len(p.horizons[h][0]) if h in p.horizons else 0 for p in judged)
              for h in horizons}
    for p in judged:
        for h, count in pooled.items():
            if count < MIN_WINDOWS:
                p.horizons.pop(h, None)
                p.skipped[h] = (f"the sessions hold {count} {h:g} s windows to judge, fewer "
                                f"than {MIN_WINDOWS}")
    return tuple(decide), predict, judged, reported


def _ahead(record: LoopRecord, config: LoopConfig, judged: list[Plan], head: int) -> Ahead:
    """Return the fitter on each session's first ``train`` of it, and the plans from there.

    The horizons are those judged over the sessions, each where the session's part ahead
    holds a window of it.
    """
    fit, plans = [], []
    for s, p, name in zip(record.sessions, judged, record.names):
        origin = max(head, round(config.train * (s.stop - s.start)))
        fit.append(slice(s.start, s.start + origin))
        plans.append(plan(slice(origin, p.segment.stop), tuple(p.horizons), config.rate,
                          config.n_starts, f"{name} ahead", 1))
    return Ahead(SessionFitter(record, tuple(fit), config), plans)


def _scores(fitter: SessionFitter, model: BoundModel, reported: list[Plan],
            config: LoopConfig) -> list[Scores]:
    """Each session's predicted errors, the model with that session's own constant."""
    out = []
    for k, where in enumerate(reported):
        bound = fitter.session(model, k)
        y = fitter.record.y[fitter.record.sessions[k]]
        out.append(scores(bound, y, where, config))
    return out


def _pool_scores(parts: list[Scores]) -> Scores:
    """Return the sessions' scores together: their errors and windows end to end."""
    horizons = sorted(set.intersection(*(set(p.outages) for p in parts))) if parts else []
    outages = {}
    for h in horizons:
        got = [p.outages[h] for p in parts]
        position = None if any(o.position is None for o in got) else np.concatenate(
            [o.position for o in got if o.position is not None])
        outages[h] = Outages(h, np.concatenate([o.bias for o in got]),
                             np.concatenate([o.mse for o in got]), position)
    return replace(parts[0], errors=np.concatenate([p.errors for p in parts]), outages=outages)


def _notes(record: LoopRecord, diagnose: Diagnostics, fitter: SessionFitter,
           family: CandidateFamily, roles: Roles, judged: list[Plan],
           names: tuple[str, ...]) -> list[str]:
    """Return the notes of the sessions' report.

    Drivers that follow the slow residual but do not vary where fitted, or follow time
    there; horizons left out.
    """
    target = fitter.target(family)
    driven = set(channels_read([*family.compensation, *family.exog_lags]))
    out = [text for ch in roles.slow if ch not in driven
           for text in [still(record, diagnose.forms, ch, target)] if text]
    out += trend_note(record, diagnose.fit, roles, diagnose.config)
    skipped = {h: why for p in judged for h, why in p.skipped.items()
               if "the sessions hold" in why}
    out += [f"the {h:g} s horizon is not judged: {why}" for h, why in skipped.items()]
    return out

"""One round of the residual loop: every candidate judged, and the one that goes in.

Slow errors are mostly stochastic, and the forms of a slow error differ in how
they run on beyond the data: a level holds still, a driver runs only as its
measured cause does, a function of time runs on regardless.  So an effect
that ``waits_for`` a kind (a drift, a step wait for the level and the drivers)
is held back while one of that kind is accepted in the same round, and tried
again in the next on top of what went in, whether or not its test still fires.
A function of time fitted on one stretch is an extrapolation.

:func:`run_rounds` is the loop over rounds, one driver for one record and for several
sessions: what differs between them (where the effects are offered, how a trial is
judged, how a model is scored and diagnosed) is the :class:`Layout` it is given.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

from ..models.bound import BoundModel
from .config import LoopConfig
from .diagnose import Finding
from .effects import CandidateFamily, Effect, Offer, effects_from
from .judge import Judgement
from .record import LoopRecord
from .roles import Roles
from .scores import Scores

Progress = Callable[[str], None]
#: Fewest windows of a horizon a prediction segment (or a session's predicted part) must
#: hold for it to be reported (its interval needs
#: :data:`fosmodel.loop.judge.MIN_INTERVAL_WINDOWS`; fewer read "undetermined").
REPORT_WINDOWS = 2
#: How a trial is judged: its model, its family and its effect give its judgement.
Judges = Callable[[BoundModel, CandidateFamily, Effect], Judgement]


class Fits(Protocol):
    """What fits a candidate family.

    One record's :class:`~fosmodel.loop.fitting.Fitter`, or the sessions'
    :class:`~fosmodel.loop.sessions.SessionFitter`.
    """

    def fit(self, family: CandidateFamily) -> BoundModel:
        """Return the family's model fitted on the fitting data."""
#: Kass and Raftery: a BIC difference of 6 or more is strong evidence.
STRONG_BIC = 6.0


@dataclass(frozen=True)
class Trial:
    """A candidate effect, its family and model (None once rejected), and its judgement."""

    effect: Effect
    family: CandidateFamily | None
    model: BoundModel | None
    judgement: Judgement


@dataclass(frozen=True)
class Rejected:
    """A candidate that did not go in: the round, the effect and its judgement."""

    round: int
    effect: Effect
    judgement: Judgement

    def to_dict(self) -> dict:
        """Return the entry of ``rejected`` in the loop's JSON."""
        return {"effect": self.effect.describe(), "kind": self.effect.kind, "round": self.round,
                "evidence": self.effect.evidence, "evaluation": self.judgement.to_dict()}


def run_round(fitter: Fits, judge: Judges, family: CandidateFamily, candidates: list[Effect],
              record: LoopRecord, say: Progress, number: int,
              ) -> tuple[Trial | None, list[Rejected], list[Effect]]:
    """Fit and judge each candidate on top of the current model; choose the one that goes in.

    Returns the chosen trial or None, the rejected candidates (``number`` is the round's)
    and the effects that wait for the next round: those held back, and those accepted but
    not chosen, which are tried again on top of it.  A rejected trial's model and columns
    live only while it is judged.
    """
    trials = []
    for i, effect in enumerate(candidates, 1):
        clock = time.perf_counter()
        trial_family = family.add(effect, record)
        model = fitter.fit(trial_family)
        judgement = judge(model, trial_family, effect)
        trials.append(Trial(effect, trial_family, model, judgement) if judgement.accepted
                      else Trial(effect, None, None, judgement))
        del trial_family, model  # now, not when the next trial's columns are already made
        say(f"  [{i}/{len(candidates)}] {effect.describe()}: {verdict_text(judgement)} "
            f"({time.perf_counter() - clock:.1f} s)")
    kept, waiting, held = screen(trials)
    rejected = [Rejected(number, t.effect, t.judgement) for t in [*held, *(
        t for t in trials if not t.judgement.accepted)]]
    if not kept:
        return None, rejected, waiting
    chosen = choose(kept)
    return chosen, rejected, waiting + [t.effect for t in kept if t is not chosen]


def screen(trials: list[Trial]) -> tuple[list[Trial], list[Effect], list[Trial]]:
    """Return the accepted trials that may go in, the effects that wait, and those held back.

    An accepted effect waits while an effect of a kind it ``waits_for`` is accepted in the
    same round; its judgement then says why.
    """
    accepted = {t.effect.kind for t in trials if t.judgement.accepted}
    kept, waiting, held = [], [], []
    for t in trials:
        if not t.judgement.accepted:
            continue
        rivals = [k for k in t.effect.waits_for if k in accepted]
        if rivals:
            reason = f"waits for {' and '.join(_kind_words(rivals))}: tried again on top of it"
            held.append(Trial(t.effect, None, None, t.judgement.held_back(reason)))
            waiting.append(t.effect)
        else:
            kept.append(t)
    return kept, waiting, held


def _kind_words(kinds: list[str]) -> list[str]:
    return [{"level": "the level", "driver": "a driver"}.get(k, f"a {k}") for k in kinds]


def choose(kept: list[Trial]) -> Trial:
    """Which kept candidate goes in first: the largest out-of-sample gain.

    The gain is that of the comparison it was kept on, averaged over the origins that
    judged every one of them (an origin that could not judge one, a step after it or a
    driver its past does not show, would compare a gain far from its data with one next
    to it); ties go to the larger t statistic.  Evidence and out-of-sample gain decide,
    not a fixed order of kinds.  A drift and a step, which look alike over a short
    stretch, are told apart by their fit to the residual when it is strongly better (BIC
    difference of :data:`STRONG_BIC` or more).
    """
    common = sorted(set.intersection(*(t.judgement.judged_from() for t in kept)))
    best = max(kept, key=lambda t: t.judgement.score(common))
    pair = {"drift": "step", "step": "drift"}
    if best.effect.kind in pair:
        other = [t for t in kept if t.effect.kind == pair[best.effect.kind]]
        if other:
            bic = {t.effect.kind: t.effect.evidence["evidence"]["bic_gain"]
                   for t in (best, other[0])}
            if abs(bic["drift"] - bic["step"]) >= STRONG_BIC:
                return max((best, other[0]), key=lambda t: bic[t.effect.kind])
    return best


def verdict_text(judgement: Judgement) -> str:
    """Return a trial's verdict in a line: kept on what, and the gains at the end."""
    head = (f"kept on {judgement.at(judgement.kept_on).label}: " if judgement.kept_on
            else "rejected: ")
    parts = []
    for c in judgement.last:
        text = f"{c.label} gain {c.gain:+.2%}"
        earlier = judgement.gains(c.key)[:-1] if judgement.earlier is not None else []
        if earlier:
            text += " (from earlier origins " + ", ".join(
                "-" if g is None else f"{g:+.1%}" for g in earlier) + ")"
        parts.append(text)
    return head + ", ".join(parts)


@dataclass
class Step:
    """One effect the loop kept: what it was, what the fit chose, why, and the errors after.

    ``chosen`` holds what the fit chose of it (a channel's dead time ``lag``, a level's
    time constant ``tau_s``); ``predict`` the predicted errors after it, pooled over the
    sessions, and ``sessions`` each session's (empty on one record).
    """

    effect: Effect
    terms_added: list[str]
    chosen: dict[str, Any]
    judgement: Judgement
    predict: Scores
    sessions: list[Scores] = field(repr=False, default_factory=list)

    @property
    def lag(self) -> int | None:
        """A channel's dead time: the lag of its first selected term."""
        return self.chosen.get("lag")

    @property
    def tau_s(self) -> float | None:
        """A level's time constant (its first selected level), or a drift's warm-up."""
        return self.chosen.get("tau_s")


class Layout(Protocol):
    """What the round driver asks of the data: one record's, or several sessions'.

    ``fit`` is where the effects are fitted and offered (the fitting segment, or each
    session's deciding part), ``fitter`` fits a family there.
    """

    @property
    def fitter(self) -> Fits:
        """What fits a candidate family where the effects are fitted."""

    @property
    def fit(self) -> tuple[slice, ...]:
        """Where the effects are fitted and offered."""

    def offered(self, cls: type[Effect]) -> bool:
        """Say whether the kind ``cls`` may be offered (several sessions: the pooled ones)."""

    def round_line(self, number: int, count: int) -> str:
        """Return the progress line of a round of ``count`` candidates."""

    def judge(self, current: BoundModel, family: CandidateFamily,
              added: Sequence[Effect]) -> Judges:
        """Return the judge of a round on top of ``current``, whose effects are ``added``."""

    def scores(self, model: BoundModel) -> tuple[Scores, list[Scores]]:
        """Return the model's predicted errors: pooled, and each session's (or none)."""

    def findings(self, model: BoundModel, family: CandidateFamily) -> list[Finding]:
        """Return the diagnostics of the model's residual where it was fitted."""

    def forget(self, family: CandidateFamily) -> None:
        """Drop what only other families than ``family`` read."""


@dataclass
class Rounds:
    """What the rounds did: the kept steps, the rejected, the final model and its findings."""

    steps: list[Step]
    rejected: list[Rejected]
    findings_before: list[Finding]
    findings_after: list[Finding]
    final_model: BoundModel
    family: CandidateFamily


def run_rounds(layout: Layout, record: LoopRecord, roles: Roles, config: LoopConfig,
               taus: tuple[float, ...], base: BoundModel, family: CandidateFamily,
               say: Progress) -> Rounds:
    """Run the loop's rounds from ``base``: offer, judge, keep the best, until none survives.

    Each round offers the effects the fired findings point to, with those that wait
    from the round before (none that is in already), and runs :func:`run_round`; it
    stops when none is left, none is kept or ``config.max_effects`` are in.
    """
    current = base
    findings = findings_before = layout.findings(current, family)
    steps: list[Step] = []
    rejected: list[Rejected] = []
    added: list[Effect] = []
    waiting: list[Effect] = []
    while len(steps) < config.max_effects:
        offer = Offer(findings, record, layout.fit, roles, config, family, taus)
        found = effects_from(offer, keep=layout.offered)
        candidates = [e for e in [*found, *(w for w in waiting
                                            if not any(w.same_as(f) for f in found))]
                      if not any(e.same_as(a) for a in added)]
        if not candidates:
            break
        say(layout.round_line(len(steps) + 1, len(candidates)))
        judge = layout.judge(current, family, added)
        chosen, refused, waiting = run_round(layout.fitter, judge, family, candidates, record,
                                             say, len(steps) + 1)
        rejected += refused
        if chosen is None or chosen.family is None or chosen.model is None:
            break
        pooled, each = layout.scores(chosen.model)
        steps.append(Step(chosen.effect, [t for t in chosen.model.model.terms_
                                          if t not in set(current.model.terms_)],
                          chosen.effect.chosen(chosen.model), chosen.judgement, pooled, each))
        added.append(chosen.effect)
        current, family = chosen.model, chosen.family
        layout.forget(family)
        say(f"kept {chosen.effect.describe()}")
        findings = layout.findings(current, family)
    return Rounds(steps, rejected, findings_before, findings, current, family)

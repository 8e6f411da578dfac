"""Close the loop: fit, read the residual, add the effect it points to, refit, report.

The record is split in time into a fitting segment, an evaluation segment and
a prediction segment (by default 50 / 20 / 30 %).  Starting from a linear FOS
model of the output's own lags:

1. the residual over the fitting segment goes through every test
   (:mod:`fosmodel.loop.findings`);
2. each fired test offers the effects of its kind (:mod:`fosmodel.loop.effects`);
   the other channels by their role (:mod:`fosmodel.loop.roles`): a driver's
   slow and fast parts, a companion only when asked;
3. each candidate's terms are added to the FOS candidate set, the model refit
   on the fitting segment, and judged out of sample (:mod:`fosmodel.loop.judge`)
   at each outage length the evaluation segment holds;
4. of the candidates kept, the one with the largest out-of-sample gain goes in;
   the others (and those that wait) are tried again on top of it
   (:mod:`fosmodel.loop.rounds`);
5. repeat until no test points to an effect that survives, or ``max_effects``.

The prediction segment is never used to decide; it gives the before/after
numbers of the report at each outage length it holds, each ratio with its
confidence interval (:mod:`fosmodel.loop.intervals`), and says so when an
effect made one of them worse.
"""

from __future__ import annotations

import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, cast, overload

import numpy as np
from numpy.typing import ArrayLike

from ..core.derived import channels_read
from ..core.exceptions import InputError
from ..core.levels import levels_for
from ..core.validation import as_channels, as_signal
from ..io.split import Split
from ..models.bound import BoundModel
from .config import LoopConfig
from .diagnose import Finding
from .driver_forms import MIN_BLOCKS, still
from .effects import CandidateFamily, Effect
from .effects.drift import trend_note
from .findings import Diagnostics, residual
from .fitting import Fitter, Judge
from .intervals import Ratio, ratios
from .judge import MIN_WINDOWS
from .outcome import LoopOutcome
from .record import LoopRecord
from .roles import Roles, channel_roles
from .rounds import REPORT_WINDOWS, Progress, Rejected, Step, run_rounds
from .scores import Plan, Scores, plan, scores

if TYPE_CHECKING:
    from .sessions import Session, SessionsResult


@dataclass
class LoopResult(LoopOutcome):
    """Everything the loop did.

    ``before_scores``/``after_scores`` are the prediction-segment errors of the starting
    and the final model (:attr:`before`/:attr:`after` their numbers); ``steps`` the kept
    effects in order; ``rejected`` the candidates that did not go in; ``findings_before``
    and ``findings_after`` the diagnostics of the first and the last model; ``judged`` and
    ``reported`` where the evaluation and the prediction segment were read (the horizons
    kept and why others were not); ``notes`` what the report must say besides.
    """

    config: LoopConfig
    segments: Split
    roles: Roles
    before_scores: Scores
    after_scores: Scores
    steps: list[Step]
    rejected: list[Rejected]
    findings_before: list[Finding]
    findings_after: list[Finding]
    base_model: BoundModel
    final_model: BoundModel
    judged: Plan
    reported: Plan
    residual_before: np.ndarray = field(repr=False)
    residual_after: np.ndarray = field(repr=False)
    level_taus: tuple[float, ...] = ()
    notes: list[str] = field(default_factory=list)

    @property
    def unexplained(self) -> list[str]:
        """Tests still firing at the end, but a companion's (cross-axis noise, not an effect)."""
        return [f.test + (f" {f.evidence['channel']}" if "channel" in f.evidence else "")
                for f in self.findings_after if f.fired and not self._companion(f)]

    def _companion(self, finding: Finding) -> bool:
        return finding.test == "aux" and finding.evidence["channel"] in self.roles.companions

    @property
    def cross_axis(self) -> list[dict[str, Any]]:
        """Each companion's correlation with the final residual: the cross-axis noise."""
        return [{"channel": f.evidence["channel"], "rho": f.evidence["rho"],
                 "lag": f.evidence["lag"], "p_value": f.p_value, "fired": f.fired,
                 "as_input": f.evidence["channel"] in self.roles.opted_in}
                for f in self.findings_after if self._companion(f)]

    def ratios(self) -> list[Ratio]:
        """Return every prediction-segment ratio of the final model to the starting one.

        Each with its interval (:mod:`fosmodel.loop.intervals`).
        """
        return ratios(self.before_scores, self.after_scores, self.config.confidence)

    def to_json_dict(self) -> dict[str, Any]:
        """``{"before", "after", "effects", ...}`` as the command line's JSON output holds it."""
        effects, previous = [], self.before_scores
        for step in self.steps:
            effects.append({**step.effect.to_dict(), **step.chosen,
                            "terms_added": step.terms_added,
                            "evaluation": step.judgement.to_dict(),
                            "mse_before": previous.mse, "mse_after": step.predict.mse})
            previous = step.predict
        found = self.ratios()
        return {"before": self.before.to_dict(), "after": self.after.to_dict(),
                "ratios": {r.key: r.to_dict() for r in found},
                "worse_on_prediction": [r.text() for r in found if r.verdict == "worse"],
                "effects": effects, "rejected": [r.to_dict() for r in self.rejected],
                "unexplained": self.unexplained, "cross_axis": self.cross_axis,
                "roles": {"drivers": list(self.roles.drivers),
                          "companions": list(self.roles.companions),
                          "companions_as_inputs": list(self.roles.opted_in),
                          "told": self.roles.told},
                "horizons_s": {"judged": sorted(self.judged.horizons),
                               "reported": sorted(self.reported.horizons),
                               "skipped": {f"{h:g}": why for h, why in
                                           {**self.judged.skipped,
                                            **self.reported.skipped}.items()}},
                "level_taus_offered": list(self.level_taus), "notes": self.notes,
                "segments_s": {k: [s.start / self.config.rate, s.stop / self.config.rate]
                               for k, s in self.segments.items()}}


@overload
def close_loop(y: ArrayLike, channels: Mapping[str, ArrayLike] | None, config: LoopConfig,
               progress: Progress | None = None) -> LoopResult: ...
@overload
def close_loop(y: Sequence[Session], channels: None, config: LoopConfig,
               progress: Progress | None = None) -> SessionsResult: ...
def close_loop(
    y: ArrayLike | Sequence[Session], channels: Mapping[str, ArrayLike] | None,
    config: LoopConfig, progress: Progress | None = None,
) -> LoopResult | SessionsResult:
    """Run the residual loop on a record.

    Parameters
    ----------
    y : array-like
        The modelled sensor column.
    channels : mapping of str to array-like, optional
        Other columns of the record, each as long as ``y``: drivers that may explain the
        residual (temperature, another sensor's specific force) and companions (the other
        axes of the same IMU and kind, channels that measure the motion), told apart by
        :func:`fosmodel.loop.roles.channel_roles`.
    config : LoopConfig
    progress : callable, optional
        Called with a line of text as each model is fitted and each effect tried.

    Returns
    -------
    LoopResult
        Or, given a sequence of :class:`fosmodel.loop.sessions.Session` as ``y`` (with
        ``channels`` None), the :class:`~fosmodel.loop.sessions.SessionsResult` of
        :func:`fosmodel.loop.sessions.close_sessions`.
    """
    from .sessions import Session, close_sessions

    if isinstance(y, (list, tuple)) and y and all(isinstance(s, Session) for s in y):
        if channels is not None:
            raise InputError("sessions carry their own channels: give channels=None")
        return close_sessions(y, config, progress)
    say = progress or (lambda _: None)
    y = as_signal(cast(ArrayLike, y), "the record")  # not sessions: checked above
    channels = as_channels(channels, list(channels or {}), len(y))
    roles = channel_roles(channels, config.sensor, config.companions, config.aux)
    record = LoopRecord.single(y, channels, config.rate)
    segments = loop_split(len(y), config)
    judged = judge_plan(segments.evaluate, config)
    reported = plan(segments.predict, config.horizons_s, config.rate, config.n_starts,
                    "prediction", REPORT_WINDOWS)
    fitter = Fitter(record, segments.train, config)
    taus = config.level_taus if config.level_taus is not None else levels_for(
        y[segments.train], config.rate)
    clock = time.perf_counter()
    family = CandidateFamily(config.max_lag)
    base = fitter.fit(family)
    say(f"starting model: {len(base.model.terms_)} terms ({time.perf_counter() - clock:.1f} s)")
    layout = OneRecord(fitter, Diagnostics(record, (slice(0, segments.train.stop),), roles,
                                           config), judged, reported)
    done = run_rounds(layout, record, roles, config, tuple(taus), base, family, say)
    steps, current = done.steps, done.final_model
    stop = segments.train.stop
    before = scores(base, y, reported, config)
    return LoopResult(config, segments, roles, before, steps[-1].predict if steps else before,
                      steps, done.rejected, done.findings_before, done.findings_after, base,
                      current, judged, reported, residual(base, y, stop),
                      residual(current, y, stop), tuple(taus),
                      notes(record, layout.diagnose, done.family, judged, reported, roles)
                      + judged_notes(steps))


class OneRecord:
    """One record's part in the round driver (:class:`fosmodel.loop.rounds.Layout`).

    Effects are fitted and offered on the fitting segment, judged on the evaluation
    segment from several origins (:class:`~fosmodel.loop.fitting.Judge`), scored on the
    prediction segment.
    """

    def __init__(self, fitter: Fitter, diagnose: Diagnostics, judged: Plan,
                 reported: Plan) -> None:
        self.fitter, self.diagnose, self.judged, self.reported = fitter, diagnose, judged, reported
        self.fit = (fitter.train,)

    def offered(self, cls: type[Effect]) -> bool:
        """Every kind is offered on one record."""
        return True

    def round_line(self, number: int, count: int) -> str:
        """Say the round's number and how many effects it tries."""
        return f"round {number}: {count} effect(s) to try"

    def judge(self, current: BoundModel, family: CandidateFamily,
              added: Sequence[Effect]) -> Judge:
        """Return the round's judge on top of ``current``."""
        return Judge(self.fitter, current, family, self.judged, added)

    def scores(self, model: BoundModel) -> tuple[Scores, list[Scores]]:
        """Return the model's prediction-segment errors (no sessions)."""
        return scores(model, self.fitter.record.y, self.reported, self.fitter.config), []

    def findings(self, model: BoundModel, family: CandidateFamily) -> list[Finding]:
        """Return the diagnostics of the model's residual over the fitting segment."""
        return self.diagnose(model, family)

    def forget(self, family: CandidateFamily) -> None:
        """Drop what only other families read."""
        self.fitter.forget(family)


def judge_plan(segment: slice, config: LoopConfig) -> Plan:
    """Where the judge reads the evaluation segment: the short outage and each horizon.

    The short outage is ``eval_horizon_s``, or shorter so that the segment holds
    :data:`fosmodel.loop.judge.MIN_WINDOWS` of it (a short record is still judged on the
    bias between updates); each horizon is judged where the segment holds that many.
    """
    length_s = (segment.stop - segment.start) / config.rate
    short = min(config.eval_horizon_s, max(length_s / MIN_WINDOWS, 1.0 / config.rate))
    return plan(segment, (float(f"{short:.3g}"), *config.horizons_s), config.rate,
                config.n_starts, "evaluation")


def notes(record: LoopRecord, diagnose: Diagnostics, family: CandidateFamily, judged: Plan,
          reported: Plan, roles: Roles) -> list[str]:
    """Return what the report must say besides its tables.

    Drivers that follow the slow residual but do not vary in the fitting segment, those
    that follow time there (no trend in time is offered), the horizons left out and why,
    how the roles were told.
    """
    comp = family.compensation_series()
    target = record.y if comp is None else record.y - comp
    out = [text for ch in roles.slow if ch not in _driven(family)
           for text in [still(record, diagnose.forms, ch, target)] if text]
    out += trend_note(record, diagnose.fit, roles, diagnose.config)
    out += [first_note(ch, diagnose.fit, diagnose.config) for ch in roles.slow
            if ch in diagnose.first]
    out += [f"the {h:g} s horizon is not judged: {why}" for h, why in judged.skipped.items()]
    out += [f"the {h:g} s horizon is not reported: {why}" for h, why in reported.skipped.items()]
    if roles.companions:
        out.append(f"channels by role: {roles.describe()}")
    return out


def first_note(channel: str, fit: tuple[slice, ...], config: LoopConfig) -> str:
    """Say that a driver was tested as the short record asks, and the length that does not."""
    fit_s = sum(s.stop - s.start for s in fit) / config.rate
    least = MIN_BLOCKS * config.slow_s
    return (f"{channel} runs as time does over the {fit_s:.4g} s of fitting data, shorter than "
            f"the {least:g} s ({MIN_BLOCKS} blocks of {config.slow_s:g} s) over which a driver "
            f"is told from a trend in time: its slow part goes first, tested without a trend "
            f"as its rival too (at level {config.alpha ** 2:g}), and a trend in time waits for "
            f"it; with fitting data of {least:g} s or more (a record of "
            f"{least / config.train:g} s at this split) it is tested beside a trend")


def judged_notes(steps: list[Step]) -> list[str]:
    """Say of each kept effect judged otherwise than the rest how it was (an onset, a horizon)."""
    return [f"{s.effect.describe()}: {s.judgement.note}" for s in steps if s.judgement.note]


def _driven(family: CandidateFamily) -> set[str]:
    return set(channels_read([*family.compensation, *family.exog_lags]))


def score_family(
    y: ArrayLike, channels: Mapping[str, ArrayLike] | None, config: LoopConfig,
    family: CandidateFamily,
) -> Scores:
    """Prediction-segment numbers of a candidate family fit on the record's fitting segment.

    With the effects a user knows to be there, this is the yardstick of what the
    loop recovers (same segments, same starting lags).
    """
    y = as_signal(y, "the record")
    channels = as_channels(channels, list(channels or {}), len(y))
    segments = loop_split(len(y), config)
    record = LoopRecord.single(y, channels, config.rate)
    model = Fitter(record, segments.train, config).fit(family)
    reported = plan(segments.predict, config.horizons_s, config.rate, config.n_starts,
                    "prediction", REPORT_WINDOWS)
    return scores(model, y, reported, config)


def loop_split(n: int, config: LoopConfig) -> Split:
    """Split ``n`` samples by ``config``'s fractions into the loop's three segments.

    Raises
    ------
    InputError
        If a segment is too short for the fit, the evaluation's outages or the prediction's
        outages at the shortest horizon.
    """
    a, b = Split.fraction_bounds(n, config.train, config.evaluate)
    need_eval = 3 * round(config.eval_horizon_s * config.rate)
    shortest = min(config.horizons_s)
    need_pred = REPORT_WINDOWS * round(shortest * config.rate)
    if a <= config.max_lag + 10 or b - a < need_eval or n - b < need_pred:
        raise InputError(
            f"the record ({n} samples, {n / config.rate:.6g} s at {config.rate:g} Hz) is too "
            f"short for the split {config.train:g} / {config.evaluate:g}: the evaluation "
            f"segment needs {need_eval} samples (three outages of "
            f"{config.eval_horizon_s:g} s) and the prediction segment {need_pred} "
            f"({REPORT_WINDOWS} outages of {shortest:g} s)")
    return Split.by_fraction(n, config.train, config.evaluate)

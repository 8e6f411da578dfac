"""Close the loop: fit, read the residual, add the effect it points to, refit, report.

The record is split in time into a fitting segment, an evaluation segment and
a prediction segment (by default 50 / 20 / 30 %).  Starting from a linear FOS
model of the output's own lags:

1. the residual over the fitting segment goes through every test of
   :mod:`fosmodel.loop.diagnose` (the periodic and nonlinearity tests on its fast
   part, so that a wandering bias is not taken for either);
2. each fired test gives a candidate effect (:func:`fosmodel.loop.effects.effects_from`);
   any slow test (trend, step, Allan) also offers the *local level*, the
   wandering bias as a stochastic level (:mod:`fosmodel.core.levels`);
3. each candidate's terms are added to the FOS candidate set, the model refit
   on the fitting segment, and judged out of sample (:mod:`fosmodel.loop.judge`):
   on the evaluation segment, from the end of the fitting segment and from
   earlier origins; a deterministic drift or step must also beat the level;
4. of the candidates kept, the one with the largest out-of-sample gain goes in;
   the others (and the slow ones that wait for the level) are tried again on
   top of it;
5. repeat until no test points to an effect that survives, or ``max_effects``.

The prediction segment is never used to decide; it gives the before/after
numbers of the report, and says so when an effect made one of them worse.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.ndimage import uniform_filter1d

from ..core.candidates import Term
from ..core.exceptions import InputError
from ..core.levels import level_name, level_series, level_tau, levels_for
from ..core.validation import as_channels, as_signal
from ..io.split import Split
from ..models.bound import BoundModel
from ..models.model import FOSModel
from ..noise.metrics import equivalent_position_error, one_step_mse, outage_metrics, to_si_scale
from .diagnose import (
    AuxChannels,
    Finding,
    allan,
    aux_correlation,
    change_point,
    nonlinearity,
    periodic,
    trend,
    whiteness,
)
from .effects import CandidateFamily, Effect, effects_from
from .judge import Forecasts, compare, forecasts, outage_windows, passes, verdict

Progress = Callable[[str], None]


@dataclass(frozen=True)
class LoopConfig:
    """Settings of the residual loop.

    Parameters
    ----------
    rate : float
        Sample rate in Hz.
    sensor, units : str, optional
        For position errors (``accel``/``gyro`` and the record's units).
    max_lag : int
        L of the starting model.
    train, evaluate : float
        Fractions of the record for fitting and for evaluation; the rest is predicted.
    alpha : float
        Level of each diagnostic test.
    accept_alpha : float
        Level of the evaluation-segment test that keeps an effect.
    max_effects : int
        Most effects added.
    aux_max_lag : int
        Lags 0..K of an auxiliary channel (tested and offered).
    nonlinear_lags : int
        Lags whose products the nonlinearity test uses.
    horizon_s, n_starts, taus
        Outage metrics of the report (prediction segment).
    eval_horizon_s : float
        Outage windows of the evaluation-segment test.
    fos_stop : str
        FOS stopping rule.
    origins : int
        Fit origins of the out-of-sample test, evenly spaced from half the
        fitting segment to its end (1: its end only).
    slow_s : float
        Time scale (s) separating slow errors (level, drift, steps) from fast
        ones: the periodic and nonlinearity tests look at the residual minus
        its moving mean over ``slow_s``, at frequencies above ``1 / slow_s``.
    level_taus : tuple of float, optional
        Time constants (s) of the level candidates; by default chosen from the
        fitting segment (:func:`fosmodel.core.levels.level_grid`).
    """

    rate: float
    sensor: str | None = None
    units: str | None = None
    max_lag: int = 10
    train: float = 0.5
    evaluate: float = 0.2
    alpha: float = 1e-3
    accept_alpha: float = 0.01
    max_effects: int = 5
    aux_max_lag: int = 10
    nonlinear_lags: int = 4
    horizon_s: float = 30.0
    eval_horizon_s: float = 5.0
    n_starts: int = 20
    taus: tuple[float, ...] = (1.0, 10.0, 30.0)
    fos_stop: str = "korenberg"
    origins: int = 4
    slow_s: float = 20.0
    level_taus: tuple[float, ...] | None = None

    def __post_init__(self) -> None:
        """Check every option.

        Raises
        ------
        InputError
            A rate, sensor, units, split, significance level or count out of range.
        """
        if not (np.isfinite(self.rate) and self.rate > 0):
            raise InputError(f"the sample rate must be positive, got {self.rate!r}")
        if (self.sensor is None) != (self.units is None):
            raise InputError("give both the sensor (accel or gyro) and its units, or neither")
        if self.sensor is not None and self.units is not None:
            to_si_scale(self.sensor, self.units)
        if not (0 < self.train < 1 and 0 < self.evaluate < 1 and self.train + self.evaluate < 1):
            raise InputError(f"the split {self.train:g} / {self.evaluate:g} must be two positive "
                             "fractions of the record adding up to less than 1")
        if isinstance(self.max_lag, bool) or int(self.max_lag) != self.max_lag or self.max_lag < 1:
            raise InputError(f"max_lag must be an integer >= 1, got {self.max_lag!r}")
        if isinstance(self.origins, bool) or int(self.origins) != self.origins \
                or self.origins < 1:
            raise InputError(f"origins must be an integer >= 1, got {self.origins!r}")


@dataclass
class Step:
    """One effect the loop kept: what it was, why, and the errors after it.

    ``lag`` is an auxiliary channel's dead time (the lag of its first selected
    term) and ``tau_s`` a level's time constant (its first selected level) or a
    drift's warm-up time constant.
    """

    effect: Effect
    terms_added: list[str]
    lag: int | None
    tau_s: float | None
    comparison: dict
    predict: dict


@dataclass
class LoopResult:
    """Everything the loop did.

    ``before``/``after`` are the prediction-segment metrics of the starting and the
    final model; ``steps`` the kept effects in order; ``rejected`` the candidates
    that did not survive the evaluation; ``findings_before`` and
    ``findings_after`` the diagnostics of the first and the last model, and
    ``unexplained`` the tests still firing at the end.
    """

    config: LoopConfig
    segments: Split
    before: dict
    after: dict
    steps: list[Step]
    rejected: list[dict]
    findings_before: list[Finding]
    findings_after: list[Finding]
    base_model: BoundModel
    final_model: BoundModel
    residual_before: np.ndarray = field(repr=False)
    residual_after: np.ndarray = field(repr=False)
    level_taus: tuple[float, ...] = ()

    @property
    def unexplained(self) -> list[str]:
        """Tests still firing at the end (an auxiliary channel's test by its channel)."""
        return [f.test + (f" {f.evidence['channel']}" if f.test == "aux" else "")
                for f in self.findings_after if f.fired]

    def worse(self, tolerance: float = 0.02) -> list[str]:
        """Prediction-segment numbers the final model made worse by more than ``tolerance``."""
        return worse_metrics(self.before, self.after, tolerance)

    def to_json_dict(self) -> dict:
        """``{"before", "after", "effects", ...}`` as ``fosmodel close-loop --json`` writes it."""
        effects, mse = [], self.before["mse"]
        for step in self.steps:
            e = step.effect
            effects.append({
                "kind": e.kind, "channel": e.channel, "lag": step.lag, "freq_hz": e.freq_hz,
                "time_s": e.time_s, "form": e.form, "tau_s": step.tau_s,
                "taus_offered": list(e.taus) if e.taus else None,
                "terms_added": step.terms_added,
                "evidence": {**e.evidence, "evaluation": step.comparison},
                "mse_before": mse, "mse_after": step.predict["mse"],
            })
            mse = step.predict["mse"]
        return {"before": self.before, "after": self.after, "effects": effects,
                "rejected": self.rejected, "unexplained": self.unexplained,
                "worse_on_prediction": self.worse(),
                "level_taus_offered": list(self.level_taus),
                "segments_s": {k: [s.start / self.config.rate, s.stop / self.config.rate]
                               for k, s in self.segments.items()}}


def worse_metrics(before: dict, after: dict, tolerance: float = 0.02) -> list[str]:
    """Return the metrics that ``after`` has more than ``1 + tolerance`` times ``before``'s.

    The metrics are the one-step MSE, the outage MSE and position error and the bias RMS at
    each tau.
    """
    pairs = [("one-step MSE", before["mse"], after["mse"]),
             ("outage MSE", before["outage_mse"], after["outage_mse"]),
             ("outage position error", before["outage_position_error_m"],
              after["outage_position_error_m"])]
    pairs += [(f"{t} s bias RMS", before["bias_rms"][t], after["bias_rms"][t])
              for t in before["bias_rms"]]
    return [f"{name} x{b / a:.3g}" for name, a, b in pairs
            if a is not None and b is not None and a > 0 and b > (1 + tolerance) * a]


def close_loop(
    y: ArrayLike, channels: Mapping[str, ArrayLike] | None, config: LoopConfig,
    progress: Progress | None = None,
) -> LoopResult:
    """Run the residual loop on a record.

    Parameters
    ----------
    y : array-like
        The modelled sensor column.
    channels : mapping of str to array-like, optional
        Other columns of the record that may explain the residual (temperature,
        another sensor), each as long as ``y``.
    config : LoopConfig
    progress : callable, optional
        Called with a line of text as each model is fitted and each effect tried.

    Returns
    -------
    LoopResult
    """
    say = progress or (lambda _: None)
    y = as_signal(y, "the record")
    channels = as_channels(channels, list(channels or {}), len(y))
    segments = loop_split(len(y), config)
    fitter = _Fitter(y, channels, segments, config)
    taus = config.level_taus if config.level_taus is not None else levels_for(
        y[segments.train], config.rate)
    clock = time.perf_counter()
    family = CandidateFamily(config.max_lag)
    current = base = fitter.fit(family)
    say(f"starting model: {len(base.model.terms_)} terms ({time.perf_counter() - clock:.1f} s)")
    diagnose = _Diagnostics(y, channels, segments, config)
    findings = findings_before = diagnose(current)
    residual_before = _residual(current, y, segments)
    steps: list[Step] = []
    rejected: list[dict] = []
    added: list[Effect] = []
    waiting: list[Effect] = []
    while len(steps) < config.max_effects:
        found = effects_from(findings, config.aux_max_lag, taus, config.slow_s)
        candidates = [e for e in [*found, *(w for w in waiting
                                            if not any(w.same_as(f) for f in found))]
                      if not any(e.same_as(a) for a in added)]
        if not candidates:
            break
        say(f"round {len(steps) + 1}: {len(candidates)} effect(s) to try")
        chosen, refused, waiting = _round(fitter, current, family, candidates, channels, y,
                                          segments, config, say, len(steps) + 1)
        rejected += refused
        if chosen is None:
            break
        effect, family, model, comparison = chosen
        steps.append(Step(effect, _new_terms(current, model), _lag_of(effect, model),
                          _tau_of(effect, model), comparison,
                          _metrics(model, y, segments.predict, config)))
        added.append(effect)
        current = model
        say(f"kept {effect.describe()}")
        findings = diagnose(current)
    return LoopResult(config, segments, _metrics(base, y, segments.predict, config),
                      _metrics(current, y, segments.predict, config), steps, rejected,
                      findings_before, findings, base, current, residual_before,
                      _residual(current, y, segments), tuple(taus))


def _round(fitter: _Fitter, current: BoundModel, family: CandidateFamily,
           candidates: list[Effect], channels: Mapping[str, np.ndarray], y: np.ndarray,
           segments: Split, config: LoopConfig, say: Progress,
           number: int) -> tuple[tuple | None, list[dict], list[Effect]]:
    """Fit and judge each candidate on top of ``current``, and choose the one that goes in.

    Returns the chosen ``(effect, family, model, comparison)`` or None, the rejected
    candidates' entries of :attr:`LoopResult.rejected` (``number`` is the round's) and the
    effects that wait for the next round: those :func:`_screen` holds back and those
    accepted but not chosen, which are tried again on top of it, firing or not.

    The trials' models and families (their columns are record-long) and the judge's
    forecasts from every origin live for the round only; a rejected trial's only while
    it is judged, unless :func:`_screen` may judge it again.
    """
    judge = _Judge(fitter, current, y, segments, config)
    trials: list[tuple] = []
    for i, effect in enumerate(candidates, 1):
        clock = time.perf_counter()
        trial_family = family.add(effect, channels, len(y), config.rate, segments.train)
        trial = fitter.fit(trial_family)
        comparison = judge(trial, effect)
        if comparison["accepted"] or _judged_again(effect):
            trials.append((effect, trial_family, trial, comparison))
        else:  # without its model and columns: nothing reads them again
            trials.append((effect, None, None, comparison))
        del trial_family, trial  # now, not when the next trial's columns are already made
        say(f"  [{i}/{len(candidates)}] {effect.describe()}: "
            f"{_verdict_text(trials[-1][3])} ({time.perf_counter() - clock:.1f} s)")
    kept, waiting = _screen(trials, judge)
    refused = [{"effect": effect.describe(), "kind": effect.kind, "round": number,
                "evidence": effect.evidence, "evaluation": comparison}
               for effect, _, _, comparison in trials if not any(k[0] is effect for k in kept)]
    if not kept:
        return None, refused, waiting
    chosen = _choose(kept)
    return chosen, refused, waiting + [k[0] for k in kept if k[0] is not chosen[0]]


def score_family(
    y: ArrayLike, channels: Mapping[str, ArrayLike] | None, config: LoopConfig,
    family: CandidateFamily,
) -> dict:
    """Prediction-segment metrics of a candidate family fit on the record's fitting segment.

    With the effects a user knows to be there, this is the yardstick of what the
    loop recovers (same segments, same starting lags).
    """
    y = as_signal(y, "the record")
    channels = as_channels(channels, list(channels or {}), len(y))
    segments = loop_split(len(y), config)
    model = _Fitter(y, channels, segments, config).fit(family)
    return _metrics(model, y, segments.predict, config)


def loop_split(n: int, config: LoopConfig) -> Split:
    """Split ``n`` samples by ``config``'s fractions into the loop's three segments.

    Raises
    ------
    InputError
        If a segment is too short for the fit, the evaluation's outages or the prediction's
        outage and bias windows.
    """
    a, b = Split.fraction_bounds(n, config.train, config.evaluate)
    need_eval = 3 * round(config.eval_horizon_s * config.rate)
    need_pred = max(round(config.horizon_s * config.rate) + 1,
                    2 * round(max(config.taus) * config.rate))
    if a <= config.max_lag + 10 or b - a < need_eval or n - b < need_pred:
        raise InputError(
            f"the record ({n} samples, {n / config.rate:.6g} s at {config.rate:g} Hz) is too "
            f"short for the split {config.train:g} / {config.evaluate:g}: the evaluation "
            f"segment needs {need_eval} samples (three {config.eval_horizon_s:g} s outages) and "
            f"the prediction segment {need_pred} (a {config.horizon_s:g} s outage and two "
            f"{max(config.taus):g} s bias windows)")
    return Split.by_fraction(n, config.train, config.evaluate)


class _Fitter:
    """Fits the FOS model of a candidate family on the fitting segment of one record.

    It also refits the weights of such a model on shorter pasts.

    The record's level series are computed once and passed with the inputs
    (a model would recompute them at every prediction and free run).
    """

    def __init__(self, y: np.ndarray, channels: Mapping[str, np.ndarray], segments: Split,
                 config: LoopConfig) -> None:
        self.y, self.channels, self.config = y, channels, config
        self.train = segments.train
        self._levels: dict[str, np.ndarray] = {}

    def levels(self, taus: tuple[float, ...]) -> dict[str, np.ndarray]:
        for tau in taus:
            name = level_name(tau)
            if name not in self._levels:
                self._levels[name] = level_series(self.y, tau, self.config.rate)
        return {level_name(tau): self._levels[level_name(tau)] for tau in taus}

    def fit(self, family: CandidateFamily) -> BoundModel:
        inputs = {**family.inputs, **family.columns, **self.levels(family.levels)}
        model = FOSModel(max_lag=family.max_lag, degree=family.degree,
                         exog_lags=dict(family.exog_lags), columns=list(family.columns),
                         levels=list(family.levels), rate=self.config.rate,
                         product_lags=family.product_lags, stop=self.config.fos_stop)
        model.fit(self.y[self.train], {k: v[self.train] for k, v in inputs.items()})
        return BoundModel(model, inputs)

    def refit(self, bound: BoundModel, stop: int) -> BoundModel:
        """``bound`` with its weights fitted on the samples before ``stop``."""
        past = {k: v[:stop] for k, v in bound.inputs.items()}
        return BoundModel(bound.model.refit_weights(self.y[:stop], past), bound.inputs)


class _Judge:
    """Judges trial models against the current one out of sample (:mod:`fosmodel.loop.judge`).

    The current model's refits and forecasts from every origin are computed once
    per round.  An origin from which a trial's new terms cannot be estimated (a
    step after it: the refit drops them) cannot judge it, and is left out.
    """

    def __init__(self, fitter: _Fitter, current: BoundModel, y: np.ndarray, segments: Split,
                 config: LoopConfig) -> None:
        self.fitter, self.y, self.config = fitter, y, config
        self.segment = segments.evaluate
        self.horizon = round(config.eval_horizon_s * config.rate)
        self.starts = outage_windows(self.segment, self.horizon)
        end = segments.train.stop
        self.origins = np.unique(np.linspace(end / 2, end, config.origins).round().astype(int))
        if len(self.origins) > 1 and self.origins[0] <= max(4 * config.max_lag, 100):
            self.origins = self.origins[-1:]  # too short a past to refit on
        self.refits = [self._refit(current, o) for o in self.origins]
        self.current = [self._forecasts(m) for m in self.refits]

    def _refit(self, model: BoundModel, origin: int) -> BoundModel:
        return model if origin == self.origins[-1] else self.fitter.refit(model, int(origin))

    def _forecasts(self, model: BoundModel) -> Forecasts:
        return forecasts(model, self.y, self.segment, self.starts, self.horizon)

    def _earlier(self, trial: BoundModel, origin: int, current: BoundModel,
                 base: Forecasts) -> dict | None:
        refit = self._refit(trial, origin)
        if set(refit.model.terms_) <= set(current.model.terms_):  # nothing new estimable
            return None
        return compare(base, self._forecasts(refit), self.config.accept_alpha)

    def __call__(self, trial: BoundModel, effect: Effect, all_origins: bool = False) -> dict:
        """Judge ``trial``: compare it at the fitting segment's end and from earlier origins.

        The result holds the comparison at the end, the gains from the earlier origins and
        the verdict (``"kept_on"``: the error kind it is kept on, or None).

        Every effect but the level is judged strictly (:func:`fosmodel.loop.judge.verdict`):
        the halves of the segment and every earlier origin catch a function of time
        that runs on, while a level holds still beyond its data, as the model
        without it does, and its bias gains are the noisiest.  The earlier origins
        are looked at only for a trial that passes at the end (or with
        ``all_origins``); otherwise their gains are None.
        """
        alpha, halves = self.config.accept_alpha, effect.kind != "level"
        last = compare(self.current[-1], self._forecasts(trial), alpha)
        out = dict(last)
        out["origins_s"] = [float(o / self.config.rate) for o in self.origins]
        if not (passes(last, halves) or all_origins):
            out.update(one_step_gain_origins=None, outage_gain_origins=None, kept_on=None,
                       accepted=False)
            return out
        found = [self._earlier(trial, o, m, f) for o, m, f in
                 zip(self.origins[:-1], self.refits[:-1], self.current[:-1])] + [last]
        for name in ("one_step", "outage"):
            out[f"{name}_gain_origins"] = [None if f is None else f[f"{name}_gain"]
                                           for f in found]
        out["kept_on"] = verdict(last, [f for f in found[:-1] if f is not None], alpha, halves)
        out["accepted"] = out["kept_on"] is not None
        return out


def _verdict_text(comparison: dict) -> str:
    parts = []
    for name, label in (("outage", "outage"), ("one_step", "one-step")):
        text = f"{label} gain {comparison[f'{name}_gain']:+.2%}"
        if comparison[f"{name}_gain_origins"]:
            text += " (from earlier origins " + ", ".join(
                "-" if g is None else f"{g:+.1%}"
                for g in comparison[f"{name}_gain_origins"][:-1]) + ")"
        parts.append(text)
    head = (f"kept on {comparison['kept_on'].replace('_', '-')}: " if comparison["accepted"]
            else "rejected: ")
    return head + ", ".join(parts)


def _screen(trials: list[tuple], judge: _Judge) -> tuple[list[tuple], list[Effect]]:
    """Return the accepted trials that may go in this round, and the effects that wait.

    Those that wait are tried in the next round; the others' comparisons say why not.

    Slow errors are mostly stochastic, and the forms of a slow error differ in
    how they run on beyond the data: a level holds still, a channel runs only
    as its cause does, a function of time runs on regardless.  So a function
    of time (a drift, a step) waits while the level or a channel is accepted
    in the round, and a channel with its slow part (its full form) waits for
    an accepted level unless it beats it clearly: from every origin it
    removes at least :data:`SLOW_MARGIN` of the outage error the level leaves.
    What waits is tried again in the next round, on top of what went in,
    whether or not its test still fires.  A channel's full form must also beat
    its own fast form clearly.  A slow relation between two sensors' wanders
    can hold over the evaluation and break the next hour, and a function of
    time fitted on one stretch is an extrapolation.
    """
    by_key = {(t[0].kind, t[0].channel, t[0].form): t for t in trials}

    def gains(key: tuple) -> list[float]:
        effect, _, model, comparison = by_key[key]
        if comparison["outage_gain_origins"] is None:  # rejected early: judge every origin
            comparison.update({k: v for k, v in judge(model, effect, all_origins=True).items()
                               if k.endswith("_origins")})
        return comparison["outage_gain_origins"]

    def accepted(key: tuple) -> bool:
        return key in by_key and by_key[key][3]["accepted"]

    level = ("level", None, None)
    channel_in = any(k[0] == "aux" and accepted(k) for k in by_key)
    kept, waiting = [], []
    for effect, family, model, comparison in trials:
        if not comparison["accepted"]:
            continue
        ours, wait, reason = comparison["outage_gain_origins"], None, None
        if effect.kind in ("drift", "step") and (accepted(level) or channel_in):
            wait = "the level" if accepted(level) else "the channels"
        elif effect.kind == "aux" and effect.is_slow:
            fast = ("aux", effect.channel, "fast")
            if fast in by_key and not _clearly_better(ours, gains(fast)):
                reason = "not clearly better than its fast form"
            elif accepted(level) and not _clearly_better(ours, gains(level)):
                wait = "the level"
        if wait:
            comparison.update(accepted=False, kept_on=None,
                              reason=f"waits for {wait}: tried again on top of it")
            waiting.append(effect)
        elif reason:
            comparison.update(accepted=False, kept_on=None, reason=reason)
        else:
            kept.append((effect, family, model, comparison))
    return kept, waiting


SLOW_MARGIN = 0.2


def _judged_again(effect: Effect) -> bool:
    """Whether :func:`_screen` may judge ``effect``'s trial again when it is rejected.

    The level and a channel's fast form are the rivals a slow form must beat clearly.
    """
    return effect.kind == "level" or effect.form == "fast"


def _clearly_better(gains: list[float], rival: list[float]) -> bool:
    """Whether ``gains`` remove at least :data:`SLOW_MARGIN` of what ``rival`` leaves.

    From every origin: ``(g - r) / (1 - r) >= SLOW_MARGIN``.
    """
    return all(g - r >= SLOW_MARGIN * (1.0 - r) for g, r in zip(gains, rival)
               if g is not None and r is not None)


def _residual(model: BoundModel, y: np.ndarray, segments: Split) -> np.ndarray:
    """One-step residual over the fitting segment, from the lag window on."""
    stop = segments.train.stop
    return (y[:stop] - model.predict(y[:stop]))[model.lag_window_:]


def _fast(x: np.ndarray, rate: float, slow_s: float,
          out: np.ndarray | None = None) -> np.ndarray:
    """``x`` minus its centred moving mean over ``slow_s`` seconds (written into ``out``).

    The mean is computed into ``out`` (a new array if None) and subtracted there: one
    array of ``x``'s length, not two.
    """
    width = max(3, round(slow_s * rate))
    mean = uniform_filter1d(x, width, mode="nearest", output=out)
    return np.subtract(x, mean, out=mean)


class _Diagnostics:
    """Every diagnostic on the residual of the fitting segment.

    Only the fitting segment: a step's time, a drift's time constant, a line's
    frequency found on the evaluation segment would fit it, and the evaluation
    would then judge its own choice.  The periodic and nonlinearity tests read
    the fast part of the residual (and of the lagged outputs): a wandering bias
    leaves a steep low-frequency spectrum and products that track it, which
    are neither a line nor a nonlinearity.  The other channels are prepared
    once (they do not change between models).
    """

    def __init__(self, y: np.ndarray, channels: Mapping[str, np.ndarray], segments: Split,
                 config: LoopConfig) -> None:
        self.y, self.channels, self.config = y, channels, config
        self.stop = segments.train.stop
        self._aux: dict[int, AuxChannels] = {}

    def __call__(self, model: BoundModel) -> list[Finding]:
        config, rate, stop, n0 = self.config, self.config.rate, self.stop, model.lag_window_
        r = (self.y[:stop] - model.predict(self.y[:stop]))[n0:]
        t = np.arange(n0, stop) / rate
        fast = _fast(r, rate, config.slow_s)
        fmin = max(5 * rate / len(r), 1.0 / config.slow_s)
        findings = [whiteness(r, alpha=config.alpha),
                    periodic(fast, t, rate, alpha=config.alpha, fmin_hz=fmin)]
        if self.channels:
            if n0 not in self._aux:
                self._aux[n0] = AuxChannels({k: v[n0:stop] for k, v in self.channels.items()})
            findings += aux_correlation(r, self._aux[n0], config.aux_max_lag, alpha=config.alpha)
        if n0 >= config.nonlinear_lags:
            findings.append(self._nonlinearity(fast, n0))
        findings += [trend(r, t, alpha=config.alpha), change_point(r, t, alpha=config.alpha),
                     allan(r, rate, alpha=config.alpha)]
        return findings

    def _nonlinearity(self, fast: np.ndarray, n0: int) -> Finding:
        """Test the residual for products of the fast parts of the lagged outputs."""
        config, stop = self.config, self.stop
        # filtered one lag at a time into the matrix: the filter of the whole matrix, or a
        # stack of the filtered columns, would hold two copies of it
        lagged = np.empty((stop - n0, config.nonlinear_lags))
        for k in range(1, config.nonlinear_lags + 1):
            _fast(self.y[n0 - k : stop - k], config.rate, config.slow_s, out=lagged[:, k - 1])
        return nonlinearity(fast, lagged, alpha=config.alpha)


def _choose(kept: list[tuple]) -> tuple:
    """Which kept candidate goes in first: the largest out-of-sample gain.

    The gain is that of the error kind it was kept on, averaged over the
    origins; ties go to the larger t statistic.  Evidence and out-of-sample
    gain decide, not a fixed order of kinds.  A drift and a step, which look
    alike over a short stretch, are told apart by their fit to the residual
    when it is strongly better (BIC difference of :data:`STRONG_BIC` or more).
    """
    def key(item: tuple) -> tuple[float, float]:
        c = item[3]
        name = c["kept_on"]
        gains = [g for g in c[f"{name}_gain_origins"] if g is not None]
        return (float(np.mean(gains)), c[f"{name}_t"])

    best = max(kept, key=key)
    if best[0].kind in ("drift", "step"):
        other = [k for k in kept if k[0].kind == {"drift": "step", "step": "drift"}[best[0].kind]]
        bic = {k[0].kind: k[0].evidence["evidence"]["bic_gain"] for k in [best, *other[:1]]}
        if other and abs(bic["drift"] - bic["step"]) >= STRONG_BIC:
            return max([best, other[0]], key=lambda k: bic[k[0].kind])
    return best


STRONG_BIC = 6.0  # Kass and Raftery: a BIC difference of 6 or more is strong evidence


def _new_terms(old: BoundModel, new: BoundModel) -> list[str]:
    return [t for t in new.model.terms_ if t not in set(old.model.terms_)]


def _lag_of(effect: Effect, model: BoundModel) -> int | None:
    """For an auxiliary channel, the lag of its first selected term: the input's dead time.

    (Seen through coloured noise, an input ``x[n-d]`` enters the one-step equation
    as ``x[n-d]`` and its filtered neighbours ``x[n-d-1]``, ...; FOS takes the
    leading one first, while a later one may end with a larger reduction.)
    """
    if effect.kind != "aux":
        return None
    channel = effect.input_name
    for name in model.model.terms_:
        lags = [lag for ch, lag in Term.parse(name).factors if ch == channel and lag is not None]
        if lags:
            return int(min(lags))
    return None


def _tau_of(effect: Effect, model: BoundModel) -> float | None:
    """Return a level's time constant (its first selected level term), or a drift's."""
    if effect.kind == "drift":
        return effect.tau_s
    if effect.kind != "level":
        return None
    for name in model.model.terms_:
        taus = [level_tau(ch) for ch, _ in Term.parse(name).factors if level_tau(ch)]
        if taus:
            return taus[0]
    return None


def _metrics(model: BoundModel, y: np.ndarray, segment: slice, config: LoopConfig) -> dict:
    """Prediction-segment metrics of a model, and its terms."""
    pred = model.predict(y)
    mse = one_step_mse(y, pred, segment)
    out = outage_metrics(model, y, config.rate, config.sensor, config.units, segment,
                         horizon_s=config.horizon_s, n_starts=config.n_starts, taus=config.taus,
                         residual=(y - pred)[segment])
    return {
        "mse": mse,
        "position_error_m": (equivalent_position_error(mse, config.sensor, config.units)
                             if config.sensor and config.units else None),
        "outage_mse": out["outage_mse"],
        "bias_rms": {f"{t:g}": v for t, v in out["bias_rms"].items()},
        "outage_position_error_m": out["outage_position_error_m"],
        "terms": list(model.model.terms_),
    }

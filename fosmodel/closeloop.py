"""Close the loop: fit, read the residual, add the effect it points to, refit, report.

The record is split in time into a fitting segment, an evaluation segment and
a prediction segment (by default 50 / 20 / 30 %).  Starting from a linear FOS
model of the output's own lags:

1. the residual over the fitting and evaluation segments goes through every
   test of :mod:`fosmodel.diagnose`;
2. each fired test gives a candidate effect (:func:`fosmodel.effects.effects_from`),
   whose candidates are added to the FOS candidate set and the model refit on
   the fitting segment;
3. a candidate is kept only if it beats the current model on the evaluation
   segment by more than noise would (forecast-encompassing tests on the
   one-step and the free-run errors, :func:`_compare`); of the kept ones one
   goes in (:func:`_choose`);
4. repeat until no test points to an effect that survives, or ``max_effects``.

The prediction segment is never used to decide; it gives the before/after
numbers of the report.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from .candidates import Term
from .diagnose import (
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
from .exceptions import InputError
from .metrics import (
    equivalent_position_error,
    free_run_errors,
    one_step_mse,
    outage_metrics,
    to_si_scale,
)
from .model import BoundModel, FOSModel
from .validation import as_channels, as_signal


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

    def __post_init__(self) -> None:
        if not (np.isfinite(self.rate) and self.rate > 0):
            raise InputError(f"the sample rate must be positive, got {self.rate!r}")
        if (self.sensor is None) != (self.units is None):
            raise InputError("give both the sensor (accel or gyro) and its units, or neither")
        if self.sensor is not None:
            to_si_scale(self.sensor, self.units)
        if not (0 < self.train < 1 and 0 < self.evaluate < 1 and self.train + self.evaluate < 1):
            raise InputError(f"the split {self.train:g} / {self.evaluate:g} must be two positive "
                             "fractions of the record adding up to less than 1")
        if isinstance(self.max_lag, bool) or int(self.max_lag) != self.max_lag or self.max_lag < 1:
            raise InputError(f"max_lag must be an integer >= 1, got {self.max_lag!r}")


@dataclass
class Step:
    """One effect the loop kept: what it was, why, and the errors after it."""

    effect: Effect
    terms_added: list[str]
    lag: int | None
    comparison: dict
    predict: dict


@dataclass
class LoopResult:
    """Everything the loop did.

    ``before``/``after`` are the prediction-segment metrics of the starting and the
    final model; ``steps`` the kept effects in order; ``rejected`` the candidates
    that did not beat noise on the evaluation segment; ``findings_before`` and
    ``findings_after`` the diagnostics of the first and the last model, and
    ``unexplained`` the tests still firing at the end.
    """

    config: LoopConfig
    segments: dict[str, slice]
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

    @property
    def unexplained(self) -> list[str]:
        return [f.test for f in self.findings_after if f.fired]

    def to_json_dict(self) -> dict:
        """``{"before", "after", "effects", ...}`` as ``fosmodel close-loop --json`` writes it."""
        effects, mse = [], self.before["mse"]
        for step in self.steps:
            e = step.effect
            effects.append({
                "kind": e.kind, "channel": e.channel, "lag": step.lag, "freq_hz": e.freq_hz,
                "time_s": e.time_s, "form": e.form, "tau_s": e.tau_s,
                "terms_added": step.terms_added,
                "evidence": {**e.evidence, "evaluation": step.comparison},
                "mse_before": mse, "mse_after": step.predict["mse"],
            })
            mse = step.predict["mse"]
        return {"before": self.before, "after": self.after, "effects": effects,
                "rejected": self.rejected, "unexplained": self.unexplained,
                "segments_s": {k: [s.start / self.config.rate, s.stop / self.config.rate]
                               for k, s in self.segments.items()}}


def close_loop(
    y: object, channels: Mapping[str, object] | None, config: LoopConfig
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

    Returns
    -------
    LoopResult
    """
    y = as_signal(y, "the record")
    channels = as_channels(channels, list(channels or {}), len(y))
    segments = _segments(len(y), config)
    time = np.arange(len(y)) / config.rate
    fit = _Fitter(y, channels, time, segments["train"], config)
    family = CandidateFamily(config.max_lag)
    current = base = fit(family)
    findings = findings_before = _diagnose(current, y, channels, time, segments, config)
    residual_before = _residual(current, y, segments)
    steps, rejected, added = [], [], []
    while len(steps) < config.max_effects:
        candidates = [e for e in effects_from(findings, config.aux_max_lag)
                      if not any(e.same_as(a) for a in added)]
        kept = []
        for effect in candidates:
            trial_family = family.add(effect, channels, time, segments["train"])
            trial = fit(trial_family)
            comparison = _compare(current, trial, y, segments["evaluate"], config)
            if comparison["accepted"]:
                kept.append((effect, trial_family, trial, comparison))
            else:
                rejected.append({"effect": effect.describe(), "kind": effect.kind,
                                 "evidence": effect.evidence, "evaluation": comparison})
        if not kept:
            break
        effect, family, model, comparison = _choose(kept)
        steps.append(Step(effect, _new_terms(current, model), _lag_of(effect, model),
                          comparison, _metrics(model, y, segments["predict"], config)))
        added.append(effect)
        current = model
        findings = _diagnose(current, y, channels, time, segments, config)
    return LoopResult(config, segments, _metrics(base, y, segments["predict"], config),
                      _metrics(current, y, segments["predict"], config), steps, rejected,
                      findings_before, findings, base, current, residual_before,
                      _residual(current, y, segments))


def score_family(
    y: object, channels: Mapping[str, object] | None, config: LoopConfig,
    family: CandidateFamily,
) -> dict:
    """Prediction-segment metrics of a candidate family fit on the record's fitting segment.

    With the effects a user knows to be there, this is the yardstick of what the
    loop recovers (same segments, same starting lags).
    """
    y = as_signal(y, "the record")
    channels = as_channels(channels, list(channels or {}), len(y))
    segments = _segments(len(y), config)
    time = np.arange(len(y)) / config.rate
    model = _Fitter(y, channels, time, segments["train"], config)(family)
    return _metrics(model, y, segments["predict"], config)


def _segments(n: int, config: LoopConfig) -> dict[str, slice]:
    a, b = round(config.train * n), round((config.train + config.evaluate) * n)
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
    return {"train": slice(0, a), "evaluate": slice(a, b), "predict": slice(b, n)}


class _Fitter:
    """Fits a FOS model of a candidate family on the fitting segment of one record."""

    def __init__(self, y, channels, time, train, config):
        self.y, self.channels, self.time, self.train, self.config = y, channels, time, train, config

    def __call__(self, family: CandidateFamily) -> BoundModel:
        inputs = {**{ch: self.channels[ch] for ch in family.exog_lags}, **family.columns}
        model = FOSModel(max_lag=family.max_lag, degree=family.degree,
                         exog_lags=dict(family.exog_lags), columns=list(family.columns),
                         stop=self.config.fos_stop)
        model.fit(self.y[self.train], {k: v[self.train] for k, v in inputs.items()})
        return BoundModel(model, inputs)


def _residual(model: BoundModel, y: np.ndarray, segments) -> np.ndarray:
    """One-step residual over the fitting and evaluation segments, from the lag window on."""
    stop = segments["evaluate"].stop
    return (y[:stop] - model.predict(y[:stop]))[model.lag_window_:]


def _diagnose(model, y, channels, time, segments, config) -> list[Finding]:
    """Every diagnostic on the residual of the fitting and evaluation segments."""
    stop, n0 = segments["evaluate"].stop, model.lag_window_
    r, t = _residual(model, y, segments), time[n0:stop]
    q = config.nonlinear_lags
    lagged = np.column_stack([y[n0 - k : stop - k] for k in range(1, q + 1)]) if n0 >= q else None
    findings = [whiteness(r, alpha=config.alpha),
                periodic(r, t, config.rate, alpha=config.alpha)]
    if channels:
        findings += aux_correlation(r, {k: v[n0:stop] for k, v in channels.items()},
                                    config.aux_max_lag, alpha=config.alpha)
    if lagged is not None:
        findings.append(nonlinearity(r, lagged, alpha=config.alpha))
    findings += [trend(r, t, alpha=config.alpha), change_point(r, t, alpha=config.alpha),
                 allan(r, config.rate, alpha=config.alpha)]
    return findings


def _compare(a: BoundModel, b: BoundModel, y, segment: slice, config: LoopConfig) -> dict:
    """Does ``b`` beat ``a`` on ``segment`` by more than noise would, all along it?

    Two forecast-encompassing tests: does the change ``b`` makes to ``a``'s
    predictions explain ``a``'s errors?  ``beta = sum(e_a d) / sum(d^2)`` with
    ``d`` the change, and its t statistic from the spread over groups: ten
    contiguous batches for the one-step errors, consecutive outage windows of
    ``eval_horizon_s`` (at most :data:`MAX_WINDOWS`, evenly spread) for the
    free-run errors.  With no effect, ``beta`` is centred
    on 0 (the candidate was fit on other samples).  ``b`` is kept if either test
    is significant at ``accept_alpha / 2`` (one-sided) and the same errors' mean
    square is lower with ``b`` over the segment and, on a segment of at least
    ``2 * MIN_HALF_WINDOWS`` outage windows, over each of its halves: an
    effect that helps only next to the fitting data (a trend fit there, which
    then runs on) fades or turns in the later half.  On a shorter segment the
    halves' errors are too few to tell that from noise.
    """
    stop = segment.stop
    pa, pb = a.predict(y[:stop])[segment], b.predict(y[:stop])[segment]
    ea = y[segment] - pa
    h = round(config.eval_horizon_s * config.rate)
    starts = np.arange(segment.start, stop - h + 1, h)
    if len(starts) > MAX_WINDOWS:  # enough for the t test; spread over the segment
        starts = starts[np.linspace(0, len(starts) - 1, MAX_WINDOWS).round().astype(int)]
    fa = free_run_errors(a, y, starts, h)
    fb = free_run_errors(b, y, starts, h)
    groups = {"one_step": list(zip(np.array_split(ea, 10), np.array_split(pb - pa, 10))),
              "outage": list(zip(fa, fa - fb))}
    judge_halves = len(starts) >= 2 * MIN_HALF_WINDOWS
    out, accepted = {"halves_judged": judge_halves}, False
    for name, pairs in groups.items():
        beta, t, p = _encompassing(pairs)
        half = len(pairs) // 2
        gain, halves = _gain(pairs), [_gain(pairs[:half]), _gain(pairs[half:])]
        out.update({f"{name}_gain": gain, f"{name}_gain_halves": halves, f"{name}_beta": beta,
                    f"{name}_t": t, f"{name}_p": p})
        judged = [gain, *halves] if judge_halves else [gain]
        accepted |= p < config.accept_alpha / 2 and min(judged) > 0
    out["accepted"] = accepted
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


MAX_WINDOWS = 100  # most outage windows of the evaluation test
MIN_HALF_WINDOWS = 20  # outage windows in each half of the evaluation segment to judge it
STRONG_BIC = 6.0  # Kass and Raftery: a BIC difference of 6 or more is strong evidence


def _choose(kept: list[tuple]) -> tuple:
    """Which kept candidate goes in first.

    An observed cause (an auxiliary channel) first; then periodic and nonlinear
    effects, by their evaluation t statistic; then slow effects.  A drift and a
    step can look alike both in the residual and over a short evaluation
    segment: the form whose fit to the residual is strongly better (BIC gain at
    least :data:`STRONG_BIC` higher) wins, otherwise the one that lowers the
    evaluation outage error more.
    """
    def t_of(item):
        c = item[3]
        return max(v for v in (c["one_step_t"], c["outage_t"]) if v == v)

    for kinds in (("aux",), ("periodic", "nonlinear")):
        group = [k for k in kept if k[0].kind in kinds]
        if group:
            return max(group, key=t_of)
    bic = {k[0].kind: k[0].evidence["evidence"]["bic_gain"] for k in kept}
    if len(kept) == 2 and abs(bic["drift"] - bic["step"]) >= STRONG_BIC:
        return max(kept, key=lambda k: bic[k[0].kind])
    return max(kept, key=lambda k: k[3]["outage_gain"])


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
    for name in model.model.terms_:
        lags = [lag for ch, lag in Term.parse(name).factors if ch == effect.channel]
        if lags:
            return int(min(lags))
    return None


def _metrics(model: BoundModel, y, segment: slice, config: LoopConfig) -> dict:
    """Prediction-segment metrics of a model, and its terms."""
    pred = model.predict(y)
    mse = one_step_mse(y, pred, segment)
    out = outage_metrics(model, y, config.rate, config.sensor, config.units, segment,
                         horizon_s=config.horizon_s, n_starts=config.n_starts, taus=config.taus,
                         residual=(y - pred)[segment])
    return {
        "mse": mse,
        "position_error_m": (equivalent_position_error(mse, config.sensor, config.units)
                             if config.sensor else None),
        "outage_mse": out["outage_mse"],
        "bias_rms": {f"{t:g}": v for t, v in out["bias_rms"].items()},
        "outage_position_error_m": out["outage_position_error_m"],
        "terms": list(model.model.terms_),
    }

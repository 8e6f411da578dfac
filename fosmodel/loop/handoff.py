"""The loop's final model handed to a navigation filter, beside the Allan model, and which to use.

The loop's segments decide the final model's structure (its terms, levels, drivers and
compensation); :func:`refit_on_all` fits its weights anew on all the data given before it is
written.  :func:`hand_off` judges it and the Allan model (white + Gauss-Markov + random-walk,
:func:`fosmodel.filter.allan_statespace.allan_state_space`) where a filter uses them: in the
1-D aided position filter (:func:`fosmodel.filter.statespace.position_velocity_error_model`
for an accelerometer, :func:`~fosmodel.filter.statespace.tilt_error_model` for a gyro),
each fitted on the record's first half and run on its second, position updates of
:data:`SIGMA_M` in update/prediction cycles of :data:`CYCLE_S` s.  The recommended model
is the one with the lowest RMS position error among those whose filter claims at least
:data:`MIN_CONSISTENCY` of its actual error (sigma / RMS); an overconfident filter trusts
a bias estimate it does not have.  Both are then written fitted on all the data
(:func:`fosmodel.filter.filter_file.write_filter_file`).

A final model with nonlinear terms is written for an extended Kalman filter and not judged.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from scipy.linalg import block_diag

from ..core.candidates import Term
from ..core.exceptions import InputError
from ..filter.allan_statespace import allan_state_space, initial_covariance
from ..filter.filter_file import write_filter_file
from ..filter.kalman import KalmanFilter, run_filter
from ..filter.statespace import (
    CONSTANT,
    NonlinearStateSpace,
    StateSpace,
    position_velocity_error_model,
    tilt_error_model,
    to_nonlinear_state_space,
    to_state_space,
)
from ..models.model import FOSModel
from ..noise.allan import allan_deviation
from ..noise.allan_fit import NoiseFit, fit_noise
from ..noise.metrics import to_si_scale
from .closeloop import LoopResult

__all__ = ["CYCLE_S", "MIN_CONSISTENCY", "SIGMA_M", "FilterScore", "Handoff", "hand_off",
           "refit_on_all"]

#: Standard deviation of the simulated position updates, m.
SIGMA_M = 0.1
#: Update / prediction cycle of the judging filter, s (shorter on a short record).
CYCLE_S = 60.0
#: Least filter sigma / RMS of a model that may be recommended.
MIN_CONSISTENCY = 0.7
LOOP, ALLAN = "loop final model", "Allan model"
FILES = {LOOP: "loop_model.json", ALLAN: "allan_model.json"}


def refit_on_all(result: LoopResult, y: np.ndarray) -> FOSModel:
    """Return the model the loop hands on with its terms' weights fitted on all of ``y``.

    The terms, levels and compensation are those the loop chose on its segments; a model
    with levels and a compensation keeps its lags and levels summing to one (as the loop
    fits it).  The compensation's weights stay those of the fitting segment.
    """
    bound, _ = result.handed_on()
    model = bound.model
    hold = bool(model.spec_.levels and model.compensation)
    return model.refit_weights(y, bound.inputs, hold=hold)


@dataclass(frozen=True)
class FilterScore:
    """A model in the judging filter: RMS position error and the RMS the filter claims."""

    rms_m: float
    sigma_m: float

    @property
    def ratio(self) -> float:
        """Filter sigma / RMS: 1 consistent, below 1 overconfident."""
        return self.sigma_m / self.rms_m if self.rms_m > 0 else math.inf

    def to_dict(self) -> dict[str, float]:
        """Return the numbers by name, the ratio too."""
        return {"rms_m": self.rms_m, "sigma_m": self.sigma_m, "sigma_over_rms": self.ratio}


@dataclass
class Handoff:
    """The two models a filter may take, fitted on all the data, and the recommendation."""

    final: FOSModel
    allan: StateSpace | None
    channels: Mapping[str, np.ndarray] = field(repr=False)
    n_samples: int
    scores: dict[str, FilterScore]
    recommended: str | None
    why: str
    cycle_s: float | None
    units: Mapping[str, str] = field(default_factory=dict)

    @property
    def linear(self) -> bool:
        """Whether the final model has degree-1 terms only (a linear state space)."""
        return _linear(self.final)

    def final_system(self) -> StateSpace | NonlinearStateSpace:
        """Return the final model's shaping filter: linear, or for an EKF."""
        return to_state_space(self.final) if self.linear else to_nonlinear_state_space(
            self.final)

    def write(self, out_dir: Path, meta: Mapping[str, Any]) -> list[Path]:
        """Write ``loop_model.json`` (and ``allan_model.json``) into ``out_dir`` (created)."""
        out_dir.mkdir(parents=True, exist_ok=True)
        system = self.final_system()
        common = {**meta, "fitted_on": f"all {self.n_samples} samples"}
        paths = [out_dir / FILES[LOOP]]
        write_filter_file(paths[0], system, P0=_start_covariance(system, self.n_samples),
                          units=self.units,
                          meta={**common, "model": "the residual loop's final model "
                                "(structure chosen on the loop's segments)"})
        if self.allan is not None:
            paths.append(out_dir / FILES[ALLAN])
            write_filter_file(paths[1], self.allan, n_samples=self.n_samples, units=self.units,
                              meta={**common, "model": "white + Gauss-Markov + random-walk "
                                    "(Allan variance fit)"})
        return paths

    def append_to(self, report: Path, heading: str = "## The filter") -> None:
        """Append :meth:`text` under ``heading`` to the Markdown page ``report``."""
        with open(report, "a", encoding="utf-8") as fh:
            fh.write(f"\n{heading}\n\n{self.text()}")

    def to_dict(self) -> dict[str, Any]:
        """Return the JSON output's ``"filter"`` entry (the files relative to ``filter/``)."""
        return {"files": {k: v for k, v in FILES.items() if k == LOOP or self.allan},
                "kind": "linear" if self.linear else "nonlinear",
                "recommended": self.recommended, "why": self.why, "cycle_s": self.cycle_s,
                "sigma_m": SIGMA_M,
                "scores": {k: s.to_dict() for k, s in self.scores.items()},
                "refit": "the final model's weights refitted on all the data; its structure "
                         "chosen on the loop's segments"}

    def text(self, where: str = "filter/") -> str:
        """Return the report's section: the files, the judgement and the recommendation."""
        lines = [f"The filter JSON of the loop's final model is `{where}{FILES[LOOP]}`"
                 + (f", the Allan model's `{where}{FILES[ALLAN]}`" if self.allan else "")
                 + ". The final model's structure (terms, levels, drivers) was chosen on the "
                 "loop's segments; its terms' weights were refitted on all the data given "
                 f"({self.n_samples} samples)"
                 + (", its compensation's weights kept from the loop's fitting segment"
                    if self.final.compensation else "")
                 + ", and so was the Allan model."]
        if self.scores:
            lines.append(f"Judged in the 1-D aided position filter, each fitted on the first "
                         f"half and run on the second, position updates of {SIGMA_M:g} m in "
                         f"{self.cycle_s:g} s / {self.cycle_s:g} s update/prediction cycles:")
            lines.append("")
            lines.append("| model | RMS position error [m] | filter sigma [m] | sigma / RMS |")
            lines.append("|---|---|---|---|")
            lines += [f"| {k} | {s.rms_m:.4g} | {s.sigma_m:.4g} | {s.ratio:.3g} |"
                      for k, s in self.scores.items()]
            lines.append("")
        lines.append(f"Recommended: {self.recommended or 'none'}. {self.why}")
        return "\n".join(lines) + "\n"


def hand_off(
    result: LoopResult, y: np.ndarray, channels: Mapping[str, np.ndarray] | None, *,
    sensor: str | None, units: str | None, allan: NoiseFit | None = None,
    column: str = "y",
) -> Handoff:
    """Refit the loop's final model on all of ``y``, judge it against the Allan model, recommend.

    Parameters
    ----------
    result : LoopResult
        The loop on the record ``y``.
    y : ndarray
        The modelled column, the loop's record.
    channels : mapping of str to ndarray, optional
        The record's other columns (the final model reads its drivers from them).
    sensor, units : str or None
        ``"accel"`` or ``"gyro"`` and the column's units: the judging filter's metres need
        them; without them nothing is judged (and the report says so).
    allan : NoiseFit, optional
        The Allan fit of all of ``y`` (computed when not given).
    column : str
        The column's name, for the inputs' units.

    Returns
    -------
    Handoff
    """
    y = np.asarray(y, dtype=float)
    channels = dict(channels or {})
    rate = result.config.rate
    unit_of = {column: units} if units else {}
    final = refit_on_all(result, y)
    known = sensor in ("accel", "gyro") and units is not None
    fit = allan
    if fit is None and known:
        fit = _allan_fit(y, rate, sensor, units)
    allan_model = allan_state_space(fit, mu=float(np.mean(y))) if fit is not None else None
    linear = _linear(final)
    scores: dict[str, FilterScore] = {}
    cycle: float | None = None
    if not known:
        why = ("Not judged: the column's sensor and units are not known, so the filter's "
               "position error cannot be put in metres.")
    elif not linear:
        why = ("The loop's final model has nonlinear terms: its filter JSON is for an extended "
               "Kalman filter (kind \"nonlinear\") and was not judged; the Allan model is the "
               "one judged linear model.")
    else:
        assert sensor is not None and units is not None
        scores, cycle, why = _judge(result, y, channels, sensor, units)
    recommended = _recommend(scores) if scores else (ALLAN if allan_model is not None
                                                     and known else None)
    if scores:
        why = _why(scores, recommended) if not why else why
    return Handoff(final, allan_model, channels, len(y), scores, recommended, why, cycle,
                   {**unit_of})


def _allan_fit(y: np.ndarray, rate: float, sensor: str | None, units: str | None) -> NoiseFit:
    return fit_noise(allan_deviation(y, rate, units=units, sensor=sensor))


def _judge(result: LoopResult, y: np.ndarray, channels: Mapping[str, np.ndarray], sensor: str,
           units: str) -> tuple[dict[str, FilterScore], float | None, str]:
    """Both models fitted on the first half, in the aided position filter on the second."""
    n, rate = len(y), result.config.rate
    half = n // 2
    cycle = round(min(CYCLE_S, (n - half) / rate / 4) * rate) / rate  # whole samples
    bound, _ = result.handed_on()
    model = bound.model
    try:
        first = model.refit_weights(y[:half], {k: v[:half] for k, v in bound.inputs.items()},
                                    hold=bool(model.spec_.levels and model.compensation))
        loop_ss = to_state_space(first)
        u = loop_ss.input_matrix(channels, n)[half:]
        fit = _allan_fit(y[:half], rate, sensor, units)
    except InputError as exc:
        return {}, None, f"Not judged: {exc}."
    allan_ss = allan_state_space(fit, mu=float(np.mean(y[:half])))
    scale = to_si_scale(sensor, units)
    noise = np.random.default_rng(len(y)).standard_normal(n - half)
    scores = {}
    for name, ss, p0, inputs in (
            (LOOP, loop_ss, initial_covariance(loop_ss, half), u),
            (ALLAN, allan_ss, initial_covariance(allan_ss, half), None)):
        reading = y[half:] - ss.mu - (inputs @ ss.D[0] if inputs is not None else 0.0)
        scores[name] = _aided(ss, p0, reading * scale, inputs, scale, sensor, rate, cycle,
                              noise)
    return scores, cycle, ""


def _aided(error: StateSpace, p0_error: np.ndarray, residual: np.ndarray,
           inputs: np.ndarray | None, scale: float, sensor: str, rate: float, cycle: float,
           noise: np.ndarray) -> FilterScore:
    """Score one error model in the 1-D aided position filter on one stretch.

    ``residual`` is the reading less the model's mean and feedthrough, in SI units; the
    truth integrates it by the filter's own recursion, the filter starts from zeros and
    ``p0_error``.  Sample 0 (both zero) is left out.
    """
    dt = 1.0 / rate
    if sensor == "gyro":
        system = tilt_error_model(error, dt, scale=scale)
        chain = system.Phi[:3, :3]
    else:
        scaled = StateSpace(Phi=error.Phi, B=error.B, G=error.G, H=error.H * scale, Q=error.Q,
                            mu=0.0, state_names=error.state_names,
                            input_names=error.input_names, rate=error.rate)
        system = position_velocity_error_model(scaled, dt)
        chain = system.Phi[:2, :2]
    k = len(chain)
    truth = _integrate(chain, residual, dt)
    updated = (np.arange(len(truth)) * dt) % (2 * cycle) < cycle
    z = np.where(updated, truth + SIGMA_M * noise, np.nan)
    p0 = block_diag(np.zeros((k, k)), p0_error)
    kf = KalmanFilter.from_state_space(system, [[SIGMA_M**2]], np.zeros(system.n_states), p0)
    period = round(2 * cycle * rate)
    position, variance = _periodic_filter(kf, z[1:], None if inputs is None else inputs[1:],
                                          period)
    err = position - truth[1:]
    return FilterScore(float(np.sqrt(np.mean(err**2))), float(np.sqrt(np.mean(variance))))


def _periodic_filter(kf: KalmanFilter, z: np.ndarray, inputs: np.ndarray | None,
                     period: int) -> tuple[np.ndarray, np.ndarray]:
    """:func:`~fosmodel.filter.kalman.run_filter`'s first state and its variance, sooner.

    The measurements come in a pattern of ``period`` samples, so the covariance (which the
    data do not move) settles to a periodic sequence: once a period ends on the previous
    period's end covariance to 1e-12 relative, the next period's gains and variances serve
    every later period and only the state is propagated.  Until then, and when the
    pattern does not repeat, it is run_filter itself.
    """
    n = len(z)
    phi, h, b = kf.Phi, kf.H[0], kf.B
    measured = np.isfinite(z)
    periodic = period > 0 and np.array_equal(measured, np.resize(measured[:period], n))
    position, variance = np.empty(n), np.empty(n)
    previous: np.ndarray | None = None
    start = 0
    while start < n:
        stop = min(start + period, n) if periodic else n
        run = run_filter(kf, z[start:stop], None if inputs is None else inputs[start:stop])
        position[start:stop], variance[start:stop] = run.x[:, 0], run.variance[:, 0]
        start = stop
        if previous is not None and np.linalg.norm(kf.P - previous) <= 1e-12 * np.linalg.norm(
                kf.P):
            break
        previous = kf.P.copy()
    if start >= n:
        return position, variance
    drive = np.zeros((n, len(kf.x))) if inputs is None else inputs @ b.T
    gains, p_diag = _one_period(kf, z[start:start + period], period)
    x = kf.x.copy()
    for i in range(start, n):
        x = phi @ x + drive[i]
        gain = gains[(i - start) % period]
        if gain is not None:
            x = x + gain * (z[i] - h @ x)
        position[i] = x[0]
    variance[start:] = np.resize(p_diag, n - start)
    return position, variance


def _one_period(kf: KalmanFilter, z: np.ndarray,
                period: int) -> tuple[list[np.ndarray | None], np.ndarray]:
    """Return the gains (None where no update) and first variances of a settled period."""
    p = kf.P.copy()
    gains: list[np.ndarray | None] = []
    p_diag = np.empty(period)
    measured = np.isfinite(z)
    for j in range(period):
        p = kf.Phi @ p @ kf.Phi.T + kf.GQG
        if j < len(z) and measured[j]:
            ph = p @ kf.H.T
            gain = ph[:, 0] / (kf.H @ ph + kf.R)[0, 0]
            a = np.eye(len(p)) - np.outer(gain, kf.H[0])
            p = a @ p @ a.T + np.outer(gain, gain) * kf.R[0, 0]
            gains.append(gain)
        else:
            gains.append(None)
        p_diag[j] = p[0, 0]
    return gains, p_diag


def _integrate(chain: np.ndarray, drive: np.ndarray, dt: float) -> np.ndarray:
    """Position of the integrators ``chain`` whose last state gains ``dt drive[k-1]``."""
    state = np.zeros(len(chain))
    out = np.empty(len(drive))
    for k in range(len(drive)):
        state = chain @ state
        if k:
            state[-1] += dt * drive[k - 1]
        out[k] = state[0]
    return out


def _linear(model: FOSModel) -> bool:
    return all(Term.parse(t).degree == 1 for t in model.terms_)


def _start_covariance(system: StateSpace | NonlinearStateSpace, n_samples: int) -> np.ndarray:
    """:func:`initial_covariance`; of a nonlinear model, that of its Jacobian at the mean."""
    if isinstance(system, StateSpace):
        return initial_covariance(system, n_samples)
    u = system.input_offsets.copy()
    if CONSTANT in system.input_names:
        u[system.input_names.index(CONSTANT)] = 1.0
    jac = system.jacobian(np.zeros(system.n_states), u)
    linearised = StateSpace(Phi=jac, B=np.zeros((system.n_states, 0)), G=system.G, H=system.H,
                            Q=system.Q, mu=system.mu, state_names=system.state_names,
                            input_names=())
    return initial_covariance(linearised, n_samples)


def _recommend(scores: Mapping[str, FilterScore]) -> str:
    consistent = {k: s for k, s in scores.items() if s.ratio >= MIN_CONSISTENCY}
    if consistent:
        return min(consistent, key=lambda k: consistent[k].rms_m)
    return max(scores, key=lambda k: scores[k].ratio)


def _why(scores: Mapping[str, FilterScore], chosen: str | None) -> str:
    assert chosen is not None
    best = scores[chosen]
    others = [k for k in scores if k != chosen]
    if best.ratio < MIN_CONSISTENCY:
        return (f"No model's filter claims {MIN_CONSISTENCY:g} of its actual error; the "
                f"{chosen} comes nearest (sigma / RMS {best.ratio:.2f}).")
    text = (f"The {chosen} has the lowest RMS position error ({best.rms_m:.3g} m) among the "
            f"models whose filter claims at least {MIN_CONSISTENCY:g} of its actual error "
            f"(sigma / RMS {best.ratio:.2f})")
    for other in others:
        s = scores[other]
        text += (f"; the {other}: {s.rms_m:.3g} m, sigma / RMS {s.ratio:.2f}"
                 + (" (overconfident)" if s.ratio < MIN_CONSISTENCY else ""))
    return text + "."

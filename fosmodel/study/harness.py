"""Train / evaluate / predict harness: every method fit, selected and scored the same way.

As in section 5 of Tamazin et al. (2013), a record is split by duration into a
training segment (3 min), an evaluation segment (3 min) and the novel
prediction segment (the rest).  Every configuration (method, order, degree) is
fit on the training samples alone; each method's best configuration is the
one with the lowest one-step MSE on the evaluation segment; every
configuration is scored on the prediction segment, which no choice has seen.

Two protocols:

``paper``
    The baselines are fit and scored on denoised data (the paper used a
    4-level wavelet low pass), FOS on the raw data, as the paper did.
``fair``
    Every method is fit and scored on the same raw data.

With ``levels`` (the default), the fair protocol also has every method about
the local level, the wandering bias as a stochastic level (:mod:`fosmodel.core.levels`):
``fos+level`` offers FOS the level candidates (a grid below the training
segment's Allan floor) beside the lags, each weighed freely; ``burg+level``,
``yw+level``, ``cov+level`` and ``gm+level`` fit the estimator to the record
minus one level (weight one, :class:`fosmodel.models.levelar.LocalLevelAR`), its time
constant chosen from the same grid on the evaluation segment like the order.

Denoising is applied to the training samples alone for fitting (so that no
later sample leaks into a fit through the filter), and to the whole record for
scoring.  Runtime is measured around ``fit`` only.

A study is a set of independent fits: :func:`plan_study` checks, splits and
denoises the record and lists the fits (:class:`FitTask`), :func:`run_task`
fits and scores one with one BLAS thread (so that it gives the same bits in any
process), and :func:`assemble` makes the rows.  :mod:`fosmodel.study.runner` runs the tasks
of one or several studies, in this process or on a Dask cluster.

References
----------
.. [1] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
"""

from __future__ import annotations

import time
import warnings
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from ..core.blas import one_blas_thread
from ..core.exceptions import InputError, UnstableModelWarning
from ..core.fos import STOP_RULES
from ..core.levels import levels_for
from ..core.validation import as_signal, check_int, check_positive
from ..io.split import Split
from ..models.baselines import METHOD_LABELS, ARModel, GaussMarkovModel, make_baseline
from ..models.levelar import LocalLevelAR
from ..models.model import FOSModel
from ..noise.denoise import DENOISERS, denoise
from ..noise.metrics import equivalent_position_error, one_step_mse, outage_metrics, to_si_scale

METHODS = ("fos", "yw", "cov", "burg", "gm")
PROTOCOLS = ("paper", "fair")
LEVEL = "+level"  # suffix of a method about the local level


@dataclass(frozen=True)
class StudyConfig:
    """What a model-order study fits and how it scores.

    Parameters
    ----------
    rate : float
        Sample rate in Hz.
    sensor, units : str
        ``"accel"`` or ``"gyro"`` and the record's units (see :mod:`fosmodel.noise.metrics`).
    orders, degrees : sequence of int
        Model orders (the maximum lag L) and FOS cross-product degrees.
    methods : sequence of str
        Among ``fos, yw, cov, burg, gm``.
    protocols : sequence of str
        ``paper`` and/or ``fair``.
    train_s, evaluate_s : float
        Segment durations.
    horizon_s, n_starts, taus : outage metrics (see :func:`fosmodel.noise.metrics.outage_metrics`).
    paper_denoise : str
        Denoiser of the baselines under the paper protocol (``wavelet`` or ``kaiser``).
    fos_stop : str
        FOS stopping rule.
    levels : bool
        Also fit every method about the local level, under the fair protocol.
    """

    rate: float
    sensor: str
    units: str
    orders: Sequence[int] = tuple(range(1, 11))
    degrees: Sequence[int] = (1, 2)
    methods: Sequence[str] = METHODS
    protocols: Sequence[str] = PROTOCOLS
    train_s: float = 180.0
    evaluate_s: float = 180.0
    horizon_s: float = 30.0
    n_starts: int = 20
    taus: Sequence[float] = (1.0, 10.0, 30.0)
    paper_denoise: str = "wavelet"
    fos_stop: str = "korenberg"
    levels: bool = True

    def __post_init__(self) -> None:
        """Store the sequences as tuples and check every option.

        Raises
        ------
        InputError
            A rate, sensor, units, order, degree, method, protocol, segment duration,
            horizon, number of starts, bias time, denoiser, stopping rule or ``levels`` out of
            range; an integer option given as a float (``3.0``) or a bool.
        """
        for name in ("orders", "degrees", "methods", "protocols", "taus"):
            value = getattr(self, name)
            if isinstance(value, (str, bytes)) or not isinstance(value, Iterable):
                raise InputError(f"{name} must be a sequence, got {value!r}")
            object.__setattr__(self, name, tuple(value))
        check_positive(self.rate, "rate")
        to_si_scale(self.sensor, self.units)
        _check_choices("method", self.methods, METHODS)
        _check_choices("protocol", self.protocols, PROTOCOLS)
        _check_choices("denoiser", [self.paper_denoise], [d for d in DENOISERS if d != "none"])
        _check_choices("stopping rule", [self.fos_stop], STOP_RULES)
        for name, values in (("order", self.orders), ("degree", self.degrees)):
            if not values or any(isinstance(v, bool) or not isinstance(v, (int, np.integer))
                                 or v < 1 for v in values):
                raise InputError(f"every {name} must be an integer >= 1, got {list(values)}")
        for name in ("train_s", "evaluate_s", "horizon_s"):
            check_positive(getattr(self, name), name)
        check_int(self.n_starts, "n_starts", 1)
        if not self.taus:
            raise InputError("taus must hold at least one bias time in seconds")
        for tau in self.taus:
            check_positive(tau, "every tau")
        if not isinstance(self.levels, (bool, np.bool_)):
            raise InputError(f"levels must be True or False, got {self.levels!r}")

    def configurations(self, protocol: str = "fair") -> list[tuple[str, int, int]]:
        """List every (method, order, degree) to fit under ``protocol``.

        FOS at each degree, AR at degree 1, GM once; with ``levels``, under the fair
        protocol, each again about the local level (method ``<method>+level``).
        """
        out = []
        level_too = self.levels and protocol == "fair"
        for method in self.methods:
            names = [method, method + LEVEL] if level_too else [method]
            for name in names:
                if method == "gm":
                    out.append((name, 1, 1))
                else:
                    degrees = self.degrees if method == "fos" else (1,)
                    out.extend((name, int(L), int(d)) for L in self.orders for d in degrees)
        return out

    def denoiser(self, protocol: str, method: str) -> str | None:
        """Return the denoiser a method's data go through under a protocol (None: raw data)."""
        return (self.paper_denoise if protocol == "paper" and not method.startswith("fos")
                else None)


def _check_choices(what: str, given: Sequence[str], valid: Sequence[str]) -> None:
    if not given:
        raise InputError(f"no {what} given; choose from {', '.join(valid)}")
    bad = [g for g in given if g not in valid]
    if bad:
        raise InputError(f"unknown {what} {bad[0]!r}; choose from {', '.join(valid)}")


def make_model(method: str, order: int, degree: int, config: StudyConfig,
               level_taus: Sequence[float] = (), level_tau: float | None = None,
               ) -> FOSModel | ARModel | GaussMarkovModel | LocalLevelAR:
    """Make a fresh, unfitted model of one configuration.

    ``fos+level`` is offered the levels ``level_taus``; a baseline about the level
    (``burg+level``, ...) uses the one level ``level_tau``.

    Raises
    ------
    InputError
        A baseline about the level without its ``level_tau``.
    """
    base, about_level = method.removesuffix(LEVEL), method.endswith(LEVEL)
    if base == "fos":
        return FOSModel(max_lag=order, degree=degree, stop=config.fos_stop,
                        levels=list(level_taus) if about_level else None,
                        rate=config.rate if about_level else None)
    model = make_baseline(base, order, rate=config.rate)
    if not about_level:
        return model
    if level_tau is None:
        raise InputError(f"{method} needs the time constant of its level (level_tau=...)")
    return LocalLevelAR(model, level_tau, config.rate)


def method_label(method: str, degree: int) -> str:
    """``FOS CP=2``, ``Burg``, ``Burg + level``...: the name of a method in tables and figures."""
    base = method.removesuffix(LEVEL)
    label = f"FOS CP={degree}" if base == "fos" else METHOD_LABELS[base]
    return label + (" + level" if method.endswith(LEVEL) else "")


@dataclass
class StudyResult:
    """All scored configurations of a study.

    Attributes
    ----------
    rows : DataFrame
        One row per (protocol, method, order, degree): ``evaluate_mse`` (selection),
        ``mse`` (one-step, prediction segment), ``position_error_m``, ``outage_mse``,
        ``outage_position_error_m``, ``bias_rms_<tau>s``, ``runtime_s`` (fit only),
        ``n_terms``, ``stable``, ``data`` (raw or the denoiser).
    config : StudyConfig
    split : Split
    warnings : list of str
        What deserves the reader's attention (e.g. unstable fitted models).
    level_taus : tuple of float
        The level time constants (s) offered about the local level.
    """

    rows: pd.DataFrame
    config: StudyConfig
    split: Split
    warnings: list[str] = field(default_factory=list)
    level_taus: tuple[float, ...] = ()

    def best(self) -> pd.DataFrame:
        """Return the row with the lowest evaluation MSE per protocol and method.

        FOS per degree; the minimum is over the orders and, about the level, the level's
        time constants.
        """
        idx = self.rows.groupby(["protocol", "method", "degree"], sort=False)["evaluate_mse"]
        return self.rows.loc[idx.idxmin()].reset_index(drop=True)

    def to_json_dict(self) -> dict:
        """Rows and best rows with the keys of ``fosmodel study --json``."""
        def records(frame: pd.DataFrame) -> list[dict]:
            out = []
            for rec in frame.to_dict(orient="records"):
                rec = {k: _json_value(v) for k, v in rec.items()}
                rec["bias_rms"] = {f"{t:g}": rec.pop(f"bias_rms_{t:g}s") for t in self.config.taus}
                out.append(rec)
            return out

        cfg = asdict(self.config)
        return {"config": cfg,
                "split_samples": {k: [s.start, s.stop] for k, s in asdict(self.split).items()},
                "rows": records(self.rows), "best": records(self.best()),
                "warnings": list(self.warnings), "level_taus_s": list(self.level_taus)}


def _json_value(v: object) -> object:
    """Python scalars for JSON; NaN (e.g. an unstable model's outage error) becomes null."""
    if isinstance(v, (np.floating, float)):
        return float(v) if np.isfinite(v) else None
    return v.item() if isinstance(v, np.generic) else v


@dataclass(frozen=True)
class FitTask:
    """One fit of a study: a configuration and the data it is fit and scored on.

    FOS sees the raw data under both protocols, so it is one task for both rows.

    Attributes
    ----------
    method : str
    order, degree : int
    denoiser : str or None
        The denoiser of the data (None: raw data).
    level_tau : float, optional
        The level's time constant (s) of a baseline about the level.
    """

    method: str
    order: int
    degree: int
    denoiser: str | None
    level_tau: float | None = None


@dataclass(frozen=True)
class FitScore:
    """The outcome of one :class:`FitTask`: its scores and what deserves attention."""

    row: dict[str, object]
    notes: tuple[str, ...] = ()


@dataclass(frozen=True)
class StudyPlan:
    """A study split into independent fits, with the data they need.

    Attributes
    ----------
    config : StudyConfig
    split : Split
    signals : dict of str or None to (ndarray, ndarray)
        Per denoiser (None: raw data), the training samples to fit on and the
        whole record to score against.
    tasks : tuple of FitTask
        Every distinct fit, in the order the rows first need it.
    level_taus : tuple of float
        The level time constants (s) offered, chosen from the training segment.
    """

    config: StudyConfig
    split: Split
    signals: dict[str | None, tuple[np.ndarray, np.ndarray]]
    tasks: tuple[FitTask, ...]
    level_taus: tuple[float, ...] = ()

    def __reduce__(self) -> tuple:
        """Pickle the plan so that it unpickles through :func:`_unpickle_plan`."""
        return _unpickle_plan, (self.config, self.split, self.signals, self.tasks,
                                self.level_taus)


def _unpickle_plan(config: StudyConfig, split: Split,
                   signals: dict[str | None, tuple[np.ndarray, np.ndarray]],
                   tasks: tuple[FitTask, ...], level_taus: tuple[float, ...] = ()) -> StudyPlan:
    """Rebuild a plan with its own copy of the signals.

    Unpickled arrays may lie at any byte offset of a received buffer (Dask's
    frames), and numpy sums arrays that are not 8-byte aligned in another
    order: the results would differ from this process's in the last bit.
    """
    copies = {d: (np.array(fit), np.array(score)) for d, (fit, score) in signals.items()}
    return StudyPlan(config, split, copies, tasks, level_taus)


def study_split(n: int, config: StudyConfig) -> Split:
    """Split a record of ``n`` samples into the study's three segments.

    Training and evaluation take the config's durations; the prediction segment, the rest,
    must hold an outage horizon and two windows of the longest bias time.

    Raises
    ------
    InputError
        If the record is too short for the split and the outage windows of the prediction.
    """
    horizon, tau = round(config.horizon_s * config.rate), max(config.taus)
    return Split.by_duration(
        n, config.rate, config.train_s, config.evaluate_s,
        min_predict=max(horizon + 1, 2 * round(tau * config.rate)),
        why=f" (a {config.horizon_s:g} s outage horizon and two {tau:g} s bias windows)")


def plan_study(y: ArrayLike, config: StudyConfig) -> StudyPlan:
    """Check and split the record ``y``, denoise it as the protocols need, list the fits.

    Raises
    ------
    InputError
        If the record is not a finite signal or too short for the split.
    """
    y = as_signal(y, "the record")
    split = study_split(len(y), config)
    level_taus = levels_for(y[split.train], config.rate) if config.levels else ()
    tasks = tuple(dict.fromkeys(task for _, task in _row_tasks(config, level_taus)))
    signals = {d: _signals(y, split, d, config.rate)
               for d in dict.fromkeys(t.denoiser for t in tasks)}
    return StudyPlan(config, split, signals, tasks, tuple(level_taus))


def _row_tasks(config: StudyConfig, level_taus: Sequence[float]) -> list[tuple[str, FitTask]]:
    """Return the (protocol, task) of every row of the study, in row order.

    A baseline about the level has one row per level time constant.
    """
    out = []
    for protocol in config.protocols:
        for method, order, degree in config.configurations(protocol):
            denoiser = config.denoiser(protocol, method)
            taus = (level_taus if method.endswith(LEVEL) and method != "fos" + LEVEL
                    else [None])
            out += [(protocol, FitTask(method, order, degree, denoiser, tau)) for tau in taus]
    return out


def run_task(plan: StudyPlan, task: FitTask) -> FitScore:
    """Fit and score one task of ``plan``, with one BLAS thread.

    It depends on nothing but its arguments, so it gives the same numbers
    (runtime aside) in this process or on any worker.
    """
    with one_blas_thread():
        return _score(task, *plan.signals[task.denoiser], plan.split, plan.config,
                      plan.level_taus)


def assemble(plan: StudyPlan, scores: Sequence[FitScore]) -> StudyResult:
    """Assemble the study result from the scores of ``plan.tasks``, in the same order."""
    if len(scores) != len(plan.tasks):
        raise ValueError(f"{len(scores)} scores for {len(plan.tasks)} tasks")
    scored = dict(zip(plan.tasks, scores))
    rows = [{"protocol": protocol, "method": task.method,
             "label": method_label(task.method, task.degree), "order": task.order,
             "degree": task.degree, "data": task.denoiser or "raw",
             "level_tau_s": np.nan if task.level_tau is None else task.level_tau,
             **scored[task].row}
            for protocol, task in _row_tasks(plan.config, plan.level_taus)]
    notes = sorted({note for score in scores for note in score.notes})
    return StudyResult(pd.DataFrame(rows), plan.config, plan.split, notes, plan.level_taus)


def _signals(y: np.ndarray, split: Split, denoiser: str | None,
             rate: float) -> tuple[np.ndarray, np.ndarray]:
    """Return (samples to fit on, samples to score against) for one kind of data."""
    train = y[split.train]
    if denoiser is None:
        return train, y
    return denoise(train, rate, denoiser), denoise(y, rate, denoiser)


def _score(task: FitTask, fit_signal: np.ndarray, score_signal: np.ndarray, split: Split,
           config: StudyConfig, level_taus: Sequence[float]) -> FitScore:
    model = make_model(task.method, task.order, task.degree, config, level_taus,
                       task.level_tau)
    t0 = time.perf_counter()
    model.fit(fit_signal)
    runtime = time.perf_counter() - t0
    label = f"{method_label(task.method, task.degree)} (L={task.order})"
    stable = model.is_stable()
    notes = () if stable else (
        f"{label}: the fitted model is unstable; its free-run metrics are NaN",)
    pred = model.predict(score_signal)
    residual = (score_signal - pred)[split.predict]
    mse = one_step_mse(score_signal, pred, split.predict)
    row: dict[str, object] = {
        "evaluate_mse": one_step_mse(score_signal, pred, split.evaluate),
        "mse": mse,
        "position_error_m": equivalent_position_error(mse, config.sensor, config.units),
    }
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UnstableModelWarning)  # reported once, above
        outage = outage_metrics(model, score_signal, config.rate, config.sensor, config.units,
                                split.predict, horizon_s=config.horizon_s,
                                n_starts=config.n_starts, taus=config.taus, residual=residual)
    row["outage_mse"] = outage["outage_mse"] if stable else np.nan
    row["outage_position_error_m"] = outage["outage_position_error_m"] if stable else np.nan
    row.update({f"bias_rms_{t:g}s": outage["bias_rms"][t] for t in config.taus})
    row.update(runtime_s=runtime, n_terms=int(model.n_terms_), stable=stable)
    return FitScore(row, notes)

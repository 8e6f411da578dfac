"""FOSModel: a Fast Orthogonal Search difference-equation model of a time series.

The model (Tamazin et al. 2013, eqs. 14-15) is

    y[n] - mu_y = a_0 + sum_m a_m P_m[n] + e[n],

where each ``P_m`` is a product of lagged, centred outputs ``y[n-l] - mu_y``
(1 <= l <= L), local levels of the centred output (:mod:`fosmodel.core.levels`),
lagged centred inputs ``x[n-k] - mu_x`` (0 <= k <= K) and user-given columns,
chosen by :func:`fosmodel.core.fos.fos_search` among all such
candidates up to the cross-product degree.  Centring on the training means
(``center=True``) makes the selected terms independent of the sensor bias:
adding an offset to the record leaves the model unchanged but for ``mu``.

References
----------
.. [1] M. J. Korenberg, "A robust orthogonal algorithm for system identification and
   time-series analysis", Biological Cybernetics 60(4), 267-276, 1989.
.. [2] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
"""

from __future__ import annotations

import copy
import logging
import os
import warnings
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any, TypeAlias

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from sklearn.base import BaseEstimator

from .._version import __version__
from ..core.blas import one_blas_thread
from ..core.candidates import (
    OUTPUT,
    CandidateSpec,
    Term,
    check_terms_fit_spec,
    count_candidates,
    evaluate_sum,
    evaluate_terms,
    generate_terms,
)
from ..core.correlations import LagCorrelations, PooledCorrelations, fast_correlations
from ..core.derived import channels_read, derive, is_derived
from ..core.exceptions import FitWarning, InputError
from ..core.fos import (
    Correlations,
    DataCorrelations,
    StopRule,
    center,
    criterion,
    deferred_center,
    fos_search,
)
from ..core.levels import (
    check_level_rate,
    check_level_series,
    checked_level_tau,
    is_level,
    level_after,
    level_series,
    levels_for,
    with_levels,
)
from ..core.validation import as_channels, as_signal, check_fitted
from ..typeset.summary import Summary
from .compensation import (
    check_compensation,
    compensation_channels,
    compensation_series,
)
from .dynamics import (
    ar_free_run,
    ar_roots,
    cut_at_divergence,
    free_run_inputs,
    is_stable,
    warn_if_unstable,
)
from .freerun import run_many, run_one, split_expansion
from .model_schema import _ADDED_IN, FORMAT, FORMAT_VERSION
from .rawform import expand_centred

log = logging.getLogger(__name__)

_SAMPLES_PER_WEIGHT = 10  # below this per weight, a fit warns that its weights are rough
_BYTES_PER_VALUE = 8
_PREDICT_ROWS = 2**20  # samples predicted at a time in a long record
#: The channels and columns of a record, by name: a dict of arrays or a DataFrame.
Exog: TypeAlias = Mapping[str, ArrayLike] | pd.DataFrame


def _floats(values: Iterable[float]) -> list[float]:
    return [float(v) for v in values]


def _float_array(values: ArrayLike) -> np.ndarray:
    return np.asarray(values, dtype=float)


def _float_dict(values: Mapping[str, float]) -> dict[str, float]:
    return {str(k): float(v) for k, v in values.items()}


#: The fitted state beside the terms, their weights and the intercept, declared once: each
#: name (an attribute ``name_``) with how it is written to JSON and read back, for
#: :meth:`FOSModel.fit`, :meth:`FOSModel.to_dict` and :meth:`FOSModel.from_dict` alike.
#: The values are JSON or numpy values of each name's own type, hence ``Any``.
_FITTED_STATE: dict[str, tuple[Callable[[Any], object], Callable[[Any], object]]] = {
    "offsets": (_float_dict, _float_dict),
    "coef_se": (_floats, _float_array),
    "intercept_se": (float, float),
    "mse_path": (_floats, _float_array),
    "q": (_floats, _float_array),
    "mse_null": (float, float),
    "n_candidates": (int, int),
    "n_samples": (int, int),
    "stop_reason": (str, str),
    "n_dependent": (int, int),
    "target_name": (str, str),
}


class FOSModel(BaseEstimator):
    """Fast Orthogonal Search model of a sensor error time series.

    Parameters
    ----------
    max_lag : int
        L, lagged outputs ``y[n-1] .. y[n-L]``.
    degree : int
        CP, the highest cross-product degree of the lagged factors.
    exog_lags : dict of str to int, optional
        K per exogenous channel: ``{"temp": 5}`` offers ``temp[n-0] .. temp[n-5]``.
    columns : list of str, optional
        Names of user-given candidate columns (passed in ``exog``), e.g. a
        sinusoid or a trend; they enter linearly.  Once fitted, a column whose
        name says how to compute it (``cos@7.3Hz``, ``step@120s``, ... see
        :mod:`fosmodel.core.derived`) need not be passed again: with ``rate`` set,
        the model rebuilds it from the record.
    levels : list of float or "auto", optional
        Time constants in seconds of local levels ``level@<tau>s`` of the output
        to offer (the exponentially weighted mean of its past; see
        :mod:`fosmodel.core.levels` and :func:`fosmodel.core.levels.level_grid`).  They
        need ``rate``.  ``"auto"`` (the CLI's ``--levels auto``) chooses them in :meth:`fit`
        from the record's length and Allan floor (:func:`fosmodel.core.levels.levels_for`),
        kept in ``levels_`` (and saved as the list).  They are computed from the output;
        ``exog`` may carry them already (``level_series`` of the raw output, under their names,
        spot-checked) to save the work on a record used many times.
    rate : float, optional
        Sample rate in Hz (needed with ``levels``).
    product_lags : int, optional
        Cross-products only of the output lags ``y[n-1] .. y[n-P]`` (by default of
        every lagged factor and level).
    max_terms : int, optional
        Most terms to select besides the constant.
    stop : str
        Stopping rule: ``"korenberg"`` (default), ``"max_terms"``, ``"variance"``,
        ``"mean_square"``, ``"aic"``, ``"bic"``, ``"fpe"``, ``"mdl"``; see
        :class:`fosmodel.core.fos.StopRule`.
    tol : float, optional
        Fraction for the ``"variance"`` and ``"mean_square"`` rules.
    center : bool
        Build the candidates from signals centred on their training means.
    dependence_tol : float
        Candidates whose orthogonal part falls to this fraction of their own
        mean square are numerically dependent and skipped.
    max_candidates : int
        Refuse candidate sets larger than this (the count is computed first).
    correlations : {"fast", "reference"}
        Korenberg's correlation tables, or point by point on the candidate
        matrix (slow, for checking).
    compensation : dict of str to float, optional
        A known part of the output with fixed weights, by derived column name
        (:mod:`fosmodel.models.compensation`): the model's terms are fitted to, and
        its levels follow, the output minus ``sum_j w_j col_j``, which every
        prediction and free run adds back.

    Attributes
    ----------
    terms_ : list of str
        Selected terms in selection order (the constant excluded).
    coef_ : ndarray
        Their weights ``a_m``.
    intercept_ : float
        ``a_0``, the constant of the centred expansion.
    offsets_ : dict of str to float
        Centring offsets ``mu`` of ``y`` and of each channel (zeros if ``center=False``).
    mse_path_ : ndarray
        Training residual MSE after each term of ``terms_``.
    q_ : ndarray
        MSE reduction ``Q`` of each term (eq. 27).
    mse_null_ : float
        Training MSE of the constant-only model (the variance of y).
    coef_se_, intercept_se_ : ndarray, float
        Least-squares standard errors of ``coef_`` and ``intercept_`` on the
        selected terms (:attr:`fosmodel.core.fos.FOSResult.coef_se`).  They take
        the terms as given: the search that chose them out of
        ``n_candidates_`` makes them too small, and correlated residuals make
        them too small again; read them as a scale, not as a test of the terms.
    n_candidates_, n_samples_, lag_window_, stop_reason_, n_dependent_, target_name_

    Examples
    --------
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(1)
    >>> y = lfilter([1.0], [1.0, -1.5, 0.7], rng.standard_normal(5000))
    >>> model = FOSModel(max_lag=5).fit(y)
    >>> model.terms_
    ['y[n-1]', 'y[n-2]']
    >>> np.round(model.coef_, 2).tolist()
    [1.5, -0.7]
    """

    def __init__(
        self,
        max_lag: int = 10,
        degree: int = 1,
        exog_lags: dict[str, int] | None = None,
        columns: list[str] | None = None,
        levels: list[float] | str | None = None,
        rate: float | None = None,
        product_lags: int | None = None,
        max_terms: int | None = None,
        stop: str = "korenberg",
        tol: float | None = None,
        center: bool = True,
        dependence_tol: float = 1e-10,
        max_candidates: int = 100_000,
        correlations: str = "fast",
        compensation: dict[str, float] | None = None,
    ) -> None:
        self.max_lag = max_lag
        self.degree = degree
        self.exog_lags = exog_lags
        self.columns = columns
        self.levels = levels
        self.rate = rate
        self.product_lags = product_lags
        self.max_terms = max_terms
        self.stop = stop
        self.tol = tol
        self.center = center
        self.dependence_tol = dependence_tol
        self.max_candidates = max_candidates
        self.correlations = correlations
        self.compensation = compensation

    # -- fitting -------------------------------------------------------------------------

    def candidate_spec(self) -> CandidateSpec:
        """Return the candidate set these parameters offer (checked; nothing is fitted).

        Raises
        ------
        InputError
            Parameters that do not make a candidate set (e.g. levels without a rate).
        """
        spec = CandidateSpec(self.max_lag, self.degree, self.exog_lags or {}, self.columns or (),
                             levels=self._levels(), product_lags=self.product_lags)
        check_level_rate(spec.levels, self.rate)
        return spec

    def _levels(self) -> tuple[float, ...] | list[float]:
        """Return the level time constants: those given, or those ``"auto"`` chose in fit."""
        if isinstance(self.levels, str):
            if self.levels != "auto":
                raise InputError("levels must be 'auto' or a list of time constants in seconds, "
                                 f"got {self.levels!r}")
            if not hasattr(self, "levels_"):
                raise InputError("levels='auto' takes its time constants from the record: "
                                 "they are chosen in fit()")
            return self.levels_
        return self.levels or ()

    def fit(
        self, y: ArrayLike, exog: Exog | None = None,
        segments: Sequence[slice] | None = None,
    ) -> FOSModel:
        """Select terms and weights on the record ``y`` (and its exogenous channels).

        Parameters
        ----------
        y : array-like of shape (N,)
            The modelled signal (numpy array, list or pandas Series).
        exog : dict or DataFrame, optional
            Exogenous channels and user columns by name, each of length N.
        segments : sequence of slice, optional
            Contiguous runs of ``y`` between gaps: the fit pools their windows,
            each with its own lag window, so that no lag reaches across a gap.
            Runs too short for the lag window are left out.

        Returns
        -------
        self
        """
        if isinstance(self.levels, str) and self.levels == "auto":
            check_level_rate((1.0,), self.rate)
            self.levels_ = list(levels_for(as_signal(y, "y"), float(self.rate or 0.0)))
        spec = self.candidate_spec()
        rule = StopRule(self.stop, self.tol, self.max_terms)
        if self.correlations not in ("fast", "reference"):
            raise InputError(
                f"correlations must be 'fast' or 'reference', not {self.correlations!r}")
        y_arr = as_signal(y, "y")
        if check_compensation(self.compensation):
            y_arr = y_arr - self._compensation(exog, len(y_arr))
        n_cand = count_candidates(spec)
        n0 = spec.lag_window
        log.info("FOS candidate set: %d candidates (L=%d, CP=%d, exog=%s, columns=%d)",
                 n_cand, spec.max_lag, spec.degree, dict(spec.exog_lags), len(spec.columns))
        runs = _usable(segments, len(y_arr), n0)
        where = f" in {len(segments)} segments" if segments is not None else ""
        if not runs:
            raise InputError(f"record too short: {len(y_arr)} samples{where}, no longer than "
                             f"the lag window of {n0} samples (the largest lag)")
        if n_cand > self.max_candidates:
            mib = n_cand * max(len(y_arr) - n0, 0) * _BYTES_PER_VALUE / 2**20
            raise InputError(
                f"{n_cand} candidates exceed max_candidates={self.max_candidates} "
                f"(as a matrix over this record they would take {mib:,.0f} MiB); "
                "lower the lag, the degree or the channels, or raise max_candidates"
            )
        window = sum(s.stop - s.start - n0 for s in runs)
        if window < n_cand + 2:
            raise InputError(
                f"record too short: {len(y_arr)} samples{where} leave {window} in the fitting "
                f"window (after the lag window of {n0}) for {n_cand} candidates; FOS needs "
                f"at least {n_cand + 2} to tell them apart: lower the lag, the degree or the "
                "channels, or give a longer record")
        if y_arr[0] == y_arr[-1] and np.ptp(y_arr) == 0:  # ends that differ need no scan
            raise InputError(f"y is constant ({y_arr[0]:g}): there is nothing to model")
        channels = as_channels(exog, [*spec.exog_lags, *spec.columns], len(y_arr))
        _refuse_own_input(y_arr, channels)
        signals, offsets, pending = self._fit_signals(
            {OUTPUT: y_arr, **channels},
            self._given_levels(exog, y_arr, None) if segments is None else {}, spec)
        terms = [t for t in generate_terms(spec) if not t.is_constant]
        pieces = [self._with_levels({k: v[s] for k, v in signals.items()}, spec) for s in runs]
        corr: Correlations
        if self.correlations == "fast":
            with one_blas_thread():  # short products: threads cost more than they give
                parts = [fast_correlations(terms, piece, n0, offsets=pending) for piece in pieces]
                corr = parts[0] if len(parts) == 1 else PooledCorrelations(parts)
                res = fos_search(corr, rule, intercept=True,
                                  dependence_tol=self.dependence_tol)
        else:
            blocks = [evaluate_terms(terms, piece, n0) for piece in pieces]
            corr = DataCorrelations(
                blocks[0] if len(blocks) == 1 else np.vstack(blocks),
                np.concatenate([piece[OUTPUT][n0:] for piece in pieces]))
            res = fos_search(corr, rule, intercept=True, dependence_tol=self.dependence_tol)

        self.spec_ = spec
        self._set_terms([terms[i] for i in res.support], res.coef, res.intercept)
        self._set_state({"offsets": offsets, "coef_se": res.coef_se,
                         "intercept_se": res.intercept_se, "mse_path": res.mse_path, "q": res.q,
                         "mse_null": res.mse_null, "n_candidates": n_cand,
                         "n_samples": res.n_samples, "stop_reason": res.stop_reason,
                         "n_dependent": res.n_dependent,
                         "target_name": getattr(y, "name", None) or OUTPUT})
        thin = self._thin()
        if thin:
            warnings.warn(FitWarning(thin), stacklevel=2)
        return self

    def _compensation(self, exog: Exog | None, n: int) -> np.ndarray:
        """Return the compensation over ``n`` samples (zeros without one)."""
        return compensation_series(check_compensation(self.compensation), exog, n, self.rate)

    def _plain(self) -> FOSModel:
        """Return this fitted model without its compensation: the model of ``y`` minus it."""
        plain = copy.copy(self)
        plain.compensation = None
        return plain

    def without_compensation(self) -> FOSModel:
        """Return the model fitted to what the compensation leaves, without the compensation.

        Its terms and weights are this model's: it models ``y - c`` with ``c`` the
        compensation series (:func:`fosmodel.models.compensation.compensation_series` of
        :attr:`compensation`, :attr:`rate`).  A model without a compensation is returned as
        a copy.
        """
        self._check_fitted()
        return self._plain()

    def _thin(self) -> str | None:
        """Return a note when the fitting window holds few samples per weight, else None."""
        weights = len(self.terms_) + 1
        if self.n_samples_ >= _SAMPLES_PER_WEIGHT * weights:
            return None
        return (f"only {self.n_samples_} samples for {weights} weights (the constant and "
                f"{weights - 1} term(s)), fewer than {_SAMPLES_PER_WEIGHT} each: the weights "
                "are rough; fit a longer record before relying on them")

    def _level_rate(self) -> float:
        """Return the sample rate that levels and rebuilt columns are computed at.

        Raises
        ------
        InputError
            The model has no ``rate``.
        """
        if self.rate is None:
            raise InputError("levels and rebuilt columns need the sample rate (rate=...)")
        return self.rate

    def _with_levels(self, signals: dict[str, np.ndarray],
                     spec: CandidateSpec) -> dict[str, np.ndarray]:
        """Add the levels of the output (those not there already) to ``signals``.

        ``signals`` are centred and one contiguous run.
        """
        missing = [name for name in spec.level_names if name not in signals]
        if not missing:
            return dict(signals)
        return with_levels(signals, missing, self._level_rate(), OUTPUT)

    def _given_levels(self, exog: Exog | None, y: np.ndarray, mu: float | None,
                      lo: int = 0) -> dict[str, np.ndarray]:
        """Return the level series passed in ``exog`` (of the raw output), checked.

        They are cut from sample ``lo`` on and centred by ``mu`` (None: as given).
        """
        if exog is None:
            return {}
        names = [n for n in self.candidate_spec().level_names if n in set(map(str, exog.keys()))]
        levels = {n: check_level_series(np.asarray(exog[n], dtype=float), y, checked_level_tau(n),
                                        self._level_rate(), n)[lo:] for n in names}
        return levels if mu is None else {n: v - mu for n, v in levels.items()}

    def _fit_signals(
        self, signals: dict[str, np.ndarray], levels: dict[str, np.ndarray], spec: CandidateSpec,
    ) -> tuple[dict[str, np.ndarray], dict[str, float], dict[str, float]]:
        """Return the fit's signals with given ``levels``, their offsets and those left to subtract.

        With the fast correlations, and no level to compute from the centred output,
        the signals stay as they are and :class:`LagCorrelations` subtracts the offsets
        (the third dict), block by block on a long record: the fit then makes no centred
        copy of the record.  Otherwise they are centred here and nothing is left.
        """
        if self.correlations != "fast" or any(n not in levels for n in spec.level_names):
            centred, offsets = self._centred(signals, None)
            return {**centred, **{n: v - offsets[OUTPUT] for n, v in levels.items()}}, offsets, {}
        if not self.center:
            return {**signals, **levels}, {k: 0.0 for k in signals}, {}
        out, offsets, pending = {}, {}, {}
        for name, values in signals.items():
            out[name], offsets[name], pending[name] = deferred_center(values)
        pending.update({n: offsets[OUTPUT] for n in levels})
        return {**out, **levels}, offsets, pending

    def _set_state(self, values: Mapping[str, object]) -> None:
        """Set the fitted state of :data:`_FITTED_STATE` (each ``name`` as ``name_``), all of it."""
        if set(values) != set(_FITTED_STATE):
            raise InputError(f"fitted state {sorted(values)} is not {sorted(_FITTED_STATE)}")
        for name, (_, load) in _FITTED_STATE.items():
            setattr(self, f"{name}_", load(values[name]))

    def _set_terms(self, terms: list[Term], coef: np.ndarray, intercept: float) -> None:
        self.lag_window_ = self.spec_.lag_window
        self._terms = terms
        self.terms_ = [t.name for t in terms]
        self.coef_ = np.asarray(coef, dtype=float)
        self.intercept_ = float(intercept)
        self._expansion = split_expansion(terms, self.coef_, self.intercept_, self.spec_.max_lag,
                                          self.spec_.level_names, self.rate)

    def _centred(
        self, signals: dict[str, np.ndarray], offsets: Mapping[str, float] | None
    ) -> tuple[dict[str, np.ndarray], dict[str, float]]:
        """Subtract the training offsets (or, when fitting, compute them)."""
        if not self.center:
            return signals, {k: 0.0 for k in signals}
        if offsets is None:
            pairs = {k: center(v) for k, v in signals.items()}
            return ({k: c for k, (c, _) in pairs.items()},
                    {k: float(m) for k, (_, m) in pairs.items()})
        return {k: v - offsets[k] for k, v in signals.items()}, dict(offsets)

    # -- using the model -----------------------------------------------------------------

    def _check_fitted(self) -> None:
        check_fitted(self, "terms_")

    def _signals(self, y: ArrayLike, exog: Exog | None,
                 levels: bool = True) -> dict[str, np.ndarray]:
        """Centred output and inputs, with the level series given in ``exog`` if ``levels``."""
        y_arr = as_signal(y, "y")
        channels = self._inputs(exog, len(y_arr))
        signals, _ = self._centred({OUTPUT: y_arr, **channels}, self._offsets_for(channels))
        if levels and self.spec_.levels:
            signals.update(self._given_levels(exog, y_arr, self.offsets_[OUTPUT]))
        return signals

    def _inputs(self, exog: Exog | None, n: int, lo: int = 0) -> dict[str, np.ndarray]:
        """Return the channels and columns of a fitted model over samples ``lo .. n-1``.

        Each is given in ``exog`` (``n`` long), or rebuilt from its name
        (:mod:`fosmodel.core.derived`).
        """
        spec = self.spec_
        names = [*spec.exog_lags, *spec.columns]
        given: set[str] = set(map(str, exog.keys())) if exog is not None else set()
        rebuilt = [c for c in names if c not in given and is_derived(c)]
        if rebuilt and self.rate is None:
            raise InputError(f"{rebuilt[0]!r} can be rebuilt only with the model's sample rate "
                             "(rate=...); pass its values instead")
        read = [c for c in names if c not in rebuilt]
        channels = as_channels(_cut(exog, read, n, lo), read, n - lo)
        if rebuilt:
            source = as_channels(exog, channels_read(rebuilt), n)
            for name in rebuilt:
                channels[name] = derive(name, n, self._level_rate(), source, self.offsets_)[lo:]
        return channels

    def _signals_from(self, y: ArrayLike, exog: Exog | None, lo: int) -> dict[str, np.ndarray]:
        """Return the centred output, inputs and levels over samples ``lo ..`` of ``y``.

        The levels come from the record's whole past: given in ``exog``, or computed.
        """
        y_arr = as_signal(y, "y")
        n = len(y_arr)
        channels = self._inputs(exog, n, lo)
        signals, _ = self._centred({OUTPUT: y_arr[lo:], **channels},
                                   self._offsets_for(channels))
        if self.spec_.levels:
            mu = self.offsets_[OUTPUT]
            given = self._given_levels(exog, y_arr, mu, lo)
            missing = [name for name in self.spec_.level_names if name not in given]
            for name in missing:  # of the raw output: a level of y - mu is its level - mu
                given[name] = (level_series(y_arr, checked_level_tau(name), self._level_rate())
                               [lo:] - mu)
            signals.update(given)
        return signals

    def input_columns(self) -> list[str]:
        """Return the record columns this fitted model reads besides its output.

        These are the inputs it cannot rebuild, and the channels those it rebuilds come from.
        """
        self._check_fitted()
        names = [*self.spec_.exog_lags, *self.spec_.columns]
        rebuilt = [c for c in names if is_derived(c)] if self.rate is not None else []
        read = [c for c in names if c not in rebuilt]
        return read + [c for c in [*channels_read(rebuilt),
                                   *compensation_channels(self.compensation or {})]
                       if c not in read]

    def _offsets_for(self, channels: Mapping[str, object]) -> dict[str, float]:
        return {OUTPUT: self.offsets_[OUTPUT], **{k: self.offsets_[k] for k in channels}}

    def predict(
        self, y: ArrayLike, exog: Exog | None = None,
        segments: Sequence[slice] | None = None, *, start: int = 0,
    ) -> np.ndarray | pd.Series:
        """One-step-ahead prediction from the true past, aligned with ``y``.

        Sample ``n`` is predicted from ``y[n-1], y[n-2], ...`` and the channels
        up to ``n``; the first ``lag_window_`` samples (of each segment, if
        ``segments`` are given) have no prediction (NaN).  With ``start``, only
        the samples from ``start`` on are predicted (the others are NaN): the
        work is that of the samples from ``start - lag_window_`` on, and the
        levels' past.

        Returns
        -------
        ndarray, or Series with the index of ``y`` if ``y`` is a Series
        """
        self._check_fitted()
        if self.compensation:
            y_arr = as_signal(y, "y")
            comp = self._compensation(exog, len(y_arr))
            pred = self._plain().predict(y_arr - comp, exog, segments, start=start)
            return _as_input_type(np.asarray(pred) + comp, y)
        n0 = self.lag_window_
        if segments is not None:
            if start:
                raise InputError("predict takes segments or a start, not both")
            signals = self._signals(y, exog, levels=False)
            runs, lo = _usable(segments, len(signals[OUTPUT]), n0), 0
        else:
            n = np.shape(y)[0] if np.ndim(y) == 1 else 0  # the one pass names what is wrong
            if n - start > _PREDICT_ROWS and self._blockable(exog, n):
                return _as_input_type(self._predict_blocks(y, exog, int(start), n), y)
            lo = max(int(start) - n0, 0)
            signals = self._signals_from(y, exog, lo)
            runs = _usable(None, len(signals[OUTPUT]), n0)
        n = lo + len(signals[OUTPUT])
        out = np.full(n, np.nan)
        for run in runs:
            piece = self._with_levels({k: v[run] for k, v in signals.items()}, self.spec_)
            values = evaluate_sum(self._terms, self.coef_, piece, n0)
            out[lo + run.start + n0 : lo + run.stop] = (values + self.intercept_
                                                        + self.offsets_[OUTPUT])
        return _as_input_type(out, y)

    def _predict_blocks(self, y: ArrayLike, exog: Exog | None, start: int,
                        n: int) -> np.ndarray:
        """:meth:`predict` of a long record ``_PREDICT_ROWS`` samples at a time.

        Each block is predicted from the record up to its end, so it holds copies of
        one block's signals, not of the record's; every sample is computed as in one
        pass (the same products and sums), so the predictions are the same.
        """
        head = _record_heads(y, exog)
        out = np.full(n, np.nan)
        for lo in range(start, n, _PREDICT_ROWS):
            hi = min(lo + _PREDICT_ROWS, n)
            out[lo:hi] = self.predict(*head(hi), start=lo)[lo:]
        return out

    def _blockable(self, exog: Exog | None, n: int) -> bool:
        """Whether a prediction of ``n`` samples can go block by block.

        Not when a level or a derived column is not given in ``exog`` (each block would
        compute it over the record's whole past again), nor when a channel is not ``n``
        long (the one-pass path names it).
        """
        given = {str(k): np.asarray(v) for k, v in exog.items()} if exog is not None else {}
        names = [*self.spec_.level_names, *(c for c in [*self.spec_.exog_lags,
                                                       *self.spec_.columns] if is_derived(c))]
        return (all(name in given for name in names)
                and all(v.shape == (n,) for v in given.values()))

    def residuals(self, y: ArrayLike, exog: Exog | None = None) -> np.ndarray | pd.Series:
        """Return ``y`` minus its one-step prediction (NaN over the lag window)."""
        pred = self.predict(y, exog)
        return (y - pred) if isinstance(pred, pd.Series) else as_signal(y, "y") - pred

    def refit_weights(
        self, y: ArrayLike, exog: Exog | None = None,
        segments: Sequence[slice] | None = None, *, hold: bool = False,
    ) -> FOSModel:
        """Return a copy with the selected terms' weights fitted anew on ``y`` (least squares).

        The terms, the candidate set and the centring offsets stay; terms that
        are numerically dependent on ``y`` (a step after its end, say) are
        dropped.  The residual loop uses it to ask how a model chosen on one
        stretch does when its weights come from an earlier one.

        With ``hold`` and a level among the terms, the weights of the output's lags and
        levels are fitted subject to summing to one (least squares under that equality,
        :func:`_held_weights`): the model is then a local level with deviations about it,
        and a free run holds the level it starts from instead of returning to the
        training mean.  Least squares alone on a stretch where the wander is weak against
        the noise puts that sum well below one, and an outage then drifts back to a mean
        the bias has left.

        Returns
        -------
        FOSModel
        """
        self._check_fitted()
        y_arr = as_signal(y, "y")
        if self.compensation:
            refit = self._plain().refit_weights(y_arr - self._compensation(exog, len(y_arr)),
                                                exog, segments, hold=hold)
            refit.compensation = self.compensation
            return refit
        n0 = self.lag_window_
        runs = _usable(segments, len(y_arr), n0)
        if sum(s.stop - s.start - n0 for s in runs) < len(self._terms) + 2:
            raise InputError(f"record too short to refit {len(self._terms)} term(s): "
                             f"{len(y_arr)} samples")
        signals = self._signals(y_arr, exog, levels=segments is None)
        pieces = [self._with_levels({k: v[s] for k, v in signals.items()}, self.spec_)
                  for s in runs]
        corr: Correlations
        if self.correlations == "reference":
            corr = DataCorrelations(
                np.vstack([evaluate_terms(self._terms, piece, n0) for piece in pieces]),
                np.concatenate([piece[OUTPUT][n0:] for piece in pieces]))
        else:
            parts = [LagCorrelations(self._terms, piece, n0) for piece in pieces]
            corr = parts[0] if len(parts) == 1 else PooledCorrelations(parts)
        with one_blas_thread():
            res = fos_search(corr, StopRule("max_terms", max_terms=len(self._terms)),
                              intercept=True, dependence_tol=self.dependence_tol)
        new = copy.copy(self)
        terms = [self._terms[i] for i in res.support]
        dynamic = [any(ch == OUTPUT or is_level(ch) for ch, _ in t.factors) and t.degree == 1
                   for t in terms]
        if hold and any(is_level(t.factors[0][0]) for t, d in zip(terms, dynamic) if d):
            res.coef, res.intercept = _held_weights(corr, res.support, np.array(dynamic))
        new._set_terms(terms, res.coef, res.intercept)
        new.mse_path_, new.q_, new.mse_null_ = res.mse_path, res.q, res.mse_null
        new.coef_se_, new.intercept_se_ = res.coef_se, res.intercept_se
        new.n_samples_, new.stop_reason_ = res.n_samples, "refit"
        new.n_dependent_ = res.n_dependent
        return new

    def shifted(self, offset: float) -> FOSModel:
        """Return a copy whose one-step predictions are ``offset`` higher (its constant moved).

        Another session of the same sensor differs by its own constant (its turn-on
        bias): ``offset`` is this model's one-step residual there with the output held at
        its mean (:func:`fosmodel.models.sessions.session_constant`).  A free run's level
        moves by ``offset`` over one minus the sum of the output's own weights.
        """
        self._check_fitted()
        new = copy.copy(self)
        new._set_terms(self._terms, self.coef_, self.intercept_ + float(offset))
        return new

    def ar_coefficients(self) -> np.ndarray:
        """Weights of the pure output lags ``y[n-l]``, l = 1..L (zeros where not selected)."""
        self._check_fitted()
        a = np.zeros(self.spec_.max_lag)
        for term, c in zip(self._terms, self.coef_):
            if term.degree == 1:
                channel, lag = term.factors[0]
                if channel == OUTPUT and lag is not None:
                    a[lag - 1] = c
        return a

    def ar_roots(self) -> np.ndarray:
        """Roots of ``z^L - a_1 z^(L-1) - ... - a_L`` for the linear output dynamics."""
        return ar_roots(self.ar_coefficients())

    def is_stable(self) -> bool:
        """Whether every root of the linear output dynamics lies inside the unit circle."""
        return is_stable(self.ar_coefficients())

    @property
    def n_terms_(self) -> int:
        """Number of selected terms besides the constant."""
        self._check_fitted()
        return len(self.terms_)

    def simulate(
        self,
        y_init: ArrayLike,
        n_steps: int,
        exog: Exog | None = None,
        noise: ArrayLike | None = None,
    ) -> np.ndarray:
        """Free run: continue ``y_init`` for ``n_steps`` samples from the model's own output.

        Parameters
        ----------
        y_init : array-like
            True past, at least ``lag_window_`` samples; the run starts after its end.
            The levels (if any) are the exponentially weighted means of all of it;
            the lags read only its last ``lag_window_`` samples.
        n_steps : int
            Samples to simulate.
        exog : dict or DataFrame, optional
            Channels and columns for ``len(y_init) + n_steps`` samples, aligned
            with ``y_init`` followed by the simulated part.
        noise : array-like, optional
            Driving noise added at each simulated step (zero by default: the
            deterministic free-run prediction).

        Returns
        -------
        ndarray of shape (n_steps,)

        Warns
        -----
        UnstableModelWarning
            If the linear output dynamics are unstable, or the run diverges
            (the samples from the divergence on are NaN).
        """
        self._check_fitted()
        if self.compensation:
            past = as_signal(y_init, "y_init")
            comp = self._compensation(exog, len(past) + int(n_steps))
            run = self._plain().simulate(past - comp[: len(past)], n_steps, exog, noise)
            return run + comp[len(past):]
        n0 = self.lag_window_
        y0, drive = free_run_inputs(y_init, n_steps, noise, n0)
        warn_if_unstable(self.ar_coefficients(), "the fitted output dynamics")
        channels = self._inputs(exog, len(y0) + int(n_steps))
        cut = len(y0) - n0  # only the last N0 samples of the past reach the lags
        recent = {OUTPUT: np.r_[y0[cut:], np.zeros(n_steps)],
                  **{k: v[cut:] for k, v in channels.items()}}
        signals, _ = self._centred(recent, self._offsets_for(channels))
        ex = self._expansion
        drive = drive + ex.intercept + evaluate_sum(
            [t for t, _ in ex.drive], [c for _, c in ex.drive], signals, n0)
        with np.errstate(over="ignore", invalid="ignore"):
            if ex.nonlinear or len(ex.gains):
                levels = self._levels_after(y0, exog)
                rests = [_rest(t.rest, signals, n0) for t in ex.nonlinear]
                out = run_one(ex, signals[OUTPUT][:n0], levels, drive, rests)
            else:
                out = ar_free_run(ex.phi, signals[OUTPUT][:n0], drive)
        return cut_at_divergence(out) + self.offsets_[OUTPUT]

    def _levels_after(self, y0: np.ndarray, exog: Exog | None) -> np.ndarray:
        """Return the centred levels at the first sample after ``y0``.

        From the series given in ``exog`` over the past and the run, or computed from ``y0``.
        """
        mu, out = self.offsets_[OUTPUT], []
        given: Exog = exog if exog is not None else {}
        for name in self.spec_.level_names:
            tau, rate = checked_level_tau(name), self._level_rate()
            if name in given:
                past = check_level_series(np.asarray(given[name], dtype=float)[: len(y0)], y0,
                                          tau, rate, name)
                a = 1.0 / (tau * rate)
                out.append((1.0 - a) * past[-1] + a * y0[-1] - mu)
            else:
                out.append(level_after(y0 - mu, tau, rate))
        return np.array(out)

    def free_runs(
        self, y: ArrayLike, starts: Sequence[int] | np.ndarray, n_steps: int,
        exog: Exog | None = None,
    ) -> np.ndarray:
        """Free runs of ``n_steps`` samples from the true past ``y[:s]``, each ``s`` in ``starts``.

        Row ``k`` equals ``simulate(y[:s_k], n_steps, exog cut to y[:s_k + n_steps])``
        (to rounding), computed for all starts at once; NaN in a row from a
        divergence on.  ``y`` (and ``exog``) must cover every run.

        Returns
        -------
        ndarray of shape (len(starts), n_steps)
        """
        self._check_fitted()
        if self.compensation:
            y_arr = as_signal(y, "y")
            comp = self._compensation(exog, len(y_arr))
            runs = self._plain().free_runs(y_arr - comp, starts, n_steps, exog)
            at = np.asarray(starts, dtype=np.int64).reshape(-1, 1) + np.arange(n_steps)
            return runs + comp[at]
        n, n0 = len(as_signal(y, "y")), self.lag_window_
        s = np.asarray(starts, dtype=np.int64).reshape(-1)
        if not s.size:
            return np.empty((0, n_steps))
        if s.min() < n0 or s.max() + n_steps > n:
            raise InputError(f"free runs of {n_steps} samples from starts {s.min()}..{s.max()} "
                             f"need samples {n0}..{s.max() + n_steps - 1}; y has {n}")
        lo = int(s.min()) - n0  # nothing before reaches a run (the levels come with the signals)
        if len(s) > 1 and s.max() + n_steps - lo > _PREDICT_ROWS and self._blockable(exog, n):
            return self._free_runs_in_groups(y, s, n_steps, exog)
        signals = self._signals_from(y, exog, lo)
        s = s - lo
        ex = self._expansion
        steps = s[:, None] + np.arange(n_steps)
        drive = ex.intercept + evaluate_sum(
            [t for t, _ in ex.drive], [c for _, c in ex.drive], signals, n0)[steps - n0]
        levels = np.column_stack([signals[name][s] for name in self.spec_.level_names]) \
            if len(ex.gains) else np.zeros((len(s), 0))
        past = signals[OUTPUT][s[:, None] + np.arange(-n0, 0)]
        rests = [None if t.rest is None else evaluate_sum([t.rest], [1.0], signals, n0)[steps - n0]
                 for t in ex.nonlinear]
        return run_many(ex, past, levels, drive, rests) + self.offsets_[OUTPUT]

    def _free_runs_in_groups(self, y: ArrayLike, starts: np.ndarray, n_steps: int,
                             exog: Exog | None) -> np.ndarray:
        """:meth:`free_runs` from starts spread over a long record, a group of them at a time.

        A group's runs and their past span at most ``_PREDICT_ROWS`` samples, so it holds
        copies of that many samples of the signals, not of the record's; each run is
        computed from the same samples as in one call.
        """
        head = _record_heads(y, exog)
        order = np.argsort(starts, kind="stable")
        ordered = starts[order]
        out = np.empty((len(starts), n_steps))
        first = 0
        while first < len(order):
            reach = ordered[first] - self.lag_window_ + _PREDICT_ROWS - n_steps
            last = max(int(np.searchsorted(ordered, reach, side="right")), first + 1)
            y_head, exog_head = head(int(ordered[last - 1]) + n_steps)
            out[order[first:last]] = self.free_runs(y_head, ordered[first:last], n_steps,
                                                    exog_head)
            first = last
        return out

    # -- reporting and persistence -------------------------------------------------------

    def summary(self) -> Summary:
        """Summarise the fit: each term, its weight, MSE reduction Q and share of the variance."""
        self._check_fitted()
        null = self.mse_null_
        share = 100.0 * self.q_ / null if null > 0 else np.zeros_like(self.q_)
        table = pd.DataFrame({
            "term": ["1", *self.terms_],
            "coef": [self.intercept_, *self.coef_],
            "std err": [self.intercept_se_, *self.coef_se_],
            "Q (MSE reduction)": [np.nan, *self.q_],
            "% var": [np.nan, *share],
            "cum % var": [np.nan, *np.cumsum(share)],
        })
        final = float(self.mse_path_[-1]) if len(self.mse_path_) else null
        spec = self.spec_
        info = [
            ("Output", str(self.target_name_)),
            ("Samples in window", f"{self.n_samples_}"),
            ("Lag window N0", f"{self.lag_window_}"),
            ("Candidates", f"{self.n_candidates_}"),
            ("Max lag L / CP", f"{spec.max_lag} / {spec.degree}"),
            ("Exogenous", ", ".join(f"{k}:0-{v}" for k, v in spec.exog_lags.items()) or "none"),
            *([("Levels offered", ", ".join(spec.level_names))] if spec.levels else []),
            ("Terms selected", f"{len(self.terms_)}"),
            ("Stop rule",
             self.stop if self.max_terms is None else f"{self.stop}, max {self.max_terms}"),
            ("Stop reason", self.stop_reason_),
            ("Dependent skipped", f"{self.n_dependent_}"),
            ("Null MSE (variance)", f"{null:.6g}"),
            ("Final MSE", f"{final:.6g}"),
            ("Variance explained", f"{100 * (1 - final / null) if null > 0 else 0:.2f} %"),
            *[(kind.upper(), f"{criterion(kind, final, len(self.terms_) + 1, self.n_samples_):.6g}")
              for kind in ("aic", "bic", "fpe")],
            ("Output offset mu_y", f"{self.offsets_[OUTPUT]:.6g}"),
            *([("Compensation", " + ".join(f"{w:.6g} {name}"
                                          for name, w in self.compensation.items()))]
              if self.compensation else []),
        ]
        notes = [
            "Terms are products of centred signals: y[n-l] stands for y[n-l] - mu_y."
            if self.center else "Terms are products of the raw signals.",
            "Q is the training MSE reduction of each term (FOS eq. 27), in selection order.",
            "Std err is least squares' on the selected terms as if they were fixed in advance: "
            "it ignores the search over the candidates and residual correlation (both make it "
            "too small).",
            "AIC = N ln MSE + 2k, BIC = N ln MSE + k ln N, FPE = MSE (N + k)/(N - k), with k the "
            "terms and the constant, on the training window: the criteria the stop rules use.",
        ]
        thin = self._thin()
        if thin:
            notes.append(thin[0].upper() + thin[1:] + ".")
        if self.compensation:
            notes.append("The terms model the output minus the compensation (fixed weights on "
                         "derived columns of the drivers); predictions and free runs add it back.")
        if spec.levels:
            notes.append("level@<tau>s is the exponentially weighted mean of the output's past "
                         "(time constant tau); in a free run it follows the model's own output.")
        return Summary("Fast Orthogonal Search model", info, table, notes)

    def save(self, path: str | os.PathLike[str],
             meta: Mapping[str, object] | None = None) -> None:
        """Write the fitted model to ``path`` as the JSON ``fosmodel fit`` writes, atomically.

        ``meta`` are the record's facts kept beside it (``source``, ``column``, ``rate_hz``);
        ``fosmodel predict`` reads the file, and :meth:`load` reads it back.

        Examples
        --------
        >>> import numpy as np
        >>> y = np.random.default_rng(0).standard_normal(500)
        >>> model = FOSModel(max_lag=2).fit(y)
        >>> import os, tempfile
        >>> path = os.path.join(tempfile.mkdtemp(), "model.json")
        >>> model.save(path, {"column": "gyro_x"})
        >>> FOSModel.load(path).terms_ == model.terms_
        True
        """
        from .model_file import save_model  # here: a model file is written only when asked

        self._check_fitted()
        save_model(path, self, meta)

    @classmethod
    def load(cls, path: str | os.PathLike[str]) -> FOSModel:
        """Read a model file (``fosmodel fit``'s, :meth:`save`'s), checked down to its numbers.

        Raises
        ------
        InputError
            The file cannot be read or is not a model file (the message names it and why).
        """
        from .model_file import load_model  # here: a model file is read only when asked

        return load_model(path, cls.from_dict)

    def to_dict(self, meta: Mapping[str, object] | None = None) -> dict:
        """JSON-serialisable form; :meth:`from_dict` restores a model that predicts identically."""
        self._check_fitted()
        return {
            "format": FORMAT,
            "format_version": FORMAT_VERSION,
            "fosmodel_version": __version__,
            "params": {**self.get_params(), "levels": list(self._levels()) or None},
            "fitted": {
                "terms": list(self.terms_),
                "coef": [float(c) for c in self.coef_],
                "intercept": float(self.intercept_),
                **{name: save(getattr(self, f"{name}_"))
                   for name, (save, _) in _FITTED_STATE.items()},
            },
            "meta": dict(meta or {}),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> FOSModel:
        """Rebuild a fitted model from :meth:`to_dict` output.

        Raises
        ------
        InputError
            Not a fosmodel model, written by a newer format version, or corrupted.
        """
        if not isinstance(data, Mapping) or data.get("format") != FORMAT:
            raise InputError("not a fosmodel FOSModel file (missing or wrong 'format')")
        version = data.get("format_version")
        if not isinstance(version, int) or version > FORMAT_VERSION:
            raise InputError(
                f"model file format version {version!r} is newer than this fosmodel "
                f"({__version__}) reads (version {FORMAT_VERSION}); upgrade fosmodel"
            )
        try:
            model = cls(**data["params"])
            fitted = data["fitted"]
            spec = model.candidate_spec()
            terms = [Term.parse(name, max_degree=spec.degree) for name in fitted["terms"]]
            check_terms_fit_spec(terms, spec)
            coef = np.asarray(fitted["coef"], dtype=float)
            if coef.shape != (len(terms),):
                raise InputError("coefficient count does not match the term count")
            model.spec_ = spec
            model._set_terms(terms, coef, float(fitted["intercept"]))
            fitted = {**_older_state(version, fitted, len(terms)), **fitted}
            model._set_state({name: fitted[name] for name in _FITTED_STATE})
            missing = {OUTPUT, *spec.exog_lags, *spec.columns} - set(model.offsets_)
            if missing:
                raise InputError(f"offsets missing for {', '.join(sorted(missing))}")
        except InputError as exc:
            raise InputError(f"corrupted model file: {exc}") from None
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"corrupted model file: {type(exc).__name__}: {exc}") from None
        model.meta_ = dict(data.get("meta") or {})
        return model

    def raw_coefficients(self) -> dict[str, float]:
        """Return the fitted model written in the raw signals: term name -> weight, ``"1"`` first.

        The products of centred factors ``z - mu`` multiplied out into raw monomials
        (:mod:`fosmodel.models.rawform`), ``mu_y`` moved into the constant; the raw form
        predicts what :meth:`predict` does.  A model fitted with ``center=False`` comes
        back as its terms and its constant ``intercept_``.
        """
        self._check_fitted()
        raw = expand_centred(self._terms, self.coef_, self.intercept_, self.offsets_)
        return {term.name: weight for term, weight in raw.items()}


def _held_weights(corr: Correlations, support: np.ndarray,
                  dynamic: np.ndarray) -> tuple[np.ndarray, float]:
    """Least-squares weights of the ``support`` terms whose ``dynamic`` ones sum to one.

    On the covariances (the intercept is ``mean(y) - means . w``): ``w = C^-1 (c + l a)``
    with ``a`` the indicator of the dynamic terms and ``l`` the Lagrange multiplier that
    makes ``a . w = 1``.
    """
    means = corr.means[support]
    cov = np.column_stack([corr.column(int(j))[support] for j in support]) - np.outer(means,
                                                                                     means)
    target = corr.target[support] - means * corr.y_mean
    a = dynamic.astype(float)
    solve = np.linalg.pinv(cov)
    base, step = solve @ target, solve @ a
    w = base + (1.0 - a @ base) / (a @ step) * step
    return w, float(corr.y_mean - means @ w)


def _older_state(version: int, fitted: Mapping[str, object], n_terms: int) -> dict[str, object]:
    """Return the fitted state a file of format ``version`` lacks, as it reads there."""
    return {name: default(n_terms) for added, names in _ADDED_IN.items() if version < added
            for name, default in names.items() if name not in fitted}


def _record_heads(
    y: ArrayLike, exog: Exog | None,
) -> Callable[[int], tuple[np.ndarray, dict[str, np.ndarray] | None]]:
    """Return a function giving the first ``hi`` samples of ``y`` and of each channel.

    ``y`` and the channels (a DataFrame's columns too) become arrays once, not at every cut:
    the long-record paths predict and free-run a record's head many times.
    """
    y_arr = np.asarray(y, dtype=float)
    columns = {k: np.asarray(v) for k, v in exog.items()} if exog is not None else None

    def head(hi: int) -> tuple[np.ndarray, dict[str, np.ndarray] | None]:
        return y_arr[:hi], ({k: v[:hi] for k, v in columns.items()} if columns is not None
                            else None)

    return head


def _as_input_type(prediction: np.ndarray, y: ArrayLike) -> np.ndarray | pd.Series:
    """Return the prediction as a Series with ``y``'s index when ``y`` is one."""
    if isinstance(y, pd.Series):
        return pd.Series(prediction, index=y.index, name="prediction")
    return prediction


def _cut(exog: Exog | None, names: Sequence[str], n: int, lo: int) -> Exog | None:
    """Return ``exog``'s channels ``names`` from sample ``lo`` on (lengths checked against n)."""
    if exog is None or not names:
        return exog
    out = {}
    for name in names:
        if name in exog:
            values = np.asarray(exog[name])
            if values.ndim != 1 or len(values) != n:
                raise InputError(f"channel {name!r} has {values.size} samples, the output has {n}")
            out[name] = values[lo:]
    return out or exog


def _rest(term: Term | None, signals: Mapping[str, np.ndarray], start: int) -> np.ndarray | None:
    """Return a nonlinear term's input factors over the simulated samples (None: it has none)."""
    return None if term is None else evaluate_sum([term], [1.0], signals, start)


def _refuse_own_input(y: np.ndarray, channels: Mapping[str, np.ndarray]) -> None:
    """Refuse an input channel equal to y: its lag 0 would be the very value predicted."""
    for name, x in channels.items():
        if np.array_equal(x, y):
            raise InputError(f"input channel {name!r} is the modelled signal itself: its lag 0 is "
                             "the value predicted (its past is in max_lag)")


def _usable(segments: Sequence[slice] | None, n: int, n0: int) -> list[slice]:
    """Return the runs of samples to use: ``segments`` (checked) or the whole record.

    Each run kept is longer than the lag window.
    """
    if segments is None:
        return [slice(0, n)] if n > n0 else []
    runs, last = [], 0
    for s in segments:
        start, stop = s.start or 0, n if s.stop is None else s.stop
        if not 0 <= start < stop <= n or start < last:
            raise InputError(f"segments must be ordered, non-overlapping runs within the "
                             f"{n} samples; got {s}")
        last = stop
        if stop - start > n0:
            runs.append(slice(start, stop))
    return runs

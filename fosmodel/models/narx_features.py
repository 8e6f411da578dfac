"""FOS candidate columns of a NARX model as a scikit-learn transformer.

A NARX model predicts ``y[n]`` from past outputs ``y[n-1] .. y[n-L]``, inputs
``x[n-0] .. x[n-K]`` and their products.  Two steps make those columns for
scikit-learn:

* :func:`lagged_rows` cuts a record once into rows, one per sample ``n`` from the
  lag window on: its lagged values (columns named ``y[n-1]``, ``x[n-0]``, ...) and
  the target ``y[n]``, aligned with them.  The first ``window`` samples, whose
  lags would reach before the record, have no row.
* :class:`NARXFeatures` forms, from such rows, the candidates of
  :mod:`fosmodel.core.candidates` for its ``max_lag``, ``degree`` and ``exog_lags``
  (any up to those of the rows), centred like :class:`~fosmodel.models.model.FOSModel`.

Each row carries its own past, so a transformer never drops rows (a scikit-learn
pipeline could not drop the target's with them) and a
:class:`~sklearn.model_selection.TimeSeriesSplit` of the rows is one of the record:
a model is tuned over the lags, the degree and the number of terms with
``GridSearchCV(Pipeline([("narx", NARXFeatures()), ("fos", FOSRegressor())]), ...)``.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from numbers import Integral

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from sklearn.base import BaseEstimator, TransformerMixin, _fit_context
from sklearn.utils._param_validation import Interval
from sklearn.utils.validation import _check_feature_names_in, validate_data

from ..core.candidates import (
    OUTPUT,
    CandidateSpec,
    Factor,
    Term,
    evaluate_terms,
    generate_terms,
)
from ..core.exceptions import InputError
from ..core.levels import is_level
from ..core.validation import as_channels, as_signal, check_fitted


def lagged_rows(
    y: ArrayLike, exog: Mapping[str, ArrayLike] | pd.DataFrame | None = None, *, max_lag: int,
    exog_lags: Mapping[str, int] | None = None,
) -> tuple[pd.DataFrame, pd.Series]:
    """Cut a record into rows of lagged values, and the target aligned with them.

    Parameters
    ----------
    y : array-like of shape (N,)
        The modelled output.
    exog : dict or DataFrame, optional
        Input channels by name, each of length N.
    max_lag : int
        Output lags ``y[n-1] .. y[n-max_lag]`` in each row (the most any model tuned
        on the rows will read).
    exog_lags : mapping of str to int, optional
        K per input channel: ``x[n-0] .. x[n-K]`` in each row.

    Returns
    -------
    X : DataFrame of shape (N - window, max_lag + sum(K + 1))
        Row ``n`` holds the lagged values at sample ``n``; its index is ``n`` (or
        the index of ``y`` if ``y`` is a Series).  ``window`` is the largest lag.
    target : Series of shape (N - window,)
        ``y[n]``, on the same index.

    Raises
    ------
    InputError
        Bad lags or channel names, a channel missing or of another length, a
        non-finite value, or a record no longer than the window.
    """
    spec = CandidateSpec(max_lag, 1, exog_lags or {}, constant=False)
    y_arr = as_signal(y, "y")
    window = spec.lag_window
    if len(y_arr) <= window:
        raise InputError(f"record too short: {len(y_arr)} samples, no longer than the lag "
                         f"window of {window} samples (the largest lag)")
    signals = {OUTPUT: y_arr, **as_channels(exog, spec.exog_lags, len(y_arr))}
    terms = generate_terms(spec)
    index = y.index[window:] if isinstance(y, pd.Series) else pd.RangeIndex(window, len(y_arr))
    rows = pd.DataFrame(evaluate_terms(terms, signals, window), index=index,
                        columns=[t.name for t in terms])
    return rows, pd.Series(y_arr[window:], index=index, name=getattr(y, "name", None) or OUTPUT)


class NARXFeatures(TransformerMixin, BaseEstimator):
    """The FOS candidates of a NARX model from rows of lagged values.

    Reads the rows :func:`lagged_rows` makes: columns named by lagged values
    (``y[n-1]``, ``x[n-0]``, ...); an array without column names holds the output
    lags ``y[n-1], y[n-2], ...`` in that order.  It returns one column per
    candidate of :func:`fosmodel.core.candidates.generate_terms` but the
    constant (the regressor fits it): the lagged values and their products up
    to ``degree``, named as FOSModel names them (``y[n-1]*x[n-1]``, ``y[n-2]^2``).

    Parameters
    ----------
    max_lag : int, optional
        L: output lags ``y[n-1] .. y[n-L]`` (by default every one the rows hold).
    degree : int
        CP: the highest degree of the products.
    exog_lags : dict of str to int, optional
        K per input channel: ``x[n-0] .. x[n-K]`` (by default every input the rows
        hold, with all its lags).
    product_lags : int, optional
        Products only of the output lags ``y[n-1] .. y[n-P]``.
    center : bool
        Subtract from each channel its mean over the fitted rows (that of its
        newest column: ``y[n-1]``, ``x[n-0]``) before forming the products, as
        ``FOSModel(center=True)`` does; with ``center=False`` the products are of
        the raw values (a different model class once the terms are few, see
        :mod:`fosmodel.models.rawform`).

    Attributes
    ----------
    spec_ : CandidateSpec
        The candidate set formed.
    offsets_ : dict of str to float
        The mean subtracted from each channel (zeros with ``center=False``).
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        Present when ``X`` had column names.
    """

    _parameter_constraints: dict = {
        "max_lag": [Interval(Integral, 0, None, closed="left"), None],
        "degree": [Interval(Integral, 1, None, closed="left")],
        "exog_lags": [dict, None],
        "product_lags": [Interval(Integral, 1, None, closed="left"), None],
        "center": ["boolean"],
    }

    def __init__(
        self,
        max_lag: int | None = None,
        degree: int = 1,
        exog_lags: dict[str, int] | None = None,
        product_lags: int | None = None,
        center: bool = True,
    ) -> None:
        self.max_lag = max_lag
        self.degree = degree
        self.exog_lags = exog_lags
        self.product_lags = product_lags
        self.center = center

    @_fit_context(prefer_skip_nested_validation=True)
    def fit(self, X: ArrayLike, y: object = None) -> NARXFeatures:
        """Choose the candidates and learn the channel means from the rows ``X``.

        Raises
        ------
        InputError
            A column that is not a lagged value, the output at ``n`` itself, or a
            lagged value the candidates need missing from ``X``.
        """
        X_checked = validate_data(self, X, dtype=np.float64)
        given = {factor: j for j, factor in enumerate(self._factors_in())}
        lags = _lags_by_channel(given)
        exog_lags = self.exog_lags if self.exog_lags is not None else {
            ch: lags[ch][-1] for ch in lags if ch != OUTPUT}
        max_lag = self.max_lag if self.max_lag is not None else max(lags.get(OUTPUT, [0]))
        spec = CandidateSpec(max_lag, self.degree, exog_lags, constant=False,
                             product_lags=self.product_lags)
        if not spec.base_factors():
            raise InputError("no candidates: max_lag is 0 and no input lags are offered")
        for factor in spec.base_factors():
            if factor not in given:
                raise InputError(f"X has no column {Term((factor,)).name!r}, which the "
                                 f"candidates read (max_lag={max_lag}, exog_lags={exog_lags})")
        self.spec_ = spec
        self._columns = given
        self._terms = generate_terms(spec)
        self.offsets_ = {ch: float(X_checked[:, given[(ch, lag[0])]].mean()) if self.center
                         else 0.0
                         for ch, lag in _lags_by_channel(spec.base_factors()).items()}
        return self

    def _factors_in(self) -> list[tuple[str, int]]:
        """Return the lagged value each column of ``X`` holds, read from its name."""
        if not hasattr(self, "feature_names_in_"):
            return [(OUTPUT, lag) for lag in range(1, self.n_features_in_ + 1)]
        factors = []
        for name in self.feature_names_in_:
            factor = _lagged_factor(str(name))
            if factor in factors:
                raise InputError(f"X has two columns {name!r}")
            factors.append(factor)
        return factors

    def transform(self, X: ArrayLike) -> np.ndarray:
        """Return the candidate columns of the rows ``X``, as :meth:`get_feature_names_out` orders.

        Returns
        -------
        ndarray of shape (n_rows, n_candidates)
        """
        check_fitted(self, "spec_")
        X_checked = validate_data(self, X, reset=False, dtype=np.float64)
        values: dict[Factor, np.ndarray] = {
            factor: X_checked[:, j] - self.offsets_[factor[0]]
            for factor, j in self._columns.items() if factor[0] in self.offsets_}
        out = np.ones((X_checked.shape[0], len(self._terms)))
        for j, term in enumerate(self._terms):
            for factor in term.factors:
                out[:, j] *= values[factor]
        return out

    def get_feature_names_out(self, input_features: ArrayLike | None = None) -> np.ndarray:
        """Return the candidates' names, e.g. ``y[n-1]``, ``y[n-1]*x[n-2]``, ``y[n-2]^2``.

        ``input_features`` is only checked against the columns seen in fit: the
        names are those of the candidates, fixed by fit.
        """
        check_fitted(self, "spec_")
        _check_feature_names_in(self, input_features)
        return np.asarray([t.name for t in self._terms], dtype=object)


def _lagged_factor(name: str) -> tuple[str, int]:
    """Return ``(channel, lag)`` of a column named like ``y[n-1]`` or ``x[n-0]``."""
    try:
        factors = Term.parse(name).factors
    except InputError:
        factors = ()
    if len(factors) == 1:
        channel, lag = factors[0]
        if lag is not None and not is_level(channel):
            if (channel, lag) == (OUTPUT, 0):
                raise InputError(f"column {name!r} of X is the output at n, the value "
                                 "predicted; give its lags from 1 on")
            return channel, lag
    raise InputError(f"column {name!r} of X is not a lagged value such as 'y[n-1]' or "
                     "'x[n-0]'")


def _lags_by_channel(factors: Iterable[Factor]) -> dict[str, list[int]]:
    """Return the lags of each channel among ``factors``, smallest (newest) first.

    A user column (no lag) has none.
    """
    lags: dict[str, list[int]] = {}
    for ch, lag in factors:
        if lag is not None:
            lags.setdefault(ch, []).append(lag)
    return {ch: sorted(values) for ch, values in lags.items()}

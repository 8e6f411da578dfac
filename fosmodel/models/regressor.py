"""FOSRegressor: Fast Orthogonal Search as a scikit-learn regressor over any candidate matrix."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike
from sklearn.base import BaseEstimator, RegressorMixin
from sklearn.utils.validation import check_is_fitted, validate_data

from ..core.fos import fos


class FOSRegressor(RegressorMixin, BaseEstimator):
    """Sparse linear model whose terms are chosen by Fast Orthogonal Search.

    Each column of ``X`` is a candidate function; FOS adds, one at a time, the
    candidate with the largest MSE reduction until the stopping rule fires.

    Parameters
    ----------
    max_terms : int, optional
        Most terms to select besides the intercept.
    stop : str
        Stopping rule (see :class:`fosmodel.core.fos.StopRule`).
    tol : float, optional
        Fraction for the ``"variance"`` / ``"mean_square"`` rules.
    fit_intercept : bool
        Fit a constant term.
    dependence_tol : float
        Relative threshold below which a candidate counts as dependent on the
        selected ones and is skipped.

    Attributes
    ----------
    coef_ : ndarray of shape (n_features,)
        Weights, zero for unselected candidates.
    intercept_ : float
    support_ : ndarray of int
        Selected columns in selection order.
    mse_path_ : ndarray
        Training residual MSE after each selected term.
    n_terms_ : int
    stop_reason_ : str
    n_features_in_ : int
    feature_names_in_ : ndarray of str
        Present when ``X`` had string column names.
    """

    def __init__(
        self,
        max_terms: int | None = None,
        stop: str = "korenberg",
        tol: float | None = None,
        fit_intercept: bool = True,
        dependence_tol: float = 1e-10,
    ) -> None:
        self.max_terms = max_terms
        self.stop = stop
        self.tol = tol
        self.fit_intercept = fit_intercept
        self.dependence_tol = dependence_tol

    def fit(self, X: ArrayLike, y: ArrayLike) -> FOSRegressor:
        """Select terms among the columns of ``X`` and fit their weights."""
        X_checked, y_checked = validate_data(self, X, y, y_numeric=True, dtype=np.float64)
        res = fos(X_checked, y_checked, max_terms=self.max_terms, stop=self.stop, tol=self.tol,
                  fit_intercept=self.fit_intercept, dependence_tol=self.dependence_tol)
        self.coef_ = np.zeros(X_checked.shape[1])
        self.coef_[res.support] = res.coef
        self.intercept_ = res.intercept
        self.support_ = res.support
        self.mse_path_ = res.mse_path
        self.n_terms_ = res.n_terms
        self.stop_reason_ = res.stop_reason
        return self

    def predict(self, X: ArrayLike) -> np.ndarray:
        """Linear prediction ``X @ coef_ + intercept_``."""
        check_is_fitted(self)
        X_checked = validate_data(self, X, reset=False, dtype=np.float64)
        return X_checked @ self.coef_ + self.intercept_

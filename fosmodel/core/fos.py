"""Fast Orthogonal Search: Korenberg's implicit Gram-Schmidt (Tamazin et al. 2013, eqs. 17-28).

The search needs only correlations: the mean of each candidate, its mean
square, its correlation with the output and, for each *selected* term, its
correlations with every candidate (one Gram column per step; the full C x C
matrix is never formed).  Where these come from is the job of a correlation
provider:

* :class:`DataCorrelations`  - point by point from a candidate matrix (reference);
* :class:`_GramCorrelations`  - from a precomputed Gram matrix;
* :class:`fosmodel.core.correlations.LagCorrelations` - Korenberg's speed-up from
  correlation tables of the lagged signals, with end corrections.

:func:`fos_search` runs the search on any provider.  The constant ``p_0 = 1``
is treated in closed form as the first orthogonal function (eqs. 17-18): after
it, ``D(m, 1..)`` are covariances, which is also how the kernel keeps its
precision on signals with a large offset.  The orthogonal functions ``w_m``
are never built point by point.

References
----------
.. [1] M. J. Korenberg, "Identifying nonlinear difference equation and functional expansion
   representations: the fast orthogonal algorithm", Annals of Biomedical Engineering 16,
   123-142, 1988.
.. [2] M. J. Korenberg, "A robust orthogonal algorithm for system identification and
   time-series analysis", Biological Cybernetics 60(4), 267-276, 1989.
.. [3] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg.lapack import dtrtrs

from .exceptions import InputError

#: Share of the target's mean square below which an MSE reduction is rounding error: on a
#: noise-free target the residual reaches ~1e-32 of it, and every rule (Korenberg's threshold
#: is then 0) would take every candidate.
ROUNDING = 1e-12
STOP_RULES = ("korenberg", "max_terms", "variance", "mean_square", "aic", "bic", "fpe", "mdl")
_CRITERIA = ("aic", "bic", "fpe", "mdl")


class Correlations(Protocol):
    """What the FOS kernel reads.  All means are over the fitting window."""

    n_samples: int
    y_mean: float  # mean(y)
    y_mean_sq: float  # mean(y^2)
    means: np.ndarray  # mean(p_c), shape (C,)
    target: np.ndarray  # mean(y p_c)
    diag: np.ndarray  # mean(p_c^2)

    def column(self, j: int) -> np.ndarray:
        """mean(p_c p_j) for every candidate c."""


@dataclass(frozen=True)
class StopRule:
    """When the forward search stops.

    Parameters
    ----------
    kind : str
        ``"korenberg"``: stop when the best MSE reduction Q is not larger than
        a white Gaussian noise candidate would give, ``Q <= 4 MSE / N_w``
        (``N_w = N - N0 + 1`` samples in the paper's inclusive indexing, MSE
        the residual after the term);
        ``"max_terms"``: only the cap ``max_terms``;
        ``"variance"`` / ``"mean_square"``: stop once the residual MSE is at or
        below ``tol`` times the variance / mean square of y;
        ``"aic"``, ``"bic"``, ``"fpe"``, ``"mdl"``: stop at the first term that
        does not lower the criterion, evaluated from the MSE path
        (``N ln MSE + 2k``, ``N ln MSE + k ln N``, ``MSE (N+k)/(N-k)``,
        Rissanen's ``N ln MSE + k ln N``, which equals BIC for Gaussian
        residuals; k counts the constant).
    tol : float, optional
        Fraction for ``"variance"`` and ``"mean_square"``.
    max_terms : int, optional
        Cap on the number of terms besides the constant, whatever the rule.
    """

    kind: str = "korenberg"
    tol: float | None = None
    max_terms: int | None = None

    def __post_init__(self) -> None:
        """Check the rule's name, tolerance and cap.

        Raises
        ------
        InputError
            An unknown rule, a tolerance out of (0, 1) where the rule needs one, or a
            negative or non-integer ``max_terms``.
        """
        if self.kind not in STOP_RULES:
            raise InputError(
                f"unknown stop rule {self.kind!r}; choose from {', '.join(STOP_RULES)}")
        if self.kind in ("variance", "mean_square"):
            if (isinstance(self.tol, bool) or not isinstance(self.tol, (float, int, np.floating))
                    or not 0 < self.tol < 1):
                raise InputError(f"stop rule {self.kind!r} needs a tolerance 0 < tol < 1")
        if self.max_terms is not None and (
            isinstance(self.max_terms, bool) or not isinstance(self.max_terms, (int, np.integer))
            or self.max_terms < 0
        ):
            raise InputError(f"max_terms must be a non-negative integer, got {self.max_terms!r}")

    def reached(self, mse: float, mse_null: float, y_mean_sq: float) -> bool:
        """Whether the residual ``mse`` is low enough already (``variance``, ``mean_square``)."""
        if self.tol is None:  # the rules without a tolerance stop on other grounds
            return False
        if self.kind == "variance":
            return mse <= self.tol * mse_null
        if self.kind == "mean_square":
            return mse <= self.tol * y_mean_sq
        return False

    def should_stop(self, q: float, mse: float, k: int, n: int) -> bool:
        """Whether the rule refuses the best next term (``korenberg``, the criteria).

        The term's MSE reduction ``q`` takes the residual from ``mse`` to ``mse - q``,
        with ``k`` parameters (the constant counted) before it, on ``n`` samples.
        """
        mse_new = max(mse - q, 0.0)
        if self.kind == "korenberg":
            return q <= 4.0 * mse_new / n
        if self.kind in _CRITERIA:
            return criterion(self.kind, mse_new, k + 1, n) >= criterion(self.kind, mse, k, n)
        return False

    def to_dict(self) -> dict:
        """Return the rule as a JSON-ready dict of its three fields."""
        return {"kind": self.kind, "tol": self.tol, "max_terms": self.max_terms}


def criterion(kind: str, mse: float, k: int, n: int) -> float:
    """Information criterion of ``k`` parameters with residual ``mse`` on ``n`` samples."""
    if kind == "fpe":
        return mse * (n + k) / (n - k) if n > k else math.inf
    log_mse = math.log(mse) if mse > 0 else -math.inf
    if kind == "aic":
        return n * log_mse + 2 * k
    if kind in ("bic", "mdl"):
        return n * log_mse + k * math.log(n)
    raise InputError(f"unknown criterion {kind!r}")


@dataclass
class FOSResult:
    """Outcome of one forward search.

    Attributes
    ----------
    support : ndarray of int
        Selected candidate indices, in selection order.
    coef : ndarray
        Weights ``a_m`` of the selected candidates in the original expansion (eq. 14).
    intercept : float
        Weight of the constant (0 without an intercept).
    g : ndarray
        Weights of the orthogonal expansion (eq. 23).
    q : ndarray
        MSE reduction of each selected term (eq. 27).
    mse_path : ndarray
        Residual MSE after each selected term (eq. 28).
    mse_null : float
        Residual MSE before the first selected term (the variance of y with an
        intercept, its mean square without).
    y_mean_sq, y_var : float
        Mean square and variance of y over the fitting window.
    n_samples : int
        Samples in the fitting window.
    n_candidates : int
    n_dependent : int
        Candidates skipped because they were numerically dependent on the
        selected terms (or constant).
    stop : StopRule
    stop_reason : str
        Which condition ended the search.
    criterion_path : ndarray or None
        Information criterion after each term (rules aic/bic/fpe/mdl).
    coef_se : ndarray
        Standard errors of ``coef`` as ordinary least squares gives them for
        the selected terms, ``sqrt(s^2 [(X'X)^-1]_mm)`` with ``s^2`` the residual
        sum of squares over ``n_samples - k`` (k weights, the constant included).
        They take the terms as fixed in advance and the residuals as white: they
        ignore the search that chose the terms (after a search over many
        candidates they are too small) and any correlation left in the residuals.
    intercept_se : float
        Standard error of ``intercept`` on the same terms (nan without an intercept).
    """

    support: np.ndarray
    coef: np.ndarray
    intercept: float
    g: np.ndarray
    q: np.ndarray
    mse_path: np.ndarray
    mse_null: float
    y_mean_sq: float
    y_var: float
    n_samples: int
    n_candidates: int
    n_dependent: int
    stop: StopRule
    stop_reason: str
    criterion_path: np.ndarray | None = field(default=None)
    coef_se: np.ndarray = field(default_factory=lambda: np.empty(0))
    intercept_se: float = math.nan

    @property
    def n_terms(self) -> int:
        """Number of selected terms, the constant not counted."""
        return len(self.support)

    @property
    def mse(self) -> float:
        """Final residual MSE."""
        return float(self.mse_path[-1]) if len(self.mse_path) else self.mse_null


class DataCorrelations:
    """Correlations point by point from the candidate matrix ``X`` (N x C): the reference path."""

    def __init__(self, X: np.ndarray, y: np.ndarray) -> None:
        n = X.shape[0]
        self.X, self.n_samples = X, n
        self.y_mean = float(y.mean())
        self.y_mean_sq = float(y @ y) / n
        self.means = X.mean(axis=0)
        self.target = (X.T @ y) / n
        self.diag = np.einsum("ij,ij->j", X, X) / n

    def column(self, j: int) -> np.ndarray:
        """Return the mean products of candidate ``j`` with every candidate (Gram column j)."""
        return (self.X.T @ self.X[:, j]) / self.n_samples


class _GramCorrelations:
    """Correlations from a precomputed Gram matrix ``mean(p_c p_r)``."""

    def __init__(
        self, gram: np.ndarray, target: np.ndarray, means: np.ndarray,
        y_mean: float, y_mean_sq: float, n_samples: int,
    ) -> None:
        self.gram, self.n_samples = gram, n_samples
        self.y_mean, self.y_mean_sq = y_mean, y_mean_sq
        self.means, self.target = means, target
        self.diag = np.diag(gram).copy()

    @classmethod
    def from_data(cls, X: np.ndarray, y: np.ndarray) -> _GramCorrelations:
        n = X.shape[0]
        return cls((X.T @ X) / n, (X.T @ y) / n, X.mean(axis=0), float(y.mean()),
                   float(y @ y) / n, n)

    def column(self, j: int) -> np.ndarray:
        return self.gram[:, j]


def fos_search(
    corr: Correlations,
    stop: StopRule,
    *,
    intercept: bool = True,
    dependence_tol: float = 1e-10,
) -> FOSResult:
    """Forward search by implicit Gram-Schmidt on the correlations ``corr``: the FOS kernel.

    Every FOS fit runs here, on a correlation provider (:class:`Correlations`):
    :class:`DataCorrelations` point by point on a candidate matrix (the reference),
    the Gram matrix in :func:`fos`, or Korenberg's lag tables
    (:class:`fosmodel.core.correlations.LagCorrelations`, the fast path).  It checks
    nothing: its callers (:func:`fos`, :class:`fosmodel.models.model.FOSModel`) validate.

    Notation of Tamazin et al. (2013): ``D(c, r)`` (eq. 19) for candidate c against
    the r-th selected term, ``alpha_cr = D(c, r) / D(r, r)`` (eq. 20),
    ``C(c)`` (eq. 22), ``g = C / D(m, m)`` (eq. 23) and ``Q = g^2 D(m, m)``
    (eq. 27).  For every remaining candidate the kernel keeps ``D(c, c)`` and
    ``C(c)`` reduced by the terms selected so far, so each step costs one Gram
    column plus O(C x terms).
    """
    n = corr.n_samples
    means = corr.means if intercept else np.zeros_like(corr.means)
    y_mean = corr.y_mean if intercept else 0.0
    mse = corr.y_mean_sq - y_mean**2  # eq. 26 after Q_0 = C(0)^2 / D(0,0) = mean(y)^2
    mse_null = mse
    c_rem = corr.target - y_mean * means  # C(c) after the constant (eq. 22)
    d_rem = corr.diag - means**2  # D(c,c) after the constant (eq. 19)
    scale = corr.diag
    floor = dependence_tol * scale  # a candidate's D(c,c) at or below this is dependent
    # a reduction below this share of the target's mean square is rounding error, not a term
    rounding = ROUNDING * corr.y_mean_sq
    n_cand = len(scale)
    cap, cap_reason = n_cand, "exhausted"
    if stop.max_terms is not None and stop.max_terms <= cap:
        cap, cap_reason = stop.max_terms, "max_terms"
    if n - int(intercept) - 1 < cap:  # keep at least one residual degree of freedom
        cap, cap_reason = max(n - int(intercept) - 1, 0), "samples"
    ic_path: list[float] = []

    active = np.ones(n_cand, dtype=bool)
    dependent = np.zeros(n_cand, dtype=bool)
    newly = np.empty(n_cand, dtype=bool)
    live_floor = floor.copy()  # floor, -inf once a candidate is selected or dependent
    # D(c,c) of a selected or dependent candidate is set to inf: its Q is then 0, never
    # above an active candidate's unless no candidate reduces the MSE (then the search
    # stops whichever it picks), so Q needs no mask
    q_all = np.empty(n_cand)
    c_sq = np.empty(n_cand)
    d_hist = np.empty((max(cap, 0), n_cand))  # D(c, r) for each selected r
    a_hist = np.empty((max(cap, 0), n_cand))  # alpha_cr = D(c, r) / D(r, r)
    support: list[int] = []
    g: list[float] = []
    q_path: list[float] = []
    mse_path: list[float] = []
    while True:
        if len(support) >= cap:
            reason = cap_reason
            break
        if stop.reached(mse, mse_null, corr.y_mean_sq):
            reason = stop.kind
            break
        # the bookkeeping of a step is a few calls on arrays of C: on small sets their
        # overhead is the cost, so they reuse buffers and count instead of any()
        if np.count_nonzero(np.less_equal(d_rem, live_floor, out=newly)):
            dependent |= newly
            active &= ~newly
            live_floor[newly], d_rem[newly] = -np.inf, np.inf
            if not np.count_nonzero(active):
                reason = "exhausted"
                break
        np.divide(np.multiply(c_rem, c_rem, out=c_sq), d_rem, out=q_all)
        j = int(q_all.argmax())
        q = float(q_all[j])
        mse_new = max(mse - q, 0.0)
        if q <= 0.0:
            reason = "no_reduction"
            break
        if q <= rounding:  # what is left is rounding error: a noise-free target is fit
            reason = "rounding"
            break
        if stop.should_stop(q, mse, int(intercept) + len(support), n):
            reason = stop.kind
            break
        r = len(support)
        d_col = np.subtract(corr.column(j), means * means[j], out=d_hist[r])
        if r:
            d_col -= a_hist[:r].T @ d_hist[:r, j]  # eq. 19
        d_jj = float(d_col[j])
        active[j], live_floor[j], d_rem[j] = False, -np.inf, np.inf
        if not d_jj > floor[j]:  # fresher than d_rem[j]; guard rounding
            dependent[j] = True
            continue
        alpha = np.divide(d_col, d_jj, out=a_hist[r])  # eq. 20
        g_j = float(c_rem[j]) / d_jj  # eq. 23
        d_rem -= alpha * d_col
        c_rem -= alpha * c_rem[j]
        support.append(j)
        g.append(g_j)
        q_path.append(q)
        mse = mse_new  # eq. 28
        mse_path.append(mse)
        if stop.kind in _CRITERIA:
            ic_path.append(criterion(stop.kind, mse, int(intercept) + len(support), n))

    m = len(support)
    sel = np.asarray(support, dtype=np.intp)
    g_arr = np.asarray(g)
    # eqs. 24-25: a = A^{-T} g with A the unit lower-triangular matrix of alpha_{s_i, s_r}
    alpha_sel = a_hist[:m, sel].T if m else np.empty((0, 0))
    coef = _solve_unit_triangular(alpha_sel.T, g_arr, lower=False) if m else g_arr
    a0 = float(y_mean - means[sel] @ coef) if intercept else 0.0
    coef_se, intercept_se = _std_errors(alpha_sel, d_hist[np.arange(m), sel], means[sel],
                                        mse, n, intercept)
    return FOSResult(
        support=sel, coef=coef, intercept=a0, g=g_arr, q=np.asarray(q_path),
        mse_path=np.asarray(mse_path), mse_null=float(mse_null), y_mean_sq=float(corr.y_mean_sq),
        y_var=float(corr.y_mean_sq - corr.y_mean**2), n_samples=n, n_candidates=n_cand,
        n_dependent=int(dependent.sum()), stop=stop, stop_reason=reason,
        criterion_path=np.asarray(ic_path) if stop.kind in _CRITERIA else None,
        coef_se=coef_se, intercept_se=intercept_se,
    )


def _solve_unit_triangular(a: np.ndarray, b: np.ndarray, lower: bool) -> np.ndarray:
    """Solve ``a x = b`` for a unit-diagonal triangular ``a`` (upper unless ``lower``).

    LAPACK's ``dtrtrs`` called as ``scipy.linalg.solve_triangular`` calls it (on
    ``a``, or on its transpose when ``a`` is not Fortran-ordered: the same solution
    to the bit), without its checks and wrappers, which cost more than the solve
    for the few terms a search selects.
    """
    if not b.size:  # no term selected
        return np.empty_like(b)
    if a.flags.f_contiguous:
        x, info = dtrtrs(a, b, lower=int(lower), trans=0, unitdiag=1)
    else:
        x, info = dtrtrs(a.T, b, lower=int(not lower), trans=1, unitdiag=1)
    if info:  # a unit diagonal is never singular; only a broken argument gets here
        raise ValueError(f"dtrtrs failed with info = {info}")
    return x


def _std_errors(
    alpha: np.ndarray, d: np.ndarray, means: np.ndarray, mse: float, n: int, intercept: bool,
) -> tuple[np.ndarray, float]:
    """Least-squares standard errors of the weights from the search's own factors.

    The selected terms' (centred, with an intercept) Gram matrix of means is
    ``S = A diag(d) A^T`` with ``A`` the unit lower-triangular ``alpha`` of the
    selected terms (eq. 20) and ``d`` their ``D(m, m)`` (eq. 19), so
    ``S^-1 = W^T diag(1/d) W`` with ``W = A^-1``: no matrix is inverted.  The
    covariance of the weights is ``s^2 / N S^-1`` with ``s^2 = N MSE / (N - k)``;
    the intercept ``ybar - means . coef`` adds ``s^2 / N`` for the mean of y.
    """
    m = len(d)
    dof = n - m - int(intercept)
    if dof <= 0:
        return np.full(m, np.nan), math.nan
    per_n = mse / dof  # s^2 / N
    inv_a = _solve_unit_triangular(alpha, np.eye(m), lower=True)
    scaled = inv_a / np.sqrt(d)[:, None]  # diag(d)^-1/2 W: S^-1 = scaled^T scaled
    coef_se = np.sqrt(per_n * np.einsum("ri,ri->i", scaled, scaled))
    if not intercept:
        return coef_se, math.nan
    spread = scaled @ means
    return coef_se, float(np.sqrt(per_n * (1.0 + spread @ spread)))


def center(a: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Subtract the mean along axis 0; an exactly constant signal or column becomes exactly zero.

    Returns the centred array and the means.  Rounding would otherwise leave a
    constant signal as noise of 1e-16 relative size, which the dependence test
    could not tell from a real, tiny signal.
    """
    mean = a.mean(axis=0)
    out = a - mean
    if len(a):
        out.reshape(len(a), -1)[:, _constant_columns(a.reshape(len(a), -1))] = 0.0  # a view
    return out, mean


def deferred_center(a: np.ndarray) -> tuple[np.ndarray, float, float]:
    """Return ``(values, mean, offset)``: a signal, its mean, and what is left to subtract.

    ``values - offset`` is :func:`center` of the 1-D ``a``, to the bit, without the copy:
    ``a`` itself with its mean to subtract, or zeros with nothing left when ``a`` is exactly
    constant (which :func:`center` makes exactly zero).
    """
    mean = float(a.mean())
    if len(a) and _constant_columns(a[:, None])[0]:
        return np.zeros_like(a), mean, 0.0
    return a, mean, mean


def _constant_columns(cols: np.ndarray) -> np.ndarray:
    """Which columns of the 2-D, non-empty ``cols`` hold one value exactly (a boolean mask)."""
    constant = cols[0] == cols[-1]  # a column whose ends differ varies: no need to scan it
    if constant.any():
        maybe = np.flatnonzero(constant)
        constant[maybe] = np.ptp(cols[:, maybe], axis=0) == 0
    return constant


def _as_finite(a: ArrayLike, name: str, ndim: int) -> np.ndarray:
    if np.iscomplexobj(a):
        raise InputError(f"{name} is complex; FOS models real signals")
    arr = np.asarray(a, dtype=float)
    if arr.ndim != ndim:
        raise InputError(f"{name} must be {ndim}-D, got shape {arr.shape}")
    bad = ~np.isfinite(arr)
    if bad.any():
        idx = np.argwhere(bad)[0]
        raise InputError(f"{name} has a non-finite value at index {tuple(int(i) for i in idx)}")
    return arr


def fos(
    X: np.ndarray,
    y: np.ndarray,
    *,
    max_terms: int | None = None,
    stop: str = "korenberg",
    tol: float | None = None,
    fit_intercept: bool = True,
    dependence_tol: float = 1e-10,
    precompute: bool | str = "auto",
) -> FOSResult:
    """Fast Orthogonal Search over the columns of a candidate matrix.

    Parameters
    ----------
    X : array of shape (n_samples, n_candidates)
        Candidate functions evaluated at each sample.
    y : array of shape (n_samples,)
        Signal to expand.
    max_terms : int, optional
        Most terms to select besides the constant.
    stop : str
        Stopping rule, see :class:`StopRule`.
    tol : float, optional
        Fraction for the ``"variance"`` and ``"mean_square"`` rules.
    fit_intercept : bool
        Include the constant ``p_0 = 1`` as the first term.
    dependence_tol : float
        A candidate whose ``D(m, m)`` falls to this fraction of its own mean
        square is numerically dependent on the selected terms: it is skipped.
    precompute : bool or "auto"
        Form the Gram matrix first (faster when many terms are selected from
        few candidates); "auto" does so when ``n_candidates <= 64``.

    Returns
    -------
    FOSResult
        ``support`` indexes the columns of ``X``.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> X = rng.standard_normal((500, 20))
    >>> y = 2.0 * X[:, 3] - 0.5 * X[:, 7] + 0.01 * rng.standard_normal(500)
    >>> res = fos(X, y, max_terms=2)
    >>> res.support.tolist(), np.round(res.coef, 2).tolist()
    ([3, 7], [2.0, -0.5])
    """
    X = _as_finite(X, "X", 2)
    y = _as_finite(y, "y", 1)
    if X.shape[0] != y.shape[0]:
        raise InputError(f"X has {X.shape[0]} rows but y has {y.shape[0]} samples")
    if X.shape[0] < 2:
        raise InputError(f"at least 2 samples are needed, got n_samples = {X.shape[0]}")
    rule = StopRule(stop, tol, max_terms)
    x_off = np.zeros(X.shape[1])
    y_off = 0.0
    if fit_intercept:
        X, x_off = center(X)
        y, y_mean = center(y)
        y_off = float(y_mean)
    if precompute == "auto":
        precompute = X.shape[1] <= 64
    corr = _GramCorrelations.from_data(X, y) if precompute else DataCorrelations(X, y)
    res = fos_search(corr, rule, intercept=fit_intercept, dependence_tol=dependence_tol)
    if fit_intercept:
        res.intercept = float(y_off + res.intercept - x_off[res.support] @ res.coef)
    return res

"""Classical baselines for FOS: AR models by Yule-Walker, covariance and Burg, and Gauss-Markov.

Every model here has FOSModel's interface (``fit``, one-step ``predict`` aligned with ``y``
and NaN over the lag window, ``residuals``, ``simulate``, ``summary``, ``to_dict`` /
``from_dict``, ``lag_window_``, ``n_terms_``), so a comparison harness treats FOS and the
baselines alike.  All of them share the convention of :mod:`fosmodel.models.dynamics`::

    y[n] - mu = sum_k phi_k (y[n-k] - mu) + e[n],   var(e) = sigma2,

with ``mu`` the training mean, used by every method alike.  The estimators are statsmodels'
(Tamazin et al. 2013, section 3); their return conventions are mapped onto this one in a single
place,
:func:`_to_dynamics`.

References
----------
.. [1] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
.. [2] M. Park, "Error Analysis and Stochastic Modeling of MEMS based Inertial Sensors for Land
   Vehicle Navigation Applications", M.Sc. thesis, UCGE Report 20194, Department of
   Geomatics Engineering, University of Calgary, 2004.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from typing import Any, NamedTuple, TypeVar

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from sklearn.base import BaseEstimator
from statsmodels.regression.linear_model import burg, yule_walker
from statsmodels.tsa.ar_model import AutoReg

from .._version import __version__
from ..core.exceptions import InputError
from ..core.validation import as_signal, check_fitted, check_int, did_you_mean
from ..typeset.summary import Summary
from .dynamics import (
    ar_free_run,
    ar_one_step,
    ar_roots,
    cut_at_divergence,
    free_run_inputs,
    is_stable,
    warn_if_unstable,
)

FORMAT_VERSION = 1

METHOD_LABELS = {"yw": "Yule-Walker", "cov": "Covariance", "burg": "Burg", "gm": "Gauss-Markov"}
_AR_CODES = {"yw": "yule_walker", "cov": "covariance", "burg": "burg"}
_AR_LABELS = {method: METHOD_LABELS[code] for code, method in _AR_CODES.items()}
_METHOD_NOTES = {
    "yule_walker": "Yule-Walker (autocorrelation) method: statsmodels yule_walker, "
                   "method='mle' (autocovariances divided by N), which always gives a stable "
                   "model but is biased on short records.",
    "covariance": "Covariance method: forward least squares over n = p..N-1 (statsmodels "
                  "AutoReg, trend='n', on the centred record); it may give an unstable model.",
    "burg": "Burg's method: statsmodels burg (forward-backward lattice), always stable.",
}


# -- statsmodels conventions -------------------------------------------------------------


class _Convention(NamedTuple):
    """How a statsmodels estimator reports its AR weights and innovation scale.

    ``sign`` is +1 when it returns the regression weights ``phi`` and -1 when it returns the
    characteristic polynomial's ``a = -phi`` (Tamazin et al. 2013, eq. 3); ``scale`` is
    ``"std"`` for an innovation standard deviation and ``"variance"`` for a variance.
    """

    sign: float
    scale: str


_CONVENTIONS = {
    "yule_walker": _Convention(+1.0, "std"),        # yule_walker -> (rho, sigma)
    "covariance": _Convention(+1.0, "variance"),    # AutoRegResults.params, .sigma2
    "burg": _Convention(+1.0, "variance"),          # burg -> (ar, sigma2)
}


def _to_dynamics(method: str, coefs: object, scale: float) -> tuple[np.ndarray, float]:
    """``(phi, sigma2)`` in the dynamics.py convention from a statsmodels estimate.

    Raises
    ------
    InputError
        The estimate is not finite (a record that AR(p) predicts perfectly, for instance).
    """
    conv = _CONVENTIONS[method]
    phi = conv.sign * np.asarray(coefs, dtype=float).ravel()
    sigma2 = float(scale) ** 2 if conv.scale == "std" else float(scale)
    if not (np.isfinite(phi).all() and math.isfinite(sigma2)):
        raise InputError(
            f"the {method} fit of AR({len(phi)}) gave non-finite weights or innovation "
            "variance; the record is perfectly predictable or numerically degenerate"
        )
    return phi, sigma2


def _estimate(method: str, x: np.ndarray, order: int) -> tuple[np.ndarray, float]:
    """Fit AR(``order``) to the centred record ``x`` with statsmodels; ``(phi, sigma2)``."""
    if method == "yule_walker":
        with warnings.catch_warnings():
            # statsmodels 0.15 warns that the tuple will become a YuleWalkerResult;
            # indexing reads both, and 0.14 has no result_object argument.
            warnings.simplefilter("ignore", FutureWarning)
            res = yule_walker(x, order=order, method="mle", demean=False)
        return _to_dynamics(method, res[0], res[1])
    if method == "covariance":
        res = AutoReg(x, lags=order, trend="n").fit()
        return _to_dynamics(method, res.params, res.sigma2)
    ar, sigma2 = burg(x, order=order, demean=False)
    return _to_dynamics(method, ar, sigma2)


# -- shared behaviour --------------------------------------------------------------------


def _check_record(y: ArrayLike, order: int) -> np.ndarray:
    """Return the training record as a finite array, long enough and not constant for AR(order)."""
    arr = as_signal(y, "y")
    needed = 2 * order + 2
    if len(arr) < needed:
        raise InputError(
            f"record too short: {len(arr)} samples, but an AR({order}) fit needs at least "
            f"{needed} ({order} for the lag window and {order + 2} more to estimate "
            f"{order} weight(s), the mean and the innovation variance)"
        )
    if np.ptp(arr) == 0:
        raise InputError(f"y is constant ({arr[0]:g}); an AR model needs a varying record")
    return arr


def _plain(value: object) -> object:
    """Return a numpy scalar as the Python scalar, for JSON."""
    return value.item() if isinstance(value, np.generic) else value


_M = TypeVar("_M", bound="_LinearAR")


class _LinearAR(BaseEstimator):
    """Fitted state, prediction, simulation and persistence shared by the AR baselines.

    A subclass sets ``_format`` (the ``to_dict`` format name) and defines ``_order()`` (the
    number of AR weights) and ``_check_params()`` (raising InputError on bad parameters).
    """

    def _set_fitted(self, mean: float, coef: np.ndarray, sigma2: float, n_samples: int) -> None:
        self.mean_ = float(mean)
        self.coef_ = np.asarray(coef, dtype=float)
        self.sigma2_ = float(sigma2)
        self.n_samples_ = int(n_samples)
        self.lag_window_ = len(self.coef_)
        self.n_terms_ = len(self.coef_)

    def _check_fitted(self) -> None:
        check_fitted(self, "coef_")

    def predict(self, y: ArrayLike) -> np.ndarray | pd.Series:
        """One-step-ahead prediction from the true past, aligned with ``y``.

        Sample ``n`` is predicted from ``y[n-1], ..., y[n-p]``; the first ``lag_window_``
        samples have no prediction (NaN).

        Returns
        -------
        ndarray, or Series with the index of ``y`` if ``y`` is a Series
        """
        self._check_fitted()
        out = ar_one_step(self.coef_, self.mean_, as_signal(y, "y"))
        if isinstance(y, pd.Series):
            return pd.Series(out, index=y.index, name="prediction")
        return out

    def residuals(self, y: ArrayLike) -> np.ndarray | pd.Series:
        """``y`` minus its one-step prediction (NaN over the lag window)."""
        pred = self.predict(y)
        return (y - pred) if isinstance(pred, pd.Series) else as_signal(y, "y") - pred

    def ar_roots(self) -> np.ndarray:
        """Roots of ``z^p - phi_1 z^(p-1) - ... - phi_p``."""
        self._check_fitted()
        return ar_roots(self.coef_)

    def is_stable(self) -> bool:
        """Whether every root lies strictly inside the unit circle."""
        self._check_fitted()
        return is_stable(self.coef_)

    def _max_root(self) -> float:
        roots = self.ar_roots()
        return float(np.max(np.abs(roots))) if len(roots) else 0.0

    def simulate(self, y_init: ArrayLike, n_steps: int, *,
                 noise: ArrayLike | None = None) -> np.ndarray:
        """Free run: continue ``y_init`` for ``n_steps`` samples from the model's own output.

        Parameters
        ----------
        y_init : array-like
            True past, at least ``lag_window_`` samples; the run starts after its end.
        n_steps : int
            Samples to simulate.
        noise : array-like, optional
            Innovations ``e[n]`` added at each simulated step (keyword only; zero by
            default: the deterministic free-run prediction, which decays to ``mean_``).

        Returns
        -------
        ndarray of shape (n_steps,)

        Warns
        -----
        UnstableModelWarning
            If the model is unstable, or the run overflows (the samples from the
            divergence on are NaN).
        """
        self._check_fitted()
        y0, drive = free_run_inputs(y_init, n_steps, noise, self.lag_window_)
        warn_if_unstable(self.coef_, "the fitted AR model")
        past = y0[len(y0) - self.lag_window_ :]  # the run reads these; centre no more
        with np.errstate(over="ignore", invalid="ignore"):
            out = ar_free_run(self.coef_, past - self.mean_, drive)
        return cut_at_divergence(out) + self.mean_

    def _coef_table(self) -> pd.DataFrame:
        return pd.DataFrame({
            "term": [f"y[n-{k + 1}]" for k in range(len(self.coef_))],
            "coef": self.coef_,
        })

    def _common_info(self) -> list[tuple[str, str]]:
        return [
            ("Samples", f"{self.n_samples_}"),
            ("Mean mu", f"{self.mean_:.6g}"),
            ("Innovation var", f"{self.sigma2_:.6g}"),
            ("Stable", "yes" if self.is_stable() else "NO"),
            ("Largest |root|", f"{self._max_root():.6g}"),
        ]

    def to_dict(self, meta: Mapping[str, object] | None = None) -> dict:
        """JSON-serialisable form; :meth:`from_dict` restores a model that predicts identically."""
        self._check_fitted()
        return {
            "format": self._format,
            "format_version": FORMAT_VERSION,
            "fosmodel_version": __version__,
            "params": {k: _plain(v) for k, v in self.get_params().items()},
            "fitted": {
                "mean": self.mean_,
                "coef": [float(c) for c in self.coef_],
                "sigma2": self.sigma2_,
                "n_samples": self.n_samples_,
            },
            "meta": dict(meta or {}),
        }

    @classmethod
    def from_dict(cls: type[_M], data: Mapping[str, Any]) -> _M:
        """Rebuild a fitted model from :meth:`to_dict` output.

        Raises
        ------
        InputError
            Not this kind of model, written by a newer format version, or corrupted.
        """
        if not isinstance(data, Mapping) or data.get("format") != cls._format:
            raise InputError(f"not a fosmodel {cls.__name__} file (missing or wrong 'format')")
        version = data.get("format_version")
        if isinstance(version, bool) or not isinstance(version, int) or version > FORMAT_VERSION:
            raise InputError(
                f"model file format version {version!r} is newer than this fosmodel "
                f"({__version__}) reads (version {FORMAT_VERSION}); upgrade fosmodel"
            )
        try:
            model = cls(**data["params"])
            model._check_params()
            fitted = data["fitted"]
            coef = np.asarray(fitted["coef"], dtype=float)
            if coef.shape != (model._order(),):
                raise InputError(f"{coef.size} coefficient(s) for order {model._order()}")
            mean, sigma2 = float(fitted["mean"]), float(fitted["sigma2"])
            if not (math.isfinite(mean) and math.isfinite(sigma2) and np.isfinite(coef).all()):
                raise InputError("mean, sigma2 and coef must be finite")
            if sigma2 < 0:
                raise InputError(f"negative innovation variance {sigma2:g}")
            model._set_fitted(mean, coef, sigma2, int(fitted["n_samples"]))
        except InputError as exc:
            raise InputError(f"corrupted model file: {exc}") from None
        except (KeyError, TypeError, ValueError) as exc:
            raise InputError(f"corrupted model file: {type(exc).__name__}: {exc}") from None
        model.meta_ = dict(data.get("meta") or {})
        return model


# -- the models --------------------------------------------------------------------------


class ARModel(_LinearAR):
    """Autoregressive model ``y[n] - mu = sum_k phi_k (y[n-k] - mu) + e[n]`` of order p.

    Parameters
    ----------
    order : int
        p >= 1, the number of AR weights.
    method : {"burg", "yule_walker", "covariance"}
        Estimator (Tamazin et al. 2013, section 3), all from statsmodels on the record centred on
        its training mean: ``"yule_walker"`` is ``yule_walker(method="mle")`` (biased
        autocovariances, always stable), ``"covariance"`` is forward least squares
        (``AutoReg(trend="n")``, may be unstable), ``"burg"`` is ``burg`` (always stable).

    Attributes
    ----------
    mean_ : float
        Training mean ``mu``.
    coef_ : ndarray of shape (order,)
        ``phi_1 .. phi_p``, positive regression sign (the ``a_k`` of Tamazin et al. 2013 are
        ``-phi_k``).
    sigma2_ : float
        Innovation variance ``var(e)``.
    method_ : str
        The estimator used.
    n_samples_, lag_window_ (= order), n_terms_ (= order)

    Examples
    --------
    >>> from scipy.signal import lfilter
    >>> rng = np.random.default_rng(1)
    >>> y = lfilter([1.0], [1.0, -1.5, 0.7], rng.standard_normal(200_000))
    >>> model = ARModel(2, "burg").fit(y)
    >>> np.round(model.coef_, 2).tolist(), round(model.sigma2_, 2)
    ([1.5, -0.7], 1.0)
    """

    _format = "fosmodel.ARModel"

    def __init__(self, order: int, method: str = "burg") -> None:
        self.order = order
        self.method = method

    def _order(self) -> int:
        return check_int(self.order, "order", 1)

    def _check_params(self) -> None:
        self._order()
        if self.method not in _CONVENTIONS:
            raise InputError(
                f"unknown AR method {self.method!r}{did_you_mean(str(self.method), _CONVENTIONS)}"
                f"; valid: {', '.join(_CONVENTIONS)}"
            )

    def fit(self, y: ArrayLike) -> ARModel:
        """Estimate the weights and innovation variance on the record ``y``.

        Parameters
        ----------
        y : array-like of shape (N,)
            Finite samples, N >= 2 * order + 2, not constant.

        Returns
        -------
        self
        """
        self._check_params()
        order = self._order()
        arr = _check_record(y, order)
        mean = float(arr.mean())
        phi, sigma2 = _estimate(self.method, arr - mean, order)
        self._set_fitted(mean, phi, sigma2, len(arr))
        return self

    def _set_fitted(self, mean: float, coef: np.ndarray, sigma2: float, n_samples: int) -> None:
        super()._set_fitted(mean, coef, sigma2, n_samples)
        self.method_ = self.method

    def summary(self) -> Summary:
        """Summarise the fit: method, order, mean, innovation variance, weights, stability."""
        self._check_fitted()
        info = [("Method", self.method_), ("Order p", f"{self.order}"), *self._common_info()]
        notes = [
            "y[n] - mu = sum_k phi_k (y[n-k] - mu) + e[n]; Tamazin et al.'s (2013) a_k are -phi_k.",
            _METHOD_NOTES[self.method_],
        ]
        if not self.is_stable():
            notes.append("The model is unstable: its free run (simulate) grows without bound.")
        title = f"AR({self.order}) model, {_AR_LABELS[self.method_]} method"
        return Summary(title, info, self._coef_table(), notes)


def _gm_time_constant(phi: float, rate: float | None) -> tuple[float, str | None]:
    """``(beta, note)``: ``beta = -ln(phi) * rate`` in 1/s, or NaN and the reason."""
    if not 0.0 < phi < 1.0:
        return math.nan, (f"phi = {phi:.6g} is not in (0, 1): the record is not a first-order "
                          "Gauss-Markov process with a positive correlation time, so beta and "
                          "the correlation time are undefined (NaN).")
    if rate is None:
        return math.nan, ("No sampling rate given: beta and the correlation time (NaN) need "
                          "GaussMarkovModel(rate=...).")
    return -math.log(phi) * float(rate), None


class GaussMarkovModel(_LinearAR):
    """First-order Gauss-Markov process: ``x[k] = exp(-beta*dt) x[k-1] + w[k]``, x = y - mu.

    The discrete form of the navigation engineer's ``dx/dt = -beta x + w(t)`` (correlation
    time ``1/beta``), i.e. an AR(1) model with ``phi = exp(-beta*dt)``, ``dt = 1/rate``.
    ``phi`` is the lag-1 autocorrelation of the centred training record (statsmodels
    ``yule_walker``, order 1, ``method="mle"``).

    Parameters
    ----------
    rate : float, optional
        Sampling rate in Hz; needed for ``beta_`` and ``correlation_time_s_``.

    Attributes
    ----------
    mean_ : float
        Training mean ``mu``.
    coef_ : ndarray of shape (1,)
        ``phi = exp(-beta*dt)``.
    beta_ : float
        ``-ln(phi) * rate`` in 1/s; NaN without a rate or unless 0 < phi < 1.
    correlation_time_s_ : float
        ``1 / beta_`` in seconds (NaN likewise).
    sigma2_ : float
        Variance of the driving noise ``w[k]``.
    process_var_ : float
        Stationary variance of x, ``sigma2 / (1 - phi^2)``.
    n_samples_, lag_window_ (= 1), n_terms_ (= 1)
    """

    _format = "fosmodel.GaussMarkovModel"

    def __init__(self, rate: float | None = None) -> None:
        self.rate = rate

    def _order(self) -> int:
        return 1

    def _check_params(self) -> None:
        rate = self.rate
        if rate is None:
            return
        if (isinstance(rate, bool) or not isinstance(rate, (int, float, np.integer, np.floating))
                or not math.isfinite(rate) or rate <= 0):
            raise InputError(f"rate must be a positive number of Hz or None, got {rate!r}")

    def fit(self, y: ArrayLike) -> GaussMarkovModel:
        """Estimate ``phi``, the driving-noise variance and the time constants on ``y``.

        Parameters
        ----------
        y : array-like of shape (N,)
            Finite samples, N >= 4, not constant.

        Returns
        -------
        self
        """
        self._check_params()
        arr = _check_record(y, 1)
        mean = float(arr.mean())
        phi, sigma2 = _estimate("yule_walker", arr - mean, 1)
        self._set_fitted(mean, phi, sigma2, len(arr))
        return self

    def _set_fitted(self, mean: float, coef: np.ndarray, sigma2: float, n_samples: int) -> None:
        super()._set_fitted(mean, coef, sigma2, n_samples)
        phi = float(self.coef_[0])
        self.beta_, self._gm_note = _gm_time_constant(phi, self.rate)
        self.correlation_time_s_ = 1.0 / self.beta_ if self.beta_ > 0 else math.nan
        self.process_var_ = self.sigma2_ / (1.0 - phi**2) if abs(phi) < 1 else math.nan

    def summary(self) -> Summary:
        """phi, beta, correlation time, noise and process variances, and stability."""
        self._check_fitted()
        info = [
            ("phi = exp(-beta dt)", f"{self.coef_[0]:.6g}"),
            ("Rate (Hz)", "none" if self.rate is None else f"{self.rate:g}"),
            ("beta (1/s)", f"{self.beta_:.6g}"),
            ("Correlation time (s)", f"{self.correlation_time_s_:.6g}"),
            ("Process var", f"{self.process_var_:.6g}"),
            *self._common_info(),
        ]
        notes = [
            "x[k] = exp(-beta dt) x[k-1] + w[k], x = y - mu, dt = 1/rate, var(w) = innovation "
            "var = process var (1 - phi^2); phi is the lag-1 autocorrelation (Yule-Walker).",
        ]
        if self._gm_note:
            notes.append(self._gm_note)
        return Summary("First-order Gauss-Markov model (AR(1))", info, self._coef_table(), notes)


def make_baseline(
    method: str, order: int, rate: float | None = None
) -> ARModel | GaussMarkovModel:
    """Return the baseline for a command-line method code.

    Parameters
    ----------
    method : {"yw", "cov", "burg", "gm"}
        Yule-Walker, covariance, Burg (:class:`ARModel`) or Gauss-Markov.
    order : int
        AR order; ignored by ``"gm"`` (always first order).
    rate : float, optional
        Sampling rate in Hz, used by ``"gm"`` only (for beta and the correlation time).

    Raises
    ------
    InputError
        Unknown method code (the valid codes are named).
    """
    if method == "gm":
        return GaussMarkovModel(rate=rate)
    if method in _AR_CODES:
        return ARModel(order=order, method=_AR_CODES[method])
    raise InputError(
        f"unknown baseline method {method!r}{did_you_mean(str(method), METHOD_LABELS)}; "
        f"valid codes: {', '.join(METHOD_LABELS)}"
    )

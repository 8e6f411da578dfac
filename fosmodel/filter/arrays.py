"""Arrays of gyros measuring one rate: averaging, the virtual-gyro Kalman filter, FOS.

Koldbæk and Totu (2011) (chapters 6-10) models ``N`` gyros on one board (eqs. 6.1-6.9)::

    z_i[k] = omega[k] + b_i[k] + v_i[k],   b_i[k+1] = b_i[k] + Ts w_i[k],   omega[k+1] = Ts w_o[k]

with white measurement noises ``v`` (covariance ``R``, eq. 6.35; ``sigma_v = ARW sqrt(rate)``)
and bias-driving noises ``w`` (covariance ``Q_w``, eq. 6.34; ``sigma_w = RRW sqrt(rate)``),
equicorrelated with a factor ``rho`` in the thesis's examples (eqs. 6.36-6.38).  Its typical
ADIS16265 values at 100 Hz, ARW 0.068 deg/sqrt(s) and RRW 0.00029 deg/sqrt(s^3) (eq. 5.4), give
``sigma_v = 0.68`` deg/s and ``sigma_w = 0.0029`` deg/s^2.

* Closed forms of chapter 7 for an average (or any fixed weighting) of the gyros:
  :func:`averaging_rate_std` (eqs. 7.10, 7.13), :func:`averaging_angle_std` (eqs. 7.15-7.16)
  and their general form for unequal gyros, :func:`angle_error_std`.
* The Kalman filter of chapter 8 on the state ``x = [omega, b_1 .. b_N]``
  (:class:`ArrayModel`): :func:`steady_state_gain` solves the Riccati equation with
  :func:`scipy.linalg.solve_discrete_are` on the observable part of the model,
  :func:`recursive_gain` iterates eqs. 8.3-8.6 with :class:`fosmodel.filter.kalman.KalmanFilter`,
  :func:`constant_gain_filter` runs eq. 8.7, and :func:`kalman_angle_std` gives the exact
  angle-error standard deviation of that filter (the thesis has no formula for it, Table 10.3).
* :func:`cross_gyro_comparison`: a FOS model of one gyro's error with the others as exogenous
  inputs against an AR model of its own past.

References
----------
.. [1] S. K. Koldbæk and L.-C. Totu, "Improving MEMS Gyroscope Performance using Homogeneous
   Sensor Fusion", Master's thesis, Department of Electronic Systems, Aalborg University,
   2011.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.linalg import block_diag, null_space, solve_discrete_are

from ..core.exceptions import InputError
from ..models.baselines import ARModel
from ..models.model import FOSModel
from ..noise.metrics import one_step_mse
from .kalman import KalmanFilter

#: Koldbæk and Totu (2011) eq. 5.4 at 100 Hz: sigma_v = 0.068 sqrt(100) deg/s,
#: sigma_w = 0.00029 sqrt(100) deg/s^2.
SIGMA_V, SIGMA_W = 0.68, 0.0029
#: Rate-state driving noise of the thesis's filters (section 8.2, chapter 10), deg/s^2.
SIGMA_OMEGA = 1e3
#: Correlation of the bias-driving noises of the three-gyro example, eq. 8.8.
CORR_EQ_8_8 = np.array([[1.0, 0.2305, -0.6411], [0.2305, 1.0, -0.8927], [-0.6411, -0.8927, 1.0]])
#: "Q_3" of eq. 10.2.  The thesis prints entry (4, 7) as -0.3457 and (7, 4) as +0.3457; only
#: -0.3457 in both places is positive definite, and it reproduces Table 10.3's 9.24 deg.
CORR_Q3 = np.array([
    [1.0000, 0.1632, 0.4347, 0.3839, -0.4230, 0.0966, -0.2550, -0.2585],
    [0.1632, 1.0000, 0.3964, 0.1554, -0.0921, 0.2230, -0.6627, -0.3817],
    [0.4347, 0.3964, 1.0000, -0.3017, -0.6241, -0.2330, -0.2450, -0.6012],
    [0.3839, 0.1554, -0.3017, 1.0000, 0.0564, 0.3664, -0.3457, -0.0694],
    [-0.4230, -0.0921, -0.6241, 0.0564, 1.0000, 0.4264, -0.3485, 0.4517],
    [0.0966, 0.2230, -0.2330, 0.3664, 0.4264, 1.0000, -0.3990, -0.2575],
    [-0.2550, -0.6627, -0.2450, -0.3457, -0.3485, -0.3990, 1.0000, 0.3837],
    [-0.2585, -0.3817, -0.6012, -0.0694, 0.4517, -0.2575, 0.3837, 1.0000]])
#: "Q_5" of eq. 10.3.
CORR_Q5 = np.array([
    [1.0000, -0.5325, -0.0919, 0.4838, 0.0233, -0.2234, -0.1018, -0.4034],
    [-0.5325, 1.0000, 0.6489, -0.7680, 0.0383, 0.4067, 0.2381, -0.4280],
    [-0.0919, 0.6489, 1.0000, -0.2542, 0.4135, 0.1250, 0.5287, -0.3604],
    [0.4838, -0.7680, -0.2542, 1.0000, 0.5041, -0.5885, 0.2546, 0.2022],
    [0.0233, 0.0383, 0.4135, 0.5041, 1.0000, -0.2143, 0.6344, 0.0025],
    [-0.2234, 0.4067, 0.1250, -0.5885, -0.2143, 1.0000, 0.2515, -0.3377],
    [-0.1018, 0.2381, 0.5287, 0.2546, 0.6344, 0.2515, 1.0000, -0.2807],
    [-0.4034, -0.4280, -0.3604, 0.2022, 0.0025, -0.3377, -0.2807, 1.0000]])


# -- closed forms (chapter 7) ------------------------------------------------------------------


def correlation(n: int, corr: float | np.ndarray) -> np.ndarray:
    """Return an ``n x n`` correlation matrix: equicorrelated for a scalar ``rho`` or given.

    Raises
    ------
    InputError
        Not symmetric with unit diagonal, or not positive semi-definite (for a scalar,
        ``rho < -1/(n-1)``, eq. 6.38).
    """
    if np.ndim(corr) == 0:
        c = np.full((n, n), float(corr))
        np.fill_diagonal(c, 1.0)
    else:
        c = np.asarray(corr, dtype=float)
    if c.shape != (n, n) or not np.allclose(c, c.T) or not np.allclose(np.diag(c), 1.0):
        raise InputError(f"need a symmetric {n} x {n} correlation matrix with unit diagonal")
    if np.linalg.eigvalsh(c).min() < -1e-9:
        raise InputError("the correlation matrix is not positive semi-definite"
                         + (f" (rho >= {-1 / (n - 1):.7g} needed)" if np.ndim(corr) == 0 else ""))
    return c


def covariance(sigmas: float | np.ndarray, corr: float | np.ndarray, n: int) -> np.ndarray:
    """``diag(sigmas) C diag(sigmas)`` for ``n`` gyros (eqs. 6.34-6.37)."""
    s = np.broadcast_to(np.asarray(sigmas, dtype=float), (n,))
    return s[:, None] * correlation(n, corr) * s[None, :]


def angle_sum(n_steps: int | np.ndarray) -> np.ndarray:
    """``N(N+1)/2 + 2 sum_{k<N} k(N-k) = N(N+1)(2N+1)/6``, the bracket of eqs. 7.15-7.16.

    It is ``sum_{k,l<=N} min(k, l)``: the covariance of ``b[k]`` and ``b[l]`` is
    ``min(k, l) Ts^2 sigma_w^2``, summed over every pair of samples of the angle.
    """
    n = np.asarray(n_steps, dtype=float)
    return n * (n + 1) * (2 * n + 1) / 6


def angle_error_std(
    n_steps: int | np.ndarray, ts: float, cov_w: np.ndarray, cov_v: np.ndarray,
    weights: np.ndarray | None = None,
) -> np.ndarray:
    """Angle-error standard deviation of a fixed weighting of the gyros after ``n_steps``.

    Eq. 7.16 for any weights ``a`` and covariances (eq. 7.14 with ``omega_est = a' z``)::

        Var = angle_sum(N) Ts^4 a' Q_w a + N Ts^2 a' R a

    The average (``a = 1/N``, the default) of equal gyros gives eq. 7.16, one gyro eq. 7.15.

    Parameters
    ----------
    n_steps : int or array of int
        ``N``, samples integrated.
    ts : float
        Sample period in seconds.
    cov_w, cov_v : ndarray of shape (n, n)
        Covariances of the bias-driving noises ``w`` and the white noises ``v``.
    weights : ndarray of shape (n,), optional
        ``a``; equal weights ``1/n`` by default.
    """
    cov_w, cov_v = np.atleast_2d(cov_w), np.atleast_2d(cov_v)
    a = np.full(len(cov_w), 1.0 / len(cov_w)) if weights is None else np.asarray(weights, float)
    n = np.asarray(n_steps, dtype=float)
    var = angle_sum(n) * ts**4 * (a @ cov_w @ a) + n * ts**2 * (a @ cov_v @ a)
    return np.sqrt(var)


def averaging_angle_std(
    duration_s: float, rate: float, sigma_w: float = SIGMA_W, sigma_v: float = SIGMA_V,
    n_gyros: int = 1, rho_w: float = 0.0, rho_v: float = 0.0,
) -> float:
    """Angle error (deg for deg/s inputs) of the average of ``n_gyros`` equal gyros (eq. 7.16).

    ``n_gyros=1`` is eq. 7.15.  With ``rho`` the equicorrelation of eq. 6.36 the sums of
    correlation factors in eq. 7.16 are ``n + n(n-1) rho``.
    """
    n = round(duration_s * rate)
    cov_w, cov_v = covariance(sigma_w, rho_w, n_gyros), covariance(sigma_v, rho_v, n_gyros)
    return float(angle_error_std(n, 1.0 / rate, cov_w, cov_v))


def averaging_rate_std(
    duration_s: float, rate: float, sigma_w: float = SIGMA_W, sigma_v: float = SIGMA_V,
    n_gyros: int = 1, rho_w: float = 0.0, rho_v: float = 0.0,
) -> float:
    """Rate-error standard deviation of the average after ``duration_s`` (eqs. 7.10, 7.13).

    ``Var = (k Ts^2 sum c^w sigma_w^2 + sum c^v sigma_v^2) / n^2`` with ``k`` the sample index.
    """
    k, ts = round(duration_s * rate), 1.0 / rate
    a = np.full(n_gyros, 1.0 / n_gyros)
    cov_w, cov_v = covariance(sigma_w, rho_w, n_gyros), covariance(sigma_v, rho_v, n_gyros)
    return float(np.sqrt(k * ts**2 * (a @ cov_w @ a) + a @ cov_v @ a))


# -- the virtual-gyro Kalman filter (chapter 8) --------------------------------------------------


@dataclass(frozen=True)
class ArrayModel:
    """Koldbæk and Totu's (2011) gyro-board state-space model (eqs. 6.4-6.9, 6.34-6.35).

    Parameters
    ----------
    cov_w : ndarray of shape (n, n)
        ``Q_w``, covariance of the bias-driving noises ``w`` ((units/s)^2).
    cov_v : ndarray of shape (n, n)
        ``R``, covariance of the white noises ``v`` (units^2).
    rate : float
        Sampling rate in Hz (``Ts = 1/rate``).
    sigma_omega : float
        Standard deviation of the rate state's driving noise, large so that the filter uses
        no dynamics of the rate (the thesis takes 10^3).
    """

    cov_w: np.ndarray
    cov_v: np.ndarray
    rate: float
    sigma_omega: float = SIGMA_OMEGA

    @classmethod
    def from_noise(
        cls, n_gyros: int, rate: float, sigma_w: float | np.ndarray = SIGMA_W,
        sigma_v: float | np.ndarray = SIGMA_V, corr_w: float | np.ndarray = 0.0,
        corr_v: float | np.ndarray = 0.0, sigma_omega: float = SIGMA_OMEGA,
    ) -> ArrayModel:
        """From noise levels (scalars or one per gyro) and correlations (``rho`` or matrices)."""
        return cls(covariance(sigma_w, corr_w, n_gyros), covariance(sigma_v, corr_v, n_gyros),
                   rate, sigma_omega)

    @property
    def n_gyros(self) -> int:
        """``N``."""
        return len(self.cov_v)

    @property
    def ts(self) -> float:
        """Sample period ``Ts``."""
        return 1.0 / self.rate

    @property
    def H(self) -> np.ndarray:
        """``[1_N  I_N]`` (eq. 6.8)."""
        return np.hstack([np.ones((self.n_gyros, 1)), np.eye(self.n_gyros)])

    @property
    def Q(self) -> np.ndarray:
        """``blockdiag(sigma_omega^2, Q_w)`` (eq. 6.34), the noise ``w`` entering as ``Ts w``."""
        return block_diag(self.sigma_omega**2, self.cov_w)

    def kalman_filter(self) -> KalmanFilter:
        """Return the array's :class:`~fosmodel.filter.kalman.KalmanFilter`.

        It has ``Phi = I``, ``G = Ts I`` (eqs. 6.7-6.9) and starts from a zero estimate known
        exactly (biases zero at power-on).
        """
        n = self.n_gyros + 1
        return KalmanFilter(np.eye(n), self.ts * np.eye(n), self.Q, self.H, self.cov_v,
                            np.zeros(n), np.zeros((n, n)))


def steady_state_gain(model: ArrayModel) -> np.ndarray:
    """Return the gain ``K`` the recursive filter converges to, from the Riccati equation.

    The model is not detectable (section 6.2): ``u = [1, -1, ..., -1]`` (rate up, every bias
    down) is invisible in ``z`` and is a random walk, so the covariance grows without bound
    and :func:`scipy.linalg.solve_discrete_are` has no solution for the full state.  The gain
    converges nonetheless (section 8.4, Bayard and Ploen).  In coordinates ``[V, u]``, ``V``
    an orthonormal basis of ``u``'s complement, ``Phi`` stays the identity and ``H u = 0``, so
    the observable block ``P_oo`` obeys a Riccati recursion of its own, which is detectable
    and solved by ``solve_discrete_are`` (a priori, steady state); the cross covariance then
    converges to the fixed point of ``P_uo <- P_uo (I - K_o H_o)' + Q_uo``, i.e.
    ``P_uo (K_o H_o)' = Q_uo``, and ``K = [V, u] [K_o; P_uo H_o' S^-1]``.

    Returns
    -------
    ndarray of shape (N + 1, N)
        Rows: ``omega``, ``b_1`` .. ``b_N``.
    """
    n = model.n_gyros
    u = np.r_[1.0, -np.ones(n)] / np.sqrt(n + 1)
    t = np.hstack([null_space(u[None, :]), u[:, None]])
    q = t.T @ (model.ts**2 * model.Q) @ t
    h_o = model.H @ t[:, :n]
    p_oo = solve_discrete_are(np.eye(n), h_o.T, q[:n, :n], model.cov_v)
    s = h_o @ p_oo @ h_o.T + model.cov_v
    k_o = np.linalg.solve(s, h_o @ p_oo).T
    p_uo = np.linalg.solve(k_o @ h_o, q[:n, n])
    k_u = np.linalg.solve(s, h_o @ p_uo)
    return t @ np.vstack([k_o, k_u])


def recursive_gain(model: ArrayModel, n_steps: int) -> np.ndarray:
    """Return the gain after ``n_steps`` predict/update cycles of the Kalman filter.

    Eqs. 8.3-8.6.

    Raises
    ------
    InputError
        ``n_steps`` below 1: no update, so no gain.
    """
    kf = model.kalman_filter()
    z = np.zeros(model.n_gyros)
    for _ in range(n_steps):
        kf.predict()
        kf.update(z)
    if kf.K is None:
        raise InputError(f"n_steps must be at least 1, got {n_steps}")
    return kf.K


def constant_gain_filter(z: np.ndarray, gain: np.ndarray) -> np.ndarray:
    """State estimates ``x[k] = (I - K H) x[k-1] + K z[k]`` from ``x = 0`` (eq. 8.7).

    Parameters
    ----------
    z : ndarray of shape (N_samples, n) or (runs, N_samples, n)
        Gyro readings (several records at once along a leading axis).
    gain : ndarray of shape (n + 1, n)

    Returns
    -------
    ndarray of shape (..., N_samples, n + 1)
        ``[omega, b_1 .. b_n]`` estimates.
    """
    z = np.asarray(z, dtype=float)
    n = gain.shape[1]
    if z.shape[-1] != n:
        raise InputError(f"z has {z.shape[-1]} gyros, the gain is for {n}")
    h = np.hstack([np.ones((n, 1)), np.eye(n)])
    a_t, drive = (np.eye(n + 1) - gain @ h).T, z @ gain.T
    out = np.empty(z.shape[:-1] + (n + 1,))
    x = np.zeros(z.shape[:-2] + (n + 1,))
    for k in range(z.shape[-2]):
        x = x @ a_t + drive[..., k, :]
        out[..., k, :] = x
    return out


def kalman_angle_std(
    model: ArrayModel, gain: np.ndarray, n_steps: int, every: int = 1
) -> np.ndarray:
    """Exact angle-error standard deviation of :func:`constant_gain_filter` on a still array.

    With the rate constant (the gyros still, as in a calibration or in data_synth's arrays),
    the estimation error ``e = x - x_hat`` obeys ``e[k] = A (e[k-1] + Ts w[k]) - K v[k]``,
    ``A = I - K H``, and the angle error ``alpha[k] = alpha[k-1] + Ts e_omega[k]``.  The
    covariance of ``[e, alpha]`` is propagated exactly from zero.

    Returns
    -------
    ndarray of shape (n_steps // every,)
        Standard deviation of the angle error after ``every, 2 every, ...`` samples.
    """
    n, ts = model.n_gyros, model.ts
    a = np.eye(n + 1) - gain @ model.H
    f = block_diag(a, 1.0)
    f[-1, :-1] = ts * a[0]
    g = np.zeros((n + 2, 2 * n))  # inputs [w_1 .. w_n, v_1 .. v_n]
    g[:-1, :n] = ts * a[:, 1:]
    g[:-1, n:] = -gain
    g[-1] = ts * g[0]
    noise = g @ block_diag(model.cov_w, model.cov_v) @ g.T
    cov = np.zeros((n + 2, n + 2))
    out = np.empty(n_steps // every)
    for k in range(1, len(out) * every + 1):
        cov = f @ cov @ f.T + noise
        if k % every == 0:
            out[k // every - 1] = cov[-1, -1]
    return np.sqrt(out)


# -- FOS with the other gyros as inputs ---------------------------------------------------------


def conditional_variance(cov: np.ndarray, target: int = 0) -> float:
    """Variance of gyro ``target``'s white noise given the others' at the same time.

    ``R_tt - R_to R_oo^-1 R_ot``: the least one-step MSE of a model that sees the other gyros
    at lag 0, when the white noise dominates.
    """
    cov = np.asarray(cov, dtype=float)
    rest = [i for i in range(len(cov)) if i != target]
    r_to = cov[target, rest]
    return float(cov[target, target] - r_to @ np.linalg.solve(cov[np.ix_(rest, rest)], r_to))


def cross_gyro_comparison(
    columns: Mapping[str, np.ndarray], target: str, *, train_fraction: float = 0.5,
    max_lag: int = 2, exog_lag: int = 0, ar_order: int = 2,
) -> dict:
    """One gyro's error from its own past (AR, FOS) and from the other gyros too (FOS).

    All three are fitted on the first ``train_fraction`` of the record and scored by the
    one-step MSE on the rest.

    Parameters
    ----------
    columns : mapping of str to ndarray
        Still gyros' readings (their errors), equal lengths.
    target : str
        The modelled gyro.
    max_lag : int
        FOS output lags.
    exog_lag : int
        Lags ``0 .. exog_lag`` of every other gyro offered to the exogenous FOS model.
    ar_order : int
        Order of the Burg AR model.

    Returns
    -------
    dict
        ``ar_mse``, ``fos_mse`` (own past only), ``fos_exog_mse`` and ``fos_exog_terms``.
    """
    y = np.asarray(columns[target], dtype=float)
    others = {k: np.asarray(v, dtype=float) for k, v in columns.items() if k != target}
    cut = round(train_fraction * len(y))
    test = slice(cut, len(y))
    ar = ARModel(ar_order).fit(y[:cut])
    own = FOSModel(max_lag=max_lag).fit(y[:cut])
    exog = FOSModel(max_lag=max_lag, exog_lags={k: exog_lag for k in others})
    exog.fit(y[:cut], {k: v[:cut] for k, v in others.items()})
    return {"ar_mse": one_step_mse(y, ar.predict(y), test),
            "fos_mse": one_step_mse(y, own.predict(y), test),
            "fos_exog_mse": one_step_mse(y, exog.predict(y, others), test),
            "fos_exog_terms": list(exog.terms_)}

"""Allan-variance noise terms as a low-order state-space error model, per axis and per IMU.

:func:`allan_state_space` turns the IEEE Std 952 coefficients of
:func:`fosmodel.noise.allan_fit.fit_noise` into the error model a navigation filter usually
carries for each sensor axis: white noise, a first-order Gauss-Markov bias for the bias
instability and a random-walk bias::

    x = [white, gauss-markov bias, random-walk bias],   y[n] = H x[n] + mu,   H = [1, 1, 1]
    white[n] = w0[n]                              var(w0) = N^2 rate
    gm[n]    = exp(-dt/Tc) gm[n-1] + w1[n]        var(w1) = sigma^2 (1 - exp(-2 dt/Tc))
    rw[n]    = rw[n-1] + w2[n]                    var(w2) = K^2 dt

(``dt = 1/rate``; ``G`` is the identity and ``Q`` diagonal, each state driven by its own
noise).  White noise of spectral density ``N^2`` sampled at ``rate`` has the variance
``N^2 rate`` per sample and the Allan deviation ``N/sqrt(tau)``; the random walk has
``K sqrt(tau/3)``.  Flicker noise, whose Allan deviation is the floor ``0.664 B``, has no
finite-order state space; the Gauss-Markov bias stands in for it where it matters most (see
:func:`gauss_markov_for_flicker`).  Where the fit holds a Gauss-Markov term ``G`` (a bounded
bias, :func:`~fosmodel.noise.allan_fit.fit_noise`), it is one more state, with the fitted
``sigma`` and ``Tc``, after the random walk.  :func:`assemble_axes` puts several axes (three
gyros and three accelerometers) into one block-diagonal model, and :func:`initial_covariance`
gives a filter its starting covariance: the random walk has no stationary one.

References
----------
IEEE Std 952-1997, *IEEE Standard Specification Format Guide and Test Procedure for
Single-Axis Interferometric Fiber Optic Gyros*, Annex C.
N. El-Sheimy, H. Hou and X. Niu, "Analysis and modeling of inertial sensors using Allan
variance", *IEEE Trans. Instrum. Meas.* 57(1), 140-149, 2008 (the Gauss-Markov Allan
deviation and its peak).
R. Brown and P. Hwang, *Introduction to Random Signals and Applied Kalman Filtering*, 4th
ed., Wiley, 2012, ch. 2-3 (discrete Gauss-Markov and random-walk states).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import block_diag, solve_discrete_lyapunov

from ..core.exceptions import InputError
from ..noise.allan import FLICKER_FLOOR
from ..noise.allan_fit import GM_PEAK_ADEV, GM_PEAK_TAU, NoiseFit, gauss_markov_avar
from .statespace import StateSpace

__all__ = ["GM_PEAK_ADEV", "GM_PEAK_TAU", "STATE_NAMES", "allan_state_space", "assemble_axes",
           "flicker_tau", "gauss_markov_adev", "gauss_markov_for_flicker", "initial_covariance",
           "model_adev", "model_terms"]

#: The terms the model carries, in state order, and their states' names: the fitted
#: Gauss-Markov term ``G`` (a bounded bias) is a state as it is.
STATE_NAMES = {"N": "white", "B": "gauss-markov bias", "G": "bounded bias",
               "K": "random-walk bias"}
#: The fitted terms that get no state, and why.
NOT_CARRIED = {
    "Q": "not carried: quantization is white in the integral, not in the rate",
    "R": "not carried: the rate ramp is a deterministic drift, not a noise",
    "S": "not carried: the sinusoid is a spectral line, not a noise",
}


class TermValue(NamedTuple):
    """The value of a noise term the model uses, and where it comes from."""

    value: float
    """In the record's units (see :attr:`fosmodel.noise.allan_fit.NoiseFit.coefficients`)."""
    source: str
    """``"fitted"``, ``"upper limit"`` (not resolved) or why the term is not carried."""


def model_terms(fit: NoiseFit) -> dict[str, TermValue]:
    """Return the value of each fitted term that :func:`allan_state_space` uses, and its source.

    :meth:`~fosmodel.noise.allan_fit.NoiseFit.conservative`: a resolved term gives its fitted
    coefficient, one that is not resolved its upper limit: the conservative choice for a filter,
    which then claims at most that much more uncertainty than the data support, where the
    fitted value (often zero) would let it trust a bias it cannot see.  Quantization, the rate
    ramp and the sinusoid are listed with the reason they get no state.

    Parameters
    ----------
    fit : NoiseFit
        From :func:`fosmodel.noise.allan_fit.fit_noise`.

    Returns
    -------
    dict of str to TermValue
        One entry per term in ``fit.terms``.
    """
    out = {}
    for term in fit.terms:
        value, source = fit.conservative(term)
        out[term] = TermValue(value, NOT_CARRIED.get(term, source))
    return out


def gauss_markov_adev(taus: ArrayLike, sigma: float, tc: float) -> np.ndarray:
    """Allan deviation of a first-order Gauss-Markov process (continuous time).

    ``sigma^2(tau) = (2 sigma^2 Tc / tau) (1 - Tc (3 - 4 exp(-tau/Tc) + exp(-2 tau/Tc)) /
    (2 tau))`` (:func:`fosmodel.noise.allan_fit.gauss_markov_avar`): rising as ``sqrt(tau)``
    (a random walk) well below ``Tc``, falling as ``1/sqrt(tau)`` (white noise) well above it,
    and peaking at :data:`GM_PEAK_ADEV` ``sigma`` at ``tau =`` :data:`GM_PEAK_TAU` ``Tc``.

    Parameters
    ----------
    taus : array-like
        Averaging times in seconds.
    sigma : float
        Standard deviation of the process.
    tc : float
        Correlation time in seconds.

    Returns
    -------
    ndarray
        The Allan deviation at each tau, in the units of ``sigma``.

    References
    ----------
    El-Sheimy, Hou and Niu (2008), eq. for the Gauss-Markov Allan variance (module references).
    """
    return sigma * np.sqrt(gauss_markov_avar(taus, tc))


def flicker_tau(n: float, k: float, taus: np.ndarray) -> float:
    """Return the tau where a flicker floor matters most, within ``taus``.

    That is the minimum of ``N^2/tau + K^2 tau/3``, ``sqrt(3) N / K`` (the floor is not seen
    beyond the record; without ``K`` that is the longest tau, without ``N`` the shortest).
    """
    tau = math.sqrt(3.0) * n / k if k > 0 else math.inf
    return float(np.clip(tau, taus[0], taus[-1]))


def gauss_markov_for_flicker(b: float, tau_b: float) -> tuple[float, float]:
    """Return the first-order Gauss-Markov bias standing in for a bias instability ``B``.

    Its Allan deviation peak (:data:`GM_PEAK_ADEV` ``sigma`` at :data:`GM_PEAK_TAU` ``Tc``)
    is put on the flicker floor ``0.664 B`` at ``tau_b``: ``sigma = 0.664 B / 0.6174`` and
    ``Tc = tau_b / 1.8926``.  One Gauss-Markov process follows the flat floor over about a
    decade around ``tau_b``; further away the white and random-walk terms dominate.

    Parameters
    ----------
    b : float
        Bias instability coefficient, in the record's units.
    tau_b : float
        Averaging time of the floor, in seconds (:func:`flicker_tau`).

    Returns
    -------
    sigma, tc : float
        Standard deviation (record's units) and correlation time (s).

    References
    ----------
    El-Sheimy, Hou and Niu (2008); IEEE Std 952-1997, Annex C (module references).
    """
    return FLICKER_FLOOR * b / GM_PEAK_ADEV, tau_b / GM_PEAK_TAU


def allan_state_space(fit: NoiseFit, mu: float = 0.0) -> StateSpace:
    """Build the white + Gauss-Markov + random-walk error model of one axis from its Allan fit.

    The terms' values come from :func:`model_terms` (fitted, or the upper limit where not
    resolved).  ``N`` gives the white state, ``B`` the Gauss-Markov bias of
    :func:`gauss_markov_for_flicker` placed at :func:`flicker_tau` of the ``N`` and ``K``
    used, ``K`` the random-walk bias, and a fitted Gauss-Markov term ``G`` its own
    Gauss-Markov state ("bounded bias", its ``sigma`` and ``Tc``) (module docstring).  A
    term the fit did not include
    (``terms=`` of :func:`~fosmodel.noise.allan_fit.fit_noise`) has no state, and its name is
    missing from ``state_names``; quantization, the rate ramp and the sinusoid get none either
    (:data:`NOT_CARRIED`).

    Parameters
    ----------
    fit : NoiseFit
        From :func:`fosmodel.noise.allan_fit.fit_noise`; its record's rate is the model's.
    mu : float
        Mean of the output (the calibrated bias), which an Allan fit does not hold.

    Returns
    -------
    StateSpace
        Diagonal ``Phi``, ``G`` the identity, diagonal ``Q``, ``H`` ones, no inputs.

    Raises
    ------
    InputError
        The fit has none of ``N``, ``B``, ``K`` and ``G``.

    References
    ----------
    IEEE Std 952-1997, Annex C; El-Sheimy, Hou and Niu (2008); Brown and Hwang (2012)
    (module references).
    """
    values = {k: v.value for k, v in model_terms(fit).items() if k in STATE_NAMES}
    if not values:
        raise InputError(f"the Allan fit has none of the terms N, B, K, G (it has "
                         f"{', '.join(fit.terms)}): there is no noise to model")
    dt = 1.0 / fit.result.rate
    phi, q = [], []
    if "N" in values:
        phi.append(0.0)
        q.append(values["N"] ** 2 / dt)
    if "B" in values:
        tau_b = flicker_tau(values.get("N", 0.0), values.get("K", 0.0), fit.fitted_taus)
        sigma, tc = gauss_markov_for_flicker(values["B"], tau_b)
        phi.append(math.exp(-dt / tc))
        q.append(sigma**2 * (1.0 - phi[-1] ** 2))
    if "K" in values:
        phi.append(1.0)
        q.append(values["K"] ** 2 * dt)
    if "G" in values and fit.gm_tc is not None:  # the fitted bounded bias, as it is
        phi.append(math.exp(-dt / fit.gm_tc))
        q.append(values["G"] ** 2 * (1.0 - phi[-1] ** 2))
    n = len(phi)
    return StateSpace(Phi=np.diag(phi), B=np.zeros((n, 0)), G=np.eye(n), H=np.ones((1, n)),
                      Q=np.diag(q), mu=float(mu),
                      state_names=tuple(STATE_NAMES[k] for k in values), input_names=(),
                      rate=float(fit.result.rate))


def model_adev(error: StateSpace, taus: ArrayLike, rate: float) -> np.ndarray:
    """Allan deviation of a one-axis :func:`allan_state_space` model, read from its matrices.

    Each state is read back from its diagonal entries: ``Phi`` 0 is white noise
    (``N^2 = q / rate``), ``Phi`` 1 a random walk (``K^2 = q rate``), anything between a
    Gauss-Markov bias (``sigma^2 = q / (1 - Phi^2)``, ``Tc = -1 / (rate ln Phi)``,
    :func:`gauss_markov_adev`).  The states are independent, so their Allan variances add.

    Parameters
    ----------
    error : StateSpace
        A one-axis model from :func:`allan_state_space`.
    taus : array-like
        Averaging times in seconds.
    rate : float
        The model's sample rate in Hz (its NoiseFit's).

    Returns
    -------
    ndarray
        The model's Allan deviation at each tau, in the record's units.

    Raises
    ------
    InputError
        A model that is not diagonal with one output summing its states.
    """
    n = error.n_states
    diagonal = all(np.array_equal(m, np.diag(np.diag(m))) for m in (error.Phi, error.Q))
    if not (diagonal and np.array_equal(error.G, np.eye(n))
            and np.array_equal(error.H, np.ones((1, n)))):
        raise InputError("model_adev reads a one-axis allan_state_space model: diagonal Phi "
                         "and Q, G the identity, H summing the states")
    t = np.asarray(taus, dtype=float)
    variance = np.zeros_like(t)
    for phi, q in zip(np.diag(error.Phi), np.diag(error.Q)):
        if phi == 0.0:
            variance += q / rate / t
        elif phi == 1.0:
            variance += q * rate * t / 3.0
        else:
            variance += gauss_markov_adev(t, math.sqrt(q / (1.0 - phi**2)),
                                          -1.0 / (rate * math.log(phi))) ** 2
    return np.sqrt(variance)


def assemble_axes(axes: Mapping[str, StateSpace]) -> StateSpace:
    """Join several axes' error models into one block-diagonal model.

    E.g. three gyros and three accelerometers.

    The axes are independent: ``Phi``, ``G``, ``Q``, ``B`` and ``H`` are block-diagonal, so
    output ``i`` (row ``i`` of ``H``) is axis ``i``'s and ``Q`` holds each axis's driving noise
    in its block.  State and input names are prefixed by the axis (``"ax: white"``).  The axes'
    means are taken as compensated (``mu = 0``), as in
    :func:`~fosmodel.filter.statespace.position_velocity_error_model`: the state holds the error
    deviations a navigation filter estimates.  :meth:`StateSpace.simulate` and
    :meth:`StateSpace.predict_measurement` give the first output; ``H @ x`` gives all.

    Parameters
    ----------
    axes : dict of str to StateSpace
        Each axis's linear model with one output (:func:`allan_state_space`, or
        :func:`~fosmodel.filter.statespace.to_state_space`), keyed by the axis name.

    Returns
    -------
    StateSpace

    Raises
    ------
    InputError
        No axes, or an axis with more than one output.
    """
    if not axes:
        raise InputError("assemble_axes needs at least one axis")
    multi = [name for name, s in axes.items() if s.H.shape[0] != 1]
    if multi:
        raise InputError(f"axis {multi[0]!r} has {axes[multi[0]].H.shape[0]} outputs; each "
                         "axis must have one")
    parts = list(axes.values())
    rates = {s.rate for s in parts}
    return StateSpace(
        Phi=block_diag(*(s.Phi for s in parts)), B=block_diag(*(s.B for s in parts)),
        G=block_diag(*(s.G for s in parts)), H=block_diag(*(s.H for s in parts)),
        Q=block_diag(*(s.Q for s in parts)), mu=0.0, D=block_diag(*(s.D for s in parts)),
        rate=rates.pop() if len(rates) == 1 else None,
        state_names=tuple(f"{a}: {n}" for a, s in axes.items() for n in s.state_names),
        input_names=tuple(f"{a}: {n}" for a, s in axes.items() for n in s.input_names))


#: Largest ``|eigenvalue|`` of a transition taken as stable; above it a state is a unit root
#: (or worse) and gets the damped covariance of :func:`initial_covariance`.
STABLE_RADIUS = 1.0 - 1e-9


def initial_covariance(error: StateSpace, n_samples: int) -> np.ndarray:
    """Covariance of an error model's state when filtering starts after calibration.

    The filter starts after ``n_samples`` of training whose mean was removed as the calibrated
    bias.  A stable model starts from its stationary covariance (the mean takes little of
    it).  A random walk (a state with ``Phi`` 1 on its diagonal, coupled to no other) has no
    stationary covariance; it starts from the spread of its last training value about the
    training mean, ``q (n - 1)(2n - 1) / (6n)`` with ``q`` its variance per step (``K^2 T/3``
    for a training time ``T``), which is what the calibration leaves of it.

    Any other model with a unit root (a local level coupled to an AR part, a drift, a loop's
    final model held to a level) starts from the damped solve ``P = (rho Phi) P (rho Phi)' +
    G Q G'``, ``rho = (1 - 3 / (2 n)) / max|eig(Phi)|``: its stable directions keep about
    their stationary covariance, and a unit root's direction gets ``q / (2 (1 - rho))``,
    ``q n / 3``, the spread a walk's last training value has about the training mean (as
    above): a large, finite prior that the measurements then narrow.

    Parameters
    ----------
    error : StateSpace
        An error model (:func:`allan_state_space`, :func:`assemble_axes`,
        :func:`~fosmodel.filter.statespace.to_state_space`, ...).
    n_samples : int
        Training samples behind the calibrated bias.

    Returns
    -------
    ndarray of shape (n_states, n_states)

    Raises
    ------
    InputError
        Fewer than one sample.
    """
    if n_samples < 1:
        raise InputError(f"n_samples must be at least 1, got {n_samples}")
    phi, gqg = error.Phi, error.process_covariance()
    radius = float(np.max(np.abs(np.linalg.eigvals(phi)))) if phi.size else 0.0
    if radius < STABLE_RADIUS:
        return error.stationary_covariance()
    walks = np.isclose(np.diag(phi), 1.0)
    rest = ~walks
    coupled = [a[np.ix_(walks, rest)] for a in (phi, phi.T, gqg)]
    decoupled = not any(np.any(c != 0.0) for c in coupled) and np.array_equal(
        phi[np.ix_(walks, walks)], np.eye(walks.sum()))
    sub_radius = (float(np.max(np.abs(np.linalg.eigvals(phi[np.ix_(rest, rest)]))))
                  if rest.any() else 0.0)
    if not decoupled or sub_radius >= STABLE_RADIUS:
        return _damped_covariance(phi, gqg, radius, n_samples)
    p0 = np.zeros_like(phi)
    n = n_samples
    p0[np.ix_(walks, walks)] = gqg[np.ix_(walks, walks)] * (n - 1) * (2 * n - 1) / (6 * n)
    if rest.any():
        p0[np.ix_(rest, rest)] = _subsystem(error, rest, gqg).stationary_covariance()
    return p0


def _damped_covariance(phi: np.ndarray, gqg: np.ndarray, radius: float,
                       n_samples: int) -> np.ndarray:
    """``P = (rho Phi) P (rho Phi)' + G Q G'`` with ``rho`` (1 - 3/(2n)) / radius, symmetrised."""
    rho = (1.0 - 1.5 / max(n_samples, 2)) / radius
    p = solve_discrete_lyapunov(rho * phi, gqg)
    return (p + p.T) / 2.0


def _subsystem(error: StateSpace, keep: np.ndarray, gqg: np.ndarray) -> StateSpace:
    """Return the states ``keep`` of ``error`` on their own, driven by their block of ``G Q G'``."""
    n = int(keep.sum())
    return StateSpace(Phi=error.Phi[np.ix_(keep, keep)], B=np.zeros((n, 0)), G=np.eye(n),
                      H=np.ones((1, n)), Q=gqg[np.ix_(keep, keep)], mu=0.0,
                      state_names=tuple(np.array(error.state_names)[keep]), input_names=())

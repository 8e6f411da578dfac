"""The six axes' noise as one state space: each axis's Allan terms, their correlations across axes.

The per-axis models of :mod:`fosmodel.filter.allan_statespace` (white noise, a Gauss-Markov
bias, a random-walk bias) treat the axes as independent.  On a real IMU they are not quite:
the axes share a supply, a clock, a temperature and a package, so their fast parts and their
slow biases move together a little.  :func:`joint_noise` keeps each axis's terms as its own
Allan fit gives them and adds, from the static record itself, the correlation of each kind of
noise across axes:

- the **white** parts: the correlation of the record's first differences, in which the slow
  terms are negligible (a sample's increment of a random walk is ``K/N`` sample noises,
  ``1e-3`` and less on MEMS sensors);
- the **biases** (Gauss-Markov and random walk together): the correlation of the overlapping
  Allan differences of the two axes (the cross Allan covariance) at the averaging times where
  both axes' fits say the biases dominate their white noise, kept only where it stands two
  standard errors (``2/sqrt(clusters)``) from zero.

The state space is the block-diagonal one of
:func:`~fosmodel.filter.allan_statespace.assemble_axes`, with the driving noise of each white
state correlated with the other axes' white states, and each bias state with the other axes'
bias states of the same kind: ``Q[i, j] = rho_ij sqrt(Q[i, i] Q[j, j])``.  A correlation
matrix pieced together pair by pair is brought to the nearest positive semi-definite one
(eigenvalues clipped at zero, diagonal back to one).

References
----------
D. W. Allan and J. A. Barnes, "A modified 'Allan variance' with increased oscillator
characterization ability", 1981, and NIST SP 1065 (2008), ch. 9 (the covariance of two
clocks' Allan differences, "three-cornered hat").
R. J. Vaccaro and A. S. Zaki, "Statistical modeling of rate gyros", *IEEE Trans. Instrum.
Meas.* 61(3), 673-684, 2012 (correlated noise across gyros of an array).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..core.exceptions import InputError
from ..noise.allan_fit import NoiseFit
from ..noise.imu_noise import ImuNoise
from .allan_statespace import allan_state_space, assemble_axes, initial_covariance
from .statespace import StateSpace

#: Which states of an axis's model share a correlation across axes: white with white, the
#: biases (Gauss-Markov, random walk) with the same kind.
_KIND = {"white": "white", "gauss-markov bias": "bias", "bounded bias": "bias",
         "random-walk bias": "bias"}
#: A tau's Allan variance is the biases' where they make this share of it on both axes...
BIAS_SHARE = 0.5
#: ...and the terms that are neither white nor a bias (the ramp, a spectral line) at most this.
OTHER_SHARE = 0.1
BIAS_TERMS = ("B", "K", "G")
OTHER_TERMS = ("R", "S")


@dataclass(frozen=True)
class JointNoise:
    """The noise of several axes of one IMU as one state space with its cross-axis covariances.

    Attributes
    ----------
    columns : tuple of str
        The axes, in the state space's order.
    sensors, units : tuple of str
        Each axis's sensor and units (the state space is in the record's units).
    rate : float
        Sample rate in Hz.
    white_correlation, bias_correlation : ndarray of shape (n, n)
        Correlations across axes of the white parts and of the biases (0 where the record
        cannot tell them from zero).
    bias_taus : ndarray of shape (n, n)
        The shortest averaging time each pair's bias correlation is read from (NaN where no
        averaging time has the biases dominant on both axes).
    model : StateSpace
        The axes' states (as :func:`~fosmodel.filter.allan_statespace.assemble_axes`) with the
        full driving-noise covariance ``Q``.
    independent : StateSpace
        The same without the cross-axis covariances: the per-axis models side by side.
    n_samples : int
        Samples of the record.
    """

    columns: tuple[str, ...]
    sensors: tuple[str, ...]
    units: tuple[str, ...]
    rate: float
    white_correlation: np.ndarray
    bias_correlation: np.ndarray
    bias_taus: np.ndarray
    model: StateSpace
    independent: StateSpace
    n_samples: int

    def initial_covariance(self) -> np.ndarray:
        """Return the model's starting covariance after calibration on the record.

        :func:`~fosmodel.filter.allan_statespace.initial_covariance`.
        """
        return initial_covariance(self.model, self.n_samples)

    def to_dict(self) -> dict[str, Any]:
        """Return the model and its correlations as JSON-ready lists."""
        return {"axes": list(self.columns), "sensors": list(self.sensors),
                "units": dict(zip(self.columns, self.units)), "rate_hz": self.rate,
                "white_correlation": self.white_correlation.tolist(),
                "bias_correlation": self.bias_correlation.tolist(),
                "bias_correlation_from_tau_s": [[None if math.isnan(t) else float(t)
                                                 for t in row] for row in self.bias_taus],
                **self.model.to_dict(), "P0": self.initial_covariance().tolist()}


def joint_noise(columns: Mapping[str, np.ndarray], noise: ImuNoise) -> JointNoise:
    """Build the axes' joint noise model from a static record and each axis's Allan fit.

    Parameters
    ----------
    columns : mapping of str to ndarray
        The record's signals by column name (each of ``noise``'s axes), in the units of the
        fits, of equal length.
    noise : ImuNoise
        Every axis's Allan fit (:func:`fosmodel.noise.imu_noise.imu_noise`) on that record.

    Returns
    -------
    JointNoise

    Raises
    ------
    InputError
        Fewer than two axes, a column missing, or columns of unequal length.
    """
    names = [a.axis.column for a in noise.axes]
    if len(names) < 2:
        raise InputError("a joint noise model needs at least two axes")
    missing = [c for c in names if c not in columns]
    if missing:
        raise InputError(f"no column {missing[0]!r} among the signals given")
    x = np.column_stack([np.asarray(columns[c], dtype=float) for c in names])
    if len({len(np.asarray(columns[c])) for c in names}) > 1:
        raise InputError("the columns differ in length")
    white = _nearest_correlation(np.corrcoef(np.diff(x, axis=0), rowvar=False))
    bias, taus = _bias_correlation(x, noise, white)
    independent = assemble_axes({a.axis.column: allan_state_space(a.fit) for a in noise.axes})
    model = _correlated(independent, names, {"white": white, "bias": bias})
    return JointNoise(tuple(names), tuple(a.axis.sensor for a in noise.axes),
                      tuple(a.axis.units for a in noise.axes), noise.rate, white, bias, taus,
                      model, independent, len(x))


def _correlated(independent: StateSpace, names: list[str],
                correlations: Mapping[str, np.ndarray]) -> StateSpace:
    """Return the block-diagonal model with ``Q[i, j] = rho sqrt(Q[i, i] Q[j, j])`` across axes."""
    q = independent.Q.copy()
    owner = [names.index(s.split(": ", 1)[0]) for s in independent.state_names]
    kind = [_KIND[s.split(": ", 1)[1]] for s in independent.state_names]
    state = {s.split(": ", 1)[1] for s in independent.state_names}
    for name in state:
        rows = [i for i, s in enumerate(independent.state_names) if s.endswith(": " + name)]
        for i in rows:
            for j in rows:
                if owner[i] != owner[j]:
                    rho = correlations[kind[i]][owner[i], owner[j]]
                    q[i, j] = rho * math.sqrt(independent.Q[i, i] * independent.Q[j, j])
    return StateSpace(Phi=independent.Phi, B=independent.B, G=independent.G, H=independent.H,
                      Q=q, mu=0.0, state_names=independent.state_names,
                      input_names=independent.input_names)


def _bias_correlation(x: np.ndarray, noise: ImuNoise,
                      white: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Correlation of the axes' biases from their cross Allan covariance, and its first tau.

    At a tau where the biases make the shares ``b_i``, ``b_j`` of the two axes' fitted Allan
    variances and the white noise ``w_i``, ``w_j``, the correlation ``r`` of their Allan
    differences is ``rho_w sqrt(w_i w_j) + rho_b sqrt(b_i b_j)``; ``rho_b`` follows from it.
    For each pair, the median over the averaging times where the biases make at least
    :data:`BIAS_SHARE` of both variances and the other terms (a ramp, a spectral line, whose
    correlation is not the biases') at most :data:`OTHER_SHARE`; kept where it is more than two
    standard errors, ``2/sqrt(clusters)`` at the shortest of those taus, from zero.
    """
    n = x.shape[1]
    taus = noise.axes[0].result.taus
    shares = [_shares(a.fit, taus) for a in noise.axes]
    share = np.array([b for b, _ in shares])
    other = np.array([o for _, o in shares])
    usable = (share >= BIAS_SHARE) & (other <= OTHER_SHARE)
    wanted = np.flatnonzero(usable.sum(axis=0) >= 2)
    phase = np.cumsum(x - x.mean(axis=0), axis=0)
    by_tau = {int(t): _allan_correlations(phase, int(round(taus[t] * noise.rate)))
              for t in wanted}
    rho, first = np.eye(n), np.full((n, n), np.nan)
    for i in range(n):
        for j in range(i + 1, n):
            both = [t for t in by_tau if usable[i, t] and usable[j, t]]
            if not both:
                continue
            white_share = 1.0 - share - other
            estimate = float(np.median([
                (by_tau[t][0][i, j] - white[i, j] * math.sqrt(white_share[i, t]
                                                              * white_share[j, t]))
                / math.sqrt(share[i, t] * share[j, t]) for t in both]))
            if abs(estimate) > 2.0 / math.sqrt(by_tau[both[0]][1]):
                rho[i, j] = rho[j, i] = estimate
                first[i, j] = first[j, i] = float(taus[both[0]])
    return _nearest_correlation(np.clip(rho, -1.0, 1.0)), first


def _shares(fit: NoiseFit, taus: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Return the shares of a fit's Allan variance at ``taus`` of its biases and of the rest.

    The biases are the bias instability and the random walk; the rest is what is neither white
    (quantization, ``N``) nor a bias: the rate ramp and the sinusoid (a spectral line the axes
    may share, which is not a bias).
    """
    total = np.maximum(fit.model_adev(taus) ** 2, np.finfo(float).tiny)
    part = {group: sum((fit.term_adev(k, taus) ** 2 for k in terms if k in fit.terms),
                       np.zeros_like(taus)) / total
            for group, terms in (("bias", BIAS_TERMS), ("other", OTHER_TERMS))}
    return part["bias"], part["other"]


def _allan_correlations(phase: np.ndarray, m: int) -> tuple[np.ndarray, int]:
    """Correlations of the axes' overlapping Allan differences at ``m`` samples.

    Also the number of non-overlapping differences (the independent ones).
    """
    d = phase[2 * m:] - 2.0 * phase[m:-m] + phase[:-2 * m]
    cross = d.T @ d
    scale = np.sqrt(np.diag(cross))
    return cross / np.outer(scale, scale), max(len(d) // (2 * m), 1)


def _nearest_correlation(c: np.ndarray) -> np.ndarray:
    """Return the nearest positive semi-definite correlation matrix (eigenvalues clipped)."""
    c = 0.5 * (c + c.T)
    values, vectors = np.linalg.eigh(c)
    if values.min() >= 0.0:
        return c
    clipped = (vectors * np.maximum(values, 0.0)) @ vectors.T
    d = np.sqrt(np.diag(clipped))
    return clipped / np.outer(d, d)

"""An error model built for a navigation filter: FOS picks the bias's time scales on block means.

A filter that predicts over tens of seconds suffers the slow part of a sensor error, not its
sub-second correlation, which a FOS model of the samples describes (its slowest time constants
are a few seconds, so its bias fades within an outage).  :class:`FOSFilterModel` keeps the
white part of the measurement apart from a bias process, and lets FOS choose the structure of
that bias on the time scale the filter predicts over::

    y[n] = mu + white[n] + sum_i gm_i[n] + rw[n] + d[n]
    gm_i[n] = exp(-dt/tau_i) gm_i[n-1] + w_i[n]      (the time scales FOS selects)
    rw[n]   = rw[n-1] + w_rw[n]                      (the reference level: a random walk)
    d[n]    = b' u[n]                                (drivers measured in use, through B u)

Fitting, on a record at ``fs``:

1. **Drivers** (``exog``, e.g. the die temperature): the record is cut into 80 blocks; FOS,
   with no intercept, selects among each channel and its square on the *differences* of the
   block means (a driver's effect follows the driver's changes; a wander common to both does
   not survive the differencing as well), on two of every three differences.  A driver is
   kept only if it lowers the mean square of the third held out (every third difference: a
   held-out last stretch that falls on a hold of the temperature could not judge); its weights
   are then refitted on all differences and its part is subtracted before the noise fit.
2. **Time scales**: on the series of block means (``block_s``, 1 s by default), the local
   levels of :mod:`fosmodel.core.levels` (exponentially weighted means of the past blocks) at
   time constants ``level_taus_s`` are the candidates and a reference level at
   ``reference_fraction`` of the record stands for the random walk.  FOS expands the next
   block's departure from the reference level in the candidates' departures from it, so the
   weights of the levels and the reference sum to one; each level selected becomes a
   first-order Gauss-Markov state with that time constant.
3. **Variances**: the white density, each Gauss-Markov variance and the random walk's rate
   are the maximum-likelihood values on the block series (the prediction-error decomposition
   of the block-rate Kalman filter: the innovation variances, statsmodels'
   :class:`~statsmodels.tsa.statespace.mlemodel.MLEModel`), then scaled to the sample rate
   (the white variance times the block length, the random walk's per-step variance divided by
   it).  None is tuned by hand.

The result is a :class:`~fosmodel.filter.statespace.StateSpace`
(:meth:`FOSFilterResults.to_state_space`) with a starting covariance
(:meth:`FOSFilterResults.initial_covariance`) and the centred driver inputs
(:meth:`FOSFilterResults.input_matrix`).  Its transition never grows: every eigenvalue is at
most 1 (checked on export).

References
----------
M. J. Korenberg, "A robust orthogonal algorithm for system identification and time-series
analysis", *Biological Cybernetics* 60, 267-276, 1989 (FOS).
A. C. Harvey, *Forecasting, Structural Time Series Models and the Kalman Filter*, Cambridge
University Press, 1989, ch. 3 (maximum likelihood by the prediction-error decomposition).
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..core.exceptions import InputError
from ..core.fos import fos
from ..core.levels import level_series
from ..core.validation import as_channels, as_signal
from .statespace import StateSpace

__all__ = ["BiasComponent", "DriverTerm", "FOSFilterModel", "FOSFilterResults"]

#: Blocks the record is cut into for the driver search (differences of their means).
DRIVER_BLOCKS = 80
#: Every this many-th driver difference is held out to confirm a driver.
HELD_OUT_EVERY = 3
#: Fewest blocks a fit needs.
MIN_BLOCKS = 50
#: Time constants (in blocks) of the default candidate levels: 4, 8, ... blocks up to the
#: reference.
_FIRST_LEVEL_BLOCKS = 4


@dataclass(frozen=True)
class BiasComponent:
    """One state of the bias process."""

    kind: str
    """``"gauss-markov"`` or ``"random walk"``."""
    tau_s: float
    """Time constant in seconds (``inf`` for the random walk)."""
    variance: float
    """Stationary variance of a Gauss-Markov state; the random walk's variance per second."""
    fos_weight: float
    """Weight of its level in the FOS expansion (the reference's for the random walk)."""

    @property
    def name(self) -> str:
        """State name, e.g. ``"gm@32s"`` or ``"random walk"``."""
        return "random walk" if self.kind == "random walk" else f"gm@{self.tau_s:g}s"


@dataclass(frozen=True)
class DriverTerm:
    """A driver's term ``coef * (form(u) - offset)``, in the output's units."""

    channel: str
    power: int
    """1: the channel about its training mean; 2: the square of that."""
    centre: float
    """Training mean of the channel."""
    offset: float
    """Training mean of the centred power (0 for power 1)."""
    coef: float

    @property
    def name(self) -> str:
        """Input name, e.g. ``"(temp_c - 25.3)^2"``."""
        base = f"{self.channel} - {self.centre:.6g}"
        return f"({base})" if self.power == 1 else f"({base})^2"

    def values(self, u: np.ndarray) -> np.ndarray:
        """Return the input column (centred so that its training mean is zero)."""
        return (u - self.centre) ** self.power - self.offset


class FOSFilterModel:
    """Fit a filter error model whose bias structure FOS selects on block means.

    Parameters
    ----------
    block_s : float
        Length of the blocks the bias is modelled on, in seconds: the shortest time scale
        the filter is meant to predict over (1 s by default).
    level_taus_s : sequence of float, optional
        Time constants of the candidate levels in seconds; by default 4, 8, 16, ... blocks,
        below the reference.
    reference_fraction : float
        The reference level's time constant as a share of the record (0.1).
    max_levels : int
        Most Gauss-Markov states FOS may select.
    stop : str
        FOS stopping rule on the block series (:class:`fosmodel.core.fos.StopRule`).
    drivers : bool
        Search the channels of ``exog`` for drivers.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> fs, n = 10.0, 40_000
    >>> y = 0.05 * rng.standard_normal(n) + np.cumsum(2e-4 * rng.standard_normal(n))
    >>> res = FOSFilterModel().fit(y, fs)
    >>> bool(res.to_state_space().n_states >= 2)
    True
    """

    def __init__(self, block_s: float = 1.0, level_taus_s: Sequence[float] | None = None,
                 reference_fraction: float = 0.1, max_levels: int = 3, stop: str = "bic",
                 drivers: bool = True) -> None:
        self.block_s = block_s
        self.level_taus_s = level_taus_s
        self.reference_fraction = reference_fraction
        self.max_levels = max_levels
        self.stop = stop
        self.drivers = drivers

    def fit(self, y: ArrayLike, fs: float,
            exog: Mapping[str, ArrayLike] | None = None) -> FOSFilterResults:
        """Fit on the record ``y`` sampled at ``fs`` Hz, with driver channels ``exog``.

        Raises
        ------
        InputError
            A bad signal or rate, a block shorter than a sample, or fewer than
            :data:`MIN_BLOCKS` blocks.
        """
        y = as_signal(y, "y")
        if not (math.isfinite(fs) and fs > 0):
            raise InputError(f"fs must be a positive rate in Hz, got {fs!r}")
        m = int(round(self.block_s * fs))
        if m < 1:
            raise InputError(f"block_s = {self.block_s!r} s is shorter than one sample at "
                             f"{fs:g} Hz")
        n_blocks = len(y) // m
        if n_blocks < MIN_BLOCKS:
            raise InputError(f"{len(y)} samples make {n_blocks} blocks of {self.block_s:g} s; "
                             f"at least {MIN_BLOCKS} are needed")
        if not 0.0 < self.reference_fraction < 1.0:
            raise InputError(f"reference_fraction must be in (0, 1), got "
                             f"{self.reference_fraction!r}")
        channels = as_channels(exog, list(exog or {}), len(y)) if exog else {}
        drivers = _select_drivers(y, channels) if self.drivers and channels else ()
        rest = y - sum((d.coef * d.values(channels[d.channel]) for d in drivers),
                       np.zeros(len(y)))
        mu = float(np.mean(rest))
        block_dt = m / fs
        blocks = rest[: n_blocks * m].reshape(n_blocks, m).mean(axis=1) - mu
        ref_blocks = self.reference_fraction * n_blocks
        taus = (np.asarray(self.level_taus_s, dtype=float) / block_dt
                if self.level_taus_s is not None else _default_taus(ref_blocks))
        taus = taus[(taus >= 1.0) & (taus < ref_blocks)]
        selected, weights = _select_levels(blocks, taus, ref_blocks, self.max_levels,
                                           self.stop)
        white_b, gm_var, rw_q = _max_likelihood(blocks, taus[selected])
        comps = [BiasComponent("gauss-markov", float(t * block_dt), float(v), float(w))
                 for t, v, w in zip(taus[selected], gm_var, weights)]
        comps.append(BiasComponent("random walk", math.inf, float(rw_q / block_dt),
                                   float(1.0 - np.sum(weights))))
        return FOSFilterResults(fs=float(fs), block_s=float(block_dt), mu=mu,
                                white_variance=float(white_b * m), components=tuple(comps),
                                drivers=drivers, n_train=len(y))


@dataclass(frozen=True, eq=False)
class FOSFilterResults:
    """A fitted :class:`FOSFilterModel`: the white variance, the bias states and the drivers."""

    fs: float
    block_s: float
    mu: float
    """Training mean of the measurement less its drivers (the calibrated bias)."""
    white_variance: float
    """Variance per sample of the white part, at ``fs``."""
    components: tuple[BiasComponent, ...]
    drivers: tuple[DriverTerm, ...]
    n_train: int

    @property
    def white_density(self) -> float:
        """The white part's density ``N`` (units sqrt(s)): ``sqrt(variance / fs)``."""
        return math.sqrt(self.white_variance / self.fs)

    @property
    def input_names(self) -> tuple[str, ...]:
        """Names of the inputs :meth:`input_matrix` builds, in order."""
        return tuple(d.name for d in self.drivers)

    def to_state_space(self) -> StateSpace:
        """Build the shaping filter: states white, Gauss-Markov..., random walk, then the drivers.

        ``H`` is ones; each noisy state has its own driving noise (``G`` picks them, ``Q``
        diagonal); the driver state ``d[n] = B u[n]`` has none.

        Raises
        ------
        InputError
            A transition with an eigenvalue above 1 (it cannot come from a fit).
        """
        dt = 1.0 / self.fs
        phi, q, names = [0.0], [self.white_variance], ["white"]
        for c in self.components:
            if c.kind == "random walk":
                phi.append(1.0)
                q.append(c.variance * dt)
            else:
                a = math.exp(-dt / c.tau_s)
                phi.append(a)
                q.append(c.variance * (1.0 - a * a))
            names.append(c.name)
        r = len(phi)
        n = r + (1 if self.drivers else 0)
        transition = np.zeros((n, n))
        transition[:r, :r] = np.diag(phi)
        b = np.zeros((n, len(self.drivers)))
        if self.drivers:
            b[r] = [d.coef for d in self.drivers]
            names.append("drivers")
        _check_bounded(transition)
        return StateSpace(Phi=transition, B=b, G=np.eye(n, r), H=np.ones((1, n)),
                          Q=np.diag(q), mu=self.mu, state_names=tuple(names),
                          input_names=self.input_names)

    def initial_covariance(self) -> np.ndarray:
        """Return the starting covariance after the training record's mean was removed.

        The stable states start from their stationary variance, the random walk from its
        spread about the training mean (as
        :func:`fosmodel.filter.allan_statespace.initial_covariance`), the drivers from 0
        (they are known from ``u``).
        """
        from .allan_statespace import initial_covariance

        return initial_covariance(self.to_state_space(), self.n_train)

    def input_matrix(self, exog: Mapping[str, ArrayLike] | None, n: int) -> np.ndarray:
        """Build the inputs ``u`` for ``n`` samples from the driver channels of ``exog``."""
        if not self.drivers:
            return np.zeros((n, 0))
        channels = as_channels(exog, [d.channel for d in self.drivers], n)
        return np.column_stack([d.values(channels[d.channel]) for d in self.drivers])

    def summary(self) -> str:
        """Return a plain-text table of the states and drivers."""
        lines = [f"FOS filter model: {self.n_train} samples at {self.fs:g} Hz, blocks of "
                 f"{self.block_s:g} s",
                 f"  mu                {self.mu:.6g}",
                 f"  white             N = {self.white_density:.4g} /sqrt(s) "
                 f"(variance {self.white_variance:.4g} per sample)"]
        for c in self.components:
            if c.kind == "random walk":
                lines.append(f"  random walk       K = {math.sqrt(c.variance):.4g} /sqrt(s)"
                             f"   reference weight {c.fos_weight:+.3f}")
            else:
                lines.append(f"  {c.name:<17} sigma = {math.sqrt(c.variance):.4g}"
                             f"   FOS weight {c.fos_weight:+.3f}")
        lines += [f"  driver {d.name:<20} {d.coef:+.5g} per unit" for d in self.drivers]
        return "\n".join(lines)


# -- the steps of the fit ------------------------------------------------------------------


def _default_taus(ref_blocks: float) -> np.ndarray:
    count = max(0, int(math.floor(math.log2(ref_blocks / _FIRST_LEVEL_BLOCKS))))
    return _FIRST_LEVEL_BLOCKS * 2.0 ** np.arange(count)


def _select_levels(blocks: np.ndarray, taus: np.ndarray, ref_blocks: float, max_levels: int,
                   stop: str) -> tuple[np.ndarray, np.ndarray]:
    """FOS on the departures from the reference level; the selected taus' indices, weights."""
    if not len(taus) or max_levels < 1:
        return np.zeros(0, dtype=int), np.zeros(0)
    burn = int(math.ceil(ref_blocks))
    ref = level_series(blocks, ref_blocks, 1.0)
    levels = np.column_stack([level_series(blocks, t, 1.0) for t in taus])
    target = (blocks - ref)[burn:]
    X = (levels - ref[:, None])[burn:]
    res = fos(X, target, max_terms=max_levels, stop=stop, fit_intercept=False)
    order = np.argsort(taus[res.support])
    return res.support[order], res.coef[order]


def _select_drivers(y: np.ndarray, channels: Mapping[str, np.ndarray]) -> tuple[DriverTerm, ...]:
    """Drivers FOS selects on differences of block means and the held-out third confirms."""
    m = len(y) // DRIVER_BLOCKS
    if m < 1:
        return ()
    forms = []
    for name, u in channels.items():
        centre = float(np.mean(u))
        for power in (1, 2):
            offset = float(np.mean((u - centre) ** power)) if power > 1 else 0.0
            forms.append(DriverTerm(name, power, centre, offset, 0.0))

    def diff_blocks(x: np.ndarray) -> np.ndarray:
        return np.diff(x[: DRIVER_BLOCKS * m].reshape(DRIVER_BLOCKS, m).mean(axis=1))

    dy = diff_blocks(y)
    X = np.column_stack([diff_blocks(f.values(channels[f.channel])) for f in forms])
    usable = X.std(axis=0) > 0
    if not usable.any():
        return ()
    # every third difference is held out: the increments of a wander are nearly independent,
    # and a last third that falls on a hold of the temperature could not judge a driver
    held_out = np.arange(len(dy)) % HELD_OUT_EVERY == HELD_OUT_EVERY - 1
    fit_on = ~held_out
    res = fos(X[fit_on][:, usable], dy[fit_on], stop="bic", max_terms=2, fit_intercept=False)
    if not res.n_terms:
        return ()
    cols = np.flatnonzero(usable)[res.support]
    held = dy[held_out] - X[held_out][:, cols] @ res.coef
    if np.mean(held**2) >= np.mean(dy[held_out] ** 2):
        return ()
    coef, *_ = np.linalg.lstsq(X[:, cols], dy, rcond=None)
    return tuple(DriverTerm(forms[c].channel, forms[c].power, forms[c].centre, forms[c].offset,
                            float(b)) for c, b in zip(cols, coef))


def _max_likelihood(blocks: np.ndarray, taus: np.ndarray) -> tuple[float, np.ndarray, float]:
    """Maximum-likelihood variances of white + Gauss-Markov(taus) + random walk on the blocks.

    Returns the white variance of a block, each Gauss-Markov's stationary variance and the
    random walk's variance per block.
    """
    from statsmodels.tools.sm_exceptions import ConvergenceWarning

    model = _BlockModel(blocks, np.exp(-1.0 / taus))
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", ConvergenceWarning)
        warnings.simplefilter("ignore", RuntimeWarning)
        fitted = model.fit(disp=False, maxiter=200)
    params = np.asarray(fitted.params, dtype=float)
    return float(params[0]), params[1:-1].copy(), float(params[-1])


def _block_model_class() -> type:
    from statsmodels.tsa.statespace.mlemodel import MLEModel

    class BlockModel(MLEModel):
        """White + first-order Gauss-Markov states + random walk, observed as their sum."""

        def __init__(self, endog: np.ndarray, phis: np.ndarray) -> None:
            k = len(phis) + 1
            super().__init__(endog, k_states=k, k_posdef=k)
            self.phis = phis
            self.ssm.initialize_approximate_diffuse(10.0 * float(np.var(endog)) + 1e-30)
            self["design"] = np.ones((1, k))
            self["transition"] = np.diag(np.r_[phis, 1.0])
            self["selection"] = np.eye(k)

        @property
        def param_names(self) -> list[str]:
            return ["white", *(f"gm{i}" for i in range(len(self.phis))), "random walk"]

        @property
        def start_params(self) -> np.ndarray:
            v = float(np.var(self.endog))
            d = float(np.var(np.diff(self.endog[:, 0]))) / 2.0
            gm = [max(v - d, 0.1 * v) / max(len(self.phis), 1)] * len(self.phis)
            return np.r_[d, gm, v / len(self.endog)]

        def transform_params(self, unconstrained: np.ndarray) -> np.ndarray:
            return np.asarray(unconstrained) ** 2

        def untransform_params(self, constrained: np.ndarray) -> np.ndarray:
            return np.sqrt(np.asarray(constrained))

        def update(self, params: np.ndarray, **kwargs: object) -> None:
            params = super().update(params, **kwargs)
            self["obs_cov", 0, 0] = params[0]
            # a Gauss-Markov's driving variance from its stationary one
            self["state_cov"] = np.diag(np.r_[params[1:-1] * (1.0 - self.phis**2),
                                              params[-1]])

    return BlockModel


def _BlockModel(blocks: np.ndarray, phis: np.ndarray):  # noqa: N802 - builds the class lazily
    return _block_model_class()(blocks, phis)


def _check_bounded(phi: np.ndarray) -> None:
    rho = float(np.max(np.abs(np.linalg.eigvals(phi)), initial=0.0))
    if rho > 1.0 + 1e-12:
        raise InputError(f"the transition grows (largest |eigenvalue| {rho:.6g} > 1)")

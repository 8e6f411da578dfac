"""Fitted error models as discrete state-space shaping filters for a navigation Kalman filter.

A fitted :class:`~fosmodel.models.baselines.ARModel`,
:class:`~fosmodel.models.baselines.GaussMarkovModel` or linear
:class:`~fosmodel.models.model.FOSModel` becomes the companion-form shaping filter that
augments a Kalman filter error state (Park 2004, eqs. 5.6-5.7)::

    x[n] = Phi x[n-1] + B u[n] + G w[n],    y[n] = H x[n] + D u[n] + mu,    var(w) = Q,

with the state ``x[n] = [y[n] - mu, y[n-1] - mu, ..., y[n-p+1] - mu]`` (``p`` the largest
output lag the model uses, at least 1; unused lags of a sparse model are zeros in the first
row of ``Phi``), ``mu`` the training mean and ``Q`` the model's innovation variance.
``Q`` is the covariance of the driving noise ``w``; the state's own noise covariance is
``G Q G'`` (:meth:`StateSpace.process_covariance`), what a filter adds to ``P`` at each step.

A model with local levels (:mod:`fosmodel.core.levels`) has one more state per level,
``level@<tau>s[n+1] = (1 - a) level[n] + a (y[n] - mu)``: the level the next sample is
predicted from, updated by the newest output.  Its rows of ``Phi``, ``B`` and ``G`` are
``(1 - a)`` on itself plus ``a`` times the output's row, so the driving noise reaches the
level through the output, as it does in the model.

Exogenous inputs enter through ``B``: the state carries the output history only, and the
caller supplies ``u[n]``, the *raw* (uncentred) values named by ``input_names``: ``"1"``
(the constant; a FOS model's intercept ``a0`` and the centring offsets of its channels sit
in its column of ``B``, so predictions equal :meth:`FOSModel.predict` exactly),
``"temp[n-0]"``, ``"temp[n-2]"`` (the lags the model uses) and user columns by name.
:meth:`StateSpace.input_matrix` builds ``u`` from the channels of a record, the constant and
every derived input (``t@s``, ``cos@0.188Hz``, ``exp(-t/413.66s)``, ``temp_c_fast20s``, their
lags; :mod:`fosmodel.core.derived`, whose :func:`~fosmodel.core.derived.describe` gives each
one's definition and unit) with it.  Time counts from the first sample of the record the
model was fitted on; ``start`` says where the samples filtered begin in it.

A FOS model with a compensation ``c = sum_j w_j col_j`` (a known function of its drivers,
:mod:`fosmodel.models.compensation`) models ``y - c``: its state is that of ``y - c`` and the
compensation is the feedthrough ``D u``, ``D`` holding the weights ``w_j`` in the columns of
``u`` that hold ``col_j``.

A FOS model with any term of degree 2 or more (products of output lags, output times input,
powers) becomes a :class:`NonlinearStateSpace` for an extended Kalman filter: the same state
and inputs, the transition ``f(x, u)`` and its analytic Jacobian.

References
----------
.. [1] M. Park, "Error Analysis and Stochastic Modeling of MEMS based Inertial Sensors for Land
   Vehicle Navigation Applications", M.Sc. thesis, UCGE Report 20194, Department of
   Geomatics Engineering, University of Calgary, 2004.
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike
from scipy.linalg import solve_discrete_lyapunov

from ..core.candidates import OUTPUT, Term
from ..core.derived import channels_read, derive, is_derived
from ..core.exceptions import InputError
from ..core.levels import checked_level_tau, level_gain, smooth_after
from ..core.validation import as_channels, as_signal, check_fitted
from ..models.baselines import ARModel, GaussMarkovModel
from ..models.model import FOSModel

CONSTANT = "1"


@dataclass(frozen=True, kw_only=True, eq=False)
class _ShapingFilter(ABC):
    """What the linear and the nonlinear shaping filters share: state, output and noise."""

    G: np.ndarray
    H: np.ndarray
    Q: np.ndarray
    mu: float
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    level_gains: np.ndarray = field(default_factory=lambda: np.zeros(0))
    D: np.ndarray = field(default_factory=lambda: np.zeros((0, 0)))
    rate: float | None = None
    channel_means: Mapping[str, float] = field(default_factory=dict)

    def __post_init__(self) -> None:
        if self.D.size == 0:  # no feedthrough: zeros of the outputs' and inputs' shape
            object.__setattr__(self, "D", np.zeros((self.H.shape[0], self.n_inputs)))
        if self.D.shape != (self.H.shape[0], self.n_inputs):
            raise InputError(f"D must be {self.H.shape[0]} x {self.n_inputs} (outputs x "
                             f"inputs), got {self.D.shape}")

    def process_covariance(self) -> np.ndarray:
        """``G Q G'``: the covariance the driving noise adds to the state at each step.

        ``Q`` is the covariance of the driving noise ``w`` (``r x r``); a filter written
        with the state's own noise (``x[n] = Phi x[n-1] + B u[n] + v[n]``) takes this as its
        ``Q``.
        """
        return self.G @ self.Q @ self.G.T

    @property
    def n_states(self) -> int:
        """``p``, the length of the state."""
        return len(self.state_names)

    @property
    def n_inputs(self) -> int:
        """``m``, the length of the input vector ``u``."""
        return len(self.input_names)

    def _inputs(self, u: ArrayLike | None) -> np.ndarray:
        if u is None and self.n_inputs == 0:
            return np.zeros(0)
        arr = np.asarray(u if u is not None else [], dtype=float).ravel()
        if arr.shape != (self.n_inputs,):
            raise InputError(f"u must hold the {self.n_inputs} input(s) "
                             f"{', '.join(self.input_names) or '(none)'}; got {arr.size} value(s)")
        return arr

    def _state(self, x: ArrayLike) -> np.ndarray:
        arr = np.asarray(x, dtype=float).ravel()
        if arr.shape != (self.n_states,):
            raise InputError(f"the state has {self.n_states} entries "
                             f"({', '.join(self.state_names)}); got {arr.size}")
        return arr

    def _drive(self, w: ArrayLike | None) -> np.ndarray:
        """Return ``G w`` for a driving noise ``w`` of ``r`` entries (a scalar when ``r`` is 1).

        Zero when ``w`` is None.
        """
        if w is None:
            return np.zeros(self.n_states)
        arr = np.asarray(w, dtype=float).ravel()
        if arr.shape != (self.G.shape[1],):
            raise InputError(f"the driving noise has {self.G.shape[1]} entries; got {arr.size}")
        return self.G @ arr

    @abstractmethod
    def step(self, x: ArrayLike, u: ArrayLike | None = None,
             w: ArrayLike | None = None) -> np.ndarray:
        """Return the next state from ``x`` with the inputs ``u`` and the driving noise ``w``."""

    def predict_measurement(self, x: ArrayLike, u: ArrayLike | None = None) -> float:
        """Return the modelled output ``H x + D u + mu`` of the state ``x`` (the first output's).

        ``u`` may be omitted without a feedthrough.
        """
        return float(self.H[0] @ self._state(x) + self._through(u)) + self.mu

    def _through(self, u: ArrayLike | None) -> float:
        """``D[0] u``: zero without a feedthrough, when ``u`` may be omitted."""
        if u is None and not np.any(self.D[0]):
            return 0.0
        return float(self.D[0] @ self._inputs(u))

    @property
    def n_lags(self) -> int:
        """States that hold past outputs (the others are levels)."""
        return self.n_states - len(self.level_gains)

    def state_from(self, y_past: ArrayLike, inputs: ArrayLike | None = None) -> np.ndarray:
        """Return the state at the last sample of ``y_past``.

        That is its last ``n_lags`` samples, centred, and the levels after it (the
        exponentially weighted means of all of it), of the output less its feedthrough
        ``D u`` (the compensation, when there is one).

        Parameters
        ----------
        y_past : array-like
            The output up to the sample the state is wanted at.
        inputs : array-like of shape (len(y_past), n_inputs), optional
            ``u`` of those samples (:meth:`input_matrix`); needed with a feedthrough.

        Raises
        ------
        InputError
            Fewer than ``n_lags`` samples, or a feedthrough without its inputs.
        """
        arr = as_signal(y_past, "y_past")
        if np.any(self.D[0] != 0.0):
            if inputs is None:
                raise InputError("this filter's output has a feedthrough D u (inputs "
                                 + ", ".join(n for n, d in zip(self.input_names, self.D[0])
                                             if d != 0.0)
                                 + "): state_from needs the inputs of y_past")
            u = np.asarray(inputs, dtype=float).reshape(len(arr), self.n_inputs)
            arr = arr - u @ self.D[0]
        p = self.n_lags
        if len(arr) < max(p, 1):
            raise InputError(f"y_past has {len(arr)} samples; the state needs {max(p, 1)}")
        levels = [smooth_after(arr - self.mu, a) for a in self.level_gains]
        return np.r_[arr[::-1][:p] - self.mu, levels]

    def input_matrix(self, exog: Mapping[str, ArrayLike] | None, n_samples: int,
                     start: int = 0) -> np.ndarray:
        """Return the inputs ``u[n]`` for ``n = 0 .. n_samples-1`` from a record's channels.

        Every input :attr:`input_names` lists is built: the constant ``"1"`` (ones), a
        channel or a user column given in ``exog`` as it is, a derived input that is not
        given (``t@s``, ``cos@0.188Hz``, ``exp(-t/413.66s)``, ``temp_c_fast20s``, ...,
        :mod:`fosmodel.core.derived`) from the channels it reads, and each input's lag.

        Parameters
        ----------
        exog : dict or DataFrame, optional
            The channels (and any user column) over the ``n_samples`` filtered, from the
            first on.
        n_samples : int
            Samples filtered.
        start : int
            Where the first of them lies in the record the model was fitted on, whose first
            sample is time zero: the functions of time are those of ``t = (start + n) /
            rate`` (a filter run on the second half of a record gives ``start`` the first
            half's length).  A derived input that reads a channel (a lag, a fast part)
            starts its memory at the first sample given.

        Returns
        -------
        ndarray of shape (n_samples, n_inputs)
            Row ``n`` is ``u[n]``; NaN where a lag reaches before the samples given.

        Raises
        ------
        InputError
            A channel missing or of another length, a derived input without the filter's
            rate, or a column ``"1"`` in ``exog`` that is not all ones (the constant input is
            built, never read).
        """
        given = {} if exog is None else {str(k): exog[k] for k in exog.keys()}
        if CONSTANT in given and not np.all(np.asarray(given[CONSTANT], dtype=float) == 1.0):
            raise InputError(f"input {CONSTANT!r} is the constant 1 (the intercept and the "
                             "centring offsets sit in its column of B); exog's column "
                             f"{CONSTANT!r} is not all ones")
        factors = {name: () if name == CONSTANT else Term.parse(name).factors
                   for name in self.input_names}
        names = sorted({f[0][0] for f in factors.values() if f})
        read = [ch for ch in names if ch in given or not is_derived(ch)]
        columns = as_channels(given, read, n_samples)
        derived = [ch for ch in names if ch not in read]
        if derived and self.rate is None:
            raise InputError(f"input {derived[0]!r} is derived from time or a channel: building "
                             "it needs the filter's rate (rate=...)")
        source = as_channels(given, channels_read(derived), n_samples)
        for ch in derived:
            assert self.rate is not None
            columns[ch] = derive(ch, n_samples, self.rate, source, self.channel_means, start)
        out = np.ones((n_samples, self.n_inputs))
        for j, factor in enumerate(factors.values()):
            if factor:
                ch, lag = factor[0]
                out[:, j] = np.r_[np.full(lag or 0, np.nan), columns[ch]][:n_samples]
        return out

    def simulate(
        self, n_steps: int, x0: ArrayLike | None = None, inputs: ArrayLike | None = None,
        noise: ArrayLike | None = None,
    ) -> np.ndarray:
        """Run the filter for ``n_steps`` samples after the state ``x0``.

        Parameters
        ----------
        n_steps : int
            Samples to simulate.
        x0 : array-like, optional
            State at the sample before the run (e.g. :meth:`state_from`); zeros (the mean)
            by default.
        inputs : array-like of shape (n_steps, n_inputs), optional
            ``u`` of each simulated sample; needed when the filter has inputs.
        noise : array-like of shape (n_steps,) or (n_steps, r), optional
            Driving noise ``w`` of each sample (one column per column of ``G``); zero by
            default.

        Returns
        -------
        ndarray of shape (n_steps,)
            The output ``y = H x + mu`` of the simulated samples (the first output's).
        """
        x = np.zeros(self.n_states) if x0 is None else self._state(x0)
        w = np.zeros((n_steps, self.G.shape[1])) if noise is None else self._noise(noise)
        u = np.zeros((n_steps, 0)) if inputs is None else np.asarray(inputs, dtype=float)
        if len(w) != n_steps or u.shape[0] != n_steps:
            raise InputError(f"noise and inputs need {n_steps} rows each, got {len(w)} and "
                             f"{u.shape[0]}")
        out = np.empty(n_steps)
        for k in range(n_steps):
            uk = u[k] if self.n_inputs else None
            x = self.step(x, uk, w[k])
            out[k] = self.H[0] @ x + self._through(uk)
        return out + self.mu

    def _noise(self, noise: ArrayLike) -> np.ndarray:
        """Driving noise as rows of ``r`` entries: a signal when ``r`` is 1, else a matrix."""
        r = self.G.shape[1]
        if r == 1:
            return as_signal(noise, "noise")[:, None]
        arr = np.asarray(noise, dtype=float)
        if arr.ndim != 2 or arr.shape[1] != r or not np.isfinite(arr).all():
            raise InputError(f"noise must be a finite (n_steps, {r}) array, got shape "
                             f"{arr.shape}")
        return arr

    def _common_dict(self) -> dict:
        return {
            "G": self.G.tolist(), "H": self.H.tolist(), "Q": self.Q.tolist(),
            "mu": float(self.mu), "state_names": list(self.state_names),
            "input_names": list(self.input_names), "level_gains": self.level_gains.tolist(),
            "D": self.D.tolist(), "rate": self.rate, "channel_means": dict(self.channel_means),
        }


@dataclass(frozen=True, kw_only=True, eq=False)
class StateSpace(_ShapingFilter):
    """Linear shaping filter ``x[n] = Phi x[n-1] + B u[n] + G w[n]``, ``y = H x + D u + mu``.

    Attributes
    ----------
    Phi : ndarray of shape (p, p)
        Companion matrix: the AR weights in the first row, ones below the diagonal.
    G : ndarray of shape (p, r)
        Noise input: ``[1, 0, ..., 0]'`` (``r = 1``) for the fitted models;
        :mod:`fosmodel.filter.allan_statespace` drives each state by its own noise.
    B : ndarray of shape (p, m)
        Input matrix (first row only); ``m = 0`` for AR and Gauss-Markov models.
    H : ndarray of shape (d, p)
        ``[1, 0, ..., 0]`` (``d = 1``): the output deviation is the first state; a sum of
        states, one row per axis, in :mod:`fosmodel.filter.allan_statespace`.
    Q : ndarray of shape (r, r)
        Covariance of the driving noise ``w`` (the fitted model's innovation variance); the
        state's is ``G Q G'`` (:meth:`process_covariance`).
    mu : float
        Mean of the output; the state holds deviations from it.
    state_names, input_names : tuple of str
        ``("y[n]", "y[n-1]", ...)`` and the inputs ``u`` (see the module docstring).
    D : ndarray of shape (d, m)
        Feedthrough of the inputs to the output: a compensation's weights; zeros without
        one (the default).
    rate : float or None
        Sample rate in Hz (needed to build derived inputs).
    channel_means : dict of str to float
        Training means of the channels, for the derived inputs that centre one (``sq(ch)``).
    """

    Phi: np.ndarray
    B: np.ndarray

    def step(self, x: ArrayLike, u: ArrayLike | None = None,
             w: ArrayLike | None = None) -> np.ndarray:
        """Return the next state ``Phi x + B u + G w``.

        ``u`` may be omitted without inputs; ``w`` has one entry per column of ``G``, zero
        by default.
        """
        return self.Phi @ self._state(x) + self.B @ self._inputs(u) + self._drive(w)

    def stationary_covariance(self) -> np.ndarray:
        """``P`` with ``P = Phi P Phi' + G Q G'``: the state covariance of the stationary process.

        Raises
        ------
        InputError
            The filter is unstable (no stationary covariance).
        """
        rho = float(np.max(np.abs(np.linalg.eigvals(self.Phi))))
        if rho >= 1.0:
            raise InputError(f"the state space is unstable (largest |eigenvalue| {rho:.6g}); "
                             "it has no stationary covariance")
        return solve_discrete_lyapunov(self.Phi, self.G @ self.Q @ self.G.T)

    def to_dict(self) -> dict:
        """JSON-serialisable matrices and names."""
        return {"kind": "linear", "Phi": self.Phi.tolist(), "B": self.B.tolist(),
                **self._common_dict()}


@dataclass(frozen=True, kw_only=True, eq=False)
class NonlinearStateSpace(_ShapingFilter):
    """Shaping filter ``x[n] = f(x[n-1], u[n]) + G w[n]`` of a nonlinear FOS model, for an EKF.

    ``f`` shifts the state and puts the model's expansion in its first entry: the sum of
    ``coef[t]`` times the product of ``z[i]`` over ``i`` in ``factors[t]``, where
    ``z = [x, u - input_offsets]`` (the state, then the inputs centred on their training
    means; the constant ``"1"`` has offset 0, so the intercept is a term on it).

    Attributes
    ----------
    coef : ndarray of shape (T,)
        Weights of the terms, the intercept first.
    factors : tuple of tuple of int
        Indices into ``z`` of each term's factors.
    term_names : tuple of str
        The terms, ``"1"`` for the intercept.
    input_offsets : ndarray of shape (m,)
        Centring offsets of the inputs.
    G, H, Q, mu, state_names, input_names
        As in :class:`StateSpace`.
    """

    coef: np.ndarray
    factors: tuple[tuple[int, ...], ...]
    term_names: tuple[str, ...]
    input_offsets: np.ndarray

    def _z(self, x: ArrayLike, u: ArrayLike | None) -> tuple[np.ndarray, np.ndarray]:
        state = self._state(x)
        return state, np.r_[state, self._inputs(u) - self.input_offsets]

    def f(self, x: ArrayLike, u: ArrayLike | None = None) -> np.ndarray:
        """Return the noise-free next state."""
        state, z = self._z(x, u)
        value = sum(c * np.prod(z[list(idx)]) for c, idx in zip(self.coef, self.factors))
        p, a = self.n_lags, self.level_gains
        return np.r_[value, state[: p - 1], (1.0 - a) * state[p:] + a * value]

    def jacobian(self, x: ArrayLike, u: ArrayLike | None = None) -> np.ndarray:
        """``df/dx`` at ``(x, u)``: product rule on each term, then the shift and the levels."""
        _, z = self._z(x, u)
        n, p = self.n_states, self.n_lags
        jac = np.zeros((n, n))
        jac[1:p, : p - 1] = np.eye(p - 1)
        for c, idx in zip(self.coef, self.factors):
            for k, i in enumerate(idx):
                if i < n:
                    jac[0, i] += c * np.prod(z[list(idx[:k] + idx[k + 1:])])
        _level_rows(jac, p, self.level_gains)
        return jac

    def step(self, x: ArrayLike, u: ArrayLike | None = None,
             w: ArrayLike | None = None) -> np.ndarray:
        """Return the next state ``f(x, u) + G w`` (``w`` zero by default)."""
        return self.f(x, u) + self._drive(w)

    def to_dict(self) -> dict:
        """JSON-serialisable terms, offsets, matrices and names."""
        terms = [{"name": n, "coef": float(c), "factors": list(i)}
                 for n, c, i in zip(self.term_names, self.coef, self.factors)]
        return {"kind": "nonlinear", "terms": terms,
                "input_offsets": self.input_offsets.tolist(), **self._common_dict()}


# -- export -------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Expansion:
    """A fitted model as ``y[n] - mu = a0 + sum_t c_t P_t + e``, ``var(e) = q``.

    ``intercept`` is None for the AR baselines, which have no constant (and no inputs).
    """

    mu: float
    q: float
    intercept: float | None
    terms: tuple[tuple[float, Term], ...]
    offsets: Mapping[str, float]
    levels: tuple[tuple[str, float], ...] = ()  # (name, gain a) of each level state
    compensation: Mapping[str, float] = field(default_factory=dict)  # feedthrough weights
    rate: float | None = None

    @property
    def n_lags(self) -> int:
        lags = [lag for _, t in self.terms for ch, lag in t.factors
                if ch == OUTPUT and lag is not None]
        return max(lags, default=1)

    @property
    def n_states(self) -> int:
        return self.n_lags + len(self.levels)

    def state_index(self, factor: tuple[str, int | None]) -> int | None:
        """Return the state a factor reads (None for an input)."""
        ch, lag = factor
        if ch == OUTPUT and lag is not None:
            return lag - 1
        names = [name for name, _ in self.levels]
        return self.n_lags + names.index(ch) if ch in names else None

    @property
    def inputs(self) -> list[tuple[str, int | None]]:
        """The distinct factors that are not states, and the compensation's columns, sorted."""
        found = {f for _, t in self.terms for f in t.factors if self.state_index(f) is None}
        found |= {(name, None) for name in self.compensation}
        return sorted(found, key=lambda f: (f[0], f[1] is None, f[1] or 0))

    def feedthrough(self) -> np.ndarray:
        """``D``: the compensation's weights in the columns of ``u`` that hold its columns."""
        names, shift = self.input_names, len(self.input_names) - len(self.inputs)
        d = np.zeros((1, len(names)))
        for name, w in self.compensation.items():
            d[0, shift + self.inputs.index((name, None))] = w
        return d

    @property
    def channel_means(self) -> dict[str, float]:
        return {k: float(v) for k, v in self.offsets.items() if k != OUTPUT}

    @property
    def input_names(self) -> tuple[str, ...]:
        names = [Term((f,)).name for f in self.inputs]
        return tuple(names if self.intercept is None else [CONSTANT, *names])


def _expansion(model: object) -> _Expansion:
    """Return the expansion of a fitted AR, Gauss-Markov or FOS model; InputError otherwise."""
    if isinstance(model, (ARModel, GaussMarkovModel)):
        check_fitted(model, "coef_")
        terms = tuple((float(c), Term(((OUTPUT, k),))) for k, c in enumerate(model.coef_, 1))
        return _Expansion(model.mean_, model.sigma2_, None, terms, {},
                          rate=getattr(model, "rate", None))
    if isinstance(model, FOSModel):
        check_fitted(model, "terms_")
        q = float(model.mse_path_[-1]) if len(model.mse_path_) else float(model.mse_null_)
        terms = tuple((float(c), Term.parse(n)) for n, c in zip(model.terms_, model.coef_))
        used = [name for name in model.spec_.level_names
                if any(f[0] == name for _, t in terms for f in t.factors)]
        levels: tuple[tuple[str, float], ...] = ()
        if used:
            rate = model.rate
            if rate is None:
                raise InputError("a model with levels needs its sample rate (rate=...)")
            levels = tuple((name, level_gain(checked_level_tau(name), rate)) for name in used)
        return _Expansion(model.offsets_[OUTPUT], q, float(model.intercept_), terms,
                          dict(model.offsets_), levels, dict(model.compensation or {}),
                          model.rate)
    raise InputError(f"cannot export a {type(model).__name__}: a state space is built from a "
                     "fitted ARModel, GaussMarkovModel or FOSModel")


def _output_matrices(ex: _Expansion) -> dict:
    n, p = ex.n_states, ex.n_lags
    e1 = np.eye(n)[:, :1]
    gains = np.array([a for _, a in ex.levels])
    g = e1.copy()
    g[p:, 0] = gains
    names = [f"y[n-{k}]" if k else "y[n]" for k in range(p)]
    names += [f"{name}[n+1]" for name, _ in ex.levels]
    return {"G": g, "H": e1.T.copy(), "Q": np.array([[ex.q]]), "state_names": tuple(names),
            "level_gains": gains, "D": ex.feedthrough(), "rate": ex.rate,
            "channel_means": ex.channel_means}


def _level_rows(matrix: np.ndarray, p: int, gains: np.ndarray) -> None:
    """Fill the level rows of a transition (or input) matrix whose first row is the output's.

    A level's row is ``(1 - a)`` on the level itself plus ``a`` times the output row.
    """
    for j, a in enumerate(gains):
        row = a * matrix[0]
        if matrix.shape[0] == matrix.shape[1]:
            row[p + j] += 1.0 - a
        matrix[p + j] = row


def to_state_space(model: ARModel | GaussMarkovModel | FOSModel) -> StateSpace:
    """Build the linear companion-form shaping filter of a fitted model.

    Parameters
    ----------
    model : ARModel, GaussMarkovModel or FOSModel
        Fitted; a FOS model must have degree-1 terms only.  A Gauss-Markov model gives the
        one-state filter ``Phi = [[exp(-beta/rate)]]``.  A FOS model's compensation (a
        temperature's, say) is the feedthrough ``D u`` (module docstring); its levels are
        states.

    Returns
    -------
    StateSpace

    Raises
    ------
    InputError
        Not a fitted model of these kinds, or a FOS model with nonlinear terms (use
        :func:`to_nonlinear_state_space` for those).
    """
    ex = _expansion(model)
    nonlinear = [t.name for _, t in ex.terms if t.degree > 1]
    if nonlinear:
        raise InputError(f"the FOS model has nonlinear term(s) {', '.join(nonlinear)}, which "
                         "a linear state space cannot carry; use to_nonlinear_state_space() "
                         "for an extended Kalman filter")
    n, p, inputs, names = ex.n_states, ex.n_lags, ex.inputs, ex.input_names
    shift = len(names) - len(inputs)  # 1 with the constant input first
    phi, b = np.zeros((n, n)), np.zeros((n, len(names)))
    phi[1:p, : p - 1] = np.eye(p - 1)
    if ex.intercept is not None:
        b[0, 0] = ex.intercept
    for c, term in ex.terms:
        factor = term.factors[0]
        state = ex.state_index(factor)
        if state is not None:
            phi[0, state] += c
        else:
            b[0, shift + inputs.index(factor)] += c
            b[0, 0] -= c * ex.offsets[factor[0]]
    outputs = _output_matrices(ex)
    _level_rows(phi, p, outputs["level_gains"])
    _level_rows(b, p, outputs["level_gains"])
    return StateSpace(Phi=phi, B=b, mu=float(ex.mu), input_names=names, **outputs)


def to_nonlinear_state_space(
    model: ARModel | GaussMarkovModel | FOSModel,
) -> NonlinearStateSpace:
    """Build the shaping filter ``f(x, u)`` of any fitted model, for an extended Kalman filter.

    Parameters
    ----------
    model : ARModel, GaussMarkovModel or FOSModel
        Fitted; any terms (linear ones give the same transition as :func:`to_state_space`).

    Returns
    -------
    NonlinearStateSpace

    Raises
    ------
    InputError
        Not a fitted model of these kinds.
    """
    ex = _expansion(model)
    n, inputs, names = ex.n_states, ex.inputs, ex.input_names
    shift = len(names) - len(inputs)

    def index(factor: tuple[str, int | None]) -> int:
        state = ex.state_index(factor)
        return n + shift + inputs.index(factor) if state is None else state

    terms = [(c, tuple(index(f) for f in t.factors), t.name) for c, t in ex.terms]
    if ex.intercept is not None:
        terms.insert(0, (ex.intercept, (n,), CONSTANT))
    offsets = [0.0] * shift + [ex.offsets.get(ch, 0.0) for ch, _ in inputs]
    return NonlinearStateSpace(
        coef=np.array([c for c, _, _ in terms]), factors=tuple(i for _, i, _ in terms),
        term_names=tuple(name for _, _, name in terms), input_offsets=np.array(offsets),
        mu=float(ex.mu), input_names=names, **_output_matrices(ex))


#: Standard gravity in m/s^2: a tilt error ``theta`` reads as ``g theta`` of horizontal force.
STANDARD_GRAVITY = 9.80665
#: Where an error model's mean goes in the navigation error models (``bias=``).
BIAS = ("compensated", "uncompensated")


def position_velocity_error_model(error: StateSpace, dt: float, *,
                                  bias: str = "compensated") -> StateSpace:
    """Build a 1-D position / velocity error state driven by an accelerometer error model.

    Park (2004), eq. 5.7: ``dp[k] = dp[k-1] + dt dv[k-1]``, ``dv[k] = dv[k-1] + dt da[k-1]``
    with ``da = H_e x_e`` the error model's output deviation, and the error model's own
    states below.

    Parameters
    ----------
    error : StateSpace
        The accelerometer error model (from :func:`to_state_space`, or
        :func:`fosmodel.filter.allan_statespace.allan_state_space`), in m/s^2; its first
        output ``H[0] x`` drives the velocity.
    dt : float
        Sampling interval in seconds.
    bias : {"compensated", "uncompensated"}
        Where the error model's mean ``mu`` goes.  ``"compensated"`` (the default): it is
        the calibrated bias, subtracted from the reading, and the error is the deviation
        about it.  ``"uncompensated"``: it stays in the error, ``dv`` gaining ``dt mu`` each
        step through the constant input ``"1"`` (added first when the model has none).
        A feedthrough ``D u`` (a compensation) is a function of what is measured, applied to
        the reading either way.

    Returns
    -------
    StateSpace
        States ``dp, dv`` then the error model's; measurement ``H = [1, 0, ...]``
        (position); the error model's noise, inputs and ``Q``; ``mu = 0``.
    """
    chain = np.array([[1.0, dt], [0.0, 1.0]])
    return _navigation_errors(error, chain, dt, ("dp", "dv"), "da", bias)


def tilt_error_model(error: StateSpace, dt: float, *, scale: float = 1.0,
                     gravity: float = STANDARD_GRAVITY,
                     bias: str = "compensated") -> StateSpace:
    """Build a 1-D position / velocity / tilt error state driven by a gyroscope error model.

    At rest or in slow level motion, a horizontal gyro's rate error tilts the platform and
    the tilt reads as horizontal specific force ``g theta`` (the gyro term of
    ``dv = da + f x dtheta``, the accelerometers' own error left out)::

        dp[k] = dp[k-1] + dt dv[k-1]
        dv[k] = dv[k-1] + dt g dtheta[k-1]
        dtheta[k] = dtheta[k-1] + dt scale H_e x_e[k-1]

    The sign is the convention of a tilt about the axis the position error is across (a
    positive tilt gives a positive force); flip ``gravity`` for the other one.

    Parameters
    ----------
    error : StateSpace
        The gyro error model (:func:`to_state_space` or
        :func:`~fosmodel.filter.allan_statespace.allan_state_space`); its first output drives
        the tilt.
    dt : float
        Sampling interval in seconds.
    scale : float
        Factor from the error model's unit to rad/s (``math.radians(1)`` for deg/s).
    gravity : float
        ``g`` in m/s^2.
    bias : {"compensated", "uncompensated"}
        Where the error model's mean goes (:func:`position_velocity_error_model`); an
        uncompensated mean drives the tilt.

    Returns
    -------
    StateSpace
        States ``dp, dv, dtheta`` then the error model's; measurement ``H = [1, 0, ...]``
        (position); the error model's noise, inputs and ``Q``; ``mu = 0``.

    References
    ----------
    R. Brown and P. Hwang, *Introduction to Random Signals and Applied Kalman Filtering*,
    4th ed., Wiley, 2012, ch. 9 (the tilt error of an inertial system at rest).
    """
    chain = np.array([[1.0, dt, 0.0], [0.0, 1.0, dt * gravity], [0.0, 0.0, 1.0]])
    return _navigation_errors(error, chain, dt * scale, ("dp", "dv", "dtheta"), "dw", bias)


def _navigation_errors(error: StateSpace, chain: np.ndarray, gain: float,
                       names: tuple[str, ...], prefix: str, bias: str) -> StateSpace:
    """Integrators ``chain`` whose last state gains ``gain`` times the error model's output."""
    if bias not in BIAS:
        raise InputError(f"bias must be one of {', '.join(BIAS)}, got {bias!r}")
    k, p = len(chain), error.n_states
    inputs, b_error = error.input_names, error.B
    if bias == "uncompensated" and CONSTANT not in inputs:
        inputs, b_error = (CONSTANT, *inputs), np.hstack([np.zeros((p, 1)), error.B])
    phi = np.zeros((k + p, k + p))
    phi[:k, :k] = chain
    phi[k - 1, k:] = gain * error.H[0]
    phi[k:, k:] = error.Phi
    b = np.vstack([np.zeros((k, len(inputs))), b_error])
    if bias == "uncompensated":
        b[k - 1, inputs.index(CONSTANT)] += gain * error.mu
    return StateSpace(
        Phi=phi, B=b, G=np.vstack([np.zeros((k, error.G.shape[1])), error.G]),
        H=np.eye(1, k + p), Q=error.Q.copy(), mu=0.0,
        state_names=(*names, *(f"{prefix} {n}" for n in error.state_names)),
        input_names=inputs, rate=error.rate, channel_means=dict(error.channel_means))

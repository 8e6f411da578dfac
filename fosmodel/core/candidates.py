"""Candidate functions of Fast Orthogonal Search (eq. 15 of Tamazin et al. (2013)).

A candidate is a product of *factors*.  A factor is a lagged channel value
``ch[n-k]`` (the modelled output is always the channel ``y``, lags 1..L; an
exogenous input ``x`` has lags 0..K), a local level of the output
``level@<tau>s`` (the exponentially weighted mean of ``y[n-1], y[n-2], ...``,
:mod:`fosmodel.core.levels`) or a user-given column evaluated at ``n`` (a sinusoid,
a trend, a step...).  The constant candidate has no factor.

Names are readable and parse back to the same term::

    1    y[n-1]    temp[n-0]    y[n-1]*y[n-3]    y[n-2]^2    level@20s    sin@0.5Hz

Factors are ordered canonically: ``y`` first, then the levels, other channels
alphabetically, then by lag; a repeated factor is written as a power.

References
----------
.. [1] M. J. Korenberg, "Identifying nonlinear difference equation and functional expansion
   representations: the fast orthogonal algorithm", Annals of Biomedical Engineering 16,
   123-142, 1988.
.. [2] M. Tamazin, A. Noureldin and M. J. Korenberg, "Robust Modeling of Low-Cost MEMS Sensor
   Errors in Mobile Devices Using Fast Orthogonal Search", Journal of Sensors (Hindawi),
   2013, Article ID 101820.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from itertools import combinations_with_replacement

import numpy as np

from .exceptions import InputError
from .levels import checked_level_tau, is_level, level_name, level_tau
from .validation import check_int

OUTPUT = "y"
_CHANNEL_RE = re.compile(r"^[A-Za-z_][A-Za-z0-9_]*$")
_COLUMN_RE = re.compile(r"^[A-Za-z_][^\s*^\[\]]*$")
_LAGGED_RE = re.compile(r"^(?P<ch>[A-Za-z_][A-Za-z0-9_]*)\[n-(?P<lag>\d+)\]$")
_POWER_RE = re.compile(r"^(?P<base>.+?)\^(?P<p>\d+)$")

Factor = tuple[str, "int | None"]
"""``(channel, lag)``; ``lag`` is None for a user-given column and 0 for a level."""


def _factor_key(f: Factor) -> tuple:
    ch, lag = f
    return (ch != OUTPUT, not is_level(ch), lag is None, ch, -1 if lag is None else lag)


def _factor_name(f: Factor) -> str:
    ch, lag = f
    return ch if lag is None or is_level(ch) else f"{ch}[n-{lag}]"


@dataclass(frozen=True)
class Term:
    """One candidate function: a product of factors (empty product = constant).

    Parameters
    ----------
    factors : tuple of (channel, lag)
        Canonicalised on construction; ``lag=None`` marks a user column.
    """

    factors: tuple[Factor, ...] = ()

    def __post_init__(self) -> None:
        """Sort the factors into canonical order, so that equal products compare equal."""
        object.__setattr__(self, "factors", tuple(sorted(self.factors, key=_factor_key)))

    @property
    def degree(self) -> int:
        """Number of factors (0 for the constant)."""
        return len(self.factors)

    @property
    def is_constant(self) -> bool:
        """Whether the term is the constant (the empty product)."""
        return not self.factors

    @cached_property
    def name(self) -> str:
        """The term's name: ``1``, ``y[n-1]``, ``x[n-2]^2``, ``y[n-1]*temp[n-0]``, a column."""
        if not self.factors:
            return "1"
        parts = []
        i = 0
        while i < len(self.factors):
            j = i
            while j < len(self.factors) and self.factors[j] == self.factors[i]:
                j += 1
            base = _factor_name(self.factors[i])
            parts.append(base if j - i == 1 else f"{base}^{j - i}")
            i = j
        return "*".join(parts)

    def __str__(self) -> str:
        """Return the term's :attr:`name`."""
        return self.name

    @classmethod
    def parse(cls, name: str, max_degree: int | None = None) -> Term:
        """Parse a term name written by :attr:`name`.

        Parameters
        ----------
        name : str
        max_degree : int, optional
            Refuse a product of more factors, before building it: a name read from a file
            (``y[n-1]^1000000000``) must not make a list that long.

        Raises
        ------
        InputError
            If ``name`` is not a valid term name, or a product of more than ``max_degree``
            factors.
        """
        text = name.strip()
        if text == "1":
            return cls(())
        if not text:
            raise InputError("empty term name")
        factors: list[Factor] = []
        for token in text.split("*"):
            power = 1
            m = _POWER_RE.match(token)
            if m:
                token, power = m.group("base"), int(m.group("p"))
                if power < 1:
                    raise InputError(f"bad power in term {name!r}")
            lagged = _LAGGED_RE.match(token)
            factor: Factor
            if level_tau(token) is not None:
                factor = (token, 0)
            elif lagged:
                factor = (lagged.group("ch"), int(lagged.group("lag")))
            elif _COLUMN_RE.match(token) and "[" not in token:
                factor = (token, None)
            else:
                raise InputError(f"cannot parse term {name!r} (bad factor {token!r})")
            if max_degree is not None and len(factors) + power > max_degree:
                raise InputError(f"term {name!r} is a product of more than {max_degree} "
                                 "factor(s)")
            factors.extend([factor] * power)
        return cls(tuple(factors))


@dataclass(frozen=True)
class CandidateSpec:
    """What candidate functions to generate.

    Parameters
    ----------
    max_lag : int
        L: lagged outputs ``y[n-1] .. y[n-L]``.
    degree : int
        CP: highest degree of the cross-products of the lagged factors.
    exog_lags : mapping of str to int
        K per exogenous channel: ``x[n-0] .. x[n-K]``.
    columns : sequence of str
        Names of user-given candidate columns (arrays supplied with the data).
        They enter linearly, not in cross-products.
    constant : bool
        Include the constant candidate ``1``.
    levels : sequence of float
        Time constants in seconds of the local levels ``level@<tau>s`` offered
        (rounded to the 4 significant digits of their names).  Like the lagged
        outputs they enter linearly and in cross-products.
    product_lags : int, optional
        Restrict the cross-products (degree 2 and more) to the output lags
        ``y[n-1] .. y[n-P]``; by default every lagged factor and level enters them.
    """

    max_lag: int = 10
    degree: int = 1
    exog_lags: Mapping[str, int] = field(default_factory=dict)
    columns: Sequence[str] = ()
    constant: bool = True
    levels: Sequence[float] = ()
    product_lags: int | None = None

    def __post_init__(self) -> None:
        """Store the options as plain dict and tuples, and check them.

        Raises
        ------
        InputError
            A lag, degree, product lag or level time constant out of range, a channel or
            column name that cannot be one, or ``constant`` not True or False.
        """
        object.__setattr__(self, "exog_lags", dict(self.exog_lags or {}))
        object.__setattr__(self, "columns", tuple(self.columns or ()))
        object.__setattr__(self, "levels", _level_taus(self.levels))
        check_int(self.max_lag, "max_lag", 0)
        check_int(self.degree, "degree", 1)
        if self.product_lags is not None:
            check_int(self.product_lags, "product_lags", 1)
        for ch, k in self.exog_lags.items():
            if not isinstance(ch, str) or not _CHANNEL_RE.match(ch) or ch == OUTPUT:
                raise InputError(
                    f"exogenous channel name {ch!r} must be an identifier other than {OUTPUT!r}"
                )
            check_int(k, f"lag of exogenous channel {ch!r}", 0)
        for name in self.columns:
            if not isinstance(name, str) or not _COLUMN_RE.match(name) or "[" in name:
                raise InputError(
                    f"candidate column name {name!r} must start with a letter or '_' and may not "
                    "contain spaces, '*', '^', '[' or ']'"
                )
            if name in self.exog_lags or name in (OUTPUT, "1") or is_level(name):
                raise InputError(f"candidate column name {name!r} clashes with a channel")
        if len(set(self.columns)) != len(self.columns):
            raise InputError("candidate column names must be unique")
        if not isinstance(self.constant, (bool, np.bool_)):
            raise InputError(f"constant must be True or False, got {self.constant!r}")

    @property
    def lag_window(self) -> int:
        """N0: the first sample index at which every candidate is defined.

        At least 1 with levels: ``level[0]`` is ``y[0]`` itself.
        """
        return max([self.max_lag, *self.exog_lags.values(), int(bool(self.levels))])

    @property
    def level_names(self) -> tuple[str, ...]:
        """``level@<tau>s`` of each level offered."""
        return tuple(level_name(t) for t in self.levels)

    @property
    def channels(self) -> tuple[str, ...]:
        """Signals the candidates read: ``y``, its levels, exogenous channels, then columns."""
        return (OUTPUT, *self.level_names, *self.exog_lags, *self.columns)

    def base_factors(self) -> list[Factor]:
        """Return the degree-1 lagged factors and levels, in canonical order."""
        out: list[Factor] = [(OUTPUT, lag) for lag in range(1, self.max_lag + 1)]
        out.extend((name, 0) for name in self.level_names)
        for ch in sorted(self.exog_lags):
            out.extend((ch, lag) for lag in range(self.exog_lags[ch] + 1))
        return out

    def product_factors(self) -> list[Factor]:
        """Return the factors that enter cross-products of degree 2 and more."""
        if self.product_lags is None:
            return self.base_factors()
        return [(OUTPUT, lag) for lag in range(1, min(self.product_lags, self.max_lag) + 1)]


def _level_taus(taus: Iterable[float] | None) -> tuple[float, ...]:
    """Level time constants as their names round them; positive and distinct."""
    out = []
    for tau in taus or ():
        if isinstance(tau, bool) or not isinstance(tau, (int, float, np.integer, np.floating)) \
                or not math.isfinite(tau) or tau <= 0:
            raise InputError(f"a level time constant must be a positive number of seconds, "
                             f"got {tau!r}")
        out.append(checked_level_tau(level_name(tau)))
    if len(set(out)) != len(out):
        raise InputError(f"level time constants repeat: {', '.join(map(level_name, out))}")
    return tuple(sorted(out))


def count_candidates(spec: CandidateSpec) -> int:
    """Count the candidates :func:`generate_terms` would produce, without building them.

    With B lagged factors, P of them in cross-products and degree D there are
    ``B + sum_{d=2..D} C(P+d-1, d)`` products (multisets), plus the constant and
    the user columns.
    """
    b, p = len(spec.base_factors()), len(spec.product_factors())
    products = b + sum(math.comb(p + d - 1, d) for d in range(2, spec.degree + 1))
    return int(spec.constant) + products + len(spec.columns)


def generate_terms(spec: CandidateSpec) -> list[Term]:
    """All candidate terms of ``spec``: constant, products by degree, then user columns."""
    key = (spec.max_lag, spec.degree, tuple(sorted(spec.exog_lags.items())), spec.columns,
           spec.constant, spec.levels, spec.product_lags)
    return list(_generate(*key))


@lru_cache(maxsize=32)
def _generate(max_lag: int, degree: int, exog_lags: tuple[tuple[str, int], ...],
              columns: Sequence[str], constant: bool, levels: Sequence[float],
              product_lags: int | None) -> tuple[Term, ...]:
    spec = CandidateSpec(max_lag, degree, dict(exog_lags), columns, constant, levels,
                         product_lags)
    terms = [Term(())] if constant else []
    terms.extend(Term((f,)) for f in spec.base_factors())
    for d in range(2, degree + 1):
        terms.extend(Term(c) for c in combinations_with_replacement(spec.product_factors(), d))
    terms.extend(Term(((name, None),)) for name in columns)
    return tuple(terms)


def term_names(terms: Iterable[Term]) -> list[str]:
    """Return the names of ``terms``, in order."""
    return [t.name for t in terms]


def check_terms_fit_spec(terms: Iterable[Term], spec: CandidateSpec) -> None:
    """Raise InputError if a term reads a channel or lag that ``spec`` does not provide."""
    for term in terms:
        for ch, lag in term.factors:
            if lag is None:
                ok = ch in spec.columns
            elif is_level(ch):
                ok = ch in spec.level_names and lag == 0
            elif ch == OUTPUT:
                ok = 1 <= lag <= spec.max_lag
            else:
                ok = ch in spec.exog_lags and lag <= spec.exog_lags[ch]
            if not ok:
                raise InputError(f"term {term.name!r} is outside the candidate spec")


def evaluate_terms(
    terms: Sequence[Term], signals: Mapping[str, np.ndarray], start: int
) -> np.ndarray:
    """Evaluate terms point by point for ``n = start .. N-1``.

    Parameters
    ----------
    terms : sequence of Term
    signals : mapping of channel name to 1-D array
        ``y`` and every channel or column the terms read, all of length N.
    start : int
        First sample index; must be at least every lag used.

    Returns
    -------
    ndarray of shape (N - start, len(terms))
    """
    n = len(next(iter(signals.values())))
    out = np.empty((n - start, len(terms)))
    for j, term in enumerate(terms):
        col = np.ones(n - start)
        for ch, lag in term.factors:
            col *= _window(term, signals, ch, lag, start, n)
        out[:, j] = col
    return out


def evaluate_sum(
    terms: Sequence[Term], weights: Sequence[float] | np.ndarray,
    signals: Mapping[str, np.ndarray], start: int,
) -> np.ndarray:
    """``evaluate_terms(terms, signals, start) @ weights``, without the term matrix.

    It holds a few arrays of ``N - start`` values, never the ``N x len(terms)``
    matrix: a prediction over hours of samples costs memory for one signal.
    The linear terms of one signal are one convolution (its weights by lag),
    the others are multiplied out term by term.
    """
    n = len(next(iter(signals.values())))
    total = np.zeros(n - start)
    kernels: dict[str, dict[int, float]] = {}
    for term, w in zip(terms, weights):
        if term.degree == 1:
            ch, lag = term.factors[0]
            _check_reach(term, lag or 0, start)
            by_lag = kernels.setdefault(ch, {})
            by_lag[lag or 0] = by_lag.get(lag or 0, 0.0) + float(w)
        elif term.is_constant:
            total += w
        else:
            value = np.full(n - start, float(w))
            for ch, lag in term.factors:
                value *= _window(term, signals, ch, lag, start, n)
            total += value
    for ch, by_lag in kernels.items() if n > start else ():
        kernel = np.zeros(max(by_lag) + 1)
        kernel[list(by_lag)] = list(by_lag.values())
        total += np.convolve(signals[ch], kernel)[start:n]  # sum_l w_l x[t - l]
    return total


def _check_reach(term: Term, lag: int, start: int) -> None:
    if lag > start:
        raise InputError(f"term {term.name!r} needs {lag} past samples, only {start} given")


def _window(term: Term, signals: Mapping[str, np.ndarray], ch: str, lag: int | None,
            start: int, n: int) -> np.ndarray:
    """``signals[ch][t - lag]`` for ``t = start .. n-1``."""
    lag = lag or 0
    _check_reach(term, lag, start)
    return signals[ch][start - lag : n - lag]

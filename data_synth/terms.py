"""Exact lag models of synthetic records, in fosmodel's term grammar.

Terms are :class:`fosmodel.core.candidates.Term` factor tuples (``(channel, lag)``
pairs in canonical order, the modelled signal being the channel ``"y"``).
A *term set* maps factor tuples to coefficients; :func:`exact_model` adds
up the lag representations of a record's components.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import cast

import numpy as np

from fosmodel.core.candidates import OUTPUT, Term, evaluate_sum

Factor = tuple[str, int]
Factors = tuple[Factor, ...]
TermSet = dict[Factors, float]


def evaluate(
    terms: Iterable[Mapping[str, float | str]], columns: Mapping[str, np.ndarray], target: str
) -> np.ndarray:
    """``sum(coef * term)`` over a record, ``y`` meaning the ``target`` column.

    Parameters
    ----------
    terms : iterable of {"term": str, "coef": float}
        As in the truth sidecar.
    columns : mapping of str to ndarray
        The record's columns.
    target : str
        Column that ``y`` stands for.

    Returns
    -------
    ndarray
        The prediction; NaN for the first samples, whose lags reach before the start.
    """
    entries = [(Term.parse(str(e["term"])), float(e["coef"])) for e in terms]
    signals = {OUTPUT: np.asarray(columns[target], dtype=float)}
    signals.update((ch, np.asarray(columns[ch], dtype=float))
                   for t, _ in entries for ch, _ in t.factors if ch != OUTPUT)
    first = max([lag or 0 for t, _ in entries for _, lag in t.factors] + [0])
    out = np.full(len(signals[OUTPUT]), np.nan)
    if entries:
        out[first:] = evaluate_sum([t for t, _ in entries], [c for _, c in entries], signals,
                                   first)
    else:
        out[first:] = 0.0
    return out


def add_term(terms: TermSet, factors: Iterable[Factor], coef: float) -> None:
    """Add ``coef`` to the coefficient of ``factors`` in ``terms`` (in place)."""
    # Term puts the factors in canonical order; they stay (channel, int lag) pairs
    key = cast(Factors, Term(tuple(factors)).factors)
    terms[key] = terms.get(key, 0.0) + float(coef)


def shift(factors: Factors, lag: int) -> Factors:
    """Delay every factor of a term by ``lag`` samples."""
    return tuple((channel, k + lag) for channel, k in factors)


def terms_json(terms: Mapping[Factors, float]) -> list[dict[str, float | str]]:
    """``[{"term": name, "coef": value}, ...]`` with exact-zero coefficients dropped."""
    return [{"term": Term(f).name, "coef": float(c)} for f, c in terms.items() if c != 0.0]


@dataclass(frozen=True)
class Representation:
    """Exact lag representation of one additive component ``c[n]``.

    ``c[n] = sum(coef * term) + innovation[n]`` where ``y`` factors in the terms
    refer to the component itself and the innovation is white with standard
    deviation ``innovation_std`` (0 for a deterministic component).
    """

    terms: TermSet = field(default_factory=dict)
    innovation_std: float = 0.0

    @property
    def recursive(self) -> bool:
        """True if a term has a ``y`` factor (the component feeds back on itself)."""
        return any(ch == OUTPUT for f in self.terms for ch, _ in f)

    @property
    def linear_ar(self) -> dict[int, float] | None:
        """``{lag: coef}`` if every term is a single ``y`` factor, else None."""
        if all(len(f) == 1 and f[0][0] == OUTPUT for f in self.terms):
            return {f[0][1]: c for f, c in self.terms.items()}
        return None


def exact_model(parts: Sequence[Representation | None]) -> Representation | None:
    """The exact model of a sum of components, or None if it has no finite one.

    The sum has a finite representation when every component has one and

    * no component feeds back on itself: the terms add up and the innovations
      add in variance; or
    * exactly one component is recursive and no other component is white noise
      (white noise on top of an AR process is ARMA, not a finite AR).  A linear
      AR component ``a(z)`` turns every other (exogenous) term ``x[n]`` into
      ``x[n] - sum_k a_k x[n-k]``; a nonlinear one admits no other component.
    """
    present = [p for p in parts if p is not None]
    if len(present) < len(parts):
        return None
    recursive = [p for p in present if p.recursive]
    others = [p for p in present if not p.recursive]
    exog: TermSet = {}
    for p in others:
        for f, c in p.terms.items():
            add_term(exog, f, c)
    if not recursive:
        return Representation(exog, math.sqrt(sum(p.innovation_std**2 for p in others)))
    if len(recursive) > 1 or any(p.innovation_std > 0 for p in others):
        return None
    (rec,) = recursive
    ar = rec.linear_ar
    if ar is None and exog:
        return None
    terms: TermSet = dict(rec.terms)
    for f, c in exog.items():
        add_term(terms, f, c)
        for lag, a in (ar or {}).items():
            add_term(terms, shift(f, lag), -a * c)
    return Representation({f: c for f, c in terms.items() if c != 0.0}, rec.innovation_std)

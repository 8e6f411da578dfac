"""A centred FOS expansion written in the raw signals.

With ``center=True`` a :class:`~fosmodel.models.model.FOSModel` is

    y[n] - mu_y = a_0 + sum_m a_m prod_{f in P_m} (z_f[n] - mu_f),

each factor ``z_f`` a lagged channel, a level or a user column and ``mu_f`` its
channel's training mean (a level of the output is offset by ``mu_y``, since the
level of ``y - mu_y`` is the level of ``y`` minus ``mu_y``).  Multiplying out every
product gives the same function of the raw signals as a sum of raw monomials,

    y[n] = c_0 + sum_k c_k prod_{f in M_k} z_f[n],

where a product of ``d`` centred factors spreads over the monomials of its
``2^d`` subsets of factors.  The two forms predict identically; they differ as
*model classes* when the terms are few: a raw product such as ``y[n-1]*x[n-1]``
is one raw term but, with a nonzero mean of ``x``, a centred product plus a
centred ``y[n-1]`` (and a ``x[n-1]`` with a nonzero mean of ``y``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from itertools import compress, product

import numpy as np

from ..core.candidates import OUTPUT, Term
from ..core.levels import is_level


def expand_centred(
    terms: Sequence[Term], coef: Sequence[float] | np.ndarray, intercept: float,
    offsets: Mapping[str, float],
) -> dict[Term, float]:
    """Return the weights of the raw monomials of a centred expansion.

    Parameters
    ----------
    terms : sequence of Term
        The terms of the centred expansion (the constant excluded).
    coef : sequence of float
        Their weights ``a_m``.
    intercept : float
        ``a_0``, the constant of the centred expansion.
    offsets : mapping of str to float
        ``mu`` of the output ``y`` and of every channel and column the terms read
        (zeros for an uncentred model, whose expansion comes back unchanged).

    Returns
    -------
    dict of Term to float
        The constant ``Term(())`` first, with ``mu_y`` moved over to it, then the
        monomials by degree, within a degree in the order the terms bring them.
        A monomial only an exactly zero offset would bring is left out.
    """
    weights: dict[Term, float] = {Term(()): float(intercept) + float(offsets[OUTPUT])}
    for term, a in zip(terms, np.asarray(coef, dtype=float)):
        shifts = [-_offset(factor, offsets) for factor in term.factors]
        for kept in product((True, False), repeat=term.degree):
            weight = float(a) * float(np.prod(list(compress(shifts, (not k for k in kept)))))
            if weight != 0.0 or all(kept):
                monomial = Term(tuple(compress(term.factors, kept)))
                weights[monomial] = weights.get(monomial, 0.0) + weight
    constant, *rest = weights.items()
    return dict([constant, *sorted(rest, key=lambda item: item[0].degree)])


def _offset(factor: tuple[str, int | None], offsets: Mapping[str, float]) -> float:
    """``mu`` of one factor: its channel's, or the output's for a level of the output."""
    channel = factor[0]
    return float(offsets[OUTPUT if is_level(channel) else channel])

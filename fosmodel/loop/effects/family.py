"""The candidate family: what the loop's FOS model may choose from, and its fixed part."""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from typing import Any, Protocol, cast

import numpy as np

from ..record import LoopRecord


class _Effect(Protocol):
    """What a family needs of an effect (:class:`fosmodel.loop.effects.base.Effect`)."""

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Return ``family`` with the effect's candidates added."""


@dataclass(frozen=True)
class CandidateFamily:
    """The candidates of a model, by what they read, and its compensation.

    ``exog_lags`` are the input channels with their lags (their values in ``inputs``),
    ``columns`` the user columns, ``levels`` the time constants (s) of the level
    candidates, ``product_lags`` the output lags the cross-products use, and
    ``compensation`` the fixed driver part (:mod:`fosmodel.models.compensation`), each
    column's weight, its values in ``comp_columns``, with the block (samples) and the
    block-scale level's gain its weights were fitted at (``comp_fit``,
    :mod:`fosmodel.loop.driver_forms`).  Every value spans the record.
    """

    max_lag: int
    degree: int = 1
    exog_lags: Mapping[str, int] = field(default_factory=dict)
    columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    levels: tuple[float, ...] = ()
    inputs: Mapping[str, np.ndarray] = field(default_factory=dict)
    product_lags: int | None = None
    compensation: Mapping[str, float] = field(default_factory=dict)
    comp_columns: Mapping[str, np.ndarray] = field(default_factory=dict)
    comp_fit: tuple[int, float] = (1, 0.0)

    def add(self, effect: _Effect, record: LoopRecord) -> CandidateFamily:
        """Return this family with the candidates of ``effect`` added (this one unchanged)."""
        return effect.add_to(self, record)

    def with_input(self, name: str, max_lag: int, record: LoopRecord) -> CandidateFamily:
        """Add a derived input channel (lags ``0..max_lag``), rebuilt from the record."""
        exog = {**self.exog_lags, name: max(self.exog_lags.get(name, 0), max_lag)}
        return replace(self, exog_lags=exog, inputs={**self.inputs, name: record.derive(name)})

    def with_columns(self, names: list[str], record: LoopRecord) -> CandidateFamily:
        """Add derived user columns, rebuilt from the record."""
        return replace(self, columns={**self.columns,
                                      **{name: record.derive(name) for name in names}})

    def with_levels(self, taus: tuple[float, ...]) -> CandidateFamily:
        """Add level candidates of these time constants (s)."""
        return replace(self, levels=tuple(sorted({*self.levels, *taus})))

    def with_compensation(self, forms: Mapping[str, float], record: LoopRecord,
                          fit: tuple[int, float] | None = None) -> CandidateFamily:
        """Add fixed driver columns with their weights to the compensation.

        ``fit`` is the block (samples) and gain the weights were fitted at.
        """
        weights = dict(self.compensation)
        for name, w in forms.items():
            weights[name] = weights.get(name, 0.0) + w
        return replace(self, compensation=weights, comp_fit=fit or self.comp_fit,
                       comp_columns={name: record.derive(name) for name in weights})

    def changed(self, **changes: object) -> CandidateFamily:
        """Return this family with some fields changed (the degree, the cross-products' lags)."""
        return replace(self, **cast(dict[str, Any], changes))

    def compensation_series(self) -> np.ndarray | None:
        """Return the compensation over the record, or None without one."""
        if not self.compensation:
            return None
        total = np.zeros(len(next(iter(self.comp_columns.values()))))
        for name, w in self.compensation.items():
            total += w * self.comp_columns[name]
        return total

    def arrays(self) -> dict[str, np.ndarray]:
        """Every record-long array the family's model reads, by name."""
        return {**self.inputs, **self.columns, **self.comp_columns}

"""The protocol every error source, effect and profile follows.

A source is a small frozen dataclass holding physical parameters.  It adds one
component to one channel of a record (or, for array sources, to several):

* :meth:`Source.generate` draws the component from its own generator,
* :meth:`Source.truth` describes it for the JSON sidecar,
* :meth:`Source.representation` gives its exact lag model, when it has one.

Three keyword-only fields are common to all sources: ``name`` (unique in a
record, default the kind; it also keys the source's random stream, so adding or
removing another source never changes this one's draw), ``channel`` (the column
it adds to, default the record's target) and ``declared`` (False marks an effect
the fit is not told about: the truth keeps it, the data file never names it).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, ClassVar

import numpy as np

from data_synth.terms import Representation, terms_json

_IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*\Z")


def check_column_name(name: str) -> str:
    """Return ``name`` if it may be a column: an identifier other than ``y``/``time``."""
    if not isinstance(name, str) or not _IDENTIFIER.match(name) or name in ("y", "time"):
        raise ValueError(f"bad column name {name!r}: need an identifier other than 'y' and 'time'")
    return name


def as_float_tuple(values: Any, what: str) -> tuple[float, ...]:
    """Coerce a scalar or sequence of numbers to a tuple of finite floats."""
    arr = np.atleast_1d(np.asarray(values, dtype=float))
    if arr.ndim != 1 or not np.all(np.isfinite(arr)):
        raise ValueError(f"{what} must be finite numbers, got {values!r}")
    return tuple(float(v) for v in arr)


@dataclass(frozen=True, kw_only=True)
class Source:
    """Base class: one additive component of a record channel.

    Parameters
    ----------
    name : str, optional
        Unique name in the record (default: the kind).  Also keys the random
        stream of the source.
    channel : str, optional
        Column the component adds to (default: the record's target).
    declared : bool
        False for an effect the modeller is not told about.
    """

    name: str | None = None
    channel: str | None = None
    declared: bool = True

    kind: ClassVar[str] = "source"
    #: True for a component that is one constant over the record (a bias): the truth
    #: adds it to the column's ``constants``.
    constant: ClassVar[bool] = False

    @property
    def label(self) -> str:
        """The name, or the kind if no name was given."""
        return self.name or self.kind

    @property
    def requires(self) -> tuple[str, ...]:
        """Columns that must be complete before this source can be generated."""
        return ()

    def outputs(self, target: str) -> tuple[str, ...]:
        """Columns this source adds to (one, except for array sources)."""
        return (self.channel or target,)

    def generate(
        self,
        n: int,
        rate: float,
        rng: np.random.Generator,
        inputs: Mapping[str, np.ndarray] | None = None,
    ) -> np.ndarray:
        """Draw ``n`` samples at ``rate`` Hz; shape ``(n,)`` or ``(n, len(outputs))``."""
        raise NotImplementedError

    def params(self, rate: float, units: str, out: np.ndarray) -> dict[str, Any]:
        """Physical parameters for the truth, with a ``"units"`` entry naming their units."""
        raise NotImplementedError

    def representation(self, rate: float, out: np.ndarray) -> Representation | None:
        """Exact lag model of the component, or None (function of time, heteroscedastic...)."""
        return None

    def truth(self, rate: float, units: str, out: np.ndarray) -> dict[str, Any]:
        """Ground truth of the realised component ``out`` on a channel in ``units``.

        Returns ``{"kind", "name", "declared", "params", "terms",
        "innovation_std", "component_std"}`` (``component_std`` is a list per
        column for array sources; :func:`~data_synth.record.compose` adds the
        ``channel``).  ``terms`` are the exact terms of the component alone
        (``y`` meaning the component itself for a recursive source), ``[]`` for
        white noise and ``None`` when it has no lag form.
        """
        rep = self.representation(rate, out)
        std = np.std(out, axis=0)
        return {
            "kind": self.kind,
            "name": self.label,
            "declared": self.declared,
            "params": self.params(rate, units, out),
            "terms": None if rep is None else terms_json(rep.terms),
            "innovation_std": None if rep is None else rep.innovation_std,
            "component_std": std.tolist() if std.ndim else float(std),
        }

    def need(self, inputs: Mapping[str, np.ndarray] | None, column: str, n: int) -> np.ndarray:
        """Fetch input ``column`` of length ``n`` or raise a clear error."""
        if inputs is None or column not in inputs:
            raise ValueError(f"source {self.label!r} needs the column {column!r}")
        values = np.asarray(inputs[column], dtype=float)
        if values.shape != (n,):
            raise ValueError(f"column {column!r} has shape {values.shape}, expected ({n},)")
        return values

"""What every effect kind is, and the one registry where the loop finds them.

An effect is a small frozen description of something the model lacks, as a
finding pointed to it: its own fields (a channel, a frequency, a time), the
evidence, and four things its class says:

* which findings offer it (:meth:`Effect.offered`);
* the candidates it adds to the FOS candidate set (:meth:`Effect.add_to`),
  columns named by how to rebuild them (:mod:`fosmodel.core.derived`);
* its label (:meth:`Effect.describe`) and JSON form (:meth:`Effect.to_dict`,
  :func:`effect_from_dict`);
* its acceptance rule: judged ``strict`` or not (:mod:`fosmodel.loop.judge`),
  from which origins (its ``onset_s``), the kinds it ``waits_for`` when they are
  accepted in the same round, and whether several sessions may share it (``pooled``).

A kind is one module of this package with one class under :func:`register`;
the package imports every module in it, so adding a kind touches nothing else.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, ClassVar, TypeVar

import numpy as np

from ...models.bound import BoundModel
from ..config import LoopConfig
from ..diagnose import Finding
from ..record import LoopRecord
from ..roles import Roles
from .family import CandidateFamily

#: Tests whose firing points to a slow error.
SLOW_TESTS = ("trend", "wander", "step", "allan")


@dataclass(frozen=True)
class Offer:
    """What the effects are offered from: the findings on the current model, and its setting.

    ``family`` is the current model's candidate family, ``fit`` the sample ranges it is
    fitted on, ``level_taus`` the level time constants to offer.
    """

    findings: Sequence[Finding]
    record: LoopRecord
    fit: tuple[slice, ...]
    roles: Roles
    config: LoopConfig
    family: CandidateFamily
    level_taus: tuple[float, ...]

    def fired(self, *tests: str) -> list[Finding]:
        """Return the findings of these tests that fired."""
        return [f for f in self.findings if f.fired and f.test in tests]

    @property
    def slow(self) -> list[Finding]:
        """The slow tests that fired (a trend, a wandering mean, a step, the Allan deviation)."""
        return self.fired(*SLOW_TESTS)


@dataclass(frozen=True)
class Effect:
    """One effect the model lacks.  Subclasses add their fields and say what they add.

    An effect is built by its kind's name with :func:`make_effect` (``make_effect("periodic",
    freq_hz=7.3)``) or by calling its kind's class.
    """

    kind: ClassVar[str] = ""
    #: Where it comes among the candidates of a round (lower first).
    rank: ClassVar[int] = 50
    #: Kinds which, accepted in the same round, make this one wait for the next.
    waits_for: ClassVar[tuple[str, ...]] = ()
    #: Whether several sessions may share it (a line's phase, a step's time are one record's).
    pooled: ClassVar[bool] = True

    evidence: dict = field(default_factory=dict, compare=False, hash=False, repr=False,
                           kw_only=True)

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the effects of this kind that the fired findings point to."""
        return []

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Return ``family`` with this effect's candidates added."""
        raise NotImplementedError

    def describe(self) -> str:
        """Return a short label: ``periodic 7.3137 Hz``, ``driver temp_c, slow part ...``."""
        raise NotImplementedError

    @property
    def strict(self) -> bool:
        """Judged strictly: on each half of the segment and from every earlier origin.

        Anything that could run on beyond its data is; what holds still (a level) or
        runs only as its measured cause does (a driver's slow part) is not.
        """
        return True

    def onset_s(self) -> float | None:
        """Return the time (s) the effect begins at inside the record, or None: from its start.

        An origin of the judge before it, or too soon after it to refit its weight, cannot
        judge it (:data:`fosmodel.loop.judge.ONSET_REFIT_SLOWS`).
        """
        return None

    def identity(self) -> tuple:
        """Return what tells two effects of this kind apart (one of a kind by default)."""
        return ()

    def same_as(self, other: Effect) -> bool:
        """Whether ``other`` is the same effect: the same kind and identity."""
        return type(self) is type(other) and self.identity() == other.identity()

    def chosen(self, model: BoundModel) -> dict[str, Any]:
        """Return what the fit chose of it (a channel's dead time, a level's time constant)."""
        return {}

    def fields(self) -> dict[str, Any]:
        """Its own fields, JSON-ready."""
        return {f.name: _json(getattr(self, f.name)) for f in dataclasses.fields(self)
                if f.name != "evidence"}

    def to_dict(self) -> dict[str, Any]:
        """``{"kind": ..., its fields..., "evidence": ...}``; :func:`effect_from_dict` reads it."""
        return {"kind": self.kind, **self.fields(), "evidence": self.evidence}

    @classmethod
    def from_fields(cls, fields: Mapping[str, Any]) -> Effect:
        """Build one from its fields as JSON gives them: lists for tuples."""
        values: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v
                                  for k, v in fields.items()}
        return cls(**values)


def _json(value: object) -> object:
    if isinstance(value, tuple):
        return [_json(v) for v in value]
    if isinstance(value, Mapping):
        return {str(k): _json(v) for k, v in value.items()}
    if isinstance(value, (np.floating, np.integer)):
        return value.item()
    return value


_KINDS: dict[str, type[Effect]] = {}
_E = TypeVar("_E", bound=type[Effect])


def register(cls: _E) -> _E:
    """Class decorator: put an effect kind in the registry, under its ``kind``.

    Raises
    ------
    ValueError
        A kind without a name, or a name taken by another class.
    """
    if not cls.kind or (cls.kind in _KINDS and _KINDS[cls.kind] is not cls):
        raise ValueError(f"effect kind {cls.kind!r} is unnamed or registered already")
    _KINDS[cls.kind] = cls
    return cls


def unregister(kind: str) -> None:
    """Take a kind out of the registry (a test's own kind, once it has run)."""
    _KINDS.pop(kind, None)


def kinds() -> tuple[str, ...]:
    """Return the registered kinds, in their rank order."""
    return tuple(sorted(_KINDS, key=lambda k: (_KINDS[k].rank, k)))


def effect_class(kind: str) -> type[Effect]:
    """Return the class of a registered kind.

    Raises
    ------
    ValueError
        An unknown kind.
    """
    if kind not in _KINDS:
        raise ValueError(f"unknown effect kind {kind!r}; known: {', '.join(kinds())}")
    return _KINDS[kind]


#: Kinds of older code, as what they are now: a channel as an input ("aux") is a driver's fast
#: part (the synthetic records' truth still names it so).
_ALIASES: dict[str, tuple[str, dict[str, Any]]] = {
    "aux": ("driver", {"part": "fast", "tau_s": 20.0})}


def make_effect(kind: str, **fields: object) -> Effect:
    """Build an effect of ``kind`` from its fields, as JSON gives them (lists for tuples)."""
    if kind in _ALIASES:
        kind, implied = _ALIASES[kind]
        fields = {**implied, **fields}
    return effect_class(kind).from_fields(fields)


#: The short name older code and tests use; :func:`make_effect` says what it makes.
make = make_effect


def effect_from_dict(data: Mapping[str, Any]) -> Effect:
    """Rebuild an effect from :meth:`Effect.to_dict`."""
    fields = {k: v for k, v in data.items() if k not in ("kind", "evidence")}
    return make_effect(data["kind"], **fields, evidence=dict(data.get("evidence") or {}))


def effects_from(offer: Offer, keep: Callable[[type[Effect]], bool] = lambda cls: True,
                 ) -> list[Effect]:
    """Every effect the fired findings point to, kind by kind in rank order.

    ``keep`` chooses the kinds (several sessions take the pooled ones only).
    """
    return [e for kind in kinds() if keep(_KINDS[kind]) for e in _KINDS[kind].offered(offer)]

"""A driver of the error: a temperature, a voltage, an accelerometer for a gyro.

A driver is measured in use, so a model may take it as an input.  It comes in two
parts, offered by two tests:

* its *slow part* (the ``driver`` test, :mod:`fosmodel.loop.driver_forms`): the
  forms of slow physics (the driver, its powers, its rate of change, its
  first-order lags), chosen and weighted on the slow residual beside a
  block-scale level, enter the model as a fixed *compensation*
  (:mod:`fosmodel.models.compensation`).  With a level in the model, or one
  offered in the same round, the level candidates come with it, of the
  compensated output: the level follows what the driver does not explain.  A
  level fitted jointly with the driver in one least-squares step would absorb
  the driver's slow swing (one-step errors hardly tell them apart), and in an
  outage it would hold still where the driver moves on.  Where a constant per
  session explains what the driver leaves better than a wandering level does
  (by BIC, :mod:`fosmodel.loop.driver_forms`), the driver is offered alone too,
  and the judge chooses;
* its *fast part* (the ``aux`` test on the one-step residual): lags ``0..K`` of
  the channel minus its own local level over ``slow_s`` (``<ch>_fast<T>s``), a
  coupling through the driver's changes, as g-sensitivity enters a gyro.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, TypeVar

import numpy as np

from ...core.candidates import Term
from ...core.derived import fast_name
from ...core.levels import levels_for
from ...models.bound import BoundModel
from ..driver_forms import TREND, compensation_of, forms_text
from ..record import LoopRecord
from .base import Effect, Offer, register
from .family import CandidateFamily
from .level import first_level_tau

_T = TypeVar("_T")


@register
@dataclass(frozen=True)
class Driver(Effect):
    """A driver's slow part or its fast part.

    The slow part has its ``forms`` (derived column names and weights), the ``block`` and
    the block-scale level (``level_blocks``) or the ``trend`` per session they were fitted
    beside, and the ``level_taus`` it comes with; the fast part its lags ``0..max_lag`` and
    the time constant ``tau_s`` of the level it leaves out.
    """

    kind = "driver"
    rank = 10
    channel: str = ""
    part: str = "slow"
    forms: tuple[tuple[str, float], ...] = ()
    level_taus: tuple[float, ...] | None = None
    max_lag: int | None = None
    tau_s: float | None = None
    block: int | None = None
    level_blocks: float | None = None
    trend: bool = False

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the slow part of each driver its test points to.

        And the fast part of each driver the residual correlates with.
        """
        drivers = set(offer.roles.drivers)
        out: list[Effect] = []
        for f in offer.fired("driver"):
            if f.evidence["channel"] in drivers:
                forms = compensation_of(f)
                block = round(f.evidence["block_s"] * offer.config.rate)
                taus = _level_taus(offer, forms)
                variants: list[tuple[float, ...] | None] = [taus] if taus else []
                if taus is None or not f.evidence["level_blocks"]:
                    variants.append(None)  # alone: no level offered, or none wanted beside it
                for with_level in variants:
                    out.append(cls(f.evidence["channel"], "slow", tuple(forms.items()),
                                   with_level, block=block,
                                   level_blocks=f.evidence["level_blocks"],
                                   trend=bool(f.evidence.get("trend")), evidence=f.to_dict()))
        out += [cls(f.evidence["channel"], "fast", max_lag=max(offer.config.aux_max_lag,
                                                               f.evidence["lag"]),
                    tau_s=offer.config.slow_s, evidence=f.to_dict())
                for f in offer.fired("aux") if f.evidence["channel"] in drivers]
        return out

    @classmethod
    def from_fields(cls, fields: Mapping[str, Any]) -> Effect:
        """Build one from JSON: ``forms`` as pairs, ``level_taus`` as a list."""
        fields = dict(fields)
        fields["forms"] = tuple((str(n), float(w)) for n, w in fields.get("forms") or ())
        if fields.get("level_taus") is not None:
            fields["level_taus"] = tuple(fields["level_taus"])
        return cls(**fields)

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Return the compensation and the compensated output's levels, or the fast part's lags."""
        if self.part == "fast":
            return family.with_input(fast_name(self.channel, _need(self.tau_s, "tau_s")),
                                     _need(self.max_lag, "max_lag"), record)
        gain = (TREND if self.trend else 0.0 if self.level_blocks is None
                else 1.0 / self.level_blocks)
        family = family.with_compensation(dict(self.forms), record, (self.block or 1, gain))
        return family.with_levels(self.level_taus) if self.level_taus else family

    @property
    def strict(self) -> bool:
        """The slow part runs only as its measured cause does: not strict; the fast part is."""
        return self.part == "fast"

    def identity(self) -> tuple:
        """Return the channel, the part, and the slow part's forms.

        With the level or without, the same forms are the same cause: once one is in, the
        other would add its weights to the compensation a second time.
        """
        return (self.channel, self.part, tuple(sorted(n for n, _ in self.forms)))

    def describe(self) -> str:
        """``driver temp_c, slow part (lag 600 s, powers 1, 2) with the level``, ..."""
        if self.part == "fast":
            return f"driver {self.channel}, fast part (lags 0-{self.max_lag})"
        return (f"driver {self.channel}, slow part ({forms_text(dict(self.forms))})"
                + (" with the level" if self.level_taus else ""))

    def chosen(self, model: BoundModel) -> dict[str, Any]:
        """Return the fast part's dead time (its first lag selected), or the slow part's level."""
        if self.part == "fast":
            return {"lag": first_lag(model, fast_name(self.channel, _need(self.tau_s, "tau_s")))}
        return {"tau_s": first_level_tau(model)}


def _level_taus(offer: Offer, forms: dict[str, float]) -> tuple[float, ...] | None:
    """Return the level grid of the compensated output, if a level is in or offered, else None.

    The compensated output has lost the driver's slow swing: its Allan deviation has its
    floor later, and so does the grid (:func:`fosmodel.core.levels.levels_for`).
    """
    if not (offer.family.levels or offer.slow):
        return None
    if offer.config.level_taus is not None:
        return offer.config.level_taus or None
    rec = offer.record
    comp = offer.family.with_compensation(forms, rec).compensation_series()
    target = rec.y if comp is None else rec.y - comp
    fitted = np.concatenate([target[s] for s in offer.fit])
    return levels_for(fitted, rec.rate) or None


def first_lag(model: BoundModel, channel: str) -> int | None:
    """Return the smallest lag of ``channel`` in the first term that reads it: its dead time.

    Seen through coloured noise, an input ``x[n-d]`` enters the one-step equation as
    ``x[n-d]`` and its filtered neighbours; FOS takes the leading one first.
    """
    for name in model.model.terms_:
        lags = [lag for ch, lag in Term.parse(name).factors if ch == channel and lag is not None]
        if lags:
            return int(min(lags))
    return None


def _need(value: _T | None, name: str) -> _T:
    if value is None:
        raise ValueError(f"a driver's fast part needs its {name}")
    return value

"""The local level: a wandering bias as a stochastic level (:mod:`fosmodel.core.levels`)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...core.candidates import Term
from ...core.levels import level_tau
from ...models.bound import BoundModel
from ..record import LoopRecord
from .base import Effect, Offer, register
from .family import CandidateFamily


@register
@dataclass(frozen=True)
class Level(Effect):
    """Levels ``level@<tau>s`` of the output over a grid of time constants ``taus`` (s).

    Offered whenever a slow test fires (a trend, a step, the Allan deviation): how each slow
    form extrapolates out of sample chooses between them.  Judged leniently: it holds still
    beyond its data, as the model without it does, and its bias gains are the noisiest.
    """

    kind = "level"
    rank = 0
    taus: tuple[float, ...] = ()

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return a level over the grid, when a slow test fired."""
        slow = offer.slow
        if not slow or not offer.level_taus:
            return []
        strongest = min(slow, key=lambda f: f.p_value)
        return [cls(tuple(offer.level_taus), evidence={
            **strongest.to_dict(), "slow_tests": [f.test for f in slow]})]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Add the level candidates."""
        return family.with_levels(self.taus)

    @property
    def strict(self) -> bool:
        """Not strict: a level holds still beyond its data."""
        return False

    def describe(self) -> str:
        """``local level (tau 1.5-30 s)``."""
        return "local level" + (f" (tau {self.taus[0]:.3g}-{self.taus[-1]:.3g} s)"
                                if self.taus else "")

    def chosen(self, model: BoundModel) -> dict[str, Any]:
        """Return the time constant of the first level the fit selected."""
        return {"tau_s": first_level_tau(model)}


def first_level_tau(model: BoundModel) -> float | None:
    """Return the time constant (s) of the first level term of ``model``, or None."""
    for name in model.model.terms_:
        taus = [level_tau(ch) for ch, _ in Term.parse(name).factors if level_tau(ch)]
        if taus:
            return taus[0]
    return None

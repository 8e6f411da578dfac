"""A nonlinearity of the output's own past: cross-products of its lags."""

from __future__ import annotations

from dataclasses import dataclass

from ..record import LoopRecord
from .base import Effect, Offer, register
from .family import CandidateFamily


@register
@dataclass(frozen=True)
class Nonlinear(Effect):
    """The cross-product degree raised to 2 over the output lags ``y[n-1]..y[n-max_lag]``."""

    kind = "nonlinear"
    rank = 40
    max_lag: int | None = None

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the products of a fired nonlinearity test."""
        return [cls(f.evidence["max_lag"], evidence=f.to_dict())
                for f in offer.fired("nonlinear")]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Raise the degree to 2 over the tested lags."""
        return family.changed(degree=max(family.degree, 2), product_lags=self.max_lag)

    def describe(self) -> str:
        """``nonlinear (cross-products of degree 2 of y[n-1]..y[n-4])``."""
        return "nonlinear (cross-products of degree 2" + (
            f" of y[n-1]..y[n-{self.max_lag}])" if self.max_lag else ")")

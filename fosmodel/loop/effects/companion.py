"""A companion taken as an input: another axis of the same IMU, only when asked for.

Another gyro for a gyro, another accelerometer for an accelerometer
(:mod:`fosmodel.loop.roles`) measures the vehicle's motion in use; the loop
reports its correlation with the residual as cross-axis noise and offers it as
an input only when the user names it (``LoopConfig.aux``).  It then enters as a
driver's fast part does, and the report says it was asked for.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...core.derived import fast_name
from ...models.bound import BoundModel
from ..record import LoopRecord
from .base import Effect, Offer, register
from .driver import first_lag
from .family import CandidateFamily


@register
@dataclass(frozen=True)
class Companion(Effect):
    """Lags ``0..max_lag`` of a companion's fast part (minus its level over ``tau_s``)."""

    kind = "companion"
    rank = 20
    channel: str = ""
    max_lag: int = 0
    tau_s: float = 20.0

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return a companion asked for, whose correlation with the residual fired."""
        asked = set(offer.roles.opted_in)
        return [cls(f.evidence["channel"], max(offer.config.aux_max_lag, f.evidence["lag"]),
                    offer.config.slow_s, evidence=f.to_dict())
                for f in offer.fired("aux") if f.evidence["channel"] in asked]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Add the companion's fast part with its lags."""
        return family.with_input(fast_name(self.channel, self.tau_s), self.max_lag, record)

    def identity(self) -> tuple:
        """Return the channel."""
        return (self.channel,)

    def describe(self) -> str:
        """``companion gz_dps as an input, as asked (fast part, lags 0-10)``."""
        return f"companion {self.channel} as an input, as asked (fast part, lags 0-{self.max_lag})"

    def chosen(self, model: BoundModel) -> dict[str, Any]:
        """Return the dead time: the first lag of the companion selected."""
        return {"lag": first_lag(model, fast_name(self.channel, self.tau_s))}

"""A step of the bias at one time of the record."""

from __future__ import annotations

from dataclasses import dataclass

from ...core.derived import step_name
from ..record import LoopRecord
from .base import Effect, Offer, register
from .family import CandidateFamily


@register
@dataclass(frozen=True)
class Step(Effect):
    """``step@<time>s``, 0 before the step the CUSUM test found and 1 after it.

    A function of time: it waits for the level and the drivers accepted in the same round,
    and is judged strictly, from the origins after its time.  One record's: a step's time does
    not carry to another session.
    """

    kind = "step"
    rank = 60
    waits_for = ("level", "driver")
    pooled = False
    time_s: float = 0.0

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the step a fired step test placed."""
        return [cls(f.evidence["time_s"], evidence=f.to_dict()) for f in offer.fired("step")]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Add the step column."""
        return family.with_columns([step_name(self.time_s)], record)

    def onset_s(self) -> float | None:
        """Return the step's time: an origin before it has not seen it."""
        return self.time_s

    def describe(self) -> str:
        """``step at 105 s``."""
        return f"step at {self.time_s:.4g} s"

"""A drift: functions of time since the record's start (a trend and a warm-up)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...core.derived import TIME_NAME, exp_name
from ...models.bound import BoundModel
from ..record import LoopRecord
from .base import Effect, Offer, register
from .family import CandidateFamily


@register
@dataclass(frozen=True)
class Drift(Effect):
    """``t@s`` and ``exp(-t/<tau>s)``, the warm-up the trend test found; FOS keeps what fits.

    A function of time fitted on one stretch runs on beyond it: it waits for the level and
    the drivers accepted in the same round, and is judged strictly.  Several sessions may
    share it, with time since each one's start (a warm-up after turn-on).
    """

    kind = "drift"
    rank = 50
    waits_for = ("level", "driver")
    form: str | None = None
    tau_s: float | None = None

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the form and warm-up of a fired trend test."""
        return [cls(f.evidence["form"], f.evidence["tau_s"], evidence=f.to_dict())
                for f in offer.fired("trend")]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Add the trend and the warm-up."""
        if self.tau_s is None:
            raise ValueError("a drift effect needs its tau_s")
        return family.with_columns([TIME_NAME, exp_name(self.tau_s)], record)

    def describe(self) -> str:
        """``drift (trend and warm-up, tau 50.9 s)``."""
        return f"drift (trend and warm-up, tau {self.tau_s:.3g} s)"

    def chosen(self, model: BoundModel) -> dict[str, Any]:
        """Return the warm-up's time constant."""
        return {"tau_s": self.tau_s}

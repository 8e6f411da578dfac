"""A line in the residual's spectrum: a sinusoid at the found frequency."""

from __future__ import annotations

from dataclasses import dataclass

from ...core.derived import cosine_name, sine_name
from ..record import LoopRecord
from .base import Effect, Offer, register
from .family import CandidateFamily

#: Lines closer than this (Hz) are the same line.
FREQ_TOL_HZ = 0.05


@register
@dataclass(frozen=True)
class Periodic(Effect):
    """``cos@<f>Hz`` and ``sin@<f>Hz`` at the frequency the periodic test refined.

    One record's: a line's phase does not carry from one session to the next.
    """

    kind = "periodic"
    rank = 30
    pooled = False
    freq_hz: float = 0.0

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the line of a fired periodic test."""
        return [cls(f.evidence["freq_hz"], evidence=f.to_dict()) for f in offer.fired("periodic")]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Add the cosine and the sine."""
        return family.with_columns([cosine_name(self.freq_hz), sine_name(self.freq_hz)], record)

    def same_as(self, other: Effect) -> bool:
        """Return the same line: frequencies within :data:`FREQ_TOL_HZ`."""
        return isinstance(other, Periodic) and abs(self.freq_hz - other.freq_hz) < FREQ_TOL_HZ

    def describe(self) -> str:
        """``periodic 7.3137 Hz``."""
        return f"periodic {self.freq_hz:.4f} Hz"

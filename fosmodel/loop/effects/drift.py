"""A drift: functions of time since the record's start (a trend and a warm-up)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from ...core.derived import TIME_NAME, exp_name
from ...models.bound import BoundModel
from ..config import LoopConfig
from ..driver_forms import follows_time
from ..record import LoopRecord
from ..roles import Roles
from .base import Effect, Offer, register
from .family import CandidateFamily


@register
@dataclass(frozen=True)
class Drift(Effect):
    """``t@s`` and ``exp(-t/<tau>s)``, the warm-up the trend test found; FOS keeps what fits.

    A function of time fitted on one stretch runs on beyond it: it waits for the level and
    the drivers accepted in the same round, and is judged strictly.  Where a measured
    driver follows time over the fitting data (:func:`~fosmodel.loop.driver_forms.follows_time`,
    ``follower``) the trend is left out (``trend`` False): there the data cannot tell time
    from the driver, and a trend fitted on a sweep would run on where the driver holds
    still; a warm-up settles.  Several sessions may share it, with time since each one's
    start (a warm-up after turn-on).
    """

    kind = "drift"
    rank = 50
    waits_for = ("level", "driver")
    form: str | None = None
    tau_s: float | None = None
    trend: bool = True
    follower: str | None = None

    @classmethod
    def offered(cls, offer: Offer) -> list[Effect]:
        """Return the form and warm-up of a fired trend test.

        Only the warm-up where a driver follows time, and nothing where the form found is
        a polynomial in time alone.
        """
        found = offer.fired("trend")
        followers = time_followers(offer.record, offer.fit, offer.roles, offer.config) \
            if found else []
        if not followers:
            return [cls(f.evidence["form"], f.evidence["tau_s"], evidence=f.to_dict())
                    for f in found]
        return [cls(f.evidence["form"], f.evidence["tau_s"], trend=False,
                    follower=followers[0][0],
                    evidence=f.to_dict())
                for f in found if "exponential" in str(f.evidence["form"])]

    def add_to(self, family: CandidateFamily, record: LoopRecord) -> CandidateFamily:
        """Add the trend (where no driver follows time) and the warm-up."""
        if self.tau_s is None:
            raise ValueError("a drift effect needs its tau_s")
        return family.with_columns([TIME_NAME] * self.trend + [exp_name(self.tau_s)], record)

    def describe(self) -> str:
        """``drift (trend and warm-up, tau 50.9 s)``, or ``drift (warm-up, tau 50.9 s; ...)``."""
        if self.trend:
            return f"drift (trend and warm-up, tau {self.tau_s:.3g} s)"
        return (f"drift (warm-up, tau {self.tau_s:.3g} s; no trend: {self.follower} follows "
                f"time in the fitting data)")

    def chosen(self, model: BoundModel) -> dict[str, Any]:
        """Return the warm-up's time constant."""
        return {"tau_s": self.tau_s}


def time_followers(record: LoopRecord, fit: tuple[slice, ...], roles: Roles,
                   config: LoopConfig) -> list[tuple[str, float]]:
    """Return the slow drivers that follow time over ``fit``, each with its correlation.

    Read on blocks of ``config.slow_s`` (:func:`~fosmodel.loop.driver_forms.follows_time`).
    """
    block = max(1, round(config.slow_s * config.rate))
    return [(ch, rho) for ch in roles.slow
            for rho in [follows_time(record, fit, ch, block)] if rho is not None]


def trend_note(record: LoopRecord, fit: tuple[slice, ...], roles: Roles,
               config: LoopConfig) -> list[str]:
    """Say of each driver that follows time in the fitting data that no trend is offered."""
    return [f"{ch} follows time in the fitting data (r = {rho:+.2f}): a trend in time is not "
            f"offered, since fitted there it could not be told from {ch} and would run on "
            f"where {ch} holds still" for ch, rho in time_followers(record, fit, roles, config)]

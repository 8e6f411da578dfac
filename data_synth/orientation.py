"""How a static IMU sits: what its axes measure of gravity and of the earth's rotation.

A static accelerometer measures the specific force ``+g`` along the local up
direction; a static gyro measures the earth's rotation, ``Omega cos(lat)`` along
north and ``Omega sin(lat)`` along up.  An :class:`Orientation` names the body
axes that point up and north (``"+z"``, ``"-y"``...), so that each session of a
multi-session record puts gravity on another axis and its accelerometer (and, by
a few millidegrees per second, gyro) means differ.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from data_synth.units import STANDARD_GRAVITY

#: Earth's rotation rate (WGS-84), 7.292115e-5 rad/s, in deg/s.
EARTH_RATE_DPS = math.degrees(7.292115e-5)
#: Latitude of Calgary (51.05 N), the default site.
CALGARY_LATITUDE_DEG = 51.05

_AXES = "xyz"


def _axis(text: str) -> np.ndarray:
    """The body unit vector of ``"+x"``, ``"-z"``..."""
    if len(text) != 2 or text[0] not in "+-" or text[1] not in _AXES:
        raise ValueError(f"an axis is written +x, -y, +z...; got {text!r}")
    vec = np.zeros(3)
    vec[_AXES.index(text[1])] = 1.0 if text[0] == "+" else -1.0
    return vec


@dataclass(frozen=True)
class Orientation:
    """A static attitude: the body axes pointing up and north, and the site's latitude.

    Parameters
    ----------
    up, north : str
        Body axes (``"+z"``, ``"-x"``...), perpendicular to each other.
    latitude_deg : float
        Latitude of the site in degrees (the earth rate's split between north and up).
    """

    up: str = "+z"
    north: str = "+x"
    latitude_deg: float = CALGARY_LATITUDE_DEG

    def __post_init__(self):
        if float(np.dot(_axis(self.up), _axis(self.north))) != 0.0:
            raise ValueError(f"up {self.up} and north {self.north} must be perpendicular axes")
        if not -90.0 <= self.latitude_deg <= 90.0:
            raise ValueError(f"latitude_deg must lie in [-90, 90], got {self.latitude_deg!r}")

    @classmethod
    def parse(cls, text: str, latitude_deg: float = CALGARY_LATITUDE_DEG) -> Orientation:
        """Read ``"UP/NORTH"`` (``"+z/+x"``)."""
        up, sep, north = text.partition("/")
        if not sep:
            raise ValueError(f"an orientation is written UP/NORTH, e.g. +z/+x; got {text!r}")
        return cls(up.strip(), north.strip(), latitude_deg)

    def specific_force(self, gravity: float = STANDARD_GRAVITY) -> np.ndarray:
        """What the x, y, z accelerometers read at rest: ``gravity`` along the up axis."""
        return gravity * _axis(self.up)

    def earth_rate(self, rate_unit_per_dps: float = 1.0) -> np.ndarray:
        """What the x, y, z gyros read at rest, in deg/s times ``rate_unit_per_dps``."""
        lat = math.radians(self.latitude_deg)
        omega = EARTH_RATE_DPS * rate_unit_per_dps
        return omega * (math.cos(lat) * _axis(self.north) + math.sin(lat) * _axis(self.up))

    def to_dict(self) -> dict[str, Any]:
        """The orientation for the truth, with what it puts on each axis."""
        return {
            "up": self.up,
            "north": self.north,
            "latitude_deg": self.latitude_deg,
            "gravity_mps2": STANDARD_GRAVITY,
            "earth_rate_dps": EARTH_RATE_DPS,
            "note": "at rest the accelerometers read +gravity along the up axis and the gyros "
            "the earth rate, cos(latitude) of it along north and sin(latitude) along up",
        }

"""What each other channel of a record is to the modelled axis: a companion or a driver.

In use, another inertial axis of the same IMU measures the vehicle's motion: a
model with it as an input is wrong once the sensor moves, however well it did on
a static record.  So the other axes of the same kind as the modelled one (a gyro
for a gyro, an accelerometer for an accelerometer) are *companions*: never
inputs unless asked for (``LoopConfig.aux``); their correlation with the
residual is reported as cross-axis noise.  So are the gyros of an
accelerometer: angular rate measures the motion too, and no error of an
accelerometer is driven by what a gyro reads.  So are the channels whose names say
they measure the motion itself (:func:`fosmodel.noise.axes.motion_kind`): a
magnetometer reads the heading, and attitude, velocity and position follow the
vehicle, however well one tracked a static record's slow bias (a magnetometer
drifts with the die temperature too).  Everything else is a *driver*, a
cause of the error measured in use: a temperature, a voltage, and the
accelerometers for a gyro (its g-sensitivity: specific force).  Axes are recognised as the
six-axis workflow recognises them (:func:`fosmodel.noise.axes.infer_axis`),
unless the companions are given.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass

from ..core.exceptions import OptionError
from ..core.validation import did_you_mean
from ..noise.axes import infer_axis, motion_kind


@dataclass(frozen=True)
class Roles:
    """The channels of a record by role, and how the roles were told.

    ``companions`` are never inputs but those in ``opted_in``; ``drivers`` may be.
    ``motion`` are the drivers that are inertial axes of the other kind (a gyro's
    accelerometers): their coupling is instantaneous (g-sensitivity), so they are offered
    in their fast part only, not in the slow forms of a temperature.
    """

    drivers: tuple[str, ...]
    companions: tuple[str, ...]
    opted_in: tuple[str, ...]
    told: str
    motion: tuple[str, ...] = ()

    @property
    def slow(self) -> tuple[str, ...]:
        """The drivers offered in the slow forms too: all but the inertial axes."""
        return tuple(c for c in self.drivers if c not in self.motion)

    @property
    def inputs(self) -> tuple[str, ...]:
        """The channels the loop may offer as inputs: the drivers and the companions asked."""
        return (*self.drivers, *self.opted_in)

    def role(self, channel: str) -> str:
        """``"driver"``, ``"companion"`` (taken as an input if asked) for a channel."""
        return "companion" if channel in self.companions else "driver"

    def describe(self) -> str:
        """Say in a sentence which channels are companions and drivers, and why."""
        parts = [f"drivers: {', '.join(self.drivers) or 'none'}",
                 f"companions: {', '.join(self.companions) or 'none'}"]
        if self.opted_in:
            parts.append(f"companions taken as inputs as asked: {', '.join(self.opted_in)}")
        return "; ".join(parts) + f" ({self.told})"


def channel_roles(channels: Iterable[str], sensor: str | None,
                  companions: Sequence[str] | None = None, aux: Sequence[str] = (),
                  sensors: Mapping[str, str] | None = None) -> Roles:
    """Tell the companions of the modelled axis from the drivers among ``channels``.

    Parameters
    ----------
    channels : iterable of str
        The record's other columns.
    sensor : {"gyro", "accel"}, optional
        The modelled axis's sensor.  Without it, every channel whose name tells an
        inertial axis is a companion: which of them could drive the error is unknown.
    companions : sequence of str, optional
        The companions, when known otherwise (the six-axis workflow resolves each axis's
        sensor from its units too); by default recognised from the names.
    aux : sequence of str
        Companions to take as inputs all the same.
    sensors : mapping of str to str, optional
        The sensor of channels whose file tells it (by their units); the others' are read
        from their names.

    Raises
    ------
    OptionError
        A companion or an ``aux`` that is not among the channels, or an ``aux`` that is
        not a companion (a driver is an input already).
    """
    names = list(channels)
    known = dict(sensors or {})

    def sensor_of(channel: str) -> str | None:
        return known.get(channel) or infer_axis(channel)[0]

    if companions is not None:
        _among(companions, names, "companions")
        found, told = [c for c in names if c in set(companions)], "as given"
    elif sensor is None:
        found = [c for c in names if sensor_of(c) is not None]
        told = ("the modelled axis's sensor is not given: every channel named as an inertial "
                "axis is a companion")
    else:
        found = [c for c in names if sensor_of(c) == sensor]
        told = f"the other {sensor} axes, recognised by their names"
    if sensor == "accel":  # a gyro measures the motion: never a cause of an accelerometer's error
        gyros = [c for c in names if c not in found and sensor_of(c) == "gyro"]
        found += gyros
        told += " (and the gyros, which measure the motion)" if gyros else ""
    moving = [c for c in names if c not in found and sensor_of(c) is None and motion_kind(c)]
    if moving:
        found += moving
        told += (f"; {', '.join(moving)} "
                 f"{'measure' if len(moving) > 1 else 'measures'} the motion, as named")
    _among(aux, names, "aux")
    stray = [c for c in aux if c not in found]
    if stray:
        raise OptionError(f"{{option}}: {stray[0]!r} is not a companion of the modelled axis "
                          f"(companions: {', '.join(found) or 'none'}); a driver is offered "
                          "as an input already", "aux")
    drivers = tuple(c for c in names if c not in found)
    return Roles(drivers, tuple(found), tuple(c for c in found if c in set(aux)), told,
                 tuple(c for c in drivers if sensor_of(c) is not None))


def _among(given: Sequence[str], names: list[str], option: str) -> None:
    missing = [c for c in given if c not in names]
    if missing:
        raise OptionError(f"{{option}}: no channel {missing[0]!r} among the other columns"
                          f"{did_you_mean(missing[0], names)}", option)

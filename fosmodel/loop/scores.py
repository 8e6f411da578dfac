"""A model's errors on the prediction segment, at every outage length the segment can hold.

Each horizon's outages are consecutive windows of the segment (at most
``n_starts``, evenly spread), each a free run from the true past: the mean
error over a window is the bias a navigation filter integrates (its RMS over
the windows is the horizon's *bias RMS*), the end-of-window position error
what it costs (:func:`fosmodel.noise.metrics.integrated_position_error`).
The arrays are kept, window by window, for the before/after ratios'
intervals (:mod:`fosmodel.loop.intervals`).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..models.bound import BoundModel
from ..noise.metrics import equivalent_position_error, free_run_errors, integrated_position_error
from .config import LoopConfig
from .judge import MIN_WINDOWS, windows


@dataclass(frozen=True)
class Outages:
    """A model's free runs over one horizon's windows.

    Each window's mean error, mean square error and end-of-outage position error (None
    without sensor and units).
    """

    horizon_s: float
    bias: np.ndarray
    mse: np.ndarray
    position: np.ndarray | None


@dataclass(frozen=True)
class Scores:
    """A model's errors on a segment: one-step, and its outages at each horizon."""

    errors: np.ndarray = field(repr=False)
    outages: dict[float, Outages] = field(repr=False)
    terms: tuple[str, ...]
    position_error_m: float | None

    @property
    def mse(self) -> float:
        """The one-step mean squared error."""
        return float(np.mean(self.errors**2))

    @property
    def horizons_s(self) -> tuple[float, ...]:
        """The outage lengths scored, in seconds."""
        return tuple(self.outages)

    @property
    def bias_rms(self) -> dict[float, float]:
        """Each horizon's RMS over its outages of their mean error, by seconds."""
        with np.errstate(over="ignore"):  # a diverging run squares to inf
            return {h: float(np.sqrt(np.mean(o.bias**2))) for h, o in self.outages.items()}

    @property
    def outage_mse(self) -> dict[float, float]:
        """Each horizon's mean over its outages of their mean squared error, by seconds."""
        return {h: float(np.mean(o.mse)) for h, o in self.outages.items()}

    @property
    def outage_position_error_m(self) -> dict[float, float | None]:
        """Each horizon's RMS end-of-outage position error (None without sensor and units)."""
        with np.errstate(over="ignore"):
            return {h: None if o.position is None else float(np.sqrt(np.mean(o.position**2)))
                    for h, o in self.outages.items()}

    def to_dict(self) -> dict[str, Any]:
        """Return the numbers as JSON, keyed by seconds (``"30"``).

        ``bias_rms``, the outages' MSE and their RMS position error at each horizon.
        """
        with np.errstate(over="ignore"):  # a diverging run squares to inf
            return {"mse": self.mse, "position_error_m": self.position_error_m,
                    "bias_rms": _by_seconds(self.bias_rms),
                    "outage_mse": _by_seconds(self.outage_mse),
                    "outage_position_error_m": _by_seconds(self.outage_position_error_m),
                    "terms": list(self.terms)}

    def __getitem__(self, key: str) -> Any:  # noqa: ANN401 (the JSON entries differ in shape)
        """Return an entry of :meth:`to_dict` (``scores["bias_rms"]["30"]``)."""
        return self.to_dict()[key]

    def __eq__(self, other: object) -> bool:
        """Two scores are equal when their numbers are."""
        return isinstance(other, Scores) and self.to_dict() == other.to_dict()


def _by_seconds(values: dict[float, Any]) -> dict[str, Any]:
    return {f"{h:g}": v for h, v in values.items()}


@dataclass(frozen=True)
class Plan:
    """Where a segment's numbers are taken: its windows per horizon, and why any is left out.

    ``horizons`` maps each horizon (s) kept to its window starts and length in samples;
    ``skipped`` says of each horizon left out why.
    """

    segment: slice
    horizons: dict[float, tuple[np.ndarray, int]]
    skipped: dict[float, str]


def plan(segment: slice, horizons_s: Sequence[float], rate: float, most: int, name: str,
         least: int = MIN_WINDOWS) -> Plan:
    """Return the horizons of ``horizons_s`` whose windows ``segment`` holds at least ``least`` of.

    ``name`` names the segment in the reasons a horizon is skipped.
    """
    kept, skipped = {}, {}
    length = segment.stop - segment.start
    for h in horizons_s:
        n = round(h * rate)
        count = length // n
        if count < least:
            skipped[h] = (f"the {name} segment ({length / rate:.6g} s) holds {count} "
                          f"{h:g} s window{'s' if count != 1 else ''}, fewer than {least}")
        else:
            kept[h] = (windows(segment, n, most), n)
    return Plan(segment, kept, skipped)


def scores(model: BoundModel, y: np.ndarray, where: Plan, config: LoopConfig) -> Scores:
    """Return the errors of ``model`` over ``where.segment`` of the record ``y``."""
    segment, rate = where.segment, config.rate
    pred = np.asarray(model.predict(y[: segment.stop], start=segment.start), dtype=float)
    errors = y[segment] - pred[segment]
    outages = {}
    for h, (starts, n) in where.horizons.items():
        runs = free_run_errors(model, y[: segment.stop], starts, n)
        with np.errstate(over="ignore", invalid="ignore"):
            position = (integrated_position_error(runs, rate, config.sensor, config.units)
                        if config.sensor and config.units else None)
            outages[h] = Outages(h, runs.mean(axis=1), np.mean(runs**2, axis=1), position)
    mse = float(np.mean(errors**2))
    position_error = (equivalent_position_error(mse, config.sensor, config.units)
                      if config.sensor and config.units else None)
    return Scores(errors, outages, tuple(model.model.terms_), position_error)

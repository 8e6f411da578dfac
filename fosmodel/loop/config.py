"""The residual loop's settings, every one checked where it is given."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..core.exceptions import OptionError
from ..core.fos import STOP_RULES
from ..io.split import EVALUATE_FRACTION, TRAIN_FRACTION
from ..noise.metrics import to_si_scale

#: The outage lengths (s) the loop judges and reports at by default: what a navigation filter
#: coasts through, from a tunnel to a long loss of satellite signals.
HORIZONS_S = (30.0, 300.0, 1800.0)


@dataclass(frozen=True)
class LoopConfig:
    """Settings of the residual loop.

    Parameters
    ----------
    rate : float
        Sample rate in Hz.
    sensor, units : str, optional
        For position errors (``accel``/``gyro`` and the record's units).
    max_lag : int
        L of the starting model.
    train, evaluate : float
        Fractions of the record for fitting and for evaluation; the rest is predicted.
    alpha : float
        Level of each diagnostic test.
    accept_alpha : float
        Level of the evaluation-segment tests that keep an effect (and find it worse).
    max_effects : int
        Most effects added.
    aux_max_lag : int
        Lags 0..K of a channel's fast part (tested and offered).
    nonlinear_lags : int
        Lags whose products the nonlinearity test uses.
    horizons_s : tuple of float
        Outage lengths (s) the loop judges on the evaluation segment and reports on the
        prediction segment, each where the segment holds enough windows
        (:data:`fosmodel.loop.judge.MIN_WINDOWS`).
    eval_horizon_s : float
        A short outage the judge also compares on: the bias a filter integrates between
        updates, judged however short the record.
    n_starts : int
        Most outage windows per horizon and segment (evenly spread when it holds more).
    fos_stop : str
        FOS stopping rule.
    origins : int
        Fit origins of the out-of-sample test, evenly spaced from half the
        fitting segment to its end (1: its end only).
    slow_s : float
        Time scale (s) separating slow errors (level, drift, steps, a driver's slow part)
        from fast ones: the periodic and nonlinearity tests look at the residual minus
        its moving mean over ``slow_s``, at frequencies above ``1 / slow_s``.
    level_taus : tuple of float, optional
        Time constants (s) of the level candidates; by default chosen from the
        fitting segment (:func:`fosmodel.core.levels.level_grid`).
    companions : tuple of str, optional
        The channels that are other axes of the same IMU and kind as the modelled one;
        by default recognised from the names (:mod:`fosmodel.loop.roles`).  Channels named
        as measuring the motion (a magnetometer, attitude, velocity, position) are
        companions whatever this says.
    aux : tuple of str
        Companions taken as inputs all the same (by default none is).
    confidence : float
        Level of the before/after intervals of the report.
    head_s : float
        With several sessions: the first seconds of a held-out session that give its own
        constant (its turn-on bias) before it is judged.
    """

    rate: float
    sensor: str | None = None
    units: str | None = None
    max_lag: int = 10
    train: float = TRAIN_FRACTION
    evaluate: float = EVALUATE_FRACTION
    alpha: float = 1e-3
    accept_alpha: float = 0.01
    max_effects: int = 5
    aux_max_lag: int = 10
    nonlinear_lags: int = 4
    horizons_s: tuple[float, ...] = HORIZONS_S
    eval_horizon_s: float = 5.0
    n_starts: int = 100
    fos_stop: str = "korenberg"
    origins: int = 4
    slow_s: float = 20.0
    level_taus: tuple[float, ...] | None = None
    companions: tuple[str, ...] | None = None
    aux: tuple[str, ...] = ()
    confidence: float = 0.95
    head_s: float = 600.0

    def __post_init__(self) -> None:
        """Check every option, and hold each sequence as a tuple.

        Raises
        ------
        OptionError
            An option out of range, of the wrong type, or a pair that does not go together;
            the message names the option.
        """
        _positive(self.rate, "rate")
        if (self.sensor is None) != (self.units is None):
            raise OptionError("give both the sensor (accel or gyro) and its units, or neither",
                              "units")
        if self.sensor is not None and self.units is not None:
            to_si_scale(self.sensor, self.units)
        for name in ("train", "evaluate"):
            _fraction(getattr(self, name), name)
        if self.train + self.evaluate >= 1:
            raise OptionError(f"the split {self.train:g} / {self.evaluate:g} must leave part of "
                              "the record to predict: {option} and evaluate add up to 1 or more",
                              "train")
        for name, least in (("max_lag", 1), ("max_effects", 0), ("aux_max_lag", 0),
                            ("nonlinear_lags", 1), ("n_starts", 2), ("origins", 1)):
            _integer(getattr(self, name), name, least)
        for name in ("alpha", "accept_alpha", "confidence"):
            _fraction(getattr(self, name), name)
        for name in ("eval_horizon_s", "slow_s", "head_s"):
            _positive(getattr(self, name), name)
        self._hold("horizons_s", _durations(self.horizons_s, "horizons_s", self.rate))
        if self.fos_stop not in STOP_RULES:
            raise OptionError(f"{{option}} must be one of {', '.join(STOP_RULES)}, got "
                              f"{self.fos_stop!r}", "fos_stop")
        if self.level_taus is not None:
            self._hold("level_taus", _durations(self.level_taus, "level_taus", self.rate,
                                                empty=True))
        if self.companions is not None:
            self._hold("companions", _names(self.companions, "companions"))
        self._hold("aux", _names(self.aux, "aux"))

    def _hold(self, name: str, value: tuple) -> None:
        object.__setattr__(self, name, value)


def _positive(value: object, name: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float, np.integer, np.floating)) \
            or not math.isfinite(value) or value <= 0:
        raise OptionError(f"{{option}} must be a finite number > 0, got {value!r}", name)
    return float(value)


def _fraction(value: object, name: str) -> float:
    if _positive(value, name) >= 1:
        raise OptionError(f"{{option}} must lie between 0 and 1, got {value!r}", name)
    return float(value)  # type: ignore[arg-type]


def _integer(value: object, name: str, least: int) -> int:
    if isinstance(value, bool) or not isinstance(value, (int, np.integer)) or value < least:
        raise OptionError(f"{{option}} must be an integer >= {least}, got {value!r}", name)
    return int(value)


def _durations(values: object, name: str, rate: float, empty: bool = False) -> tuple[float, ...]:
    """``values`` as increasing distinct durations (s), each at least one sample long."""
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) \
            or (not values and not empty):
        raise OptionError(f"{{option}} must be a sequence of durations in seconds, got "
                          f"{values!r}", name)
    out = sorted(_positive(v, name) for v in values)
    if len(set(out)) != len(out):
        raise OptionError(f"{{option}} repeats a duration: {values!r}", name)
    short = [v for v in out if v * rate < 1]
    if short:
        raise OptionError(f"{{option}}: {short[0]:g} s is shorter than one sample at "
                          f"{rate:g} Hz", name)
    return tuple(out)


def _names(values: object, name: str) -> tuple[str, ...]:
    if isinstance(values, (str, bytes)) or not isinstance(values, Sequence) \
            or not all(isinstance(v, str) and v for v in values):
        raise OptionError(f"{{option}} must be a sequence of column names, got {values!r}",
                          name)
    return tuple(values)

"""A record's three segments: training, evaluation (model choices) and prediction (the score).

The harness splits by duration (Tamazin et al.'s (2013) 3 min + 3 min, the rest predicted), the
residual loop by fraction; both judge a model on a segment it was not fitted on, and choose
nothing on the prediction segment.  :class:`SplitSpec` is a split as a user gives it, before
the record is read: each length a duration or a percent of the record.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass

from ..core.exceptions import InputError

#: Seconds in each unit of a duration; ``%`` is a percent of the record.
_SECONDS = {"s": 1.0, "min": 60.0, "h": 3600.0}
#: The default split of the steps that judge a model on records of any length (the residual
#: loop, the six-axis workflow): half the record fitted, a fifth evaluated, the rest predicted.
#: In proportion to the record, so that a long record's fit is not its warm-up alone.
TRAIN_FRACTION, EVALUATE_FRACTION = 0.5, 0.2


@dataclass(frozen=True)
class Split:
    """Sample ranges of the three segments."""

    train: slice
    evaluate: slice
    predict: slice

    @classmethod
    def by_duration(
        cls, n: int, rate: float, train_s: float, evaluate_s: float, min_predict: int = 1,
        why: str = "",
    ) -> Split:
        """Split ``n`` samples at ``rate`` Hz: ``train_s`` s, then ``evaluate_s`` s, then the rest.

        Raises
        ------
        InputError
            If a segment is empty or the prediction segment is shorter than ``min_predict``
            (``why`` says what needs them).
        """
        a, b = round(train_s * rate), round((train_s + evaluate_s) * rate)
        if a < 1 or b <= a:
            raise InputError(f"the split {train_s:g} s / {evaluate_s:g} s leaves an empty "
                             "training or evaluation segment")
        if n - b < min_predict:
            raise InputError(
                f"the record has {n} samples ({n / rate:.6g} s at {rate:g} Hz); the split "
                f"{train_s:g} s / {evaluate_s:g} s leaves {max(n - b, 0)} samples to predict, "
                f"{min_predict} are needed{why}"
            )
        return cls(slice(0, a), slice(a, b), slice(b, n))

    @classmethod
    def by_fraction(cls, n: int, train: float, evaluate: float) -> Split:
        """Split ``n`` samples: the first ``train`` of them, the next ``evaluate``, the rest.

        Raises
        ------
        InputError
            If a segment is empty.
        """
        a, b = cls.fraction_bounds(n, train, evaluate)
        if a < 1 or b <= a or b >= n:
            raise InputError(f"the split {train:g} / {evaluate:g} of {n} samples leaves an empty "
                             "segment")
        return cls(slice(0, a), slice(a, b), slice(b, n))

    @staticmethod
    def fraction_bounds(n: int, train: float, evaluate: float) -> tuple[int, int]:
        """Return where the evaluation and the prediction segments of :meth:`by_fraction` start."""
        return round(train * n), round((train + evaluate) * n)

    def describe(self, rate: float) -> str:
        """Say the segments' bounds and shares: ``fitting 0-300 s (50 %), evaluation ...``."""
        n = self.predict.stop
        return ", ".join(
            f"{name} {part.start / rate:.6g}-{part.stop / rate:.6g} s "
            f"({100 * (part.stop - part.start) / n:.3g} %)"
            for name, part in zip(("fitting", "evaluation", "prediction"),
                                  (self.train, self.evaluate, self.predict)))

    def items(self) -> list[tuple[str, slice]]:
        """``("train", slice)``, ``("evaluate", ...)``, ``("predict", ...)``, in order."""
        return [("train", self.train), ("evaluate", self.evaluate), ("predict", self.predict)]


@dataclass(frozen=True)
class SplitSpec:
    """The training and evaluation lengths of a split, each a duration or a percent.

    A length is ``(value, unit)`` with ``unit`` one of ``"s"``, ``"min"``, ``"h"``
    or ``"%"`` (of the record); :meth:`seconds` and :meth:`fractions` resolve both
    against a record of ``n`` samples at ``rate`` Hz.

    Examples
    --------
    >>> spec = SplitSpec.parse("3min,25%")
    >>> spec.seconds(60_000, 100.0), spec.fractions(60_000, 100.0)
    ((180.0, 150.0), (0.3, 0.25))
    >>> str(spec)
    '3min,25%'
    """

    train: tuple[float, str]
    evaluate: tuple[float, str]

    def __post_init__(self) -> None:
        """Check both lengths: a positive number and a unit each, leaving some to predict.

        Raises
        ------
        InputError
            A length that is not ``(value, unit)`` with a finite value > 0 and a unit among
            ``s``, ``min``, ``h`` and ``%``, or percents that add up to 100 or more.
        """
        for name in ("train", "evaluate"):
            length = getattr(self, name)
            value, unit = length if isinstance(length, tuple) and len(length) == 2 else (0, "")
            if (isinstance(value, bool) or not isinstance(value, (int, float))
                    or not math.isfinite(value) or value <= 0 or unit not in (*_SECONDS, "%")):
                raise InputError(f"the {name} length must be (value, unit) with a value > 0 and "
                                 f"a unit among s, min, h and %, got {length!r}")
        percent = sum(value for value, unit in (self.train, self.evaluate) if unit == "%")
        if percent >= 100:
            raise InputError(f"the split {str(self)!r} takes {percent:g}% of the record for "
                             "training and evaluation and leaves nothing to predict")

    @classmethod
    def parse(cls, text: str) -> SplitSpec:
        """Read ``TRAIN,EVALUATE``, each with its unit: ``180s,180s`` or ``50%,20%``.

        Raises
        ------
        InputError
            Not two positive lengths with units (a bare number is refused: seconds or a
            fraction?), or percents that leave nothing to predict.
        """
        parsed = [_length(part) for part in text.split(",")]
        lengths = [length for length in parsed if length is not None]
        if len(parsed) != 2 or len(lengths) != 2:
            raise InputError(f"expected TRAIN,EVALUATE with units: durations like 180s,180s "
                             f"(s, min or h) or percents of the record like 50%,20%, got {text!r}")
        return cls(lengths[0], lengths[1])

    def seconds(self, n: int, rate: float) -> tuple[float, float]:
        """Return the training and evaluation durations of ``n`` samples at ``rate`` Hz."""
        return _seconds(self.train, n, rate), _seconds(self.evaluate, n, rate)

    def fractions(self, n: int, rate: float) -> tuple[float, float]:
        """Return the training and evaluation fractions of a record of ``n`` samples at ``rate`` Hz.

        Raises
        ------
        InputError
            If the two leave nothing of the record to predict.
        """
        train, evaluate = (value / 100 if unit == "%" else _seconds((value, unit), n, rate)
                           * rate / n for value, unit in (self.train, self.evaluate))
        if train + evaluate >= 1:
            raise InputError(f"the split {self} leaves nothing of the record ({n} samples, "
                             f"{n / rate:.6g} s at {rate:g} Hz) to predict")
        return train, evaluate

    def __str__(self) -> str:
        """Write the split as it is parsed: ``180s,180s``, ``50%,20%``."""
        return ",".join(f"{value:g}{unit}" for value, unit in (self.train, self.evaluate))


#: :data:`TRAIN_FRACTION` and :data:`EVALUATE_FRACTION` as a split a user gives: ``50%,20%``.
PROPORTIONAL = SplitSpec((100 * TRAIN_FRACTION, "%"), (100 * EVALUATE_FRACTION, "%"))


def _length(text: str) -> tuple[float, str] | None:
    """``(value, unit)`` of a positive length like ``180s``, ``3min`` or ``50%``, else None."""
    match = re.fullmatch(r"\s*(.+?)\s*(s|min|h|%)\s*", text)
    if match is None:
        return None
    try:
        value = float(match[1])
    except ValueError:
        return None
    return (value, match[2]) if math.isfinite(value) and value > 0 else None


def _seconds(length: tuple[float, str], n: int, rate: float) -> float:
    value, unit = length
    return value / 100 * n / rate if unit == "%" else value * _SECONDS[unit]

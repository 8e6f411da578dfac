"""A record's three segments: training, evaluation (model choices) and prediction (the score).

The harness splits by duration (the FOS paper's 3 min + 3 min, the rest predicted), the
residual loop by fraction; both judge a model on a segment it was not fitted on, and choose
nothing on the prediction segment.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..core.exceptions import InputError


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
        a, b = round(train * n), round((train + evaluate) * n)
        if a < 1 or b <= a or b >= n:
            raise InputError(f"the split {train:g} / {evaluate:g} of {n} samples leaves an empty "
                             "segment")
        return cls(slice(0, a), slice(a, b), slice(b, n))

    def items(self) -> list[tuple[str, slice]]:
        """``("train", slice)``, ``("evaluate", ...)``, ``("predict", ...)``, in order."""
        return [("train", self.train), ("evaluate", self.evaluate), ("predict", self.predict)]

"""A fitted model bound to the inputs of one record, for code that treats every model alike."""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
from numpy.typing import ArrayLike

from .model import FOSModel


class BoundModel:
    """A fitted :class:`FOSModel` with the full-length inputs of one record.

    Code that treats every model alike (the harness, the metrics) calls
    ``predict(y)`` and ``simulate(y_init, n_steps)`` with the output alone; this
    supplies the exogenous channels and user columns, cut to the same samples
    (sample ``n`` of ``y`` is sample ``n`` of the record).
    """

    def __init__(self, model: FOSModel, inputs: Mapping[str, np.ndarray]) -> None:
        self.model = model
        self.inputs = {k: np.asarray(v, dtype=float) for k, v in inputs.items()}

    @property
    def lag_window_(self) -> int:
        """Past samples the model reads (see :attr:`FOSModel.lag_window_`)."""
        return self.model.lag_window_

    @property
    def n_terms_(self) -> int:
        """Number of selected terms (see :attr:`FOSModel.n_terms_`)."""
        return self.model.n_terms_

    def is_stable(self) -> bool:
        """Whether the model's linear part is stable (see :meth:`FOSModel.is_stable`)."""
        return self.model.is_stable()

    def _cut(self, n: int) -> dict[str, np.ndarray] | None:
        return {k: v[:n] for k, v in self.inputs.items()} if self.inputs else None

    def predict(self, y: np.ndarray, *, start: int = 0) -> np.ndarray:
        """Predict ``y``, the first ``len(y)`` samples of the record, one step ahead.

        From sample ``start`` on; see :meth:`FOSModel.predict`.
        """
        return self.model.predict(y, self._cut(len(y)), start=start)

    def simulate(self, y_init: np.ndarray, n_steps: int,
                 noise: ArrayLike | None = None) -> np.ndarray:
        """Free run after ``y_init`` (the record's first samples) for ``n_steps`` samples.

        Without levels only the last ``lag_window_`` samples of the past reach
        the run, so only they (and the inputs from there on) are passed on.
        """
        start, n0 = len(y_init), self.lag_window_
        cut = 0 if self.model.spec_.levels else max(start - n0, 0)
        inputs = ({k: v[cut : start + n_steps] for k, v in self.inputs.items()}
                  if self.inputs else None)
        return self.model.simulate(np.asarray(y_init)[cut:], n_steps, inputs, noise)

    def free_runs(self, y: np.ndarray, starts: Sequence[int], n_steps: int) -> np.ndarray:
        """:meth:`FOSModel.free_runs` on the record's first ``len(y)`` samples."""
        return self.model.free_runs(y, starts, n_steps, self._cut(len(y)))

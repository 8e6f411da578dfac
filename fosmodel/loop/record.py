"""The record the residual loop works on: the output, its channels, and its sessions.

Several recordings of one sensor are laid end to end, each a *session*: every
column derived from time or from a channel (:mod:`fosmodel.core.derived`) restarts
at its session's first sample, as it would on that recording alone.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field

import numpy as np

from ..core.derived import derive


@dataclass(frozen=True)
class LoopRecord:
    """The modelled output ``y`` and the other channels, over one or several sessions.

    ``sessions`` are the sample ranges of the sessions in ``y`` (one: the whole record),
    ``names`` what each is called.  Derived columns are computed once and kept.
    """

    y: np.ndarray
    channels: Mapping[str, np.ndarray]
    rate: float
    sessions: tuple[slice, ...]
    names: tuple[str, ...] = ()
    _derived: dict[str, np.ndarray] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def single(cls, y: np.ndarray, channels: Mapping[str, np.ndarray],
               rate: float) -> LoopRecord:
        """One recording: a single session."""
        return cls(y, channels, rate, (slice(0, len(y)),), ("record",))

    @property
    def n(self) -> int:
        """Samples in all."""
        return len(self.y)

    def derive(self, name: str) -> np.ndarray:
        """Return the derived column ``name`` over the record, computed session by session.

        The same array each time it is asked for (read-only).
        """
        if name not in self._derived:
            parts = [derive(name, s.stop - s.start, self.rate,
                            {k: v[s] for k, v in self.channels.items()}, {})
                     for s in self.sessions]
            values = parts[0] if len(parts) == 1 else np.concatenate(parts)
            values.flags.writeable = False
            self._derived[name] = values
        return self._derived[name]

    def forget(self, keep: set[str]) -> None:
        """Drop the derived columns not in ``keep`` (the trials' columns, once judged)."""
        for name in [k for k in self._derived if k not in keep]:
            del self._derived[name]

"""The record the loader returns: validated columns, their sample rate and time.

Beside them, what the loader found (:func:`fosmodel.io.loader.load_record` builds it).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from ..core.exceptions import InputError
from ..core.validation import did_you_mean


@dataclass
class Record:
    """A validated record: equally long, finite float columns and their sample rate.

    Attributes
    ----------
    source : str
        File it came from.
    data : dict of str to ndarray
        Numeric columns in file order (the time column excluded), scaled as asked.
    rate : float or None
        Sample rate in Hz (None when the file has no time and none was given).
    time : ndarray or None
        Time column in seconds, if the file had one (sample number / rate with
        ``uniform=True``).
    notes : list of str
        What the loader found and did that deserves the user's attention.
    metadata : dict of str to str
        Preamble entries other than the sample rate, e.g. ``{"Logging Type": "1"}``, or
        the format and topic of a log.
    outliers : dict of str to ndarray
        For each column with outliers, their sample indices in the file (before any drop).
    segments : list of slice or None
        With ``gaps="segments"``, the contiguous runs of samples between the
        time column's gaps; None for a contiguous record.
    units : dict of str to str
        The units of the columns whose file says them (a ROS bag's or a ULog's
        ``gx``: ``"rad/s"``) or whose name spells them (``gx_dps``: ``"deg/s"``,
        ``ax_mps2``: ``"m/s^2"``, ``temp_c``: ``"degC"``;
        :func:`fosmodel.io.column_names.units_from_name`); a column scaled with ``scale``
        loses its entry.
    held : dict of str to str
        With ``load_record(..., hold=True)``, the columns whose content would have refused the
        record, each with the one-line refusal: refused if analysed, else left out with a note
        (:func:`fosmodel.io.content.settle`).
    """

    def require_contiguous(self, what: str) -> None:
        """Refuse a record in segments for ``what``, which needs one contiguous run."""
        if self.segments is not None and len(self.segments) > 1:
            raise InputError(f"{self.source}: {what} needs a contiguous record, this one has "
                             f"{len(self.segments)} segments; pass gaps='fill' instead of "
                             "gaps='segments'")

    source: str
    data: dict[str, np.ndarray]
    rate: float | None
    time: np.ndarray | None = None
    notes: list[str] = field(default_factory=list)
    metadata: dict[str, str] = field(default_factory=dict)
    outliers: dict[str, np.ndarray] = field(default_factory=dict)
    segments: list[slice] | None = None
    units: dict[str, str] = field(default_factory=dict)
    held: dict[str, str] = field(default_factory=dict)

    @property
    def n_samples(self) -> int:
        """Number of samples of every column."""
        return len(next(iter(self.data.values())))

    @property
    def names(self) -> list[str]:
        """The column names, in the record's order."""
        return list(self.data)

    def column(self, name: str) -> np.ndarray:
        """One column by name; a missing name gets the closest existing one suggested."""
        if name not in self.data:
            raise InputError(
                f"{self.source}: no column {name!r}{did_you_mean(name, self.data)}; "
                f"columns: {', '.join(self.data)}"
            )
        return self.data[name]

    def require_rate(self) -> float:
        """Return the sample rate in Hz.

        Raises
        ------
        InputError
            The record has no time column and was given no rate.
        """
        if self.rate is None:
            raise InputError(f"{self.source}: no time column; give the sample rate with rate=HZ")
        return self.rate

    def between(self, start: float | None = None, stop: float | None = None) -> Record:
        """Return the stretch from ``start`` to ``stop`` seconds after the first sample.

        Every column, the time and the segments are cut alike, and a note says what was
        kept; ``start`` defaults to the first sample, ``stop`` to the record's end.

        Raises
        ------
        InputError
            A ``start`` or ``stop`` that is negative or beyond the record, or a ``start`` not
            before ``stop``, or no rate.
        """
        rate = self.require_rate()
        n = self.n_samples
        t = self.time - self.time[0] if self.time is not None else np.arange(n) / rate
        length = float(t[-1]) + 1.0 / rate
        lo, hi = 0.0 if start is None else float(start), length if stop is None else float(stop)
        for name, value in (("start", start), ("stop", stop)):
            if value is not None and not 0 <= value <= length:
                raise InputError(f"{self.source}: {name}={value:g} s is beyond the record, "
                                 f"which lasts {length:g} s")
        if lo >= hi:
            raise InputError(f"{self.source}: start={lo:g} s is not before stop={hi:g} s")
        i0, i1 = (int(i) for i in np.searchsorted(t, [lo, hi], side="left"))
        if i1 - i0 < 2:
            raise InputError(f"{self.source}: from {lo:g} s to {hi:g} s the record holds "
                             f"{i1 - i0} sample(s)")
        segments = None if self.segments is None else [
            slice(max(s.start, i0) - i0, min(s.stop, i1) - i0) for s in self.segments
            if s.stop > i0 and s.start < i1]
        note = (f"start={lo:g} s and stop={hi:g} s: kept that stretch of the record's "
                f"{length:g} s ({i1 - i0} of {n} samples)")
        return replace(self, data={k: v[i0:i1] for k, v in self.data.items()},
                       time=None if self.time is None else self.time[i0:i1],
                       notes=[*self.notes, note], segments=segments)

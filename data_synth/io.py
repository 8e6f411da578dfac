"""Write a record as the CSV that ``fosmodel fit/study`` read, plus its truth sidecar.

The CSV has one header row of column names (``time`` first when written, then
the target, then the other columns) and one row per sample; every value is
written with Python's shortest round-trip representation (``repr``), so the
float64 values are recovered exactly and the same record always gives the same
bytes.  Nothing else goes into the file: no comment, no metadata, so an
undeclared effect leaves no trace there.  The ground truth goes to
``<stem>.truth.json`` beside it.  The sessions of a multi-session record go to
``<stem>_s1.csv``, ``<stem>_s2.csv``... (:func:`write_sessions`).
"""

from __future__ import annotations

import copy
import json
import os
from collections.abc import Sequence
from pathlib import Path

from data_synth.record import SynthRecord
from fosmodel.io.output import atomic_write, write_text

_CHUNK = 65536


def truth_path(path_csv: str | os.PathLike[str]) -> Path:
    """Sidecar path of a CSV path: ``out/rec.csv`` -> ``out/rec.truth.json``."""
    return Path(path_csv).with_suffix(".truth.json")


def truth_json(record: SynthRecord, *, time: bool = True) -> str:
    """The sidecar text: the record's truth as indented JSON (strict: no NaN/inf)."""
    truth = copy.deepcopy(record.truth)
    if time:
        truth["columns"]["time"]["written"] = True
    else:
        truth["columns"].pop("time", None)
    return json.dumps(truth, indent=2, allow_nan=False) + "\n"


def write_record(
    record: SynthRecord, path_csv: str | os.PathLike[str], *, time: bool = True
) -> tuple[Path, Path]:
    """Write ``record`` to ``path_csv`` and its truth to ``<stem>.truth.json``.

    Parameters
    ----------
    record : SynthRecord
        The record.
    path_csv : path-like
        Destination CSV; its directory must exist.  Both files are written
        atomically (a failed write leaves the previous files).
    time : bool
        Write the leading ``time`` column (seconds, ``n/rate``).

    Returns
    -------
    (Path, Path)
        The CSV and sidecar paths.
    """
    path_csv = Path(path_csv)
    sidecar = truth_path(path_csv)
    text = truth_json(record, time=time)
    names = (["time"] if time else []) + list(record.columns)
    values = ([record.time()] if time else []) + list(record.columns.values())
    lists = [v.tolist() for v in values]
    row = ",".join(["%r"] * len(lists)) + "\n"
    with atomic_write(path_csv, "w") as fh:
        fh.write(",".join(names) + "\n")
        for start in range(0, record.n_samples, _CHUNK):
            chunk = [col[start : start + _CHUNK] for col in lists]
            fh.write("".join(row % r for r in zip(*chunk)))
    write_text(sidecar, text)
    return path_csv, sidecar


def session_paths(path_csv: str | os.PathLike[str], count: int) -> list[Path]:
    """The CSV paths of ``count`` sessions: ``out/rec.csv`` -> ``out/rec_s1.csv``, ..."""
    path = Path(path_csv)
    return [path.with_name(f"{path.stem}_s{k}{path.suffix}") for k in range(1, count + 1)]


def write_sessions(
    records: Sequence[SynthRecord], path_csv: str | os.PathLike[str], *, time: bool = True
) -> list[tuple[Path, Path]]:
    """Write each session with :func:`write_record`, one file each (:func:`session_paths`).

    Returns
    -------
    list of (Path, Path)
        The CSV and sidecar paths, session by session.
    """
    return [write_record(rec, path, time=time)
            for rec, path in zip(records, session_paths(path_csv, len(records)))]

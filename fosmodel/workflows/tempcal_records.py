"""The records of a thermal calibration: each file a session, its axes and its temperature.

A table (CSV, ``.npy``, Parquet) is one group: its gyro and accelerometer columns and the
temperature column they share.  A PX4 ULog gives two, each with its own temperature and
``device_id``: the ``sensor_gyro`` and ``sensor_accel`` topics of one ``instance`` (the
sensor PX4's thermal calibration fits, ``TC_G<i>``/``TC_A<i>``), unless a ``topic`` is
chosen.  Every file must hold the same groups and axes.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from ..core.exceptions import InputError
from ..core.validation import did_you_mean
from ..io.loader import load_record
from ..io.record import Record
from ..io.ulog import is_ulog, ulog_imu_topics
from ..noise.axes import UnitsSpec
from ..noise.checks import check_units
from .imu import TEMPERATURE, record_axes
from .tempcal import AxisGroup, TempSession

#: The ULog topics a thermal calibration reads, by the group each makes.
ULOG_TOPICS = {"gyro": "sensor_gyro", "accel": "sensor_accel"}


def tempcal_groups(paths: Sequence[str | Path], *, columns: Sequence[str] | None = None,
                   units: UnitsSpec | None = None, temperature: str | None = None,
                   instance: int = 0, topic: str | None = None,
                   notes: list[str] | None = None, **loader: object) -> list[AxisGroup]:
    """Read every file as a session and return its groups of axes over all of them.

    Parameters
    ----------
    paths : sequence of path
        One file per session.
    columns : sequence of str, optional
        The axes, ``COLUMN`` or ``COLUMN:SENSOR:UNITS`` each (default: every column whose name
        or file tells a gyro or an accelerometer).
    units : UnitsSpec, optional
        Units given for every column or per column.
    temperature : str, optional
        The temperature column (default: one named like ``temperature``, ``temp_c``).
    instance : int
        A ULog's sensor instance (``sensor_gyro:<instance>``).
    topic : str, optional
        One topic of a log to read instead.
    notes : list of str, optional
        Collects the loader's notes, each after its file.
    **loader
        :func:`fosmodel.io.load_record`'s options (``rate``, ``gaps``, ...).

    Raises
    ------
    InputError
        A file without a temperature column, whose axes differ from the first file's, whose
        accelerometers' units gravity contradicts, or that the loader refuses.
    """
    per_file: list[dict[str, tuple[AxisGroup, TempSession]]] = []
    for path in paths:
        found = {}
        for name, rec in _records(Path(path), instance, topic, loader):
            for note in rec.notes:
                (notes if notes is not None else []).append(f"{path}: {note}")
            pair = _session(rec, name, columns, units, temperature)
            if pair is not None:
                found[name] = pair
        per_file.append(found)
    first = per_file[0]
    read = [a.column for group, _ in first.values() for a in group.axes]
    missing = [c for c in (s.split(":")[0] for s in columns or ()) if c not in read]
    if missing:
        raise InputError(f"{paths[0]}: no column {missing[0]!r}{did_you_mean(missing[0], read)}; "
                         f"its axes: {', '.join(read) or 'none'}")
    for path, found in zip(paths[1:], per_file[1:]):
        for name in {*first, *found}:
            mine = [a.column for a in found[name][0].axes] if name in found else []
            theirs = [a.column for a in first[name][0].axes] if name in first else []
            if mine != theirs:
                raise InputError(f"{path}: its {name} axes ({', '.join(mine) or 'none'}) differ "
                                 f"from {paths[0]}'s ({', '.join(theirs) or 'none'}); every "
                                 "session must hold the same axes")
    out = []
    for name, (group, _) in first.items():
        out.append(AxisGroup(name, group.axes, group.temperature,
                             tuple(found[name][1] for found in per_file), group.device_id))
    return out


def _records(path: Path, instance: int, topic: str | None,
             loader: Mapping[str, Any]) -> list[tuple[str, Record]]:
    """Return the file's records, each with the name of its group."""
    if not is_ulog(path) or topic:
        return [("imu" if not is_ulog(path) else topic or "imu",
                 load_record(path, topic=topic, **loader))]
    names = {t.name for t in ulog_imu_topics(path)}
    out = []
    for group, base in ULOG_TOPICS.items():
        wanted = f"{base}:{instance}"
        name = wanted if wanted in names else base if instance == 0 and base in names else None
        if name:
            out.append((group, load_record(path, topic=name, **loader)))
    if not out:
        raise InputError(f"{path}: no sensor_gyro or sensor_accel topic of instance {instance} "
                         f"(its IMU topics: {', '.join(sorted(names)) or 'none'}); choose "
                         "another with instance=N, or one topic with topic=")
    return out


def _session(rec: Record, group: str, columns: Sequence[str] | None,
             units: UnitsSpec | None, temperature: str | None
             ) -> tuple[AxisGroup, TempSession] | None:
    """Return one record's group (its axes, temperature and device) and its session.

    None for a record that holds none of the ``columns`` asked for (a ULog's other topic).
    """
    named = temperature or next((c for c in rec.names if TEMPERATURE.match(c)), None)
    if named is None:
        raise InputError(f"{rec.source}: no temperature column (columns: "
                         f"{', '.join(rec.names)}); a thermal calibration needs one: name it "
                         "with temperature=COLUMN")
    wanted = [c for c in columns if c.split(":")[0] in rec.names] if columns else None
    if wanted == []:
        return None
    axes, _ = record_axes(rec, wanted, units, named)
    check_units({a.column: rec.column(a.column) for a in axes}, axes, rec.source)
    device = rec.metadata.get("device id")
    session = TempSession(rec.source, {a.column: rec.column(a.column) for a in axes},
                          rec.column(named), rec.require_rate())
    return AxisGroup(group, tuple(axes), named, (session,),
                     int(device) if device else None), session

"""A fleet of records: the six-axis workflow of each, in this process or on a Dask cluster.

Characterisation comes in batches (tens to thousands of IMUs).  Each record is one task: it
is read, its axes go through the chosen steps of the six-axis workflow (the Allan analysis,
the model-order study and the residual loop, as :func:`fosmodel.workflows.imu.run_imu` runs
them) and its results are written to the store, in a folder of its own published in one
rename with its completion marker inside.  A rerun skips the records whose marker is there
and matches the file and the configuration, so an interrupted run resumes without redoing
them; a record's folder stays whatever happens to the others (it is published outside the
command line's all-or-nothing, :func:`fosmodel.io.journal.durable`).  A record refused
leaves nothing: no folder, no marker (the error names it; a rerun does it again), and a fleet
refused whole leaves no store.  The tasks run one after the other in this process, or on
the workers of a Dask client (:func:`fosmodel.study.runner.dask_client`); each limits BLAS to
one thread, so both give the same bits.  On a cluster, the workers read the records and write
the store: both must be on a file system they share with this process.

Layout of the store::

    fleet.md fleet.csv fleet.tex   the summary: a row per record and axis
    RECORD/rows.csv                 the record's rows of the summary
    RECORD/done.json                the completion marker: file, configuration, run times
    RECORD/report/                  the record's reports (``reports=True``)
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

import pandas as pd
from tqdm import tqdm

from ..core.exceptions import InputError
from ..io.journal import durable
from ..io.output import write_tables
from .fleet_record import MARKER, FleetConfig, fingerprint, record_name, run_record
from .imu import STEPS

if TYPE_CHECKING:  # only for the annotations: Dask is an optional extra
    from distributed import Client

__all__ = ["MARKER", "FleetConfig", "FleetResult", "record_name", "run_fleet", "run_record"]


@dataclass
class FleetResult:
    """The fleet's summary and what this run did.

    ``table`` has a row per record and axis; ``ran`` names the records computed in this run,
    ``skipped`` those found finished in the store; ``seconds`` is each record's task time (s),
    as its marker holds it.
    """

    table: pd.DataFrame
    ran: list[str]
    skipped: list[str]
    seconds: dict[str, float]


def run_fleet(
    files: Sequence[str | os.PathLike[str]], store: str | os.PathLike[str],
    config: FleetConfig | None = None, *, client: Client | None = None, progress: bool = False,
) -> FleetResult:
    """Run the chosen steps on every record not yet finished in ``store``; tabulate them all.

    Parameters
    ----------
    files : sequence of path-like
        The records, one IMU each; their names (:func:`record_name`) must differ.
    store : path-like
        The results store (created); see the module's documentation for its layout.
    config : FleetConfig, optional
    client : distributed.Client, optional
        Run the records on its Dask cluster; by default one after the other in this process.
    progress : bool
        Show one progress bar over the whole fleet on stderr.

    Returns
    -------
    FleetResult
        Its table also written as ``fleet.md``, ``fleet.csv`` and ``fleet.tex`` in ``store``.

    Raises
    ------
    InputError
        No file, a file missing, two records of one name, an unknown step (before any
        work); or a record refused (the first to fail is named, after every other record has
        run and been stored).
    """
    config = config or FleetConfig()
    names = _names(files)
    _check_steps(config.steps)
    store = Path(store)  # made with the first record stored: a fleet refused whole leaves none
    prints = {name: fingerprint(path, config) for name, path in names.items()}
    todo = [n for n in names if not _finished(store / n, prints[n])]
    todo.sort(key=lambda n: -_size(names[n]))  # longest first: the last task is a short one
    failures: dict[str, BaseException] = {}
    with tqdm(total=len(names), initial=len(names) - len(todo), disable=not progress,
              file=sys.stderr, desc="fleet", unit="record") as bar, durable():
        for name, error in _run(todo, names, store, config, client):
            if error is not None:
                failures[name] = error
            bar.update()
    if failures:
        _raise(failures, len(names), store)
    markers = {n: json.loads((store / n / MARKER).read_text()) for n in names}
    table = pd.concat([pd.read_csv(store / n / "rows.csv") for n in names], ignore_index=True)
    write_tables(table, store, "fleet", "Fleet summary: a row per record and axis",
                 report="fleet")
    return FleetResult(table, [n for n in names if n in todo],
                       [n for n in names if n not in todo],
                       {n: markers[n]["seconds"]["total"] for n in names})


def _names(files: Sequence[str | os.PathLike[str]]) -> dict[str, str]:
    if not files:
        raise InputError("no record in the fleet")
    names: dict[str, str] = {}
    for path in files:
        name = record_name(path)
        if not Path(path).exists():  # before any work, as every command does
            raise InputError(f"{path}: no such file")
        if name in names:
            raise InputError(f"two records named {name!r} ({names[name]} and {path}): the "
                             "store keeps a folder per name; rename one")
        names[name] = os.fspath(path)
    return names


def _check_steps(steps: Sequence[str]) -> None:
    unknown = [s for s in steps if s not in STEPS]
    if unknown or not steps:
        raise InputError(f"unknown step {', '.join(map(repr, unknown)) or 'list (empty)'}; "
                         f"the steps are {', '.join(STEPS)}")


def _finished(folder: Path, print_: str) -> bool:
    try:
        return json.loads((folder / MARKER).read_text())["fingerprint"] == print_
    except (OSError, ValueError, KeyError):
        return False


def _size(path: str) -> int:
    p = Path(path)
    return sum(f.stat().st_size for f in p.rglob("*") if f.is_file()) if p.is_dir() \
        else p.stat().st_size


def _run(todo: list[str], names: Mapping[str, str], store: Path, config: FleetConfig,
         client: Client | None) -> Iterator[tuple[str, BaseException | None]]:
    """Run the records' tasks; yield each name as it ends, with its error if it raised."""
    if client is None:
        for name in todo:
            try:
                run_record(names[name], store, config)
            except Exception as exc:  # the others still run; raised at the end
                yield name, exc
            else:
                yield name, None
        return
    from distributed import as_completed

    futures = {client.submit(run_record, names[n], store, config, key=f"fleet-{n}-{i}",
                             pure=False): n for i, n in enumerate(todo)}
    for future in as_completed(futures):
        if future.status == "finished":
            yield futures[future], None
        else:  # raised, or cancelled (its worker lost)
            yield futures[future], (future.exception() if future.status == "error" else
                                    RuntimeError(f"the task was {future.status}"))


def _raise(failures: Mapping[str, BaseException], total: int, store: Path) -> None:
    name, error = next(iter(failures.items()))
    if not isinstance(error, InputError):
        raise error
    done = total - len(failures)
    raise InputError(f"record {name}: {error} ({len(failures)} of {total} records failed"
                     + (f"; the other {done} are stored in {store}, and a rerun does only the "
                        "failed)" if done else ")"))

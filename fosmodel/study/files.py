"""Studies of several columns of several files: one plan per column, one report each.

Each (file, column) gets its own report directory, named after both
(:func:`report_name`: ``imu1_gx`` for column ``gx`` of ``imu1.csv.gz``);
:func:`check_report_names` refuses, before any work, two that would share one.
:func:`plan_columns` plans a record's columns, :func:`write_reports` writes every
report at once (one record's in the output directory itself, several in a
directory each with their best rows side by side), and :func:`overview` and
:func:`studies_json` give the console table and the JSON.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import NamedTuple

import pandas as pd

from ..core.exceptions import InputError
from ..io.loader import Record
from ..io.output import report_directory, write_tables
from .harness import StudyConfig, StudyPlan, StudyResult, plan_study
from .report import paper_table, study_table, write_study

_COMPRESSED = (".gz", ".bz2", ".xz")
#: The columns of the overview of several records (besides the MSE and outage columns).
_OVERVIEW = ("Record", "Protocol", "Method", "Data", "Order L")


class ColumnStudy(NamedTuple):
    """One column of one file in a study, with its plan and the name of its report."""

    file: str
    column: str
    name: str
    plan: StudyPlan


def report_name(path: str, column: str) -> str:
    """``imu1_gx`` for column gx of ``imu1.csv(.gz)``: the subdirectory of its report."""
    p = Path(path)
    stem = Path(p.stem).stem if p.suffix in _COMPRESSED else p.stem
    return re.sub(r"[^\w.-]+", "_", f"{stem}_{column}")


def check_report_names(files: Sequence[str], columns: Sequence[str]) -> None:
    """Refuse two (file, column) pairs whose reports would share a directory.

    Raises
    ------
    InputError
        No column, or two pairs with the same :func:`report_name`.
    """
    if not columns:
        raise InputError("no column given")
    seen: dict[str, tuple[str, str]] = {}
    for path in files:
        for column in columns:
            name = report_name(path, column)
            if name in seen:
                raise InputError(f"{seen[name][0]} column {seen[name][1]!r} and {path} column "
                                 f"{column!r} would both be reported in {name}/; give each "
                                 "file a distinct name")
            seen[name] = (path, column)


def plan_columns(record: Record, path: str,
                 configs: Mapping[str, StudyConfig]) -> list[ColumnStudy]:
    """Check and plan each column of ``configs`` in ``record`` under its own config.

    Each config carries its column's sensor and units; ``path`` names the file in messages.

    Raises
    ------
    InputError
        The record has gaps, or a column cannot be studied (the message names file and column).
    """
    record.require_contiguous("the model-order study")
    out = []
    for column, config in configs.items():
        try:
            plan = plan_study(record.column(column), config)
        except InputError as exc:
            raise InputError(f"{path}, column {column!r}: {exc}") from None
        out.append(ColumnStudy(path, column, report_name(path, column), plan))
    return out


def _title(study: ColumnStudy, title: str | None, single: bool) -> str:
    """``title`` for a lone study; before the study's own title when there are several."""
    own = f"{study.column} of {Path(study.file).name}"
    if single:
        return title or own
    return f"{title}: {own}" if title else own


def write_reports(studies: Sequence[ColumnStudy], results: Sequence[StudyResult], out: Path,
                  title: str | None = None, inputs: Sequence[str] = ()) -> None:
    """One study's report in ``out``; several in a directory each and their best rows.

    Everything is written beside ``out`` first and moved into place, so a failure leaves
    ``out`` as it was, and nothing replaces one of ``inputs``
    (:func:`fosmodel.io.output.report_directory`).
    """
    single = len(studies) == 1
    with report_directory(out, inputs) as tmp:
        for study, result in zip(studies, results):
            write_study(result, tmp if single else tmp / study.name,
                        _title(study, title, single))
        if not single:
            write_tables(combined_best(studies, results), tmp, "best",
                         f"{title or 'Studies'}: the best configuration of each method on every "
                         "record", report=title or "studies")


def combined_best(studies: Sequence[ColumnStudy],
                  results: Sequence[StudyResult]) -> pd.DataFrame:
    """Every study's best rows in one table, led by its report's name, file and column."""
    lead = ["Record", "File", "Column"]
    frame = pd.concat([study_table(result, result.best()).assign(
        Record=study.name, File=study.file, Column=study.column)
        for study, result in zip(studies, results)], ignore_index=True)
    return frame[lead + [c for c in frame.columns if c not in lead]]


def overview(studies: Sequence[ColumnStudy], results: Sequence[StudyResult]) -> pd.DataFrame:
    """Return the comparison table of one study, or the main columns of every study's best."""
    if len(studies) == 1:
        return paper_table(results[0])
    table = combined_best(studies, results)
    return table[[c for c in table.columns
                  if c in _OVERVIEW or c.startswith(("MSE", "Outage position"))]]


def studies_json(studies: Sequence[ColumnStudy], results: Sequence[StudyResult]) -> dict:
    """One study as ``StudyResult.to_json_dict``; several as a list of those."""
    if len(studies) == 1:
        return results[0].to_json_dict()
    return {"records": [{"file": study.file, "column": study.column, "report": study.name,
                         **result.to_json_dict()} for study, result in zip(studies, results)]}

"""The six-axis workflow's report: one page, the noise exports, each axis's reports.

One page with a table per step, the noise exports, the error models for a filter, and each
axis's own reports beneath it.

Layout of the report directory::

    report.md            the page: noise, study and loop tables (a row per axis), run times
    noise.* study.* loop.* timing.*   each table as Markdown, CSV and LaTeX
    noise/               the Allan report of all axes: imu.yaml (Kalibr), the OpenVINS,
                         VINS, ORB-SLAM3, PX4 and ArduPilot files, imu_params.m (MATLAB),
                         imu_noise.json, the figures, each axis under noise/axes/
    study/AXIS/          each axis's model-order study
    loop/AXIS/           each axis's residual loop
    models/AXIS.json     each axis's FOS error model (``fosmodel predict`` reads it)
    filter/allan_model.json   the axes' Allan error models as one state-space shaping filter
    filter/joint_model.json   the same with the axes' correlations in its driving noise
    filter/AXIS/         each axis's loop final model (refitted on all the data) and Allan
                         model as filter JSON (:mod:`fosmodel.filter.filter_file`), which
                         the aided position filter recommends in the page
"""

from __future__ import annotations

import json
import textwrap
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from ..core.parallel import in_workers
from ..io.model_file import write_model
from ..io.output import path_name, write_tables, write_text
from ..loop.closeloop import LoopResult
from ..loop.handoff import Handoff, hand_off
from ..loop.loop_report import CONSOLE_WIDTH, write_loop_report
from ..noise.allan_fit import NoiseFit
from ..noise.axes import Axis
from ..noise.exports import export_listing
from ..noise.imu_noise import ImuNoise, write_imu_noise
from ..noise.metrics import metric_definitions, segment_text
from ..study.harness import StudyResult
from ..study.report import write_study
from ..typeset.markdown import markdown_table
from .imu import AxisResult, ImuResult, study_columns


def axis_handoffs(result: ImuResult, columns: Mapping[str, np.ndarray],
                  aux: Mapping[str, np.ndarray] | None = None) -> dict[str, Handoff]:
    """Hand each axis's loop final model to a filter (:func:`fosmodel.loop.handoff.hand_off`).

    Parameters
    ----------
    result : ImuResult
    columns : mapping of str to ndarray
        The record's axes by column (those :func:`~fosmodel.workflows.imu.run_imu` read).
    aux : mapping of str to ndarray, optional
        The auxiliary channels the loops read (a temperature).

    Returns
    -------
    dict of str to Handoff
        By axis column, each with the axis's Allan fit of the whole record.
    """
    channels = {**{a.axis.column: columns[a.axis.column] for a in result.axes}, **(aux or {})}
    fits = {a.axis.column: a.fit for a in result.noise.axes}
    calls = [(_handoff, (a, channels, fits.get(a.axis.column))) for a in result.axes]
    found = in_workers(calls, result.config.n_jobs)
    return {a.axis.column: h for a, h in zip(result.axes, found)}


def _handoff(a: AxisResult, channels: Mapping[str, np.ndarray],
             fit: NoiseFit | None) -> Handoff:
    others = {k: v for k, v in channels.items() if k != a.axis.column}
    return hand_off(a.loop, channels[a.axis.column], others, sensor=a.axis.sensor,
                    units=a.axis.units, allan=fit, column=a.axis.column)


def write_imu_report(result: ImuResult, out_dir: Path, title: str,
                     handoffs: Mapping[str, Handoff] | None = None) -> list[Path]:
    """Write the whole report of :func:`fosmodel.workflows.imu.run_imu` into ``out_dir``.

    Parameters
    ----------
    result : ImuResult
    out_dir : Path
        An existing directory (the command publishes it atomically).
    title : str
        The report's title.
    handoffs : mapping of str to Handoff, optional
        Each axis's filter models (:func:`axis_handoffs`), written under ``filter/AXIS/``
        with a section of the page.

    Returns
    -------
    list of Path
        Every file written.
    """
    tables = write_imu_tables(result, out_dir, title)
    paths = [out_dir / f"{stem}.{ext}" for stem in tables for ext in ("md", "csv", "tex")]
    for part in in_workers(_parts(result, out_dir, title), result.config.n_jobs):
        paths += part
    models = [_write_model(result, a, _mkdir(out_dir / "models")) for a in result.axes]
    filter_path = _mkdir(out_dir / "filter") / "allan_model.json"
    write_text(filter_path, json.dumps(result.filter_dict(), indent=1) + "\n")
    if result.joint is not None:
        write_text(out_dir / "filter" / "joint_model.json",
                   json.dumps({"source": result.source, **result.joint.to_dict()}, indent=1)
                   + "\n")
    axis_files = [p for column, h in (handoffs or {}).items()
                  for p in h.write(out_dir / "filter" / path_name(column),
                                   {"source": result.source, "column": column})]
    report = out_dir / "report.md"
    write_text(report, _page(result, title, tables, models)
               + (_handoff_section(handoffs) if handoffs else ""))
    joint = [out_dir / "filter" / "joint_model.json"] if result.joint is not None else []
    return [*paths, *(p for p, _ in models), filter_path, *joint, *axis_files, report]


def _handoff_section(handoffs: Mapping[str, Handoff]) -> str:
    """Return the page's section on each axis's filter models and the one recommended."""
    rows = []
    for column, h in handoffs.items():
        loop, allan = h.scores.get("loop final model"), h.scores.get("Allan model")
        rows.append({"axis": column, "recommended": h.recommended or "none",
                     "loop RMS [m]": loop.rms_m if loop else np.nan,
                     "loop sigma / RMS": loop.ratio if loop else np.nan,
                     "Allan RMS [m]": allan.rms_m if allan else np.nan,
                     "Allan sigma / RMS": allan.ratio if allan else np.nan})
    first = next(iter(handoffs.values()))
    cycle = next((h.cycle_s for h in handoffs.values() if h.cycle_s), None)
    lines = ["", "## Filter models per axis", "",
             "Each axis's loop final model and Allan model as filter JSON in "
             "`filter/AXIS/loop_model.json` and `filter/AXIS/allan_model.json` (see the docs' "
             "Kalman page, \"The filter JSON\"). The final model's structure was chosen on "
             "the loop's segments and its terms' weights refitted on all the data "
             f"({first.n_samples} samples; a compensation's weights stay those of the loop's "
             "fitting segment); the Allan model is the fit of the whole record. "
             "Each model was judged in the 1-D aided position filter (the tilt error model for "
             "a gyro), fitted on the first half of the record and run on the second, with "
             "position updates of 0.1 m"
             + (f" in {cycle:g} s / {cycle:g} s update/prediction cycles" if cycle else "")
             + "; the recommended one has the lowest RMS position error among those whose "
             "filter claims at least 0.7 of its actual error (sigma / RMS).", "",
             markdown_table(pd.DataFrame(rows), digits=4), ""]
    lines += [f"- {column}: {h.why}" for column, h in handoffs.items()]
    return "\n".join(lines) + "\n"


def write_imu_tables(result: ImuResult, out_dir: Path,
                     title: str) -> dict[str, tuple[pd.DataFrame, str]]:
    """Write the report's four tables (noise, study, loop, timing) as Markdown, CSV and LaTeX.

    Returns
    -------
    dict
        Each table's stem to the table and its caption.
    """
    study, loop = _segments(result)
    cfg = result.config
    tables = {
        "noise": (result.noise.table(), f"{title}: Allan noise parameters of every axis"),
        "study": (result.study_table(), f"{title}: best FOS and best baseline of each axis "
                  f"(chosen on the evaluation segment), errors on {study}: outage error, the "
                  f"RMS position error at the end of {cfg.n_starts} free runs of "
                  f"{cfg.horizon_s:g} s; one-step bias RMS, the RMS of the one-step residual's "
                  "30 s means (in the axis's units)"),
        "loop": (result.loop_table(), f"{title}: the residual loop of each axis, errors on "
                 f"{loop} before and after the effects kept (outage error: at the end of "
                 f"{cfg.horizon_s:g} s free runs; free-run bias RMS, the RMS of their 30 s mean "
                 "errors, in the axis's units)"),
        "timing": (result.timing_table(), f"{title}: run time of each step"),
    }
    for stem, (frame, caption) in tables.items():
        write_tables(frame, out_dir, stem, caption, report=title)
    return tables


def _parts(result: ImuResult, out_dir: Path, title: str) -> list[tuple[Callable, tuple]]:
    """List the reports beneath the page, each a writer and its arguments.

    Most of the time of a report goes into drawing their figures, so they are drawn in
    parallel.
    """
    return report_parts(out_dir, title, [a.axis for a in result.axes], result.noise,
                        {a.axis.column: a.study for a in result.axes},
                        {a.axis.column: a.loop for a in result.axes}, result.config.inflate)


def report_parts(
    out_dir: Path, title: str, axes: Sequence[Axis], noise: ImuNoise | None = None,
    studies: Mapping[str, StudyResult] | None = None,
    loops: Mapping[str, LoopResult] | None = None, inflate: float = 1.0,
) -> list[tuple[Callable, tuple]]:
    """List the reports of the steps given, each a writer and its arguments.

    The noise of every axis in ``noise/`` (its exports times ``inflate``), and each axis's
    study and loop in ``study/AXIS/`` and ``loop/AXIS/`` (a fleet's record writes those of
    the steps it ran), ``AXIS`` the column's name as a file name
    (:func:`fosmodel.io.output.path_name`).
    """
    parts: list[tuple[Callable, tuple]] = []
    if noise is not None:
        parts.append((write_imu_noise, (noise, _mkdir(out_dir / "noise"), title, inflate)))
    for a in axes:
        if studies:
            parts.append((write_study, (studies[a.column],
                                        out_dir / "study" / path_name(a.column),
                                        f"{title} {a.column} ({a.units})")))
        if loops:
            parts.append((write_loop_report, (loops[a.column],
                                              out_dir / "loop" / path_name(a.column),
                                              f"{title} {a.column}")))
    return parts


def _mkdir(path: Path) -> Path:
    path.mkdir(parents=True, exist_ok=True)
    return path


def _write_model(result: ImuResult, a: AxisResult, folder: Path) -> tuple[Path, str]:
    """Save the loop's final model of the axis, or its starting model if that did better.

    The starting model is saved when the effects kept made the prediction segment worse;
    return the file and which model it holds.
    """
    bound, which = a.loop.handed_on()
    path = folder / f"{path_name(a.axis.column)}.json"
    meta = {"source": result.source, "column": a.axis.column, "units": a.axis.units,
            "sensor": a.axis.sensor, "rate_hz": result.rate, "n_samples": result.n_samples,
            "fitted_on": "close-loop fitting segment", "model": which}
    write_model(path, bound.model, meta)
    return path, which


def _page(result: ImuResult, title: str, tables: dict[str, tuple[pd.DataFrame, str]],
          models: list[tuple[Path, str]]) -> str:
    duration = result.n_samples / result.rate
    lines = [f"# {title}", "",
             f"Record: `{result.source}`, {result.n_samples:,} samples per axis at "
             f"{result.rate:g} Hz ({duration / 3600:.3g} h); axes: "
             + ", ".join(a.axis.describe() for a in result.axes)
             + (f"; auxiliary channels of the loop: {', '.join(result.aux)}" if result.aux
                else "") + ".", "", split_text(result), ""]
    sections = [
        ("Noise parameters (Allan variance)", "noise",
         "IEEE Std 952 terms fitted to each axis's overlapping Allan deviation; exports for "
         + export_listing("noise/") + ", "
         "MATLAB (`noise/imu_params.m`) and JSON (`noise/imu_noise.json`)"
         + (f", inflated {result.config.inflate:g}x for a moving platform" if
            result.config.inflate != 1.0 else "")
         + "; figures `noise/allan_gyro.png`, `noise/allan_accel.png`."),
        ("Model-order study", "study",
         "Each method fitted on the first segment, its order chosen on the second, scored on "
         "the rest (fair protocol: every method on the same raw data). Each axis's full "
         "report is in `study/AXIS/`."),
        ("Residual loop", "loop",
         "Effects kept only when they lower the error on data the model was not fitted on; "
         "errors on the prediction segment, which no choice has seen. Each axis's report is "
         "in `loop/AXIS/`."),
    ]
    for heading, stem, text in sections:
        frame, caption = tables[stem]
        lines += [f"## {heading}", "", text, "", f"Table: {caption}.", "",
                  markdown_table(frame, digits=4), ""]
        if stem == "noise":
            lines += _noise_warnings(result.noise)
        else:
            lines += [*_definitions(result, stem), ""]
        if stem == "loop":
            lines += [*driver_notes(result), *_loop_warnings(result)]
    lines += ["## Error models for a filter", "",
              "- `filter/allan_model.json`: every axis's Allan error model (white noise, a "
              "first-order Gauss-Markov bias instability, a random-walk bias) as one "
              "block-diagonal shaping filter at the record's rate: Phi, G, Q, H and the "
              "initial covariance P0 (see the docs' Kalman page)."]
    if result.joint is not None:
        lines.append("- `filter/joint_model.json`: the same states with the axes' correlations "
                     "in the driving noise (white parts from the first differences, biases from "
                     "the cross Allan covariance), and the correlation matrices.")
    lines += [f"- `models/{p.name}`: {which} (FOS; `fosmodel predict` reads it)."
              for p, which in models]
    frame, caption = tables["timing"]
    lines += ["", "## Run times", "",
              f"Allan analysis of all axes: {result.allan_seconds:.1f} s; then the study and "
              f"the loop of each axis, {result.config.n_jobs} at a time.", "",
              markdown_table(frame, digits=4), ""]
    return "\n".join(lines)


def split_text(result: ImuResult) -> str:
    """Say the split the study and the loop used: each segment's bounds and share of the record."""
    a = result.axes[0]  # every axis is split alike
    study, loop = a.study.split.describe(result.rate), a.loop.segments.describe(result.rate)
    if study == loop:
        return f"Split (the study's and the loop's): {study}."
    return f"Split: the study's {study}; the loop's {loop}."


def _segments(result: ImuResult) -> tuple[str, str]:
    """Name the prediction segments of the study and of the loop, with their bounds (s)."""
    a = result.axes[0]
    return (segment_text("prediction", a.study.split.predict, result.rate),
            segment_text("prediction", a.loop.segments.predict, result.rate))


def _definitions(result: ImuResult, stem: str) -> list[str]:
    """Define the study's or the loop's columns: units, horizon, segment."""
    study, loop = _segments(result)
    cfg = result.config
    defined = metric_definitions(None, cfg.horizon_s, cfg.n_starts,
                                 study if stem == "study" else loop)
    same = (" (the study's: both steps score on one segment)" if study == loop
            else f" (not the study's {study.removeprefix('the ')})")
    bias = defined["free_run_bias_rms" if stem == "loop" else "bias_rms"]
    lines = [f"- {defined['outage_position_error_m']}",
             f"- {bias.replace('(units)', '(the axis units)')}"]
    if stem == "loop":
        lines.insert(0, f"- Errors on {loop}{same}, of the loop's starting model (before) and "
                        "final model (after).")
    else:
        lines.append("- FOS / baseline (outage): the first outage error over the second; below "
                     "1, FOS does better.")
    return ["What the columns are:", "", *lines]


def _noise_warnings(noise: ImuNoise) -> list[str]:
    """Warn, one line per axis, where the Allan fit misses the measured deviation."""
    lines = [f"- WARNING: {line} (`noise/axes/{path_name(line.split(':')[0])}/`)."
             for line in noise.fit_warnings()]
    return [*lines, ""] if lines else []


def driver_notes(result: ImuResult) -> list[str]:
    """Say which auxiliary channels served as the loops' drivers, and which axes kept them.

    A channel such as ``temp_c`` is offered to every axis's loop as a measured cause (its slow
    and fast parts), never analysed as an axis of its own; its own excursions (a warm-up) are
    the driver's signal, not outliers of an axis.
    """
    out = []
    for name in result.aux:
        using = [a.axis.column for a in result.axes
                 if any(name in s.effect.describe() for s in a.loop.steps)]
        out.append(f"{name} served as a driver: each axis's loop was offered it as a measured "
                   "cause (its slow and fast parts), judged on data the model was not fitted "
                   "on; " + (f"kept on {', '.join(using)}." if using else "kept on no axis."))
    return [*out, ""] if out else []


def _loop_warnings(result: ImuResult) -> list[str]:
    """Say in a plain sentence for every axis whose kept effects made unseen data worse."""
    out = []
    for a in result.axes:
        worse = a.loop.worse()
        if worse and a.loop.steps:
            out.append(f"On {a.axis.column} the effects kept made the prediction segment "
                       f"worse ({', '.join(worse)}): they do not hold up, and the model "
                       f"written for it is the loop's starting model.")
    return [*out, ""] if out else []


def console_summary(result: ImuResult) -> str:
    """Summarise the report for a console, in lines of at most 100 characters.

    A line per axis: its noise terms, the outage error of the best FOS and the best
    baseline, and the loop's effects with the error before and after them (the report has
    the rest); then a sentence for each axis whose effects did not hold up.
    """
    noise = result.noise.table().set_index("Column")
    study, loop = result.study_table(), result.loop_table()
    outage = study_columns(result.config.horizon_s)[0]
    frame = pd.DataFrame({
        "axis": study["axis"],
        "N": [noise.loc[c, "N fitted"] for c in study["axis"]],
        "B": [noise.loc[c, "B fitted"] for c in study["axis"]],
        "K": [noise.loc[c, "K fitted"] for c in study["axis"]],
        "FOS (m)": study[f"FOS {outage}"].map(_brief_number),
        "base (m)": study[f"baseline {outage}"].map(_brief_number),
        "kept": loop["effects kept"],
        "loop (m)": ["-" if np.isnan(b) or np.isnan(a) else f"{b:.3g} -> {a:.3g}" for b, a in
                     zip(loop["30 s outage error before (m)"],
                         loop["30 s outage error after (m)"])],
    })
    lines = [textwrap.fill(split_text(result), CONSOLE_WIDTH),
             f"Noise terms (Allan), {result.config.horizon_s:g} s outage position error of "
             "the best FOS and baseline "
             "(study),", "effects kept and outage error before -> after (loop), prediction "
             "segment:", frame.to_string(index=False)]
    lines += [textwrap.fill(line, CONSOLE_WIDTH) for line in _loop_warnings(result)[:-1]]
    return "\n".join(lines)


def _brief_number(value: float) -> str:
    """Three significant digits; ``-`` for a side the study did not run (NaN)."""
    return "-" if value != value else f"{value:.3g}"

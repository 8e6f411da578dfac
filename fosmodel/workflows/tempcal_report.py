"""A thermal calibration's report: its table, its two figures, its files for the firmware.

:func:`write_tempcal` writes, in one folder, the summary table (Markdown, CSV, LaTeX), the
bias against temperature with the fits and every session's block means
(``bias_vs_temperature``), the held-out residual against time (``residual_vs_time``), the
report (``report.md``), the JSON of every model and its validation (``tempcal.json``), and
the firmware's files (:mod:`fosmodel.workflows.tempcal_exports`): ``px4.params`` for
QGroundControl, ``px4_console.txt`` of ``param set`` lines, ``ardupilot.parm``.
"""

from __future__ import annotations

import json
import math
from collections.abc import Mapping
from functools import partial
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..io.figures import legend_outside
from ..io.output import save_figure, write_tables, write_text
from ..typeset.latex import mathtext_units
from ..typeset.markdown import markdown_table
from .tempcal import AxisCal, TempcalResult
from .tempcal_exports import (
    ardupilot_parameters,
    ardupilot_params,
    px4_console,
    px4_parameters,
    qgc_params,
)
from .tempcal_heldout import MIN_SESSIONS, Hysteresis

#: What each held-out residual is called in the tables and the figures.
LABELS = {"before": "no compensation", "model": "fosmodel's model",
          "firmware": "its firmware polynomial", "px4": "PX4's procedure"}
#: Each session's points: the colours the fits' lines do not take.
_SESSION_COLOURS = ("C1", "C2", "C4", "C5", "C6", "C8", "C9")
_STYLES: dict[str, dict[str, Any]] = {
    "before": {"color": "0.65", "lw": 2.2}, "model": {"color": "C0", "lw": 1.2},
    "firmware": {"color": "C2", "lw": 1.0, "ls": "--"}, "px4": {"color": "C3", "lw": 1.0,
                                                              "ls": ":"}}


def summary_table(result: TempcalResult) -> pd.DataFrame:
    """Return a row per axis: its model, the held-out residual bias RMS of each fit, ratios."""
    rows = []
    for cal in result.axes:
        rms, ratios = cal.held.rms, cal.held.ratios
        loop = cal.hysteresis.get("firmware")
        rows.append({
            "axis": cal.axis.column, "units": cal.axis.units,
            "range (C)": f"{cal.tmin:.3g} to {cal.tmax:.3g}", "model": cal.model.describe(),
            "RMS before": rms["before"], "RMS model": rms["model"],
            "model/before": ratios["model/before"].short().split(" x", 1)[-1],
            "RMS firmware": rms["firmware"], "RMS PX4": rms["px4"],
            "model/PX4": ratios["model/px4"].short().split(" x", 1)[-1],
            "firmware/PX4": ratios["firmware/px4"].short().split(" x", 1)[-1],
            "hysteresis (firmware)": _hysteresis_text(loop)})
    return pd.DataFrame(rows)


def _hysteresis_text(loop: Hysteresis | None) -> str:
    if loop is None:
        return "not both ways"
    if math.isnan(loop.low):
        return f"{loop.difference:.3g} ({loop.sessions} session{'s' * (loop.sessions > 1)})"
    return (f"{loop.difference:.3g} ({loop.low:.3g} to {loop.high:.3g})"
            + (" found" if loop.found else ""))


def bias_figure(result: TempcalResult, title: str) -> Figure:
    """Plot each axis's bias against temperature: every session's block means and the fits.

    The bias is each block's mean less its session's constant (the chosen model's); the
    firmware polynomial and PX4's procedure over the calibrated range, each with the
    constant that fits the block means best (both leave the constant to a later
    calibration or to the filter); a model with a lag drawn as it runs through each session.
    """
    fig, axes = _panels(len(result.axes), title, "Bias against temperature")
    for ax, cal in zip(axes, result.axes):
        temps = np.concatenate([t for t, _ in cal.points])
        biases = np.concatenate([b for _, b in cal.points])
        for k, (temp, bias) in enumerate(cal.points):
            ax.plot(temp, bias, ".", ms=2.5, color=_SESSION_COLOURS[k % len(_SESSION_COLOURS)],
                    alpha=0.6, label="block means, a colour per session" if k == 0 else None)
        grid = np.linspace(cal.tmin, cal.tmax, 200)
        for curve, style in ((partial(cal.firmware.bias, rate=cal.rate),
                              {"color": "k", "lw": 1.3, "label": "firmware polynomial"}),
                             (cal.px4.offset, {"color": "C3", "lw": 1.0, "ls": ":",
                                               "label": "PX4's procedure"})):
            constant = float(np.mean(biases - curve(temps)))
            ax.plot(grid, curve(grid) + constant, **style)
        if not cal.model.firmware_form:
            for temp, bias in _model_paths(cal):
                ax.plot(temp, bias, color="C0", lw=0.8, label="fosmodel's model, its lag "
                        "through each session")
        ax.set_title(f"{cal.axis.column}: {cal.model.describe().split(', beside')[0]}",
                     fontsize="medium")
        ax.set_xlabel("temperature (C)")
        ax.set_ylabel(mathtext_units(f"bias ({cal.axis.units})"))
        ax.grid(True, alpha=0.3)
    legend_outside(fig)
    return fig


def _model_paths(cal: AxisCal) -> list[tuple[np.ndarray, np.ndarray]]:
    """Return the chosen model's bias through each session, at its blocks' temperatures."""
    out = []
    for temp, _ in cal.points:
        per = cal.block  # the points are block means: the lag runs over them held
        bias = cal.model.bias(np.repeat(temp, per), cal.rate)
        out.append((temp, bias.reshape(-1, per).mean(axis=1)))
    return out


def residual_figure(result: TempcalResult, title: str) -> Figure:
    """Plot each axis's held-out residual bias against time, each fit's (sessions in order)."""
    fig, axes = _panels(len(result.axes), title, "Held-out residual bias")
    for ax, cal in zip(axes, result.axes):
        held = cal.held
        offset, x = 0.0, np.empty(len(held.times))
        for k in np.unique(held.session):
            sel = held.session == k
            x[sel] = (offset + held.times[sel]) / 3600.0
            offset += held.times[sel].max() + cal.block / cal.rate
            if k:
                ax.axvline(x[sel].min(), color="0.8", lw=0.8)
        for name, style in _STYLES.items():
            ax.plot(x, held.blocks[name], label=LABELS[name], **style)
        ax.set_title(cal.axis.column, fontsize="medium")
        ax.set_xlabel("time held out (h), sessions in order")
        ax.set_ylabel(mathtext_units(f"residual bias ({cal.axis.units})"))
        ax.grid(True, alpha=0.3)
    legend_outside(fig)
    return fig


def _panels(n: int, title: str, what: str) -> tuple[Figure, list]:
    cols = min(3, n)
    rows = math.ceil(n / cols)
    fig = Figure(figsize=(4.6 * cols, 3.4 * rows + 1.0), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols)).ravel()
    for ax in axes[n:]:
        ax.set_visible(False)
    fig.suptitle(f"{what}: {title}")
    return fig, list(axes[:n])


def write_tempcal(result: TempcalResult, out: Path, title: str, instance: int = 0,
                  device_ids: Mapping[str, int | None] | None = None) -> list[str]:
    """Write the report, the JSON and the firmware's files in ``out``; return the notes.

    ``instance`` is the firmware's slot (PX4's ``TC_G<instance>``, ArduPilot's
    ``INS_TCAL<instance+1>``), ``device_ids`` the sensors' PX4 ``device_id`` where the
    records do not give it.
    """
    px4, px4_notes = px4_parameters(result, instance, device_ids)
    ardupilot, ap_notes = ardupilot_parameters(result, instance)
    notes = list(dict.fromkeys([*result.notes, *px4_notes, *ap_notes]))
    header = [f"thermal compensation written by fosmodel tempcal: {title}",
              "the firmware polynomial of each axis (tempcal.json holds the models and their "
              "validation)"]
    files = []
    if px4:
        write_text(out / "px4.params", qgc_params(px4, [*header, "load in QGroundControl "
                   "(Parameters, Tools, Load from file), then reboot"]))
        write_text(out / "px4_console.txt", px4_console(px4))
        files += ["px4.params", "px4_console.txt"]
    if ardupilot:
        write_text(out / "ardupilot.parm", ardupilot_params(ardupilot, [*header, "load in "
                   "Mission Planner or MAVProxy (param load), then reboot"]))
        files.append("ardupilot.parm")
    table = summary_table(result)
    write_tables(table, out, "summary", "Thermal calibration, held-out residual bias", title)
    save_figure(bias_figure(result, title), out, "bias_vs_temperature")
    save_figure(residual_figure(result, title), out, "residual_vs_time")
    data = {"title": title, **result.to_dict(), "exports": files, "notes": notes,
            "px4_parameters": {p.name: p.value for p in px4},
            "ardupilot_parameters": {p.name: p.value for p in ardupilot}}
    write_text(out / "tempcal.json", json.dumps(data, indent=1, default=_json) + "\n")
    write_text(out / "report.md", report_text(result, title, table, files, notes))
    return notes


def _json(value: object) -> object:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"not JSON: {type(value).__name__}")


def report_text(result: TempcalResult, title: str, table: pd.DataFrame, files: list[str],
                notes: list[str]) -> str:
    """Return the report in Markdown: how it was judged, the table, each axis, the files."""
    first = result.axes[0]
    outside = int(first.held.outside.sum())
    beyond = (f"  {outside} of the {len(first.held.outside)} held-out blocks lie beyond the "
              "range their fits were fitted over, where the fits are clipped as the firmware "
              "clips them." if outside else "")
    lines = [f"# Thermal calibration: {title}", "",
             f"Sessions: {', '.join(s.name for s in result.groups[0].sessions)}.  Judged "
             f"out of sample: {first.held.how}; the residual bias is the residual's mean over "
             f"blocks of {result.config.block_s:g} s, its RMS over every held-out block "
             f"(intervals at {result.config.confidence:.0%}; each model's coefficients hold "
             f"together at it).{beyond}", "",
             markdown_table(table, digits=3), "",
             "![bias against temperature](bias_vs_temperature.png)", "",
             "![held-out residual bias](residual_vs_time.png)", ""]
    for cal in result.axes:
        p = cal.model.p_value
        lines += [f"## {cal.axis.column}", "", f"- model: {cal.model.describe()} "
                  f"(p {'< 1e-15' if p < 1e-15 else f'= {p:.2g}'} against no temperature "
                  "effect)"]
        for name, w, (lo, hi) in zip(cal.model.forms, cal.model.weights,
                                     cal.model.intervals(result.config.confidence)):
            lines.append(f"  - `{name}`: {w:.6g} ({lo:.6g} to {hi:.6g}) {cal.axis.units}")
        if not cal.model.firmware_form:
            grow = cal.held.ratios["firmware/model"]
            lines.append(f"- the firmware cannot evaluate it; its nearest polynomial in the "
                         f"temperature is exported, and the held-out residual bias grows "
                         f"x{grow.value:.3g} for it")
        spread = np.std(cal.constants["model"]) if len(cal.constants["model"]) > 1 else 0.0
        lines.append(f"- session constants (turn-on bias and what the orientation puts on the "
                     f"axis): {', '.join(f'{c:.4g}' for c in cal.constants['model'])}"
                     + (f" (spread {spread:.3g})" if spread else ""))
        fits = [("firmware", "the firmware polynomial")]
        fits += [] if cal.model.firmware_form else [("model", "the model")]
        for name, what in fits:
            loop = cal.hysteresis.get(name)
            lines.append(f"- warming less cooling, after {what}: "
                         + ("the data do not both warm and cool over a common range"
                            if loop is None else _hysteresis_sentence(loop, cal.axis.units)))
        lines.append("")
    lines += ["## Files", ""] + [f"- `{f}`" for f in files] + ["- `tempcal.json`", ""]
    if notes:
        lines += ["## Notes", ""] + [f"- {n}" for n in notes] + [""]
    return "\n".join(lines)


def _hysteresis_sentence(loop: Hysteresis, units: str) -> str:
    each = ", ".join(f"{d:.3g}" for d in loop.each)
    if math.isnan(loop.low):
        return (f"{loop.difference:.3g} {units} (each session: {each}); no interval from fewer "
                f"than {MIN_SESSIONS} sessions that warm and cool: within one, the wander of "
                "the bias between the two reads as hysteresis")
    verdict = ("they read apart: hysteresis, or a lag the model lacks" if loop.found
               else "no difference beyond the interval")
    return (f"{loop.difference:.3g} {units} ({loop.low:.3g} to {loop.high:.3g}; each session: "
            f"{each}): {verdict}")


def console_summary(result: TempcalResult) -> str:
    """Return the table as the command prints it."""
    cols = ["axis", "model", "RMS before", "RMS model", "RMS firmware", "RMS PX4", "model/PX4"]
    return summary_table(result)[cols].to_string(index=False,
                                                 float_format=lambda v: f"{v:.3g}")

"""Report of the residual loop: before/after table, diagnostics, figures, in one Markdown page."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..io.output import save_figure, write_tables, write_text
from ..typeset.latex import mathtext_units
from ..typeset.markdown import markdown_table
from .closeloop import LoopResult, worse_metrics
from .diagnose import Finding
from .judge import MIN_GAIN, MIN_HALF_WINDOWS


def effects_table(result: LoopResult) -> pd.DataFrame:
    """Tabulate the prediction-segment metrics before the loop and after each effect it kept.

    Each row also says what the effect made worse there (more than 2 %).
    """
    taus = list(result.before["bias_rms"])
    rows = [("before (starting model)", "", "", result.before, "")]
    previous = result.before
    for step in result.steps:
        rows.append((step.effect.describe(), ", ".join(step.terms_added),
                     _evidence(step.effect.evidence), step.predict,
                     "; ".join(worse_metrics(previous, step.predict)) or "nothing"))
        previous = step.predict
    u = result.config.units or "units"
    frame = pd.DataFrame([{
        "Model": name, "Terms added": terms, "Evidence": evidence,
        f"One-step MSE ({u})^2": m["mse"], "Position error (m)": m["position_error_m"],
        f"Outage MSE ({u})^2": m["outage_mse"],
        f"Outage position error (m, {result.config.horizon_s:g} s)": m["outage_position_error_m"],
        **{f"Bias RMS {t} s ({u})": m["bias_rms"][t] for t in taus},
        "Worse than the row above": worse,
    } for name, terms, evidence, m, worse in rows])
    return frame.dropna(axis=1, how="all")


def _evidence(ev: dict) -> str:
    e = ev.get("evidence", {})
    detail = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                       for k, v in e.items() if k not in ("bic_gain", "range"))
    return f"{ev.get('test', '')} p={ev.get('p_value', float('nan')):.2g} ({detail})"


def findings_table(before: list[Finding], after: list[Finding]) -> pd.DataFrame:
    """Each test on the first and on the final model: statistic, p-value, fired."""
    rows = []
    for b, a in zip(before, after):
        name = b.test + (f" {b.evidence['channel']}" if b.test == "aux" else "")
        rows.append({"Test": name, "Statistic before": b.statistic, "p before": b.p_value,
                     "Fired before": "yes" if b.fired else "no", "Statistic after": a.statistic,
                     "p after": a.p_value, "Fired after": "yes" if a.fired else "no"})
    return pd.DataFrame(rows)


#: How the first (before) and the final (after) model are drawn: the first wide and grey, the
#: final thin, blue and dashed over it, so both show where they coincide.
_STYLES: dict[str, dict[str, Any]] = {"before": {"color": "0.6", "lw": 2.6, "ls": "-"},
           "after": {"color": "C0", "lw": 1.1, "ls": "--"}}


def residual_figure(result: LoopResult, title: str) -> Figure:
    """Plot the residual diagnostics of the first (wide, grey) and the final (thin, blue) model.

    Every panel has its axes' labels.
    """
    fig = Figure(figsize=(16, 7.5), layout="constrained")
    axes = fig.subplots(2, 4).ravel()
    rate = result.config.rate
    for findings, label in ((result.findings_before, "before"),
                            (result.findings_after, "after")):
        style = _STYLES[label]
        by = {f.test: f for f in findings}
        acf = by["whiteness"].plot["acf"]
        axes[0].plot(np.arange(len(acf)) / rate, acf, label=label, **style)
        spec = by["periodic"].plot
        axes[1].semilogy(spec["freqs"], _smooth(spec["spectrum"]), label=label, **style)
        al = by["allan"].plot
        axes[2].loglog(al["taus"], al["adev"], marker="o" if label == "before" else "s",
                       ms=5 if label == "before" else 3, label=label, **style)
        aux = [f for f in findings if f.test == "aux"]
        for k, f in enumerate(aux):
            axes[3].plot(f.plot["lags"], f.plot["rho"], label=f"{label} {f.evidence['channel']}",
                         **{**style, "ls": ["-", "--", ":", "-."][k % 4]})
        tr = by["trend"].plot
        axes[4].plot(tr["second"], tr["mean"], label=label, **style)
        axes[4].plot(tr["time"], tr["fit"], **{**style, "lw": 2 * style["lw"]})
        cp = by["step"].plot
        axes[5].plot(cp["time"], cp["cusum"], label=label, **style)
        if "nonlinear" in by:
            nl = by["nonlinear"].plot
            axes[6].plot(nl["product"], nl["mean_residual"], marker="o", label=label,
                         **style)
    white = result.findings_before[-1].plot
    axes[2].loglog(white["taus"], white["white"], "k:", label="white noise")
    band = result.findings_before[0].plot["band"]
    for ax in (axes[0], axes[3]):
        ax.axhspan(-band, band, color="0.9", zorder=0)
    for ax, (text, xlabel, ylabel) in zip(axes, _panels(result.config.units or "units")):
        ax.set_title(text, fontsize="medium")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        if ax.lines:
            ax.legend(fontsize="x-small", loc="upper right")  # "best" is slow on long records
    axes[7].axis("off")
    axes[7].text(0, 1, _fired_text(result), va="top", family="monospace", fontsize="small")
    fig.suptitle(mathtext_units("Residual diagnostics of the first (wide, grey) and the final "
                                f"(thin, blue) model: {title}"))
    return fig


def _panels(units: str) -> list[tuple[str, str, str]]:
    """Each panel's title, x label and y label, the units typeset for matplotlib."""
    u = mathtext_units(units)
    return [("residual autocorrelation", "lag (s)", "autocorrelation"),
            ("least-squares spectrum (smoothed)", "frequency (Hz)", "fraction of the variance"),
            ("Allan deviation of the residual", r"averaging time $\tau$ (s)",
             f"Allan deviation ({u})"),
            ("cross-correlation with the channels", "lag (samples)", "correlation"),
            ("slow part: 1 s means and trend fit", "time (s)", f"residual ({u})"),
            ("CUSUM of the residual (step test)", "time (s)", f"cumulative sum ({u})"),
            ("residual against the strongest product",
             f"binned product of two lags, {mathtext_units(f'({units})^2')}",
             f"mean residual ({u})")]


def _smooth(s: np.ndarray, width: int = 25) -> np.ndarray:
    return np.convolve(s, np.ones(width) / width, mode="same")


def _fired_text(result: LoopResult) -> str:
    lines = ["tests that fire (before -> after):"]
    for b, a in zip(result.findings_before, result.findings_after):
        name = b.test + (f" {b.evidence['channel']}" if b.test == "aux" else "")
        yes = {True: "yes", False: "no"}
        lines.append(f"  {name:<18} {yes[b.fired]:>3} -> {yes[a.fired]}")
    lines.append("effects kept:")
    lines += [f"  {s.effect.describe()}" for s in result.steps] or ["  none"]
    return "\n".join(lines)


def write_loop_report(result: LoopResult, out_dir: Path, title: str) -> list[Path]:
    """Write ``report.md``, the effects and diagnostics tables and the residual figure."""
    out_dir.mkdir(parents=True, exist_ok=True)
    effects = effects_table(result)
    diagnostics = findings_table(result.findings_before, result.findings_after)
    paths = write_tables(effects, out_dir, "effects",
                         f"Residual loop, {title}: prediction-segment errors before and after "
                         "each effect kept", report=title)
    paths += write_tables(diagnostics, out_dir, "diagnostics",
                          f"Residual loop, {title}: diagnostics of the first and the final "
                          "model", report=title)
    paths += save_figure(residual_figure(result, title), out_dir, "residual")
    paths.append(out_dir / "report.md")
    write_text(paths[-1], report_markdown(result, title, effects, diagnostics))
    return paths


def report_markdown(result: LoopResult, title: str, effects: pd.DataFrame,
                    diagnostics: pd.DataFrame) -> str:
    """Write the loop's report as Markdown: its setting, effects, diagnostics and outcome."""
    cfg, seg = result.config, result.segments
    spans = ", ".join(f"{k} {s.start / cfg.rate:g}-{s.stop / cfg.rate:g} s" for k, s in seg.items())
    origins = ", ".join(f"{o:g}" for o in _origins(result)) or "the fitting segment's end"
    lines = [
        f"# Residual loop: {title}", "",
        f"Segments: {spans}. Starting model: FOS, lags 1-{cfg.max_lag}, CP 1. Each diagnostic "
        f"is a test at level {cfg.alpha:g} on the fitting segment's residual. An effect is kept "
        f"only if it lowers the evaluation segment's one-step error or its outage bias (mean "
        f"free-run error over {cfg.eval_horizon_s:g} s windows) beyond noise (forecast-"
        f"encompassing t test at {cfg.accept_alpha:g}) by at least {MIN_GAIN:.1%}, over the "
        f"segment and, when each half holds at least {MIN_HALF_WINDOWS} windows, over each "
        f"half (not asked of a level, which holds still beyond its data); and if, with its "
        f"weights refitted on the past before earlier origins ({origins} s), it still loses "
        "nothing on that segment. A drift, a step or a channel's slow part must also clearly "
        "beat the local level. Level time constants offered: "
        + (", ".join(f"{t:g}" for t in result.level_taus) or "none") + " s. "
        "The prediction segment decides nothing: it gives the numbers below.", "",
        _verdict_line(result), "",
        "## Before and after, prediction segment", "", markdown_table(effects, digits=4), "",
        "## Diagnostics of the first and the final model", "",
        markdown_table(diagnostics, digits=3), "",
    ]
    if result.rejected:
        lines += ["## Candidates that did not survive the evaluation segment", ""]
        for r in result.rejected:
            reason = r["evaluation"].get("reason")
            lines.append(f"- round {r.get('round', 1)}, {r['effect']}: "
                         f"{evaluation_text(r['evaluation'])}" + (f"; {reason}" if reason else ""))
        lines.append("")
    if result.unexplained:
        lines += [f"Still firing at the end, with no effect that survives: "
                  f"{', '.join(still_firing(result))}.", ""]
    lines += ["![residual diagnostics before and after](residual.png)", ""]
    return "\n".join(lines)


def evaluation_text(ev: dict) -> str:
    """Put a candidate's evaluation in words.

    Each test's gain, p-value and, when judged, its gains on the two halves of the segment
    and from the earlier origins.
    """
    parts = []
    for name, label in (("one_step", "one-step"), ("outage", "outage bias")):
        text = f"{label} gain {ev[f'{name}_gain']:.2g} (p {ev[f'{name}_p']:.2g}"
        if ev.get("halves_judged"):
            first, second = ev[f"{name}_gain_halves"]
            text += f"; halves {first:.2g}, {second:.2g}"
        earlier = (ev.get(f"{name}_gain_origins") or [])[:-1]
        if earlier:
            text += "; earlier origins " + ", ".join(
                "-" if g is None else f"{g:.2g}" for g in earlier)
        parts.append(text + ")")
    return ", ".join(parts)


def _origins(result: LoopResult) -> list[float]:
    for ev in [s.comparison for s in result.steps] + [r["evaluation"] for r in result.rejected]:
        if ev.get("origins_s"):
            return ev["origins_s"][:-1]
    return []


def _verdict_line(result: LoopResult) -> str:
    """Say the outcome on the prediction segment in one plain sentence."""
    if not result.steps:
        return "No effect survived the evaluation: the final model is the starting model."
    b, a = result.before, result.after
    change = [f"one-step MSE {a['mse'] / b['mse']:.3g}x"]
    if b["outage_position_error_m"]:
        change.append(f"{result.config.horizon_s:g} s outage position error "
                      f"{a['outage_position_error_m'] / b['outage_position_error_m']:.3g}x")
    last = list(b["bias_rms"])[-1]
    if b["bias_rms"][last]:
        change.append(f"{last} s bias RMS {a['bias_rms'][last] / b['bias_rms'][last]:.3g}x")
    worse = result.worse()
    return ("On the prediction segment, which chose nothing, the final model against the "
            "starting one: " + ", ".join(change) + ". "
            + (f"It is WORSE there in: {'; '.join(worse)}." if worse
               else "Nothing there got worse by more than 2 %."))


def still_firing(result: LoopResult) -> list[str]:
    """List the tests that still fire on the final model, each with where it fires.

    An auxiliary channel with its lag, a periodic test with its frequency, the nonlinear test
    with its strongest product, ...
    """
    return [describe_finding(f) for f in result.findings_after if f.fired]


def describe_finding(finding: Finding) -> str:
    """``aux temp_c (lag 3)``, ``periodic 7.314 Hz``, ``nonlinear (y[n-1]*y[n-2])``, ..."""
    e = finding.evidence
    where = {"aux": lambda: f" {e['channel']} (lag {e['lag']})",
             "periodic": lambda: f" {e['freq_hz']:.4g} Hz",
             "nonlinear": lambda: f" ({e['strongest']})",
             "trend": lambda: f" ({e['form']})",
             "step": lambda: f" at {e['time_s']:.4g} s",
             "allan": lambda: f" (tau {e['tau_max_s']:.3g} s)",
             "whiteness": lambda: f" (lags 1-{e['lags']})"}
    return finding.test + where.get(finding.test, str)()


#: The width of the console summary of the loop.
CONSOLE_WIDTH = 100
_MODEL_WIDTH = 38


def console_summary(result: LoopResult, width: int = CONSOLE_WIDTH) -> str:
    """Write the loop's outcome for a terminal, every line at most ``width`` characters.

    A row per model (the starting one, then after each effect kept) with the number of terms
    the effect added (the report lists them) and the main prediction-segment numbers, an
    effect's name cut with ``...`` beyond 38 characters; then, wrapped, the names that were
    cut, what each effect made worse and the tests still firing with their channels, lags
    and frequencies.
    """
    cfg = result.config
    last = list(result.before["bias_rms"])[-1]
    u = cfg.units or "units"
    metrics = [result.before] + [step.predict for step in result.steps]
    full = ["before (starting model)"] + [s.effect.describe() for s in result.steps]
    names = [_clip(name, _MODEL_WIDTH) for name in full]
    terms = ["-"] + [str(len(s.terms_added)) for s in result.steps]
    w = max(len(name) for name in names)
    columns = ("MSE", "Outage pos. err.", f"Bias RMS {last} s")
    table = [f"row  {'Model':<{w}}  Terms" + "".join(f"  {c:>10}" for c in columns)]
    for row, (name, count, m) in enumerate(zip(names, terms, metrics)):
        values = (m["mse"], m["outage_position_error_m"], m["bias_rms"][last])
        table.append(f"{row:>3}  {name:<{w}}  {count:>5}" + "".join(
            f"  {_number(v):>{max(10, len(c))}}" for v, c in zip(values, columns)))
    notes = [f"row {row}: {name}" for row, name in enumerate(full) if name != names[row]]
    notes += [f"row {row} made worse: " + "; ".join(worse_metrics(previous, m))
             for row, (previous, m) in enumerate(zip(metrics, metrics[1:]), start=1)
             if worse_metrics(previous, m)]
    if result.unexplained:
        notes.append("still firing, with no effect that survives: "
                     + ", ".join(still_firing(result)))
    head = (f"prediction segment: MSE ({u})^2, outage position error (m, {cfg.horizon_s:g} s), "
            f"bias RMS ({u})")
    return "\n".join([*textwrap.wrap(head, width), *(_clip(line, width) for line in table),
                      *(line for note in notes
                        for line in textwrap.wrap(note, width, subsequent_indent="    "))])


def _number(value: float | None) -> str:
    return "-" if value is None else f"{value:.4g}"


def _clip(text: str, width: int, mark: str = "...") -> str:
    """``text`` cut to ``width`` characters, ending in ``mark`` when cut."""
    if len(text) <= width:
        return text
    return text[:width - len(mark)].rstrip() + mark

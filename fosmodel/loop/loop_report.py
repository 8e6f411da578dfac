"""Report of the residual loop: before/after tables with intervals, diagnostics, figures."""

from __future__ import annotations

import textwrap
from pathlib import Path

import pandas as pd

from ..io.output import save_figure, write_tables, write_text
from ..typeset.markdown import markdown_table
from .closeloop import LoopResult
from .diagnose import Finding
from .intervals import Ratio, ratios
from .judge import (
    MAX_POINT_LOSS,
    MIN_GAIN,
    MIN_HALF_WINDOWS,
    MIN_OUTAGE_GAIN,
    MIN_WINDOWS,
    ONSET_REFIT_SLOWS,
    Judgement,
)
from .loop_figure import finding_name, residual_figure
from .outcome import LoopOutcome
from .rounds import REPORT_WINDOWS, Rejected

__all__ = ["CONSOLE_WIDTH", "console_summary", "describe_finding", "effects_table",
           "evaluation_text", "findings_table", "ratios_table", "report_markdown",
           "residual_figure", "still_firing", "write_loop_report"]


def effects_table(result: LoopResult) -> pd.DataFrame:
    """Tabulate the prediction-segment numbers before the loop and after each effect it kept.

    Each row also says what the effect made worse there: the ratios to the row above whose
    interval lies above 1.
    """
    u = result.config.units or "units"
    rows, previous = [], result.before_scores
    for name, terms, evidence, s in [("before (starting model)", "", "", result.before_scores),
                                     *((st.effect.describe(), ", ".join(st.terms_added),
                                        _evidence(st.effect.evidence), st.predict)
                                       for st in result.steps)]:
        m = s.to_dict()
        worse = [r.text() for r in ratios(previous, s, result.config.confidence)
                 if r.verdict == "worse"]
        rows.append({
            "Model": name, "Terms added": terms, "Evidence": evidence,
            f"One-step MSE ({u})^2": m["mse"], "Position error (m)": m["position_error_m"],
            **{f"Outage position error (m, {h} s)": v
               for h, v in m["outage_position_error_m"].items()},
            **{f"Outage MSE {h} s ({u})^2": v for h, v in m["outage_mse"].items()},
            **{f"Free-run bias RMS {t} s ({u})": v for t, v in m["bias_rms"].items()},
            "Worse than the row above": ("" if s is result.before_scores
                                         else "; ".join(worse) or "nothing")})
        previous = s
    return pd.DataFrame(rows).dropna(axis=1, how="all")


def ratios_table(result: LoopResult) -> pd.DataFrame:
    """Each ratio of the final model to the starting one, its interval and what it says."""
    level = f"{result.config.confidence:.0%}"
    return pd.DataFrame([{"Number": r.name, "After / before": r.value,
                          f"{level} interval": ("-" if r.low != r.low
                                                else f"{r.low:.3g}-{r.high:.3g}"),
                          "Windows": r.windows,
                          "Verdict": r.verdict + (f" ({r.why})" if r.why else "")}
                         for r in result.ratios()])


def _evidence(ev: dict) -> str:
    e = ev.get("evidence", {})
    detail = ", ".join(f"{k} {v:.4g}" if isinstance(v, float) else f"{k} {v}"
                       for k, v in e.items() if k not in ("bic_gain", "range", "forms"))
    return f"{ev.get('test', '')} p={ev.get('p_value', float('nan')):.2g} ({detail})"


def findings_table(before: list[Finding], after: list[Finding]) -> pd.DataFrame:
    """Each test on the first and on the final model: statistic, p-value, fired."""
    return pd.DataFrame([{"Test": finding_name(b), "Statistic before": b.statistic,
                          "p before": b.p_value, "Fired before": "yes" if b.fired else "no",
                          "Statistic after": a.statistic, "p after": a.p_value,
                          "Fired after": "yes" if a.fired else "no"}
                         for b, a in zip(before, after)])


def write_loop_report(result: LoopResult, out_dir: Path, title: str) -> list[Path]:
    """Write ``report.md``, the effects, ratios and diagnostics tables and the figure."""
    out_dir.mkdir(parents=True, exist_ok=True)
    effects, changes = effects_table(result), ratios_table(result)
    diagnostics = findings_table(result.findings_before, result.findings_after)
    paths = write_tables(effects, out_dir, "effects",
                         f"Residual loop, {title}: prediction-segment errors before and after "
                         "each effect kept", report=title)
    paths += write_tables(changes, out_dir, "ratios",
                          f"Residual loop, {title}: the final model against the starting one "
                          "on the prediction segment, with intervals", report=title)
    paths += write_tables(diagnostics, out_dir, "diagnostics",
                          f"Residual loop, {title}: diagnostics of the first and the final "
                          "model", report=title)
    paths += save_figure(residual_figure(result, title), out_dir, "residual")
    paths.append(out_dir / "report.md")
    write_text(paths[-1], report_markdown(result, title, effects, diagnostics, changes))
    return paths


def report_markdown(result: LoopResult, title: str, effects: pd.DataFrame,
                    diagnostics: pd.DataFrame, changes: pd.DataFrame | None = None) -> str:
    """Write the loop's report as Markdown: its setting, effects, diagnostics and outcome."""
    cfg, seg = result.config, result.segments
    changes = ratios_table(result) if changes is None else changes
    spans = ", ".join(f"{k} {s.start / cfg.rate:g}-{s.stop / cfg.rate:g} s" for k, s in seg.items())
    lines = [f"# Residual loop: {title}", "", f"Segments: {spans}. " + _setting(result), "",
             _verdict_line(result), "",
             "## Before and after, prediction segment", "", markdown_table(effects, digits=4),
             "", f"The final model against the starting one ({cfg.confidence:.0%} intervals, "
             "from the windows' long-run variance):", "", markdown_table(changes, digits=4),
             ""]
    if result.cross_axis:
        lines += ["## Cross-axis noise", "", _cross_axis_text(result), ""]
    lines += ["## Diagnostics of the first and the final model", "",
              markdown_table(diagnostics, digits=3), ""]
    lines += rejected_section(result.rejected)
    if result.unexplained:
        lines += [f"Still firing at the end, with no effect that survives: "
                  f"{', '.join(still_firing(result))}.", ""]
    if result.notes:
        lines += ["## Notes", "", *(f"- {note[0].upper()}{note[1:]}." for note in result.notes),
                  ""]
    lines += ["![residual diagnostics before and after](residual.png)", ""]
    return "\n".join(lines)


def _setting(result: LoopResult) -> str:
    """How the loop decided, in words, with this run's settings."""
    cfg = result.config
    judged = ", ".join(f"{h:g} s" for h in sorted(result.judged.horizons)) or "none"
    reported = ", ".join(f"{h:g} s" for h in sorted(result.reported.horizons)) or "none"
    origins = ", ".join(f"{o:g}" for o in _origins(result)) or "the fitting segment's end"
    return (
        f"Starting model: FOS, lags 1-{cfg.max_lag}, CP 1. Each diagnostic is a test at level "
        f"{cfg.alpha:g} on the fitting segment's residual. An effect is kept only if, on the "
        f"evaluation segment, it lowers the one-step error or the outage bias (mean free-run "
        f"error over the windows of an outage length: {judged}, each where the segment holds "
        f"at least {MIN_WINDOWS} windows) beyond noise (forecast-encompassing t test at "
        f"{cfg.accept_alpha:g}) by at least {MIN_GAIN:.1%} ({MIN_OUTAGE_GAIN:.0%} for an outage "
        "bias), and makes none of them worse "
        f"beyond noise, nor any outage bias's sum of squares more than {MAX_POINT_LOSS:.0%} "
        "larger however few its windows; a function of time or a fast effect must also gain "
        "over each half of "
        f"the segment (when each holds at least {MIN_HALF_WINDOWS} windows) and, with its "
        f"weights refitted on the past before earlier origins ({origins} s), lose nothing "
        "there; a function of time is not kept on an outage length judged only right after "
        "its data (halves too few to judge, no earlier origin). An effect with an onset (a "
        f"step) is judged only from the origins {ONSET_REFIT_SLOWS * cfg.slow_s:g} s or more "
        "after it and after those of the effects already in. An outage length the "
        "segment holds fewer windows of is judged from the "
        f"earliest origin that can judge to its end, where that stretch holds {MIN_WINDOWS}: "
        "nothing may lose there. A drift or a step waits for the level and the drivers. "
        "Channels: "
        f"{result.roles.describe()}. Level time constants offered: "
        + (", ".join(f"{t:g}" for t in result.level_taus) or "none") + " s. The prediction "
        f"segment decides nothing: it gives the numbers below, at the outage lengths it holds "
        f"at least {REPORT_WINDOWS} windows of ({reported}).")


def _cross_axis_text(result: LoopResult) -> str:
    rows = [f"{c['channel']} {c['rho']:+.3f} at lag {c['lag']} (p {c['p_value']:.2g}"
            + (", taken as an input as asked" if c["as_input"] else "") + ")"
            for c in result.cross_axis]
    return ("The other axes of the same IMU and kind, and the channels named as measuring "
            "the motion, are companions: never inputs unless asked for. Their largest "
            "correlation with the final model's residual on the "
            "fitting segment (lags 0-" + f"{result.config.aux_max_lag}): " + "; ".join(rows) + ".")


def evaluation_text(judgement: Judgement) -> str:
    """Put a candidate's evaluation in words.

    Each comparison's gain and p-value and, when judged, its gains on the two halves of the
    segment and from the earlier origins.
    """
    parts = []
    for c in judgement.last:
        text = f"{c.label} gain {c.gain:.2g} (p {c.p:.2g}"
        if c.halves:
            text += f"; halves {c.halves[0]:.2g}, {c.halves[1]:.2g}"
        earlier = judgement.gains(c.key)[:-1] if judgement.earlier is not None else []
        if earlier:
            text += "; earlier origins " + ", ".join("-" if g is None else f"{g:.2g}"
                                                     for g in earlier)
        parts.append(text + ")")
    return ", ".join(parts)


def rejected_section(rejected: list[Rejected]) -> list[str]:
    """Return the report's lines on the candidates that did not go in (none if there were none).

    Each with its round, its evaluation and, where the loop held an accepted one back, why.
    """
    if not rejected:
        return []
    return ["## Candidates that did not go in", "",
            *(f"- round {r.round}, {r.effect.describe()}: {evaluation_text(r.judgement)}"
              + (f"; {r.judgement.reason}" if r.judgement.reason else "") for r in rejected),
            ""]


def _origins(result: LoopResult) -> list[float]:
    for judgement in [s.judgement for s in result.steps] + [r.judgement for r in result.rejected]:
        if len(judgement.origins_s) > 1:
            return list(judgement.origins_s[:-1])
    return []


def _verdict_line(result: LoopResult) -> str:
    """Say the outcome on the prediction segment in plain sentences."""
    if not result.steps:
        return "No effect survived the evaluation: the final model is the starting model."
    found = result.ratios()
    unsure = [r.name for r in found if r.verdict == "undetermined"]
    text = better_or_worse("On the prediction segment, which chose nothing, the final model "
                           "against the starting one: ", found,
                           [r.short() for r in found if r.verdict == "worse"], " there")
    if unsure:
        text += f" Too close or too few windows to tell: {', '.join(unsure)}."
    return text


def better_or_worse(lead: str, found: list[Ratio], worse: list[str], where: str = "",
                    pooled: str = "") -> str:
    """Return ``lead``, what is better beyond its interval, and what is worse or that nothing is.

    ``where`` and ``pooled`` place the sentence (`` there``; ``, pooled``).
    """
    better = [r.short() for r in found if r.verdict == "better"]
    return (lead + (f"better in {'; '.join(better)}. " if better else "")
            + (f"It is WORSE{where} in: {'; '.join(worse)}." if worse
               else f"Nothing{where} is worse beyond its interval{pooled}."))


def still_firing(result: LoopOutcome) -> list[str]:
    """List the tests that still fire on the final model, each with where it fires.

    A driver with its lag, a periodic test with its frequency, the nonlinear test with its
    strongest product, ...; a companion's correlation is cross-axis noise, not listed.
    """
    companions = set(result.roles.companions)
    return [describe_finding(f) for f in result.findings_after
            if f.fired and not (f.test == "aux" and f.evidence["channel"] in companions)]


def describe_finding(finding: Finding) -> str:
    """``aux temp_c (lag 3)``, ``periodic 7.314 Hz``, ``nonlinear (y[n-1]*y[n-2])``, ..."""
    e = finding.evidence
    where = {"aux": lambda: f" {e['channel']} (lag {e['lag']})",
             "driver": lambda: f" {e['channel']} (slow part, {e['share']:.0%} of the slow "
                               "innovations)",
             "periodic": lambda: f" {e['freq_hz']:.4g} Hz",
             "nonlinear": lambda: f" ({e['strongest']})",
             "trend": lambda: f" ({e['form']})",
             "step": lambda: f" at {e['time_s']:.4g} s",
             "wander": lambda: " (of the mean)",
             "allan": lambda: f" (tau {e['tau_max_s']:.3g} s)",
             "whiteness": lambda: f" (lags 1-{e['lags']})"}
    return finding.test + where.get(finding.test, str)()


#: The width of the console summary of the loop.
CONSOLE_WIDTH = 100
_MODEL_WIDTH = 38


def console_summary(result: LoopResult, width: int = CONSOLE_WIDTH) -> str:
    """Write the loop's outcome for a terminal, every line at most ``width`` characters.

    A row per model (the starting one, then after each effect kept) with the number of terms
    the effect added (the report lists them) and the main prediction-segment numbers at the
    longest outage reported, an effect's name cut with ``...`` beyond 38 characters; then,
    wrapped, the names that were cut, the final ratios with their intervals, what each effect
    made worse, the tests still firing and the notes.
    """
    cfg = result.config
    scores = [result.before_scores] + [step.predict for step in result.steps]
    metrics = [s.to_dict() for s in scores]
    horizon = f"{max(result.reported.horizons):g}" if result.reported.horizons else None
    last = list(metrics[0]["bias_rms"])[-1]
    full = ["before (starting model)"] + [s.effect.describe() for s in result.steps]
    names = [_clip(name, _MODEL_WIDTH) for name in full]
    terms = ["-"] + [str(len(s.terms_added)) for s in result.steps]
    w = max(len(name) for name in names)
    # two-line heads, so that the table fits the width whole (a cut head or value misleads)
    heads = (("", "MSE"), ("Outage pos.", f"err. {horizon} s" if horizon else "err."),
             ("Free-run", f"bias RMS {last} s"))
    widths = [max(10, *(len(h) for h in head)) for head in heads]
    table = [f"{'':<5}{'':<{w}}  {'':>5}" + "".join(f"  {h[0]:>{n}}"
                                                    for h, n in zip(heads, widths)),
             f"row  {'Model':<{w}}  Terms" + "".join(f"  {h[1]:>{n}}"
                                                   for h, n in zip(heads, widths))]
    for row, (name, count, m) in enumerate(zip(names, terms, metrics)):
        values = (m["mse"], m["outage_position_error_m"].get(horizon) if horizon else None,
                  m["bias_rms"][last])
        table.append(f"{row:>3}  {name:<{w}}  {count:>5}" + "".join(
            f"  {_number(v):>{n}}" for v, n in zip(values, widths)))
    notes = [f"row {row}: {name}" for row, name in enumerate(full) if name != names[row]]
    if result.steps:
        notes.append("final against starting model: "
                     + "; ".join(r.text() for r in result.ratios() if r.verdict != "unchanged"))
    notes += [f"row {row} made worse: " + "; ".join(worse)
              for row, (previous, s) in enumerate(zip(scores, scores[1:]), start=1)
              for worse in [[r.text() for r in ratios(previous, s, cfg.confidence)
                             if r.verdict == "worse"]] if worse]
    if result.unexplained:
        notes.append("still firing, with no effect that survives: "
                     + ", ".join(still_firing(result)))
    notes += [f"note: {note}" for note in result.notes]
    head = (f"prediction segment: MSE ({cfg.units or 'units'})^2, outage position error (m), "
            f"free-run bias RMS ({cfg.units or 'units'})")
    return "\n".join([*textwrap.wrap(head, width), *(line.rstrip() for line in table),
                      *(line for note in notes
                        for line in textwrap.wrap(note, width, subsequent_indent="    "))])


def _number(value: float | None) -> str:
    return "-" if value is None else f"{value:.4g}"


def _clip(text: str, width: int, mark: str = "...") -> str:
    """``text`` cut to ``width`` characters, ending in ``mark`` when cut."""
    if len(text) <= width:
        return text
    return text[:width - len(mark)].rstrip() + mark

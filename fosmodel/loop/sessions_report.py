"""Report of the residual loop over sessions: a row per session, a pooled verdict, the effects."""

from __future__ import annotations

import textwrap
from pathlib import Path
from typing import Any

import pandas as pd

from ..io.output import save_figure, write_tables, write_text
from ..typeset.markdown import markdown_table
from .intervals import Ratio
from .judge import MIN_WINDOWS
from .loop_figure import residual_figure
from .loop_report import (
    CONSOLE_WIDTH,
    better_or_worse,
    evaluation_text,
    findings_table,
    rejected_section,
    still_firing,
)
from .sessions import SessionsResult


def sessions_table(result: SessionsResult) -> pd.DataFrame:
    """Tabulate each session's predicted part before and after, and all of them pooled.

    Each ratio with its interval and verdict, at every horizon the parts hold.
    """
    rows = [_row(name, c, result.ratios(k)) for k, (name, c) in
            enumerate(zip(result.names, result.constants))]
    rows.append(_row("pooled", None, result.ratios()))
    return pd.DataFrame(rows)


def _row(name: str, constant: float | None, found: list[Ratio]) -> dict[str, Any]:
    return {"Session": name, "Own constant": constant,
            **{r.name + " after / before": r.short().split(" x", 1)[-1] for r in found},
            "Verdict": "; ".join(f"{r.name} {r.verdict}" for r in found
                                 if r.verdict in ("worse", "better")) or "unchanged"}


def sessions_markdown(result: SessionsResult, title: str, table: pd.DataFrame,
                      diagnostics: pd.DataFrame) -> str:
    """Write the sessions' report as Markdown: setting, rows per session, effects, verdict."""
    cfg = result.config
    lines = [
        f"# Residual loop over {len(result.names)} sessions: {title}", "",
        f"Sessions: {', '.join(result.names)}. The first {cfg.train + cfg.evaluate:.0%} of each "
        "session decides, the rest is predicted and decides nothing. Dynamics and driver "
        "sensitivities are shared, each session keeps its own constant (its turn-on bias; "
        "the within fit of panel data). Each candidate is fitted on all but one session and "
        f"judged on that one, after its first {cfg.head_s:g} s, which give it its own constant "
        "as an alignment would; every session held out in turn, the comparisons pooled "
        f"(horizons with at least {MIN_WINDOWS} windows over the sessions). A function of "
        "time, and any effect judged strictly, is also judged ahead: fitted on the first "
        f"{cfg.train:.0%} of the other sessions, judged on the held-out one from there to the "
        "end of its deciding part (the gains 'from earlier origins', one per session). "
        "Channels: "
        f"{result.roles.describe()}.", "", _verdict(result), "",
        "## Each session's predicted part, and all of them pooled", "",
        markdown_table(table, digits=4), "",
        "The constants are each session's, relative to the written model's (the mean "
        "session's); a new session's comes from its first minutes "
        "(fosmodel.models.sessions.session_constant).", "",
        "## Effects kept", ""]
    lines += [f"- {s.effect.describe()} ({', '.join(s.terms_added) or 'a compensation'}): "
              f"{evaluation_text(s.judgement)}" for s in result.steps] or ["- none"]
    lines.append("")
    lines += rejected_section(result.rejected)
    lines += ["## Diagnostics of the first and the final model", "",
              markdown_table(diagnostics, digits=3), ""]
    firing = still_firing(result)
    if firing:
        lines += [f"Still firing at the end: {', '.join(firing)}.", ""]
    if result.notes:
        lines += ["## Notes", "", *(f"- {n[0].upper()}{n[1:]}." for n in result.notes), ""]
    lines += ["![residual diagnostics before and after](residual.png)", ""]
    return "\n".join(lines)


def _verdict(result: SessionsResult) -> str:
    if not result.steps:
        return "No effect survived the sessions held out: the final model is the starting one."
    return (better_or_worse("Pooled over the sessions' predicted parts, the final model "
                            "against the starting one: ", result.ratios(), result.worse(),
                            pooled=", pooled")
            + "".join(f" In {name} alone it is worse in: {'; '.join(result.worse_in(k))}."
                      for k, name in enumerate(result.names) if result.worse_in(k)))


def write_sessions_report(result: SessionsResult, out_dir: Path, title: str) -> list[Path]:
    """Write ``report.md``, the sessions and diagnostics tables and the residual figure."""
    out_dir.mkdir(parents=True, exist_ok=True)
    table = sessions_table(result)
    diagnostics = findings_table(result.findings_before, result.findings_after)
    paths = write_tables(table, out_dir, "sessions",
                         f"Residual loop over sessions, {title}: each session's predicted part "
                         "and all pooled, the final model against the starting one",
                         report=title)
    paths += write_tables(diagnostics, out_dir, "diagnostics",
                          f"Residual loop over sessions, {title}: diagnostics", report=title)
    paths += save_figure(residual_figure(result, title), out_dir, "residual")
    paths.append(out_dir / "report.md")
    write_text(paths[-1], sessions_markdown(result, title, table, diagnostics))
    return paths


def sessions_console(result: SessionsResult, width: int = CONSOLE_WIDTH) -> str:
    """Summarise the sessions' loop for a terminal, every line at most ``width`` characters."""
    lines = [f"effects kept: {'; '.join(s.effect.describe() for s in result.steps) or 'none'}"]
    for k, name in enumerate([*result.names, "pooled"]):
        found = result.ratios(None if name == "pooled" else k)
        lines.append(f"{name}: " + "; ".join(r.text() for r in found if r.verdict != "unchanged")
                     if result.steps else f"{name}: unchanged")
    lines += [f"note: {n}" for n in result.notes]
    return "\n".join(part for line in lines
                     for part in textwrap.wrap(line, width, subsequent_indent="    "))

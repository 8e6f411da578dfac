"""The residual loop's residual figure: each diagnostic of the first and the final model."""

from __future__ import annotations

from typing import Any

import numpy as np
from matplotlib.figure import Figure

from ..typeset.latex import mathtext_units
from .closeloop import LoopResult
from .diagnose import Finding


def finding_name(finding: Finding) -> str:
    """Return a test as the tables name it, with its channel (``aux temp_c``) if it has one."""
    channel = finding.evidence.get("channel")
    return finding.test + (f" {channel}" if channel else "")


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
        aux = [f for f in findings if f.test == "aux" and f.plot]
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
    white = next(f for f in result.findings_before if f.test == "allan").plot
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
        yes = {True: "yes", False: "no"}
        lines.append(f"  {finding_name(b):<18} {yes[b.fired]:>3} -> {yes[a.fired]}")
    lines.append("effects kept:")
    lines += [f"  {s.effect.describe()}" for s in result.steps] or ["  none"]
    return "\n".join(lines)

"""The Allan analysis of one axis as a figure and files: the curve, its fit, their tables.

:func:`allan_figure` draws the classic log-log plot (the deviation with its 68 % band, each
fitted term, their sum, the classic read-offs, and below it the fit over the data);
:func:`write_allan` writes it with the deviation's and the noise terms' tables.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..io.output import save_figure, write_tables
from ..typeset.latex import mathtext_units
from .allan import AllanResult
from .allan_fit import NoiseFit


def allan_figure(result: AllanResult, fit: NoiseFit, title: str) -> Figure:
    """Plot the log-log Allan deviation with its 68 % band and the fit over it.

    Each fitted term's line, their sum and the classic read-offs; below, the fit over the
    data with the data's 68 % band.
    """
    fig = Figure(figsize=(7.5, 6.6), layout="constrained")
    ax, low = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    ax.fill_between(result.taus, result.lower, result.upper, color="C0", alpha=0.25,
                    label="68 % confidence interval")
    left_out = slice(0, fit.start)
    ax.loglog(result.taus[fit.start:], result.adev[fit.start:], "o", color="C0", ms=3.5,
              label="overlapping ADEV")
    if fit.start:
        ax.loglog(result.taus[left_out], result.adev[left_out], "o", mfc="none", color="C0",
                  ms=3.5, label="left out (the sensor's filtering)")
    grid = np.geomspace(result.taus[0], result.taus[-1], 400)
    for i, k in enumerate(fit.terms):
        if fit.coefficients[k] > 0:
            ax.loglog(grid, fit.term_adev(k, grid), "--" if fit.resolved[k] else ":",
                      color=f"C{i + 1}", label=_legend(fit, k))
    ax.loglog(grid, fit.model_adev(grid), "-", color="k", lw=1.2, label="fitted sum")
    _readoff_marks(ax, fit)
    ax.set_ylim(result.lower.min() / 3.0, result.upper.max() * 3.0)
    ax.set_ylabel(f"Allan deviation ({mathtext_units(result.units or 'units')})")
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize="x-small")
    ax.set_title(mathtext_units(f"Allan deviation and the fitted noise terms: {title}"))
    model = fit.model_adev(result.taus)
    low.fill_between(result.taus, model / result.upper, model / result.lower, color="C0",
                     alpha=0.25, label="data's 68 % interval")
    low.semilogx(result.taus, model / result.adev, "o-", color="k", ms=3, lw=0.8,
                 label="fit / data")
    low.axhline(1.0, color="0.4", lw=0.8)
    if fit.start:
        low.axvspan(result.taus[0], fit.fitted_taus[0], color="0.85", label="left out")
    low.set_xlabel(r"averaging time $\tau$ (s)")
    low.set_ylabel("fit / data")
    low.grid(True, which="both", alpha=0.3)
    low.legend(fontsize="x-small")
    return fig


def _readoff_marks(ax: Axes, fit: NoiseFit) -> None:
    """Mark the classic read-offs as crosses: N at 1 s, K at 3 s, and the minimum (B)."""
    marks = [("N", 1.0, fit.readoff.get("N", math.nan), "N read-off (-1/2 line at 1 s)"),
             ("K", 3.0, fit.readoff.get("K", math.nan), "K read-off (+1/2 line at 3 s)"),
             ("B", fit.readoff.get("min_tau_s", math.nan), fit.readoff.get("min_adev", math.nan),
              "minimum (in-run bias stability = 0.664 B)")]
    for _, tau, value, label in marks:
        if np.isfinite(tau) and np.isfinite(value):
            ax.plot([tau], [value], "x", color="0.2", ms=8, mew=1.5, label=label)


def _legend(fit: NoiseFit, term: str) -> str:
    nav = fit.navigation(term)
    value, units = nav if nav is not None else (fit.coefficients[term], fit.units(term))
    text = f"{term} {fit.name(term)} = {value:.3g} {mathtext_units(units)}"
    return text if fit.resolved[term] else f"{text} (not resolved)"


def write_allan(result: AllanResult, fit: NoiseFit, out_dir: Path, title: str) -> list[Path]:
    """``allan.png/svg``, ``allan.md/csv/tex`` (the deviation) and ``noise.md/csv/tex``."""
    out_dir.mkdir(parents=True, exist_ok=True)
    paths = save_figure(allan_figure(result, fit, title), out_dir, "allan")
    paths += write_tables(result.to_frame(), out_dir, "allan",
                          f"{title}: overlapping Allan deviation", report=title)
    return paths + write_tables(fit.summary().to_frame(), out_dir, "noise",
                                f"{title}: IEEE Std 952 noise terms fitted to the Allan "
                                "deviation", report=title)

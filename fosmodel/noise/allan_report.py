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

from ..io.figures import legend_outside, wrap_title
from ..io.output import save_figure, write_tables
from ..typeset.latex import mathtext_units
from .allan import AllanResult
from .allan_fit import NoiseFit

#: The fit/data panels' range: within a factor of two is where the fit is judged; a point
#: beyond is drawn at the edge rather than flattening the rest.
RATIO_RANGE = (0.5, 2.0)
#: The legend entry of the points beyond it.
BEYOND = f"fit / data beyond {RATIO_RANGE[0]:g}-{RATIO_RANGE[1]:g} (at the edge)"


def allan_figure(result: AllanResult, fit: NoiseFit, title: str) -> Figure:
    """Plot the log-log Allan deviation with its 68 % band and the fit over it.

    The resolved terms' lines, their sum and the classic read-offs (the terms not resolved are
    upper limits, in the tables); below, the fit over the data with the data's 68 % band.  The
    scale follows the data and the sum, not the terms' lines, which run out of the panel; one
    legend beside the panels.
    """
    fig = Figure(figsize=(7.5, 7.2), layout="constrained")
    ax, low = fig.subplots(2, 1, sharex=True, height_ratios=[3, 1])
    ax.set_xscale("log")
    ax.set_yscale("log")
    ax.fill_between(result.taus, result.lower, result.upper, color="C0", alpha=0.25)
    left_out = slice(0, fit.start)
    ax.plot(result.taus[fit.start:], result.adev[fit.start:], "o", color="C0", ms=3.5,
            label="overlapping ADEV and its 68 % interval")
    if fit.start:  # hollow: the lower panel's shading says why
        ax.plot(result.taus[left_out], result.adev[left_out], "o", mfc="none", color="C0",
                ms=3.5)
    grid = np.geomspace(result.taus[0], result.taus[-1], 400)
    ax.plot(grid, fit.model_adev(grid), "-", color="k", lw=1.2, label="fitted sum")
    for i, k in enumerate(fit.terms):  # asymptotes: they leave the scale to the data
        if fit.coefficients[k] > 0 and fit.resolved[k]:
            ax.plot(grid, fit.term_adev(k, grid), "--", color=f"C{i + 1}", label=_legend(fit, k),
                    scalex=False, scaley=False)
    _readoff_marks(ax, fit, result)
    ax.set_ylabel(f"Allan deviation ({mathtext_units(result.units or 'units')})")
    ax.grid(True, which="both", alpha=0.3)
    model = fit.model_adev(result.taus)
    low.fill_between(result.taus, *np.clip([model / result.upper, model / result.lower],
                                           *RATIO_RANGE), color="C0", alpha=0.25,
                     label="data's 68 % interval")
    if plot_ratio(low, result.taus, model / result.adev, fit.start, "k", label="fit / data"):
        frame_ratio(low)
    low.axhline(1.0, color="0.4", lw=0.8)
    if fit.start:
        low.axvspan(result.taus[0], fit.fitted_taus[0], color="0.85",
                    label="left out (the sensor's filtering)")
    low.set_xlabel(r"averaging time $\tau$ (s)")
    low.set_ylabel("fit / data")
    low.grid(True, which="both", alpha=0.3)
    legend_outside(fig)
    wrap_title(ax, mathtext_units(f"Allan deviation and the fitted noise terms: {title}"))
    return fig


def plot_ratio(ax: Axes, taus: np.ndarray, ratio: np.ndarray, start: int, color: str,
               label: str | None = None) -> bool:
    """Plot fit/data against tau in ``ax``, within :data:`RATIO_RANGE`; say if any is beyond.

    Dots joined by a line; hollow before ``start`` (the taus left out of the fit); a point
    beyond the range a triangle at its edge, pointing the way it goes, so that one far-off
    tau does not flatten the range the fit is judged in.  With a ``label``, the dots have it
    and the triangles :data:`BEYOND`.
    """
    ratio = np.asarray(ratio, dtype=float)
    low, high = RATIO_RANGE
    beyond = (ratio < low) | (ratio > high)
    ax.semilogx(taus, np.where(beyond, np.nan, ratio), "-", color=color, lw=0.8)
    fitted = np.arange(len(ratio)) >= start
    ax.plot(taus[fitted & ~beyond], ratio[fitted & ~beyond], "o", color=color, ms=3,
            label=label)
    ax.plot(taus[~fitted & ~beyond], ratio[~fitted & ~beyond], "o", color=color, mfc="none",
            ms=3)
    for edge, side, marker in ((high, ratio > high, "^"), (low, ratio < low, "v")):
        if side.any():
            ax.plot(taus[side], np.full(int(side.sum()), edge), marker, color=color, ms=5,
                    clip_on=False, label=BEYOND if label and marker == "^" else None)
    return bool(beyond.any())


def frame_ratio(ax: Axes) -> None:
    """Set a fit/data panel with points beyond :data:`RATIO_RANGE` to that range, labelled.

    Its edges are where the triangles of :func:`plot_ratio` sit; left to the autoscaling, a
    band or a layout could widen it past them.
    """
    from matplotlib.ticker import FixedLocator

    ax.set_ylim(*RATIO_RANGE)
    low, high = RATIO_RANGE
    ax.yaxis.set_major_locator(FixedLocator(np.arange(low, high + low / 2, low).tolist()))


def _readoff_marks(ax: Axes, fit: NoiseFit, result: AllanResult) -> None:
    """Mark the classic read-offs as crosses, one series: N at 1 s, K at 3 s, the minimum (B).

    Only those within the data's range: a read-off far off the curve says nothing the
    tables do not.
    """
    marks = [(1.0, fit.readoff.get("N", math.nan)), (3.0, fit.readoff.get("K", math.nan)),
             (fit.readoff.get("min_tau_s", math.nan), fit.readoff.get("min_adev", math.nan))]
    shown = [(t, v) for t, v in marks if np.isfinite(t) and np.isfinite(v)
             and result.lower.min() <= v <= result.upper.max()]
    if shown:
        taus, values = zip(*shown)
        ax.plot(taus, values, "x", color="0.2", ms=8, mew=1.5, scalex=False, scaley=False,
                label="classic read-offs: N at 1 s, K at 3 s, the minimum (0.664 B)")


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

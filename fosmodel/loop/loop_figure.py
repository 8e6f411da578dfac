"""The residual loop's residual figure: each diagnostic of the first and the final model."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from ..io.figures import PLAIN_DECADES, fit_title, legend_outside, plain_labels
from ..typeset.latex import mathtext_units
from .diagnose import Finding
from .outcome import LoopOutcome


def finding_name(finding: Finding) -> str:
    """Return a test as the tables name it, with its channel (``aux temp_c``) if it has one."""
    channel = finding.evidence.get("channel")
    return finding.test + (f" {channel}" if channel else "")


#: How the first (before) and the final (after) model are drawn: the first wide and grey, the
#: final thin, blue and dashed over it, so both show where they coincide.
_STYLES: dict[str, dict[str, Any]] = {"before": {"color": "0.6", "lw": 2.6, "ls": "-"},
           "after": {"color": "C0", "lw": 1.1, "ls": "--"}}
#: The channels the cross-correlation panel draws, those of the largest correlation: each is
#: two series (before, after), and more than a few cannot be told apart; the others are named
#: in the text panel.
_SHOWN_CHANNELS = 2
#: The shown channels' line styles and markers, in order of correlation: none is the before
#: or the after style of the other panels, so that each legend entry has a style of its own.
_CHANNEL_LINES = (("-.", "o"), (":", "^"))


def residual_figure(result: LoopOutcome, title: str) -> Figure:
    """Plot the residual diagnostics of the first (wide, grey) and the final (thin, blue) model.

    Every panel has its axes' labels; one legend below the panels; the cross-correlation
    panel draws the :data:`_SHOWN_CHANNELS` channels of the largest correlation and the text
    panel names the others with their largest one.
    """
    fig = Figure(figsize=(16, 7.5), layout="constrained")
    axes = fig.subplots(2, 4).ravel()
    rate = result.config.rate
    shown = _strongest_channels(result)
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
        aux = {f.evidence["channel"]: f for f in findings if f.test == "aux" and f.plot}
        for channel, (ls, marker) in zip(shown, _CHANNEL_LINES):
            f = aux[channel]
            axes[3].plot(f.plot["lags"], f.plot["rho"], label=f"{label} {channel}",
                         **{**style, "ls": ls}, marker=marker, ms=3)
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
    if not shown:
        axes[3].text(0.5, 0.5, "no other channel in the record", ha="center", va="center",
                     transform=axes[3].transAxes)
    for ax, band_too in zip(axes[:7], (True, False, False, True, False, False, False)):
        _frame(ax, "x")
        _frame(ax, "y", [-band, band] if band_too else [])
    for ax, (text, xlabel, ylabel) in zip(axes, _panels(result.config.units or "units")):
        ax.set_title(text, fontsize="medium")
        ax.set_xlabel(xlabel)
        ax.set_ylabel(ylabel)
        ax.grid(True, alpha=0.3)
        for name in ("x", "y"):
            _plain_ticks(ax, name)
    axes[7].axis("off")
    axes[7].text(0, 1, _fired_text(result, shown), va="top", family="monospace",
                 fontsize="small")
    legend_outside(fig)
    fit_title(fig, "Residual diagnostics of the first (wide, grey) and the final (thin, blue) "
              "model", mathtext_units(title))
    return fig


def _strongest_channels(result: LoopOutcome) -> list[str]:
    """Return the channels the cross-correlation panel draws, the largest correlation first."""
    largest = _largest_correlations(result)
    return sorted(largest, key=lambda channel: -largest[channel])[:_SHOWN_CHANNELS]


def _largest_correlations(result: LoopOutcome) -> dict[str, float]:
    """Each channel's largest ``|rho|`` over the lags, of the first or the final model."""
    largest: dict[str, float] = {}
    for f in (*result.findings_before, *result.findings_after):
        if f.test == "aux" and f.plot:
            channel = f.evidence["channel"]
            rho = float(np.max(np.abs(f.plot["rho"])))
            largest[channel] = max(largest.get(channel, 0.0), rho)
    return largest


def _frame(ax: Axes, name: str, also: list[float] | None = None) -> None:
    """Fix the limits and labelled ticks of one axis of ``ax`` to enclose its curves (and ``also``).

    A linear axis: round steps, its ends labelled; a log one: limits at the 1, 2, 5 x 10^k
    values (whole decades from :data:`fosmodel.io.figures.PLAIN_DECADES` on) that
    :func:`fosmodel.io.figures.tidy` labels.  Set here, not left to ``tidy``'s bracketing:
    within a decade ``tidy`` labels a log axis at round linear steps, none of which lies
    below a curve that dips under the lowest one (the spectrum's), and the linear panels
    keep the same frame before and after a model, whatever their data.
    """
    from matplotlib import ticker

    if not ax.lines:
        return  # an empty panel keeps matplotlib's frame
    values = np.concatenate([np.asarray(line.get_ydata() if name == "y" else line.get_xdata(),
                                        dtype=float) for line in ax.lines] + [also or []])
    axis, set_lim = (ax.yaxis, ax.set_ylim) if name == "y" else (ax.xaxis, ax.set_xlim)
    log = axis.get_scale() == "log"
    values = values[np.isfinite(values) & ((values > 0) | (not log))]
    if not values.size:
        return
    low, high = float(values.min()), float(values.max())
    if log:
        set_lim(*_log_limits(low, high))
        return
    if high - low <= 1e-9 * max(abs(low), abs(high)):  # one value, but for its last digits
        low, high = low - 1.0, high + 1.0
    ticks = ticker.MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]).tick_values(low, high)
    # The locator's ticks, computed in floating point, may fall a rounding short of the ends.
    first = max((t for t in ticks if t <= low), default=low)
    last = min((t for t in ticks if t >= high), default=high)
    kept = [t for t in ticks if first <= t <= last] or [first, last]
    axis.set_major_locator(ticker.FixedLocator(kept))
    set_lim(first, last)


def _plain_ticks(ax: Axes, name: str) -> None:
    """Label a linear axis without an offset text: a power of ten goes into its label.

    Matplotlib writes values of 1e-6 as ``1e-6`` at the axis's end, over the label; here the
    ticks read ``-2``, ``0``, ``2`` and the label ``... ($10^{-6}$ (rad/s)$^{2}$)``.
    """
    from matplotlib import ticker

    axis = ax.yaxis if name == "y" else ax.xaxis
    if axis.get_scale() != "linear" or not ax.lines:
        return
    ticks = np.asarray(axis.get_majorticklocs(), dtype=float)
    largest = float(np.max(np.abs(ticks))) if ticks.size else 0.0
    power = math.floor(math.log10(largest)) if largest > 0 else 0
    if -3 <= power < 4:
        axis.set_major_formatter(ticker.ScalarFormatter(useOffset=False))
        return
    power = 3 * math.floor(power / 3)  # engineering: 10^-6, 10^-3, 10^3
    axis.set_major_locator(ticker.FixedLocator(ticks.tolist()))
    axis.set_major_formatter(ticker.FixedFormatter(plain_labels((ticks / 10.0**power).tolist())))
    label = axis.get_label().get_text()
    factor = f"$10^{{{power}}}$"
    at = label.rfind(" (") + 2 if label.endswith(")") else 0
    axis.set_label_text(f"{label[:at]}{factor} {label[at:]}" if at > 1
                        else f"{label} ({factor})")


def _log_limits(low: float, high: float) -> tuple[float, float]:
    """Return the 1, 2, 5 x 10^k values around ``low`` and ``high``, a decade apart at least."""
    bottom, top = _round_125(low, up=False), _round_125(high, up=True)
    if top / bottom < 10.0:  # within a decade tidy labels round steps that need not end here
        bottom = _round_125(top / 10.0, up=False)
    if math.log10(top / bottom) >= PLAIN_DECADES:  # labelled at the powers of ten only
        bottom = 10.0 ** math.floor(math.log10(bottom) + 1e-12)
        top = 10.0 ** math.ceil(math.log10(top) - 1e-12)
    return bottom, top


def _round_125(value: float, up: bool) -> float:
    """Round ``value`` down (or ``up``) to a 1, 2, 5 x 10^k value."""
    decade = 10.0 ** math.floor(math.log10(value))
    steps = [1.0, 2.0, 5.0, 10.0]
    if up:
        return min(s for s in steps if s * decade >= value * (1 - 1e-12)) * decade
    return max(s for s in steps if s * decade <= value * (1 + 1e-12)) * decade


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
             f"binned product of two lags ({mathtext_units(f'({units})^2')})",
             f"mean residual ({u})")]


def _smooth(s: np.ndarray, width: int = 25) -> np.ndarray:
    """Return the moving mean of ``s``; at the ends, the mean of the samples the window holds.

    (``mode="same"`` alone averages zeros in at the ends and bends the curve down there.)
    """
    window = np.ones(width)
    return np.convolve(s, window, mode="same") / np.convolve(np.ones_like(s), window,
                                                             mode="same")


def _fired_text(result: LoopOutcome, shown: list[str]) -> str:
    lines = ["tests that fire (before -> after):"]
    for b, a in zip(result.findings_before, result.findings_after):
        yes = {True: "yes", False: "no"}
        lines.append(f"  {finding_name(b):<18} {yes[b.fired]:>3} -> {yes[a.fired]}")
    lines.append("effects kept:")
    lines += [f"  {s.effect.describe()}" for s in result.steps] or ["  none"]
    largest = _largest_correlations(result)
    hidden = [c for c in largest if c not in shown]
    if hidden:  # the cross-correlation panel draws only the strongest channels
        lines.append("cross-correlation not drawn:")
        lines += [f"  {c:<16} max |rho| {largest[c]:.3f}" for c in hidden]
    return "\n".join(lines)

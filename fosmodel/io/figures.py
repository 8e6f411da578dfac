"""Figures that read: tick labels that differ, curves between labels, legends off the data.

Every figure fosmodel writes goes through :func:`fosmodel.io.output.save_figure`, which first
calls :func:`tidy`:

* a log axis spanning less than three decades gets plain labels at 1, 2 and 5 times the
  powers of ten (``0.02``, ``0.05``, ``0.1``; matplotlib would write ``1.22x10^1``, or
  label two decades only), or at round steps within one decade, each with the fewest digits
  that keep the labels apart (five ``0.118`` on a narrow axis say nothing);
* the limits of an autoscaled axis reach out to the next labelled tick beyond the data (the
  ticks of the panel as laid out), so that every point of a curve can be read between two
  labels.

:func:`figure_problems` checks a drawn figure for what a reader cannot read: tick labels that
repeat, a curve outside the labels' range or outside its axes, a legend over the data, more
series in a panel than a reader can tell apart, a title or label cut by the figure's edge.
``save_figure`` runs it on every figure when the environment variable ``FOSMODEL_FIGURE_LOG``
names a file, and appends a line per figure to that file (the tests read it, also from the
worker processes that draw a report's figures).
:func:`legend_outside` puts one legend for a whole figure beside its panels; :func:`fit_title`
puts a long title on two lines rather than past the figure's edges, :func:`wrap_title` a
panel's on as many as keep it within the panel.
"""

from __future__ import annotations

import math
import os
import re
import textwrap
from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np

from ..typeset.tables import text_width

if TYPE_CHECKING:
    from matplotlib.artist import Artist
    from matplotlib.axes import Axes
    from matplotlib.axis import Axis
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.text import Text
    from matplotlib.ticker import Formatter
    from matplotlib.transforms import BboxBase

#: The most series one panel shows (its legend's entries): beyond, facet or highlight.
MAX_SERIES = 6
#: A legend's "small" font against the 10 pt of :func:`fosmodel.typeset.tables.text_width`,
#: and a legend entry's key and padding (pt).
_SMALL, _LEGEND_KEY = 0.95, 45.0
#: A report's temporary folder (:func:`fosmodel.io.output.report_directory`) and its name.
_TEMPORARY = re.compile(r"^\.(.+)\.\d+\.[0-9a-f]{12}\.tmpdir$")
#: A log axis spanning fewer decades is labelled at 1, 2 and 5 times the powers of ten.
PLAIN_DECADES = 3
#: The most layouts and bracketings :func:`tidy` runs (see there).
_BRACKET_PASSES = 4
#: The environment variable naming the file :func:`log_problems` appends to.
FIGURE_LOG = "FOSMODEL_FIGURE_LOG"


def tidy(fig: Figure) -> None:
    """Label the axes of ``fig`` so that they read: plain, distinct, bracketing the data."""
    for ax in fig.axes:
        for axis, name in ((ax.xaxis, "x"), (ax.yaxis, "y")):
            low, high = sorted(_limits(ax, name))
            if axis.get_scale() == "log" and low > 0 and math.log10(high / low) < PLAIN_DECADES:
                _plain_log(axis, high / low)
    # A locator's ticks depend on its panel's size: the panels are sized first (the layout
    # engine runs in a draw), so that the ticks bracketed are those the saved figure labels.
    # Wider limits can lengthen the tick labels and so shrink a panel: bracketed again, until
    # a layout leaves every limit where it was.
    for _ in range(_BRACKET_PASSES):
        fig.draw_without_rendering()
        widened = [_bracket(ax, axis, name) for ax in fig.axes
                   for axis, name in ((ax.xaxis, "x"), (ax.yaxis, "y"))]
        if not any(widened):
            return


def _limits(ax: Axes, name: str) -> tuple[float, float]:
    return ax.get_xlim() if name == "x" else ax.get_ylim()


def _plain_log(axis: Axis, ratio: float) -> None:
    """Major ticks at 1, 2, 5 x 10^k over one to three decades, round steps within one."""
    from matplotlib import ticker  # here: writing tables or text needs no matplotlib

    axis.set_major_locator(ticker.LogLocator(base=10, subs=(1.0, 2.0, 5.0)) if ratio >= 10
                           else ticker.MaxNLocator(nbins=6, steps=[1, 2, 2.5, 5, 10]))
    axis.set_major_formatter(plain_formatter())
    axis.set_minor_formatter(ticker.NullFormatter())


def _bracket(ax: Axes, axis: Axis, name: str) -> bool:
    """Widen an autoscaled axis to the labelled ticks just beyond its curves' data.

    Returns whether its limits moved.
    """
    autoscaled = ax.get_autoscalex_on() if name == "x" else ax.get_autoscaley_on()
    low, high = sorted(_limits(ax, name))
    # what the autoscaling saw (curves drawn with scalex/scaley False, as asymptotes, are not)
    first, last = sorted(ax.dataLim.intervalx if name == "x" else ax.dataLim.intervaly)
    if not autoscaled or not (np.isfinite(first) and np.isfinite(last)) or first == last:
        return False  # set by hand, or nothing drawn
    # the ticks of a range that holds the data: a curve past the view's limits (a log axis
    # autoscaled within a decade) is bracketed too
    ticks = [t for t in axis.get_major_locator().tick_values(min(low, first), max(high, last))
             if np.isfinite(t) and (t > 0 or axis.get_scale() != "log")]
    # a tick computed as 0.010000000000000002 still labels a curve starting at 0.01
    below = max((t for t in ticks if t <= first + 1e-9 * abs(first)), default=low)
    above = min((t for t in ticks if t >= last - 1e-9 * abs(last)), default=high)
    new = (min(low, below), max(high, above))
    if new == (low, high):
        return False
    if name == "x":  # auto=None: a shared axis stays autoscaled for the next panel
        ax.set_xlim(*new, auto=None)
    else:
        ax.set_ylim(*new, auto=None)
    return True


def _data_lines(ax: Axes, name: str) -> Iterator[Line2D]:
    """Yield the visible lines of ``ax`` whose ``name`` coordinate is data (not an axhline's x)."""
    data = ax.transData
    own = ax.get_yaxis_transform() if name == "y" else ax.get_xaxis_transform()
    for line in ax.get_lines():
        if line.get_visible() and line.get_transform() in (data, own):
            yield line


def _values(line: Line2D, name: str) -> np.ndarray:
    values = np.asarray(line.get_ydata() if name == "y" else line.get_xdata(), dtype=float)
    return values[np.isfinite(values)]


def plain_formatter() -> Formatter:
    """Return a tick formatter of positional labels, as few digits as keep them apart.

    ``0.02``, ``0.05``, ``0.1``; ``0.1175``, ``0.118``, ``0.1185`` where three digits would
    print ``0.118`` thrice (:func:`plain_labels`).
    """
    from matplotlib import ticker  # here: writing tables or text needs no matplotlib

    class PlainFormatter(ticker.Formatter):
        def __call__(self, x: float, pos: int | None = None) -> str:
            return _plain(x, 3)

        def format_ticks(self, values: Sequence[float]) -> list[str]:
            return plain_labels(values)

    return PlainFormatter()


def plain_labels(values: Sequence[float]) -> list[str]:
    """Return the tick labels of ``values``: positional, as few digits as keep them apart."""
    for digits in range(3, 10):
        labels = [_plain(v, digits) for v in values]
        if len(set(labels)) == len(labels):
            return labels
    return labels


def _plain(value: float, digits: int) -> str:
    return np.format_float_positional(value, precision=digits, unique=True, fractional=False,
                                      trim="-")


def fit_title(fig: Figure, head: str, tail: str) -> None:
    """Title ``fig`` ``head: tail``, on two lines where one would be wider than the figure.

    A narrow figure of a record with a long name: ``tail`` goes under ``head``.
    """
    title = fig.suptitle(f"{head}: {tail}")
    if title.get_window_extent().width > fig.bbox.width:
        title.set_text(f"{head}:\n{tail}")


def wrap_title(ax: Axes, text: str, fontsize: str | float | None = None) -> Text:
    """Title ``ax`` ``text``, on as many lines as keep it within the axes' width.

    Broken first after its first ``: `` (the head above a record's and a column's name), then
    between words; a title no break fits (one long word) is set smaller.  The figure is laid
    out first, so that the width is the axes' as saved.
    """
    title = ax.set_title(text)
    if fontsize is not None:
        title.set_fontsize(fontsize)
    # a subfigure's panel: its root figure lays it out
    fig = cast("Figure", getattr(ax.figure, "figure", ax.figure))
    fig.draw_without_rendering()  # the layout engine sizes the axes in a draw
    width = ax.get_window_extent().width

    def fits(candidate: str) -> bool:
        title.set_text(candidate)
        return title.get_window_extent().width <= width

    head, colon, tail = text.partition(": ")
    candidates = [text, *([f"{head}:\n{tail}"] if colon else []),
                  *(textwrap.fill(text, columns, break_long_words=False, break_on_hyphens=False)
                    for columns in range(len(text) - 4, 15, -4))]
    if any(fits(candidate) for candidate in candidates):
        return title
    size = float(title.get_fontsize())
    while size > 6 and not fits(title.get_text()):
        size -= 1
        title.set_fontsize(size)
    return title


def legend_outside(fig: Figure, axes: Sequence[Axes] | None = None) -> None:
    """Put one legend of the labelled series of ``axes`` (default: all) below the panels.

    Each label once, in the order first drawn, in up to four columns; the figure needs the
    constrained layout.
    """
    seen: dict[str, Artist] = {}
    for ax in axes if axes is not None else fig.axes:
        handles, labels = ax.get_legend_handles_labels()
        for handle, label in zip(handles, labels):
            seen.setdefault(label, handle)
    if seen:  # as many columns as the figure's width holds the longest label in
        longest = max(text_width(str(label)) for label in seen) * _SMALL
        columns = int(fig.get_figwidth() * 72 // (longest + _LEGEND_KEY))
        fig.legend(list(seen.values()), list(seen), loc="outside lower center",
                   ncols=max(1, min(len(seen), 4, columns)), fontsize="small")


def figure_problems(fig: Figure) -> list[str]:
    """Say what a reader of the drawn ``fig`` cannot read; an empty list if nothing.

    Checked per panel (axes with something drawn): its tick labels in view are distinct; each
    curve has points in view and they lie within half a tick interval of the labelled
    range; a panel shows at most :data:`MAX_SERIES` labelled series; no legend covers a
    point of a curve; no title, axis label or legend reaches beyond the figure's edge.  Call
    it after the figure is drawn (saved).
    """
    problems = []
    for i, ax in enumerate(fig.axes):
        if not ax.axison or not ax.get_lines():
            continue
        where = f"panel {i + 1} ({ax.get_title() or ax.get_ylabel() or 'untitled'})"
        for axis, name in ((ax.xaxis, "x"), (ax.yaxis, "y")):
            problems += [f"{where}: {p}" for p in _axis_problems(ax, axis, name)]
        labelled = [t for t in ax.get_legend_handles_labels()[1] if not str(t).startswith("_")]
        if len(labelled) > MAX_SERIES:
            problems.append(f"{where}: {len(labelled)} series, more than {MAX_SERIES}")
    problems += _legend_problems(fig)
    return problems + _text_problems(fig)


def _labelled_ticks(ax: Axes, axis: Axis, name: str) -> tuple[list[float], list[str]]:
    """Return the major tick positions in view and their labels, as drawn."""
    low, high = sorted(_limits(ax, name))
    span = high - low
    locs = [t for t in axis.get_majorticklocs() if low - 1e-9 * span <= t <= high + 1e-9 * span]
    labels = list(axis.get_major_formatter().format_ticks(locs)) if locs else []
    kept = [(t, s) for t, s in zip(locs, labels) if s.strip()]
    return [t for t, _ in kept], [s for _, s in kept]


def _axis_problems(ax: Axes, axis: Axis, name: str) -> list[str]:
    ticks, labels = _labelled_ticks(ax, axis, name)
    out = []
    repeated = sorted({s for s in labels if labels.count(s) > 1})
    if repeated:
        out.append(f"{name} tick labels repeat: {', '.join(repeated)}")
    if len(ticks) < 2:
        return out + ([f"fewer than two labelled {name} ticks"] if _any_data(ax, name) else [])
    # compare in display coordinates: the same rule for linear and log axes
    to_display = ax.transData.transform
    pos = [to_display((t, 0.0) if name == "x" else (0.0, t))[0 if name == "x" else 1]
           for t in ticks]
    low_tick, high_tick = min(pos), max(pos)
    slack = 0.5 * min(np.diff(sorted(pos)))
    box = ax.get_window_extent()
    for line in _data_lines(ax, name):
        xy = _shown(line)
        if not len(xy):
            continue
        inside = ((xy[:, 0] >= box.x0 - 1) & (xy[:, 0] <= box.x1 + 1) & (xy[:, 1] >= box.y0 - 1)
                  & (xy[:, 1] <= box.y1 + 1))
        label = _name(line)
        if not inside.any():
            out.append(f"{label} lies outside its axes")
            continue
        seen = xy[inside, 0 if name == "x" else 1]
        if seen.min() < low_tick - slack or seen.max() > high_tick + slack:
            out.append(f"{label} reaches beyond the labelled {name} ticks "
                       f"({labels[0]}..{labels[-1]})")
    return out


def _any_data(ax: Axes, name: str) -> bool:
    return any(len(_values(line, name)) for line in _data_lines(ax, name))


def _legend_problems(fig: Figure) -> list[str]:
    """Name each legend cut by the figure's edge, or whose box holds a point of a curve."""
    legends = [*fig.legends, *(ax.get_legend() for ax in fig.axes)]
    out = []
    for legend in (legend for legend in legends if legend is not None):
        box = legend.get_window_extent()
        if _beyond(box, fig.bbox):
            out.append("a legend reaches beyond the figure's edge")
        for ax in fig.axes:
            clip = ax.get_window_extent()
            for line in ax.get_lines():
                xy = _shown(line)
                xy = xy[(xy[:, 0] >= clip.x0) & (xy[:, 0] <= clip.x1)
                        & (xy[:, 1] >= clip.y0) & (xy[:, 1] <= clip.y1)]
                if ((xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0)
                        & (xy[:, 1] < box.y1)).any():
                    out.append(f"the legend covers {_name(line)} in panel "
                               f"{fig.axes.index(ax) + 1}")
    return sorted(set(out))


def _text_problems(fig: Figure) -> list[str]:
    """Name each title and axis label that the figure's edge cuts."""
    # a text keeps the renderer that last drew it: after a save at 300 dpi its extent would be
    # in that save's pixels, the figure's box in its own
    fig.draw_without_rendering()
    texts = [*fig.texts, *(t for ax in fig.axes if ax.axison
                           for t in (ax.title, ax.xaxis.label, ax.yaxis.label))]
    return [f"'{text.get_text()}' reaches beyond the figure's edge" for text in texts
            if text.get_visible() and text.get_text().strip()
            and _beyond(text.get_window_extent(), fig.bbox)]


def _beyond(box: BboxBase, edge: BboxBase) -> bool:
    """Whether ``box`` reaches more than a pixel past ``edge``."""
    return box.x0 < edge.x0 - 1 or box.x1 > edge.x1 + 1 or box.y0 < edge.y0 - 1 \
        or box.y1 > edge.y1 + 1


def _shown(line: Line2D) -> np.ndarray:
    """Return the finite points of a visible ``line`` in display coordinates (none if hidden)."""
    if not line.get_visible():
        return np.empty((0, 2))
    xy = np.column_stack([np.asarray(line.get_xdata(), dtype=float),
                          np.asarray(line.get_ydata(), dtype=float)])
    xy = line.get_transform().transform(xy)
    return xy[np.isfinite(xy).all(axis=1)]


def _name(line: Line2D) -> str:
    label = str(line.get_label())
    return "a curve" if label.startswith("_") else label


def log_problems(fig: Figure, path: os.PathLike[str] | str) -> None:
    """Append ``path`` and what :func:`figure_problems` finds to the file :data:`FIGURE_LOG`.

    One line per figure: the end of its path (a report's temporary folder named as the
    report), a tab, the problems joined by ``; `` (none: nothing); nothing when the variable
    is not set.
    """
    log = os.environ.get(FIGURE_LOG)
    if not log:
        return
    where = "/".join(_TEMPORARY.sub(r"\1", part) for part in Path(path).parts[-4:])
    line = f"{where}\t{'; '.join(figure_problems(fig))}\n"
    with open(log, "a", encoding="utf-8") as fh:  # one short write: whole lines from workers
        fh.write(line)

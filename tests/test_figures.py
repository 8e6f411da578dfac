"""Figures for a paper: 300 dpi PNGs, plain log ticks, labelled panels, titles that say what."""

from __future__ import annotations

import matplotlib.image
import numpy as np
import pytest
from matplotlib.figure import Figure
from scipy.signal import lfilter

from fosmodel.io.output import FIGURE_DPI, save_figure
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.loop_report import residual_figure
from fosmodel.noise.allan import allan_deviation
from fosmodel.noise.allan_fit import fit_noise
from fosmodel.noise.allan_report import allan_figure
from fosmodel.study.harness import StudyConfig
from fosmodel.study.report import order_figure
from fosmodel.study.runner import run_study
from fosmodel.typeset.latex import mathtext_units


def _labels(axis) -> list[str]:
    """The texts of an axis's tick labels in view, major and minor."""
    low, high = sorted(axis.get_view_interval())
    return [t.get_text() for minor in (False, True) for t in axis.get_ticklabels(minor=minor)
            if t.get_text() and low <= t.get_position()[axis is axis.axes.yaxis] <= high]


def _plain(labels: list[str]) -> bool:
    return all("times" not in s and "^" not in s and "\u00d7" not in s for s in labels)


def test_the_png_has_300_dpi_and_the_svg_is_written_beside_it(tmp_path):
    fig = Figure(figsize=(4.0, 2.5))
    fig.subplots().plot([0, 1], [0, 1])
    png, svg = save_figure(fig, tmp_path, "line")
    assert FIGURE_DPI == 300
    assert matplotlib.image.imread(png).shape[:2] == (2.5 * 300, 4.0 * 300)
    assert svg.read_text().lstrip().startswith("<?xml")


def test_the_svg_is_drawn_once_in_the_layout_of_the_png(tmp_path):
    # the PNG's save lays the figure out (one walk without drawing, then the drawing); the
    # SVG's draws once in that layout, even under rc settings that ask for another engine
    with matplotlib.rc_context({"figure.autolayout": True}):
        fig = Figure(figsize=(4.0, 3.0), layout="constrained")
        ax = fig.subplots()
        ax.plot([0, 1], [0, 1])
        ax.set_ylabel("a long label that the layout makes room for")
        draws, positions = [], []
        draw = fig.draw

        def counted(renderer):
            draws.append(type(renderer).__name__)
            draw(renderer)
            positions.append(ax.get_position().bounds)

        fig.draw = counted
        save_figure(fig, tmp_path, "layout")
    assert draws == ["RendererAgg", "RendererAgg", "MixedModeRenderer"]  # the last: SVG
    assert positions[1] == positions[2] != (0.125, 0.11, 0.775, 0.77)  # not matplotlib's default
    assert fig.get_layout_engine() is None


@pytest.mark.parametrize(("low", "high"), [(12.2, 18.0), (0.0012, 0.009), (2e-5, 1.5e-4),
                                           (0.05, 2.0)])
def test_a_log_axis_of_less_than_two_decades_has_plain_tick_labels(tmp_path, low, high):
    fig = Figure(figsize=(4.0, 3.0))
    ax = fig.subplots()
    ax.semilogy([0, 1], [low, high])
    ax.set_xscale("log")
    ax.set_xlim(1.0, 1000.0)  # three decades: powers of ten, as matplotlib writes them
    save_figure(fig, tmp_path, "log")
    labels = _labels(ax.yaxis)
    assert len(labels) >= 2 and _plain(labels), labels
    assert all(float(s) > 0 for s in labels)
    assert _labels(ax.xaxis) == ["$\\mathdefault{10^{0}}$", "$\\mathdefault{10^{1}}$",
                                 "$\\mathdefault{10^{2}}$", "$\\mathdefault{10^{3}}$"]


def test_units_read_one_way_in_every_figure():
    assert mathtext_units("MSE (m/s^2)^2") == "MSE (m/s$^{2}$)$^{2}$"
    assert mathtext_units("N = 0.1 deg/sqrt(h), cost $5") == (
        "N = 0.1 deg/$\\sqrt{\\mathrm{h}}$, cost \\$5")


@pytest.fixture(scope="module")
def loop_result():
    n, rate = 12_000, 50.0
    e = np.random.default_rng(3).standard_normal(n + 500)
    temp = np.linspace(20.0, 30.0, n)
    y = 0.05 * lfilter([1.0], [1.0, -0.8, 0.3], e)[500:] + 0.02 * (temp - 25.0) ** 2
    return close_loop(y, {"temp_c": temp}, LoopConfig(rate=rate, sensor="accel", units="m/s^2"))


def test_every_panel_of_the_loop_figure_has_its_axes_labelled(loop_result):
    fig = residual_figure(loop_result, "gx of rec.csv")
    panels = [ax for ax in fig.axes if ax.axison]
    assert len(panels) == 7
    assert all(ax.get_xlabel() and ax.get_ylabel() for ax in panels), [
        (ax.get_title(), ax.get_xlabel(), ax.get_ylabel()) for ax in panels]
    assert panels[2].get_ylabel() == "Allan deviation (m/s$^{2}$)"
    assert fig.get_suptitle().startswith("Residual diagnostics of the first")


def test_the_loop_figure_draws_before_wide_under_after(loop_result):
    fig = residual_figure(loop_result, "gx")
    for ax in [ax for ax in fig.axes if ax.axison][:6]:
        by_label = {line.get_label(): line for line in ax.lines}
        before = next(v for k, v in by_label.items() if k.startswith("before"))
        after = next(v for k, v in by_label.items() if k.startswith("after"))
        # the final model's trace lies over the first one's and is thinner, so both show
        assert ax.lines.index(after) > ax.lines.index(before)
        assert after.get_linewidth() < before.get_linewidth()
        assert after.get_color() != before.get_color()


def test_the_study_figure_says_what_it_shows_and_has_plain_log_ticks(tmp_path):
    e = np.random.default_rng(0).standard_normal(7000)
    y = lfilter([1.0], [1.0, -0.8, 0.3], e)[1000:] * 0.01
    config = StudyConfig(rate=10.0, sensor="accel", units="m/s^2", orders=(1, 2, 3, 4),
                         degrees=(1,), train_s=200.0, evaluate_s=200.0, n_starts=3)
    fig = order_figure(run_study(y, config), "fair", "accelerometer (paper_accel_y)")
    save_figure(fig, tmp_path, "order")
    assert fig.get_suptitle() == ("Prediction error against model order, fair protocol: "
                                  "accelerometer (paper_accel_y)")
    mse, outage = fig.axes
    assert mse.get_ylabel() == "one-step prediction MSE (m/s$^{2}$)$^{2}$"
    for ax in (mse, outage):
        low, high = ax.get_ylim()
        assert high / low < 100 and _plain(_labels(ax.yaxis)), _labels(ax.yaxis)


def test_the_allan_figure_has_a_title_that_says_what_it_shows(tmp_path):
    y = np.random.default_rng(1).standard_normal(5000)
    result = allan_deviation(y, 100.0, units="deg/s", sensor="gyro")
    fig = allan_figure(result, fit_noise(result), "gx of rec.csv")
    save_figure(fig, tmp_path, "allan")
    assert fig.axes[0].get_title() == "Allan deviation and the fitted noise terms: gx of rec.csv"
    assert all(ax.get_xlabel() or ax is fig.axes[0] for ax in fig.axes)

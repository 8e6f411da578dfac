"""Figures for a paper: 300 dpi PNGs, plain log ticks, labelled panels, titles that say what."""

from __future__ import annotations

import matplotlib.image
import numpy as np
import pytest
from matplotlib.figure import Figure
from scipy.signal import lfilter

from fosmodel.io.figures import figure_problems, fit_title, legend_outside, plain_labels, tidy
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
    # tidy lays the figure out to pick its ticks (one draw without rendering), the PNG's save
    # lays it out again (one walk without drawing, then the drawing); the SVG's draws once in
    # that layout, even under rc settings that ask for another engine
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
    assert draws == ["RendererAgg"] * 3 + ["MixedModeRenderer"]  # the last: SVG
    assert positions[2] == positions[3] != (0.125, 0.11, 0.775, 0.77)  # not matplotlib's default
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


def test_the_loop_figure_reads_with_one_legend_below_the_panels(loop_result, tmp_path):
    fig = residual_figure(loop_result, "gx of rec.csv")
    save_figure(fig, tmp_path, "residual")
    assert figure_problems(fig) == []
    assert len(fig.legends) == 1 and not any(ax.get_legend() for ax in fig.axes)


def test_the_loop_figure_of_a_six_axis_record_reads(tmp_path, figure_log, capsys):
    """Five channels beside the modelled one: the cross-correlation panel draws the two of the
    largest correlation (four series), the text panel names the other three; the spectrum's
    and the Allan deviation's curves lie between labelled ticks."""
    from fosmodel.cli import main

    log = figure_log()
    csv = tmp_path / "rec.csv"
    assert main(["synth", "static_imu", "--duration", "600", "--seed", "1", "--out",
                 str(csv)]) == 0
    assert main(["close-loop", str(csv), "--column", "gx_dps", "--out",
                 str(tmp_path / "loop")]) == 0
    capsys.readouterr()
    checked = log()
    assert [path.rsplit("/", 1)[-1] for path in checked] == ["residual.png"]
    assert {path: problems for path, problems in checked.items() if problems} == {}


def test_the_loop_figure_draws_the_strongest_channels_and_names_the_others():
    n, rate = 15_000, 50.0
    rng = np.random.default_rng(5)
    drive = rng.standard_normal(n)
    # the residual follows "strong" at lag 0, "middle" less; three channels are unrelated
    y = 0.6 * drive + 0.3 * np.roll(drive, 1) + rng.standard_normal(n)
    channels = {"strong": drive, "middle": np.roll(drive, 1) + 2.0 * rng.standard_normal(n),
                **{f"noise{k}": rng.standard_normal(n) for k in range(3)}}
    result = close_loop(y, channels, LoopConfig(rate=rate, sensor="gyro", units="deg/s"))
    fig = residual_figure(result, "gx")
    panel = fig.axes[3]
    assert sorted({line.get_label().split()[1] for line in panel.lines}) == ["middle", "strong"]
    text = fig.axes[7].texts[0].get_text()
    assert "cross-correlation not drawn:" in text
    assert all(f"noise{k}" in text.split("cross-correlation not drawn:")[1] for k in range(3))


def test_the_study_figure_says_what_it_shows_and_reads(tmp_path):
    e = np.random.default_rng(0).standard_normal(7000)
    y = lfilter([1.0], [1.0, -0.8, 0.3], e)[1000:] * 0.01
    config = StudyConfig(rate=10.0, sensor="accel", units="m/s^2", orders=(1, 2, 3, 4),
                         degrees=(1,), train_s=200.0, evaluate_s=200.0, n_starts=3)
    fig = order_figure(run_study(y, config), "fair", "accelerometer (paper_accel_y)")
    save_figure(fig, tmp_path, "order")
    assert fig.get_suptitle() == ("Prediction error against model order, fair protocol: "
                                  "accelerometer (paper_accel_y)")
    (mse, mse_level), (outage, outage_level) = np.reshape(fig.axes, (2, 2))
    assert mse.get_ylabel() == "one-step prediction MSE (m/s$^{2}$)$^{2}$"
    assert [ax.get_title() for ax in (mse, mse_level)] == ["methods as they are",
                                                          "methods about the local level"]
    assert figure_problems(fig) == []
    assert len(fig.legends) == 1 and not any(ax.get_legend() for ax in fig.axes)
    for ax in fig.axes:
        assert _plain(_labels(ax.yaxis)), _labels(ax.yaxis)


def test_the_allan_figure_has_a_title_that_says_what_it_shows(tmp_path):
    y = np.random.default_rng(1).standard_normal(5000)
    result = allan_deviation(y, 100.0, units="deg/s", sensor="gyro")
    fig = allan_figure(result, fit_noise(result), "gx of rec.csv")
    save_figure(fig, tmp_path, "allan")
    assert fig.axes[0].get_title() == "Allan deviation and the fitted noise terms: gx of rec.csv"
    assert all(ax.get_xlabel() or ax is fig.axes[0] for ax in fig.axes)


def _drawn(fig):
    fig.canvas.draw()
    return figure_problems(fig)


def test_the_checks_find_what_a_reader_cannot_read():
    """The study figure as it was: five tick labels 0.118, a legend over the data, twelve
    series in a panel, curves below the lowest tick label."""
    from matplotlib import ticker

    fig = Figure(figsize=(8.0, 3.5), layout="constrained")
    left, right = fig.subplots(1, 2)
    orders = np.arange(1, 11)
    for k in range(12):
        left.plot(orders, 0.1176 + 0.00001 * k + 0.000001 * orders, marker="o", label=f"m{k}")
    left.set_yscale("log")
    left.yaxis.set_major_locator(ticker.MaxNLocator(nbins=6))
    left.yaxis.set_major_formatter(ticker.FuncFormatter(lambda v, _: f"{v:.3g}"))
    left.legend(loc="center")
    right.plot(orders, np.linspace(10.4, 17.6, 10), label="outage")
    right.set_yscale("log")
    right.set_ylim(10.2, 18.2)
    right.yaxis.set_major_locator(ticker.FixedLocator([12, 14, 16, 18]))
    right.yaxis.set_major_formatter(ticker.ScalarFormatter())
    problems = _drawn(fig)
    assert any(p.startswith("panel 1 (untitled): y tick labels repeat: 0.118") for p in problems)
    assert "panel 1 (untitled): 12 series, more than 6" in problems
    assert any(p.startswith("the legend covers m") for p in problems)
    assert "panel 2 (untitled): outage reaches beyond the labelled y ticks (12..18)" in problems


def test_a_title_cut_by_the_edge_is_found_and_a_long_one_goes_on_two_lines(tmp_path):
    """The paper figure of the demo's accelerometer: seven inches wide, its one-line title
    reached past both edges."""
    fig = Figure(figsize=(7.0, 3.0), layout="constrained")
    fig.subplots().plot([1, 2, 3], [1.0, 2.0, 3.0])
    head, tail = ("Prediction error against model order, paper protocol",
                  "accelerometer (paper_accel_y, seed 2013)")
    fig.suptitle(f"{head}: {tail}")
    assert f"'{head}: {tail}' reaches beyond the figure's edge" in _drawn(fig)
    fit_title(fig, head, tail)
    assert fig.get_suptitle() == f"{head}:\n{tail}"
    assert not [p for p in _drawn(fig) if "edge" in p]
    fit_title(fig, head, "gx")  # a short one stays on one line
    assert fig.get_suptitle() == f"{head}: gx"


def test_tidy_labels_apart_and_brackets_the_curves():
    fig = Figure(figsize=(6.0, 3.0), layout="constrained")
    left, right = fig.subplots(1, 2)
    left.semilogy([1, 2, 3], [0.11755, 0.1178, 0.11805])
    right.plot([1, 2, 3], [10.4, 14.0, 17.6])
    tidy(fig)
    assert _drawn(fig) == []
    low, high = right.get_ylim()
    assert low <= 10.0 and high >= 18.0  # the labelled ticks beyond the data
    assert plain_labels([0.1175, 0.118, 0.1185]) == ["0.1175", "0.118", "0.1185"]
    assert plain_labels([0.02, 0.05, 0.1]) == ["0.02", "0.05", "0.1"]


@pytest.mark.parametrize("seed", range(5))
def test_tidy_brackets_with_the_ticks_of_the_laid_out_panels(tmp_path, seed):
    # a small figure of many panels: the constrained layout shrinks them, and a locator on the
    # shrunken panel labels fewer ticks than on the panel before the layout
    rng = np.random.default_rng(seed)
    fig = Figure(figsize=(6, 4), layout="constrained")
    for ax in fig.subplots(3, 3).flat:
        level, span = rng.uniform(-5, 5), 10 ** rng.uniform(-2, 2)
        x = np.linspace(0, rng.uniform(1, 1000), 50)
        for label in ("a", "b"):
            ax.plot(x, level + span * rng.random(50), label=label)
        ax.set(title="t", ylabel="a long label\nof two lines")
    fig.suptitle("panels")
    legend_outside(fig)
    save_figure(fig, tmp_path, "panels")
    assert figure_problems(fig) == []


def test_every_figure_of_a_study_reads(tmp_path, figure_log, capsys):
    """Each figure of ``study`` (both protocols), checked as it is written; the demo's figures
    are checked in tests/test_cli.py's run of the demo, the residual loop's below."""
    from fosmodel.cli import main

    log = figure_log()
    csv = tmp_path / "rec.csv"
    assert main(["synth", "static_imu", "--duration", "600", "--seed", "1", "--out",
                 str(csv)]) == 0
    assert main(["study", str(csv), "--column", "gx_dps", "--orders", "1-4", "--out",
                 str(tmp_path / "s")]) == 0
    capsys.readouterr()
    checked = log()
    assert sorted(path.rsplit("/", 2)[-1] for path in checked) == ["order_fair.png",
                                                                   "order_paper.png"]
    assert {path: problems for path, problems in checked.items() if problems} == {}


@pytest.mark.slow
def test_every_figure_of_the_allan_commands_reads(tmp_path, figure_log, capsys):
    """``allan --column`` and ``allan --columns``: each axis's figure and each sensor's."""
    from fosmodel.cli import main

    log = figure_log()
    csv = tmp_path / "rec.csv"
    assert main(["synth", "static_imu", "--duration", "600", "--seed", "2", "--out",
                 str(csv)]) == 0
    assert main(["allan", str(csv), "--column", "gz_dps", "--out", str(tmp_path / "one")]) == 0
    assert main(["allan", str(csv), "--columns", "gx_dps,gy_dps,gz_dps,ax_mps2,ay_mps2,az_mps2",
                 "--out", str(tmp_path / "six")]) == 0
    capsys.readouterr()
    checked = log()
    assert len(checked) == 1 + 2 + 6
    assert {path: problems for path, problems in checked.items() if problems} == {}


def test_a_long_allan_title_is_wrapped_within_its_panel(tmp_path):
    """A record's name after the head would run past the panel's right edge on one line."""
    y = np.random.default_rng(1).standard_normal(5000)
    result = allan_deviation(y, 100.0, units="m/s^2", sensor="accel")
    fig = allan_figure(result, fit_noise(result), "static_imu_record_long_name.csv.gz: ax_mps2")
    save_figure(fig, tmp_path, "allan")
    fig.draw_without_rendering()  # the extents in the figure's own renderer
    title, panel = fig.axes[0].title, fig.axes[0]
    assert title.get_text() == ("Allan deviation and the fitted noise terms:\n"
                                "static_imu_record_long_name.csv.gz: ax_mps2")
    assert title.get_window_extent().width <= panel.get_window_extent().width
    assert figure_problems(fig) == []


@pytest.fixture(scope="module")
def filtered():
    """Three gyro axes averaged over 20 samples: below 0.2 s the deviation falls under the
    white noise line the fit (from 1 s on) draws, the fit over the data up to about 4."""
    from scipy.ndimage import uniform_filter1d

    rng = np.random.default_rng(4)
    return {f"g{a}_dps": uniform_filter1d(rng.standard_normal(60_000), 20) for a in "xyz"}


def _ratio_checks(low, fig):
    from fosmodel.noise.allan_report import BEYOND, RATIO_RANGE

    assert low.get_ylim() == RATIO_RANGE  # whatever the layout, the band or the title
    shown = np.concatenate([line.get_ydata() for line in low.lines if len(line.get_ydata())])
    assert np.nanmax(shown) <= RATIO_RANGE[1] + 1e-12  # the far-off taus at the edge
    edge = [line for line in low.lines if line.get_marker() == "^" and len(line.get_ydata())]
    assert edge and all(np.all(line.get_ydata() == RATIO_RANGE[1]) for line in edge)
    labels = [t.get_text() for legend in [*fig.legends, *(a.get_legend() for a in fig.axes)]
              if legend for t in legend.get_texts()]
    assert BEYOND in labels
    hollow = [line for line in low.lines if line.get_markerfacecolor() == "none"
              and len(line.get_xdata())]
    assert hollow and max(max(line.get_xdata()) for line in hollow) < 1.0  # the left-out taus


def test_the_allan_fit_over_data_keeps_to_the_range_that_matters(filtered, tmp_path):
    result = allan_deviation(filtered["gx_dps"], 100.0, units="deg/s", sensor="gyro")
    fit = fit_noise(result, min_tau=1.0)
    assert (fit.model_adev(result.taus) / result.adev).max() > 3  # what would flatten it
    fig = allan_figure(result, fit, "a_rather_long_record_name_of_a_phone.csv.gz: gx_dps")
    save_figure(fig, tmp_path, "allan")
    _ratio_checks(fig.axes[1], fig)
    assert figure_problems(fig) == []


def test_the_combined_allan_figure_marks_the_taus_left_out(filtered, tmp_path):
    from fosmodel.noise.axes import resolve_axes
    from fosmodel.noise.imu_noise import imu_noise

    axes = resolve_axes(list(filtered))
    fig = imu_noise(filtered, axes, 100.0, "rec.csv", min_tau=1.0).figures()["gyro"]
    save_figure(fig, tmp_path, "allan_gyro")
    top, low = fig.axes
    left_out = [line for line in top.lines if line.get_markerfacecolor() == "none"]
    assert len([line for line in left_out if len(line.get_xdata())]) == 3  # one per axis
    assert "left out of the fit (the sensor's filtering)" in [
        t.get_text() for t in top.get_legend().get_texts()]
    _ratio_checks(low, fig)
    assert figure_problems(fig) == []


def _style(handle):
    return (str(handle.get_color()), handle.get_linestyle(), handle.get_linewidth(),
            handle.get_marker())


def test_every_legend_entry_of_the_loop_figure_has_a_style_of_its_own(loop_result):
    fig = residual_figure(loop_result, "gx")
    legend = fig.legends[0]
    labels = [t.get_text() for t in legend.get_texts()]
    assert "before temp_c" in labels and "before" in labels
    styles = [_style(h) for h in legend.legend_handles]
    assert len(set(styles)) == len(styles), dict(zip(labels, styles))


def test_the_loop_figure_puts_a_power_of_ten_in_the_label_not_over_it(tmp_path):
    """A gyro in rad/s: residuals of 1e-4, products of two lags of 1e-8."""
    n, rate = 12_000, 50.0
    e = np.random.default_rng(3).standard_normal(n + 500)
    y = 1e-4 * lfilter([1.0], [1.0, -0.8, 0.3], e)[500:]
    result = close_loop(y, {}, LoopConfig(rate=rate, sensor="gyro", units="rad/s"))
    fig = residual_figure(result, "gx")
    save_figure(fig, tmp_path, "residual")
    panel = fig.axes[6]
    assert panel.get_xlabel().startswith("binned product of two lags ($10^{-")
    assert panel.get_xlabel().endswith("$ (rad/s)$^{2}$)")
    for ax in fig.axes[:7]:
        for axis in (ax.xaxis, ax.yaxis):
            assert axis.get_offset_text().get_text() == "", (ax.get_title(), axis)
    assert figure_problems(fig) == []


def test_no_empty_decade_before_the_taus_left_out():
    """The shading of the left-out taus starts at the first tau, 0.01 s: a tick a rounding
    above 0.01 was taken for one that does not label it, and the axis widened to 0.001."""
    from data_synth import make_scenario

    y = make_scenario("static_imu", duration=900.0, seed=0).columns["ax_mps2"]
    result = allan_deviation(y, 100.0, units="m/s^2", sensor="accel")
    fig = allan_figure(result, fit_noise(result, min_tau=2.0), "x.csv.gz: ax")
    tidy(fig)
    assert fig.axes[1].get_xlim()[0] > result.taus[0] / 2

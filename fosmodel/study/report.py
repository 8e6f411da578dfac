"""Study reports: tables (Markdown, CSV, LaTeX) and figures (PNG, SVG) for papers and reports.

The comparison table follows the layout of Tamazin et al.'s (2013) Tables 1-2 (a block
per model order, a row per method) with the outage metrics added; the figure
is the paper's Figures 6-7 (prediction MSE against model order, log scale)
with the 30 s outage position error beside it.  Every file is written
atomically.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ..io.figures import fit_title, legend_outside
from ..io.output import save_figure, write_tables, write_text
from ..noise.metrics import caption_note, metric_definitions, segment_text
from ..typeset.latex import mathtext_units
from ..typeset.markdown import markdown_table
from .harness import LEVEL, StudyResult, method_label

_ORDER = ["yw", "cov", "burg", "gm", "fos"]


def _headers(result: StudyResult) -> dict[str, str]:
    u = result.config.units
    cols = {
        "label": "Method", "data": "Data", "order": "Order L", "mse": f"MSE ({u})^2",
        "position_error_m": "Position error (m)", "outage_mse": f"Outage MSE ({u})^2",
        "outage_position_error_m": f"Outage position error (m, {result.config.horizon_s:g} s)",
    }
    cols.update({f"bias_rms_{t:g}s": f"One-step bias RMS {t:g} s ({u})"
                 for t in result.config.taus})
    cols.update(runtime_s="Fit time (s)", n_terms="Terms")
    return cols


def study_table(result: StudyResult, frame: pd.DataFrame | None = None) -> pd.DataFrame:
    """Every scored configuration (or the rows of ``frame``), with readable headers.

    The columns that name a configuration come first (protocol, method, data, order, CP), so
    that a table split across pages repeats them.
    """
    frame = result.rows if frame is None else frame
    headers = _headers(result)
    names = {k: headers.pop(k) for k in ("label", "data", "order")}
    cols = {"protocol": "Protocol", **names, "degree": "CP",
            "evaluate_mse": f"Evaluate MSE ({result.config.units})^2", **headers}
    return frame[list(cols)].rename(columns=cols)


def paper_table(result: StudyResult, orders: tuple[int, ...] | None = None) -> pd.DataFrame:
    """Lay out the paper's Table 1/2: per model order, every method and the data it was fit on.

    The orders default to the lowest and the highest the study fitted (:func:`table_orders`).
    FOS is fit on the raw data under both protocols, so it appears once; the
    baselines appear on denoised data (paper protocol) and on raw data (fair).
    Gauss-Markov is a first-order model and appears in the block of the lowest order.
    """
    orders = table_orders(result) if orders is None else orders
    rows = result.rows[~result.rows["method"].str.endswith(LEVEL)]
    rows = rows[rows["order"].isin(orders) | (rows["method"] == "gm")]
    rows = rows.drop_duplicates(subset=["method", "order", "degree", "data"])
    blocks = []
    for order in orders:
        block = rows[(rows["order"] == order) & ((rows["method"] != "gm") | (order == min(orders)))]
        block = block.assign(_m=block["method"].map(_ORDER.index)).sort_values(
            ["_m", "degree", "data"], kind="stable")
        blocks.append(block.assign(order=order))
    frame = pd.concat(blocks) if blocks else rows.iloc[:0]
    cols = _headers(result)
    keep = ["order", "label", "data", "mse", "position_error_m", "outage_position_error_m",
            f"bias_rms_{max(result.config.taus):g}s", "runtime_s", "n_terms"]
    return frame[keep].rename(columns=cols).reset_index(drop=True)


def table_orders(result: StudyResult) -> tuple[int, ...]:
    """Return the orders of the comparison table: the lowest and the highest of the study."""
    return tuple(sorted({min(result.config.orders), max(result.config.orders)}))


def level_table(result: StudyResult) -> pd.DataFrame:
    """Fair protocol: each method's best configuration as it is and about the local level.

    FOS about the level is offered level candidates it weighs freely; a baseline
    about the level is fitted to the record minus one level (weight one), whose
    time constant is chosen on the evaluation segment with the order.
    """
    best = result.best()
    best = best[best["protocol"] == "fair"]
    cols = _headers(result)
    keep = ["label", "order", "level_tau_s", "mse", "outage_position_error_m",
            f"bias_rms_{max(result.config.taus):g}s", "n_terms"]
    frame = best.assign(_level=best["method"].str.endswith(LEVEL)).sort_values(
        ["_level", "method", "degree"], kind="stable")
    return frame[keep].rename(columns={**cols, "level_tau_s": "Level tau (s)"}).reset_index(
        drop=True)


def order_figure(result: StudyResult, protocol: str, title: str) -> Figure:
    """One-step prediction MSE and outage position error against model order, per method.

    A row of panels per metric and, under the fair protocol with levels, a column per
    family: the methods as they are, and about the local level, so that each panel shows a
    handful of series.  A method keeps its colour and marker in every panel, methods whose
    points coincide are set a little apart along the order axis so that none hides another,
    and one legend sits beside the panels.  A row's scale is logarithmic when its values span
    more than a decade.
    """
    cfg = result.config
    rows = result.rows[result.rows["protocol"] == protocol]
    # about the level a baseline has a row per time constant: the one chosen on evaluation
    rows = rows.loc[rows.groupby(["method", "order", "degree"], sort=False)["evaluate_mse"]
                    .idxmin()]
    level = rows["method"].str.endswith(LEVEL)
    families = [("as they are", ~level), ("about the local level", level)] if level.any() \
        else [("", ~level)]
    styles = _styles(rows)
    fig = Figure(figsize=(3.4 + 3.6 * len(families), 6.2), layout="constrained")
    axes = fig.subplots(2, len(families), squeeze=False, sharex=True, sharey="row")
    metrics = (("mse", mathtext_units(f"one-step prediction MSE ({cfg.units})^2")),
               ("outage_position_error_m",
                # two lines: one would run into the MSE label of the panel above
                f"position error after\na {cfg.horizon_s:g} s outage (m)"))
    for column, (family, chosen) in enumerate(families):
        series = list(rows[chosen].groupby(["method", "degree"], sort=False))
        dodge = np.linspace(-0.25, 0.25, len(series)) if len(series) > 1 else [0.0]
        for row, (key, ylabel) in enumerate(metrics):
            ax = axes[row][column]
            for shift, ((method, degree), group) in zip(dodge, series):
                base = method.removesuffix(LEVEL)
                color, marker = styles[base, degree]
                data = group["data"].iloc[0]
                label = method_label(base, degree) + ("" if data == "raw" else f" ({data})")
                if base == "gm":
                    ax.axhline(group[key].iloc[0], ls="--", color=color, label=label)
                else:
                    group = group.sort_values("order")
                    ax.plot(group["order"] + shift, group[key], marker=marker, color=color,
                            label=label, lw=1.2, ms=4.5)
            ax.set_xticks(sorted(rows["order"].unique()))
            ax.grid(True, which="both", alpha=0.3)
            if column == 0:
                ax.set_ylabel(ylabel)
            if row == 0 and family:
                ax.set_title(f"methods {family}", fontsize="medium")
            if row == 1:
                ax.set_xlabel("model order (maximum lag L)")
        for row, (key, _) in enumerate(metrics):
            values = rows[key].to_numpy(dtype=float)
            values = values[np.isfinite(values) & (values > 0)]
            if len(values) and values.max() > 10 * values.min():
                axes[row][0].set_yscale("log")
    legend_outside(fig)
    fit_title(fig, f"Prediction error against model order, {protocol} protocol",
              mathtext_units(title))
    return fig


def _styles(rows: pd.DataFrame) -> dict[tuple[str, int], tuple[str, str]]:
    """Give each method (FOS per degree) one colour and marker for every panel."""
    order = ["fos", *(m for m in _ORDER if m != "fos")]  # FOS first: the blue, the circles
    keys = sorted({(m.removesuffix(LEVEL), int(d)) for m, d in zip(rows["method"], rows["degree"])},
                  key=lambda k: (order.index(k[0]), k[1]))
    markers = "osD^vPX*"
    return {k: (f"C{i % 10}", markers[i % len(markers)]) for i, k in enumerate(keys)}


def write_study(result: StudyResult, out_dir: Path, title: str) -> list[Path]:
    """Every table and figure of a study, plus ``report.md`` that shows them."""
    out_dir.mkdir(parents=True, exist_ok=True)
    orders = " and ".join(map(str, table_orders(result)))
    note = caption_note(result.config.horizon_s, result.config.n_starts,
                        segment_text("prediction", result.split.predict, result.config.rate))
    tables = {
        "comparison": (paper_table(result), f"{title}: prediction and outage errors of every "
                       f"method at model orders {orders} (the layout of "
                       "Tamazin et al. 2013, Tables 1-2). "
                       f"{note}"),
        "study": (study_table(result), f"{title}: every configuration scored. {note}"),
        "best": (study_table(result, result.best()),
                 f"{title}: the best configuration of each method, chosen on the evaluation "
                 f"segment. {note}"),
    }
    if result.config.levels and "fair" in result.config.protocols:
        tables["level"] = (level_table(result), f"{title}: each method about the local level "
                           f"(fair protocol). {note}")
    paths = []
    for stem, (table, caption) in tables.items():
        paths += write_tables(table, out_dir, stem, caption, report=title)
    figures = []
    for protocol in result.config.protocols:
        figures += save_figure(order_figure(result, protocol, title), out_dir, f"order_{protocol}")
    paths += figures
    paths.append(out_dir / "report.md")
    write_text(paths[-1], report_markdown(result, title))
    return paths


def report_markdown(result: StudyResult, title: str) -> str:
    """Write the study as one Markdown page: setup, comparison, best rows, figures, warnings."""
    cfg, split = result.config, result.split
    n = split.predict.stop
    lines = [
        f"# {title}", "",
        f"{n} samples at {cfg.rate:g} Hz ({n / cfg.rate:.6g} s), {cfg.sensor}, units {cfg.units}. "
        f"Training {cfg.train_s:g} s, evaluation {cfg.evaluate_s:g} s, prediction "
        f"{(split.predict.stop - split.predict.start) / cfg.rate:.6g} s. Orders "
        f"{min(cfg.orders)}-{max(cfg.orders)}, FOS degrees {', '.join(map(str, cfg.degrees))}, "
        f"FOS stop rule {cfg.fos_stop}. Paper protocol: baselines on {cfg.paper_denoise}-"
        "denoised data, FOS on raw data; fair protocol: every method on raw data. Errors are "
        "one-step prediction errors on the prediction segment; outage metrics are free runs of "
        f"{cfg.horizon_s:g} s from {cfg.n_starts} starts across it.", "",
        f"## Comparison at orders {' and '.join(map(str, table_orders(result)))} "
        "(Tamazin et al. 2013, Tables 1-2 layout)", "",
        markdown_table(paper_table(result), digits=4), "",
        *_definitions(result), "",
        "## Best configuration per method (chosen on the evaluation segment)", "",
        markdown_table(study_table(result, result.best()), digits=4), "",
    ]
    if cfg.levels and "fair" in cfg.protocols:
        taus = ", ".join(f"{t:g}" for t in result.level_taus) or "none (record too short)"
        lines += [
            "## About the local level (fair protocol)", "",
            "The wandering bias as a stochastic level (the exponentially weighted mean of the "
            "output's past, time constants " + taus + " s, chosen below the training "
            "segment's Allan floor). FOS + level: FOS offered these levels beside its lags, "
            "each weighed freely. Baseline + level: the estimator fitted to the record minus "
            "one level (weight one), the level's time constant chosen on the evaluation "
            "segment with the order. Compare each method with its own + level row, and FOS + "
            "level with the best baseline + level.", "",
            markdown_table(level_table(result), digits=4), ""]
    for protocol in cfg.protocols:
        lines += [f"![{protocol} protocol](order_{protocol}.png)", ""]
    if result.warnings:
        lines += ["## Warnings", "", *[f"- {w}" for w in result.warnings], ""]
    lines += ["All rows: `study.csv` (also `.md`, `.tex`).", ""]
    return "\n".join(lines)


def _definitions(result: StudyResult) -> list[str]:
    """List under the first table what each metric is: its units, horizon and segment."""
    cfg, split = result.config, result.split
    defined = metric_definitions(cfg.units, cfg.horizon_s, cfg.n_starts,
                                 segment_text("prediction", split.predict, cfg.rate),
                                 segment_text("evaluation", split.evaluate, cfg.rate))
    keys = ("mse", "position_error_m", "outage_position_error_m", "bias_rms", "evaluate_mse")
    return ["What the columns are:", "", *[f"- {defined[k]}" for k in keys]]

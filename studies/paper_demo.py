"""The demo study from scratch: Tables 1-2 and Figures 6-7 of Tamazin et al. (2013), paper-like.

Runs ``fosmodel demo`` into ``studies/results/paper_demo/`` and rewrites the
section ``paper-demo`` of docs/pages/studies.md, with the two comparison tables, one figure and
the comparisons below them, all taken from this run.

Run: ``python studies/paper_demo.py``
"""

from __future__ import annotations

from pathlib import Path

from doc_pages import README, replace_section, show_figure

from fosmodel.demo import run_demo
from fosmodel.study import StudyResult, paper_table
from fosmodel.typeset import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "paper_demo"


def best_mse(result: StudyResult, protocol: str, methods: tuple[str, ...], col: str) -> tuple:
    best = result.best()
    rows = best[(best["protocol"] == protocol) & best["method"].isin(methods)]
    row = rows.loc[rows[col].idxmin()]
    return row["label"], int(row["order"]), float(row[col])


def comparison(name: str, result: StudyResult) -> str:
    """Sentences comparing the best FOS with the best AR baseline, per protocol and metric."""
    units = result.config.units
    lines = []
    for protocol in result.config.protocols:
        for col, what in (("mse", f"one-step MSE ({units})^2"),
                          ("outage_position_error_m", "30 s outage position error (m)")):
            fos = best_mse(result, protocol, ("fos",), col)
            ar = best_mse(result, protocol, ("yw", "cov", "burg", "gm"), col)
            lines.append(f"- {name}, {protocol} protocol, {what}: {fos[0]} (L={fos[1]}) "
                         f"{fos[2]:.4g}, best baseline {ar[0]} (L={ar[1]}) {ar[2]:.4g}: "
                         f"FOS / baseline = {fos[2] / ar[2]:.3g}.")
    return "\n".join(lines)


def main() -> None:
    results = run_demo(OUT)
    rel = OUT.relative_to(README.parent)
    parts = []
    for number, (name, result) in enumerate(results.items(), start=1):
        parts += [f"**Table {number}: {name}** (orders 1 and 10; all rows in "
                  f"`{rel}/{name}/study.csv`)", "", markdown_table(paper_table(result), digits=3),
                  "", comparison(name, result), ""]
    figure = show_figure(OUT / "accelerometer" / "order_fair.png", "paper_demo_order_fair.png")
    parts += [f"![accelerometer, fair protocol]({figure})", ""]
    replace_section("paper-demo", "\n".join(parts))
    print(f"section paper-demo of docs/pages/studies.md rewritten from {OUT}")


if __name__ == "__main__":
    main()

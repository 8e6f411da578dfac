"""Allan variance noise fit on a gyro with known ARW and RRW (Koldbæk and Totu 2011).

Twelve hours of gyro 1 of the ``gyro_array_8`` scenario at 102.4 Hz with the typical
values of Koldbæk and Totu (2011, eq. 5.4: ARW 0.068 deg/sqrt(s), RRW 0.00029 deg/sqrt(s^3));
the overlapping Allan deviation with its 68 % intervals and the five-term weighted
least-squares fit (quantization, ARW, bias instability, RRW, rate ramp), set against the truth.
Writes the deviation, the fit and the figure to ``studies/results/allan_arw_rrw/`` and rewrites the
documentation's section
``allan-arw-rrw`` from this run.

Run: ``python studies/allan_arw_rrw.py`` (about a minute).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from doc_pages import replace_section, show_figure

from data_synth import make_scenario
from fosmodel.noise import TERMS, allan_deviation, fit_noise, write_allan
from fosmodel.typeset import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "allan_arw_rrw"
HOURS = 12.0


def main() -> None:
    rec = make_scenario("gyro_array_8", duration=HOURS * 3600.0, seed=0, typical=True)
    truth = {"N": rec.truth["sources"][0]["params"]["densities"][0],
             "K": rec.truth["sources"][1]["params"]["densities"][0]}
    result = allan_deviation(rec.columns["gyro_1"], rec.rate, units="deg/s", sensor="gyro")
    fit = fit_noise(result)
    write_allan(result, fit, OUT, f"gyro_array_8 gyro_1, {HOURS:g} h at {rec.rate:g} Hz")
    rows = []
    for term in TERMS:
        lo, hi = fit.interval(term)
        rows.append({"Term": fit.name(term), "Units": fit.units(term),
                     "True": truth.get(term, 0.0),
                     "Fitted": fit.coefficients[term] if fit.resolved[term] else float("nan"),
                     "68 % interval": "not resolved" if not fit.resolved[term]
                     else f"{lo:.4g} - {hi:.4g}",
                     "Upper limit": fit.limits.get(term, float("nan"))})
    table = pd.DataFrame(rows)
    table.to_csv(OUT / "truth.csv", index=False)
    replace_section("allan-arw-rrw", "\n".join([
        f"`python studies/allan_arw_rrw.py`: {HOURS:g} h of gyro 1 of `gyro_array_8` at "
        f"{rec.rate:g} Hz with Koldbæk and Totu's (2011) ARW {truth['N']} deg/sqrt(s) and RRW "
        f"{truth['K']} "
        f"deg/sqrt(s^3), {len(result.taus)} averaging times from {result.taus[0]:.3g} to "
        f"{result.taus[-1]:.4g} s:", "",
        markdown_table(table, digits=4), "",
        f"![Allan deviation with the fitted lines]"
        f"({show_figure(OUT / 'allan.png', 'allan_arw_rrw.png')})"]))
    print(fit.summary())
    print(f"results in {OUT}; section allan-arw-rrw of docs/pages/allan.md rewritten")


if __name__ == "__main__":
    main()

"""The residual loop on synthetic records with undeclared effects: the table of the README.

For every loop scenario of data_synth (one undeclared effect each, two at once,
and two controls) the loop runs on seeds 0-9 (controls: 0-19).  The table
gives, for seed 0, the effect found and the prediction-segment error before
the loop, after it, and with the true effect added to the same starting model
(one-step MSE for fast effects, outage MSE for slow ones), and over all seeds
how often the right effect was found.  Full reports for seed 0 go to
``studies/results/close_loop/<scenario>/``; the README section
``close-loop-synthetic`` is rewritten from this run.

Run: ``python studies/close_loop_synthetic.py``
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
from readme_section import README, replace_section

from data_synth import make_scenario
from data_synth.true_effects import true_effects
from fosmodel.closeloop import LoopConfig, close_loop, score_family
from fosmodel.effects import CandidateFamily
from fosmodel.loop_report import write_loop_report
from fosmodel.summary import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "close_loop"
EFFECTS = ["undeclared_temperature", "undeclared_vibration", "undeclared_nonlinear",
           "undeclared_drift", "undeclared_aux_lag", "undeclared_step",
           "temperature_and_vibration"]
CONTROLS = ["clean", "unrelated_temperature"]


def run(name: str, seed: int):
    rec = make_scenario(name, seed=seed)
    y = rec.columns[rec.target]
    channels = {k: v for k, v in rec.columns.items() if k != rec.target}
    config = LoopConfig(rate=rec.rate, sensor="gyro", units=rec.truth["units"])
    return rec, y, channels, config, close_loop(y, channels, config)


def truth_metrics(rec, y, channels, config, res):
    """Prediction-segment metrics of the starting model with the true effects added."""
    time = np.arange(len(y)) / config.rate
    family = CandidateFamily(config.max_lag)
    for effect, _ in true_effects(rec.truth):
        family = family.add(effect, channels, time, res.segments["train"])
    return score_family(y, channels, config, family)


def describe(step) -> str:
    text = step.effect.describe()
    return text + (f", lag {step.lag}" if step.lag is not None else "")


def effect_rows() -> list[dict]:
    rows = []
    for name in EFFECTS:
        found = 0
        for seed in range(10):
            rec, y, channels, config, res = run(name, seed)
            truths = true_effects(rec.truth)
            ok = len(res.steps) == len(truths) and all(
                any(s.effect.same_as(t) for s in res.steps) for t, _ in truths)
            found += ok
            if seed == 0:
                write_loop_report(res, OUT / name, f"{name} (seed 0)")
                metric = "outage_mse" if any(slow for _, slow in truths) else "mse"
                true = truth_metrics(rec, y, channels, config, res)[metric]
                row = {"Record": name, "Found (seed 0)": "; ".join(map(describe, res.steps)),
                       "Metric": "outage MSE" if metric == "outage_mse" else "one-step MSE",
                       "Before": res.before[metric], "After": res.after[metric],
                       "True model": true,
                       "Share of the true gain": (res.before[metric] - res.after[metric])
                       / (res.before[metric] - true)}
        row["Found in seeds 0-9"] = f"{found}/10"
        rows.append(row)
    return rows


def control_rows() -> list[dict]:
    rows = []
    for name in CONTROLS:
        added, worst = 0, 0.0
        for seed in range(20):
            _, _, _, _, res = run(name, seed)
            added += bool(res.steps)
            worst = max(worst, res.after["mse"] / res.before["mse"] - 1)
        rows.append({"Record": name, "Records where an effect was added": f"{added}/20",
                     "Largest one-step MSE increase": f"{100 * worst:.2f} %"})
    return rows


def main() -> None:
    effects = pd.DataFrame(effect_rows())
    controls = pd.DataFrame(control_rows())
    OUT.mkdir(parents=True, exist_ok=True)
    effects.to_csv(OUT / "effects_found.csv", index=False)
    controls.to_csv(OUT / "controls.csv", index=False)
    rel = OUT.relative_to(README.parent)
    replace_section("close-loop-synthetic", "\n".join([
        markdown_table(effects, digits=4), "", markdown_table(controls), "",
        f"Reports for seed 0, with their residual figures: `{rel}/<record>/report.md`.", "",
        f"![undeclared temperature and vibration, seed 0]"
        f"({rel}/temperature_and_vibration/residual.png)"]))
    print(effects.to_string(index=False))
    print(controls.to_string(index=False))


if __name__ == "__main__":
    main()

"""The residual loop on synthetic records with undeclared effects: the tables of the documentation
(docs/pages/loop.md).

For every loop scenario of data_synth the loop runs on seeds 0-9 (controls:
0-19): the 5-minute records with one undeclared effect each (two at once in
one), and the 15-minute records with slow errors (a bias random walk,
warm-ups of 20, 60 and 180 s, a warm-up plus a linear drift, two bias steps,
and a random walk or a drift with a temperature that drives the bias).

For each record the table gives, for seed 0, what the loop kept and the
prediction-segment error before the loop, after it, and with the true effects
added to the same starting model (one-step MSE for fast effects, outage MSE
for slow ones); and over the seeds how often each true effect was *named*
(the loop kept that kind of effect: the channel, the line, the drift, the
step), how often a slow one was at least *followed* (named, or taken as the
local level, the stochastic form of a wandering bias), what else was kept,
and in how many seeds the prediction segment's 30 s bias RMS ended lower.
Full reports for seed 0 go to ``studies/results/close_loop/<record>/``; the
Section ``close-loop-synthetic`` of docs/pages/loop.md is rewritten from this run.

Run: ``python studies/close_loop_synthetic.py`` (about ten minutes).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
from doc_pages import README, replace_section, show_figure

from data_synth import make_scenario
from data_synth.true_effects import true_effects
from fosmodel.loop.closeloop import LoopConfig, close_loop, score_family
from fosmodel.loop.effects import CandidateFamily, Effect
from fosmodel.loop.loop_report import write_loop_report
from fosmodel.typeset.markdown import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "close_loop"
# (record name, scenario, overrides)
EFFECTS = [(name, name, {}) for name in (
    "undeclared_temperature", "undeclared_vibration", "undeclared_nonlinear",
    "undeclared_drift", "undeclared_aux_lag", "undeclared_step", "temperature_and_vibration",
    "slow_random_walk")]
EFFECTS += [(f"slow_warmup (tau {tau:g} s)", "slow_warmup", {"tau_s": tau})
            for tau in (20.0, 60.0, 180.0)]
EFFECTS += [(name, name, {}) for name in ("slow_warmup_drift", "slow_steps",
                                          "slow_random_walk_temperature",
                                          "slow_warmup_drift_temperature")]
CONTROLS = ["clean", "unrelated_temperature", "slow_clean", "slow_unrelated_temperature"]
SEEDS, CONTROL_SEEDS = range(10), range(20)


def run(scenario: str, seed: int, **overrides):
    rec = make_scenario(scenario, seed=seed, **overrides)
    y = rec.columns[rec.target]
    channels = {k: v for k, v in rec.columns.items() if k != rec.target}
    config = LoopConfig(rate=rec.rate, sensor="gyro", units=rec.truth["units"])
    return rec, y, channels, config, close_loop(y, channels, config)


def truth_metrics(rec, y, channels, config, res):
    """Prediction-segment metrics of the starting model with the true effects added (a
    random walk as the level the loop would offer)."""
    family = CandidateFamily(config.max_lag)
    for effect, _ in true_effects(rec.truth):
        if effect.kind == "level":
            effect = Effect("level", taus=res.level_taus)
        family = family.add(effect, channels, len(y), config.rate, res.segments.train)
    return score_family(y, channels, config, family)


def names(step_effect, true) -> bool:
    """Whether a kept effect is the true one: its kind, and its channel or frequency."""
    if step_effect.kind != true.kind:
        return False
    if true.kind == "aux":
        return step_effect.channel == true.channel
    if true.kind == "periodic":
        return abs(step_effect.freq_hz - true.freq_hz) < 0.05
    return True


def describe(step) -> str:
    text = step.effect.describe()
    if step.effect.kind == "level" and step.tau_s:
        text = f"local level (tau {step.tau_s:.3g} s)"
    return text + (f", lag {step.lag}" if step.lag is not None else "")


def _tally(res, truths) -> tuple[int, int, int]:
    """(true effects named, slow ones at least followed, other effects kept)."""
    kept = [s.effect for s in res.steps]
    level = any(e.kind == "level" for e in kept)
    named = [any(names(e, t) for e in kept) for t, _ in truths]
    followed = [n or (slow and level) for n, (_, slow) in zip(named, truths)]
    others = [e for e in kept if not any(names(e, t) for t, _ in truths)
              and not (e.kind == "level" and any(slow for _, slow in truths))]
    return sum(named), sum(followed), len(others)


def effect_row(label: str, scenario: str, overrides: dict) -> dict:
    counts = {"named": 0, "followed": 0, "others": 0, "lower": 0}
    for seed in SEEDS:
        rec, y, channels, config, res = run(scenario, seed, **overrides)
        truths = true_effects(rec.truth)
        named, followed, others = _tally(res, truths)
        counts["named"] += named == len(truths)
        counts["followed"] += followed == len(truths)
        counts["others"] += others > 0
        counts["lower"] += res.after["bias_rms"]["30"] < res.before["bias_rms"]["30"]
        if seed == 0:
            folder = scenario + "".join(f"_{v:g}s" for v in overrides.values())
            write_loop_report(res, OUT / folder, f"{label} (seed 0)")
            slow = any(s for _, s in truths)
            metric = "outage_mse" if slow else "mse"
            true = truth_metrics(rec, y, channels, config, res)[metric]
            row = {"Record": label, "Kept (seed 0)": "; ".join(map(describe, res.steps)) or "none",
                   "Metric": "outage MSE" if slow else "one-step MSE",
                   "Before": res.before[metric], "After": res.after[metric], "True model": true,
                   "Share of the true gain": (res.before[metric] - res.after[metric])
                   / (res.before[metric] - true)}
    n = len(SEEDS)
    row["Named in seeds 0-9"] = f"{counts['named']}/{n}"
    row["Followed (named or as a level)"] = f"{counts['followed']}/{n}"
    row["Seeds with other effects kept"] = f"{counts['others']}/{n}"
    row["30 s bias RMS lower (prediction)"] = f"{counts['lower']}/{n}"
    return row


def control_row(name: str) -> dict:
    added, worst = 0, 0.0
    for seed in CONTROL_SEEDS:
        _, _, _, _, res = run(name, seed)
        added += bool(res.steps)
        worst = max(worst, res.after["mse"] / res.before["mse"] - 1)
    return {"Record": name, "Records where an effect was added":
            f"{added}/{len(CONTROL_SEEDS)}",
            "Largest one-step MSE increase": f"{100 * worst:.2f} %"}


def main() -> None:
    effects = pd.DataFrame([effect_row(*e) for e in EFFECTS])
    controls = pd.DataFrame([control_row(name) for name in CONTROLS])
    OUT.mkdir(parents=True, exist_ok=True)
    effects.to_csv(OUT / "effects_found.csv", index=False)
    controls.to_csv(OUT / "controls.csv", index=False)
    rel = OUT.relative_to(README.parent)
    figure = show_figure(OUT / "slow_random_walk_temperature" / "residual.png",
                         "loop_residual.png")
    replace_section("close-loop-synthetic", "\n".join([
        markdown_table(effects, digits=4), "", markdown_table(controls), "",
        f"Reports for seed 0, with their residual figures: `{rel}/<record>/report.md`.", "",
        f"![a bias random walk with a temperature effect, seed 0]"
        f"({figure})"]))
    print(effects.to_string(index=False))
    print(controls.to_string(index=False))


if __name__ == "__main__":
    main()

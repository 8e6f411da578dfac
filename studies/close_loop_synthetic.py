"""The residual loop on synthetic records with undeclared effects: the tables of the documentation
(docs/pages/loop.md).

Four parts, each a section of the page:

* ``close-loop-synthetic``: every short loop scenario of data_synth on seeds 0-9
  (controls: 0-19): the 5-minute records with one undeclared effect each (two at
  once in one), the 15-minute records with slow errors (a step a third of the way in and
  a warm-up that starts late among them) and a ten-minute record whose bias follows a
  cooling die temperature.  For seed 0 what the loop
  kept and the prediction-segment error before the loop, after it, and with the true
  effects added to the same starting model (the 30 s outage MSE for slow effects,
  the one-step MSE for fast ones); over the seeds how often each true effect was
  *named* (the loop kept that kind of effect: the driver, the line, the drift, the
  step), how often a slow one was at least *followed* (named, or taken as the local
  level), what else was kept, and in how many seeds the 30 s bias RMS ended lower.
* ``close-loop-sweeps``: one IMU at 1 Hz whose gx_dps and ax_mps2 biases follow the
  temperature (data_synth's ``temperature_sweep``, ``temperature_sweep_lag`` with a
  30 min thermal lag, and three day-long ``temperature_sessions``, together and days 2
  and 3 alone), seeds 0-9: the
  temperature named, the 30 min outage bias RMS of the prediction segment (of every
  session's predicted part, pooled) against the starting model with the level alone,
  and their controls (no temperature effect, the same draws), seeds 0-19.
* ``close-loop-axes``: every axis of the three-day record, each day alone and the three
  together, seeds 0-9: the temperature named (on the four axes it does not drive, a false
  driver) and the runs with any ratio worse on prediction.
* ``close-loop-companions``: six axes whose noise is correlated across the gyros and
  across the accelerometers (``companion_noise``): the other axes of each one's kind
  are never inputs, and their correlation with the residual is reported beside the
  truth.

Full reports for seed 0 go to ``studies/results/close_loop/<record>/``.

Run: ``python studies/close_loop_synthetic.py [--jobs N] [--parts PART,...]`` (the parts:
synthetic, sweeps, axes, companions); ``--parts`` runs those parts only and rewrites only
their sections.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
from doc_pages import README, replace_section, show_figure

from data_synth import make_scenario, make_sessions
from data_synth.true_effects import true_effects
from fosmodel.core import in_workers, power_name
from fosmodel.loop import (
    CandidateFamily,
    Effect,
    LoopConfig,
    LoopRecord,
    Session,
    close_loop,
    close_sessions,
    make_effect,
    score_family,
    score_sessions,
    write_loop_report,
    write_sessions_report,
)
from fosmodel.typeset import markdown_table

OUT = Path(__file__).resolve().parent / "results" / "close_loop"
REL = OUT.relative_to(README.parent)
JOBS = int(sys.argv[sys.argv.index("--jobs") + 1]) if "--jobs" in sys.argv else 2
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
# effects that begin inside the record, and a driver on ten minutes
EFFECTS += [(name, name, {}) for name in ("slow_step_third", "slow_late_warmup",
                                          "short_driver")]
CONTROLS = ["clean", "unrelated_temperature", "slow_clean", "slow_unrelated_temperature",
            "short_driver_control"]
SEEDS, CONTROL_SEEDS = range(10), range(20)
#: The day-long records: (label, scenario, column, the one session looped alone or None for
#: all).  Days 2 and 3 of the three are looped alone too, as one looks at a single session of
#: a multi-session record: their fitting halves span a temperature change (day 1's does not).
SWEEPS = [("one day, gx_dps", "temperature_sweep", "gx_dps", None),
          ("one day, ax_mps2", "temperature_sweep", "ax_mps2", None),
          ("one day, 30 min thermal lag, gx_dps", "temperature_sweep_lag", "gx_dps", None),
          ("three days, gx_dps", "temperature_sessions", "gx_dps", None),
          ("three days, ax_mps2", "temperature_sessions", "ax_mps2", None),
          ("day 2 of three alone, gx_dps", "temperature_sessions", "gx_dps", 2),
          ("day 3 of three alone, gx_dps", "temperature_sessions", "gx_dps", 3),
          ("day 2 of three alone, ax_mps2", "temperature_sessions", "ax_mps2", 2),
          ("day 3 of three alone, ax_mps2", "temperature_sessions", "ax_mps2", 3)]
SWEEP_CONTROLS = [("one day, control", "temperature_sweep_control", "gx_dps", None),
                  ("three days, control", "temperature_sessions_control", "gx_dps", None)]
#: Every axis of the three-day record, each day looped alone and the three together: the
#: axes no temperature drives (gy, gz, ay, az) are controls drawn with the driven ones.
AXES_RUNS = [("day 1 alone", 1), ("day 2 alone", 2), ("day 3 alone", 3), ("three days", None)]
AXES = ("gx_dps", "gy_dps", "gz_dps", "ax_mps2", "ay_mps2", "az_mps2")
DRIVEN = ("gx_dps", "ax_mps2")
UNITS = {"g": ("gyro", "deg/s"), "a": ("accel", "m/s^2")}


# -- the short records -----------------------------------------------------------------------


def loop_truth(truth: dict) -> list[tuple[Effect, bool]]:
    """The undeclared effects as the loop names them: a temperature bias as a driver's slow
    part with its true forms and weights, another channel's input as a driver's fast part."""
    bias = {s["params"]["input"]: s["params"] for s in truth["sources"]
            if s["kind"] == "temperature_bias" and not s["declared"]}
    out = []
    for effect, slow in true_effects(truth):
        channel = getattr(effect, "channel", None)
        if effect.kind == "driver" and channel in bias:
            p = bias[channel]
            effect = make_effect("driver", channel=channel, part="slow",
                          forms=[[power_name(channel, k, p["t_ref_c"]), c]
                                 for k, c in enumerate(p["coefs"]) if k and c])
        out.append((effect, slow))
    return out


def run(scenario: str, seed: int, **overrides):
    rec = make_scenario(scenario, seed=seed, **overrides)
    y, channels = _split(rec, rec.target)
    config = LoopConfig(rate=rec.rate, sensor="gyro", units=rec.truth["units"])
    return rec, y, channels, config, close_loop(y, channels, config)


def truth_metrics(rec, y, channels, config, res) -> dict:
    """Prediction-segment numbers of the starting model with the true effects added (a
    random walk as the level the loop offers)."""
    record = LoopRecord.single(y, channels, config.rate)
    family = CandidateFamily(config.max_lag)
    for effect, _ in loop_truth(rec.truth):
        if effect.kind == "level":
            effect = make_effect("level", taus=res.level_taus)
        family = family.add(effect, record)
    return score_family(y, channels, config, family)


def carries_level(step) -> bool:
    """Whether a kept step put a local level in the model: the level itself, or a driver's
    slow part that came with the level of its compensated output and kept one."""
    return step.effect.kind == "level" or (step.effect.kind == "driver"
                                           and bool(getattr(step.effect, "level_taus", None))
                                           and step.tau_s is not None)


def names(step, true: Effect) -> bool:
    """Whether a kept step is the true effect: its kind, and its channel or frequency (a
    driver's slow part with the level names a random walk too)."""
    kept = step.effect
    if true.kind == "level":
        return carries_level(step)
    if kept.kind != true.kind:
        return False
    if true.kind == "driver":
        return getattr(kept, "channel", None) == getattr(true, "channel", None)
    if true.kind == "periodic":
        return abs(getattr(kept, "freq_hz", 0) - getattr(true, "freq_hz", 0)) < 0.05
    return True


def describe(step) -> str:
    text = step.effect.describe()
    if step.effect.kind == "level" and step.tau_s:
        text = f"local level (tau {step.tau_s:.3g} s)"
    return text + (f", lag {step.lag}" if step.lag is not None else "")


def effect_seed(label: str, scenario: str, overrides: dict, seed: int) -> dict[str, Any]:
    """One seed of a short record: what was named, and (seed 0) its row and report."""
    rec, y, channels, config, res = run(scenario, seed, **overrides)
    truths = loop_truth(rec.truth)
    level = any(carries_level(s) for s in res.steps)
    named = [any(names(s, t) for s in res.steps) for t, _ in truths]
    followed = [n or (slow and level) for n, (_, slow) in zip(named, truths)]
    others = [s for s in res.steps if not any(names(s, t) for t, _ in truths)
              and not (s.effect.kind == "level" and any(slow for _, slow in truths))]
    out = {"named": all(named), "followed": all(followed), "others": bool(others),
           "lower": res.after["bias_rms"].get("30", np.inf)
           < res.before["bias_rms"].get("30", -np.inf)}
    if seed == 0:
        folder = scenario + "".join(f"_{v:g}s" for v in overrides.values())
        write_loop_report(res, OUT / folder, f"{label} (seed 0)")
        slow = any(s for _, s in truths)

        def metric(m: dict) -> float:
            return m["outage_mse"]["30"] if slow else m["mse"]

        true = metric(truth_metrics(rec, y, channels, config, res))
        before, after = metric(res.before), metric(res.after)
        out["row"] = {"Record": label, "Kept (seed 0)": "; ".join(map(describe, res.steps))
                      or "none", "Metric": "30 s outage MSE" if slow else "one-step MSE",
                      "Before": before, "After": after, "True model": true,
                      "Share of the true gain": (before - after) / (before - true)}
    return out


def control_seed(name: str, seed: int) -> dict[str, Any]:
    _, _, _, _, res = run(name, seed)
    return {"added": bool(res.steps), "worse": bool(res.worse())}


# -- the day-long records ---------------------------------------------------------------------


def _config(column: str, rate: float) -> LoopConfig:
    sensor, units = UNITS[column[0]]
    return LoopConfig(rate=rate, sensor=sensor, units=units)


def sweep_seed(label: str, scenario: str, column: str, day: int | None,
               seed: int) -> dict[str, Any]:
    """One seed of a day-long record or of three (or of one ``day`` of three): the driver
    named, the 30 min bias against the level alone, and (seed 0) the report."""
    sessions = make_sessions(scenario, seed=seed)
    if day is not None:
        sessions = sessions[day - 1:day]
    config = _config(column, sessions[0].rate)
    if len(sessions) > 1:
        res: Any = close_sessions(_sessions(sessions, column), config)
        level = score_sessions(_sessions(sessions, column), config,
                               [make_effect("level", taus=res.level_taus)])
        write = write_sessions_report
    else:
        rec = sessions[0]
        y, channels = _split(rec, column)
        res = close_loop(y, channels, config)
        family = CandidateFamily(config.max_lag).add(make_effect("level", taus=res.level_taus),
                                                     LoopRecord.single(y, channels, rec.rate))
        level = score_family(y, channels, config, family)
        write = write_loop_report
    kept = [s.effect for s in res.steps]
    drivers = _temperature_drivers(res)
    after, alone = res.after["bias_rms"].get("1800"), level["bias_rms"].get("1800")
    out = {"named": bool(drivers), "slow": any(e.part == "slow" for e in drivers),  # type: ignore
           "lower": after is not None and alone is not None and after < alone,
           "ratio": None if after is None or alone is None else after / alone,
           "worse": bool(res.worse()), "kept": "; ".join(e.describe() for e in kept) or "none"}
    if seed == 0:
        write(res, OUT / (f"{scenario}_{column}" + (f"_day{day}" if day else "")),
              f"{label} (seed 0)")
    return out


def axis_seed(day: int | None, column: str, seed: int) -> dict[str, Any]:
    """One axis of the three-day record, one day alone or all three: the temperature named,
    and what came out worse on prediction (pooled, or in any one session)."""
    sessions = make_sessions("temperature_sessions", seed=seed)
    config = _config(column, sessions[0].rate)
    if day is None:
        res: Any = close_sessions(_sessions(sessions, column), config)
        worse = [*res.worse(), *(w for k in range(len(sessions)) for w in res.worse_in(k))]
    else:
        res = close_loop(*_split(sessions[day - 1], column), config)
        worse = res.worse()
    return {"named": bool(_temperature_drivers(res)), "worse": sorted(set(worse))}


def _split(rec, column: str) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """A record's modelled column, and its other columns."""
    return rec.columns[column], {k: v for k, v in rec.columns.items() if k != column}


def _sessions(records: list, column: str) -> list[Session]:
    """Each day of a multi-session record as a session of the loop, ``day 1``..."""
    return [Session(*_split(r, column), f"day {i + 1}") for i, r in enumerate(records)]


def _temperature_drivers(res: Any) -> list[Effect]:
    """The effects kept that take the temperature as a driver."""
    return [s.effect for s in res.steps
            if s.effect.kind == "driver" and getattr(s.effect, "channel", "") == "temp_c"]


# -- companions ---------------------------------------------------------------------------------


def companion_rows() -> list[dict[str, Any]]:
    """Each axis of ``companion_noise`` (seed 0): its companions' correlation, and no input."""
    rec = make_scenario("companion_noise", seed=0)
    rows = []
    for column in [c for c in rec.columns if c[0] in "ga"]:
        config = _config(column, rec.rate)
        res = close_loop(*_split(rec, column), config)
        inputs = [s.effect.describe() for s in res.steps if s.effect.kind == "companion"]
        rows.append({"Axis": column, "Companions": ", ".join(res.roles.companions),
                     "Taken as inputs": ", ".join(inputs) or "none",
                     "Cross-axis correlation with the residual (lag)": "; ".join(
                         f"{c['channel']} {c['rho']:+.2f} ({c['lag']})" for c in res.cross_axis),
                     "True noise correlation": "; ".join(
                         f"{k} {v:+.2f}" for k, v in _truth_corr(column).items()),
                     "Effects kept": "; ".join(s.effect.describe() for s in res.steps)
                     or "none"})
        if column == "gx_dps":
            write_loop_report(res, OUT / "companion_noise_gx_dps", "companion_noise gx_dps "
                              "(seed 0)")
    return rows


def _truth_corr(column: str) -> dict[str, float]:
    """The true equal-time correlation of ``column``'s shared noise with each other axis."""
    from data_synth.imu import ACCEL_CORR, ACCELS, GYRO_CORR, GYROS

    for axes, corr in ((GYROS, GYRO_CORR), (ACCELS, ACCEL_CORR)):
        if column in axes:
            i = axes.index(column)
            return {a: corr[i][j] for j, a in enumerate(axes) if j != i}
    return {}


# -- the pages ----------------------------------------------------------------------------------


def _tasks(parts: list[str]) -> list[tuple]:
    """Every run of ``parts`` as ``(key, function, arguments)``; the key is ``(kind, record,
    seed)``."""
    tasks = []
    if "synthetic" in parts:
        tasks += [(("effect", label, seed), effect_seed, (label, scenario, overrides, seed))
                  for label, scenario, overrides in EFFECTS for seed in SEEDS]
        tasks += [(("control", name, seed), control_seed, (name, seed))
                  for name in CONTROLS for seed in CONTROL_SEEDS]
    if "sweeps" in parts:
        tasks += [(("sweep", label, seed), sweep_seed, (label, scenario, column, day, seed))
                  for label, scenario, column, day in [*SWEEPS, *SWEEP_CONTROLS]
                  for seed in (CONTROL_SEEDS if "control" in scenario else SEEDS)]
    if "axes" in parts:
        tasks += [(("axis", label, column, seed), axis_seed, (day, column, seed))
                  for label, day in AXES_RUNS for column in AXES for seed in SEEDS]
    return tasks


def synthetic_section(done: dict) -> dict[str, list[dict[str, Any]]]:
    """The short records' table and their controls', into the page."""
    effects, controls = [], []
    for label, _, _ in EFFECTS:
        seeds = [done["effect", label, s] for s in SEEDS]
        n = len(SEEDS)
        effects.append({**seeds[0]["row"],
                        "Named in seeds 0-9": f"{sum(s['named'] for s in seeds)}/{n}",
                        "Followed (named or as a level)":
                            f"{sum(s['followed'] for s in seeds)}/{n}",
                        "Seeds with other effects kept": f"{sum(s['others'] for s in seeds)}/{n}",
                        "30 s bias RMS lower (prediction)":
                            f"{sum(s['lower'] for s in seeds)}/{n}"})
    for name in CONTROLS:
        seeds = [done["control", name, s] for s in CONTROL_SEEDS]
        controls.append({"Record": name, "Records where an effect was added":
                         f"{sum(s['added'] for s in seeds)}/{len(CONTROL_SEEDS)}",
                         "Records worse on prediction":
                         f"{sum(s['worse'] for s in seeds)}/{len(CONTROL_SEEDS)}"})
    figure = show_figure(OUT / "slow_random_walk_temperature" / "residual.png",
                         "loop_residual.png")
    replace_section("close-loop-synthetic", "\n".join([
        markdown_table(pd.DataFrame(effects), digits=4), "",
        markdown_table(pd.DataFrame(controls)), "",
        f"Reports for seed 0, with their residual figures: `{REL}/<record>/report.md`.", "",
        f"![a bias random walk with a temperature effect, seed 0]({figure})"]))
    return {"effects_found": effects, "controls": controls}


def sweeps_section(done: dict) -> dict[str, list[dict[str, Any]]]:
    """The day-long records' table and their controls', into the page."""
    sweeps, sweep_controls = [], []
    for label, *_ in SWEEPS:
        seeds = [done["sweep", label, s] for s in SEEDS]
        ratios = [s["ratio"] for s in seeds if s["ratio"] is not None]
        sweeps.append({"Record": label, "Kept (seed 0)": seeds[0]["kept"],
                       "Temperature named": f"{sum(s['named'] for s in seeds)}/{len(SEEDS)}",
                       "as its slow part": f"{sum(s['slow'] for s in seeds)}/{len(SEEDS)}",
                       "30 min bias RMS lower than the level alone":
                           f"{sum(s['lower'] for s in seeds)}/{len(SEEDS)}",
                       "Its ratio to the level alone (median, range)":
                           f"{np.median(ratios):.3g} ({min(ratios):.3g}-{max(ratios):.3g})"
                           if ratios else "-",
                       "Worse on prediction": f"{sum(s['worse'] for s in seeds)}/{len(SEEDS)}"})
    for label, *_ in SWEEP_CONTROLS:
        seeds = [done["sweep", label, s] for s in CONTROL_SEEDS]
        sweep_controls.append({"Record": label, "Temperature named":
                               f"{sum(s['named'] for s in seeds)}/{len(CONTROL_SEEDS)}",
                               "Worse on prediction":
                               f"{sum(s['worse'] for s in seeds)}/{len(CONTROL_SEEDS)}"})
    replace_section("close-loop-sweeps", "\n".join([
        markdown_table(pd.DataFrame(sweeps), digits=3), "",
        markdown_table(pd.DataFrame(sweep_controls)), "",
        f"Reports for seed 0: `{REL}/temperature_sweep_gx_dps/report.md`, "
        f"`{REL}/temperature_sessions_gx_dps/report.md`..."]))
    return {"sweeps": sweeps, "sweep_controls": sweep_controls}


def axes_section(done: dict) -> dict[str, list[dict[str, Any]]]:
    """Every axis of the three-day record, into the page: named, and worse on prediction."""
    rows = []
    for label, _ in AXES_RUNS:
        row: dict[str, Any] = {"Run": label}
        for column in AXES:
            seeds = [done["axis", label, column, s] for s in SEEDS]
            named = sum(s["named"] for s in seeds)
            worse = sum(bool(s["worse"]) for s in seeds)
            row[column + (" (driven)" if column in DRIVEN else "")] = (
                f"{named}/{len(SEEDS)} named, {worse} worse")
        rows.append(row)
    worse = [(label, column, seed, w) for label, _ in AXES_RUNS for column in AXES
             for seed in SEEDS for w in done["axis", label, column, seed]["worse"]]
    replace_section("close-loop-axes", "\n".join([
        markdown_table(pd.DataFrame(rows)), "",
        "Worse on prediction, each ratio whose interval lies above 1: " + ("; ".join(
            f"{label}, {column}, seed {seed}: {w}" for label, column, seed, w in worse)
            or "none") + "."]))
    return {"axes": rows}


def companions_section(_: dict) -> dict[str, list[dict[str, Any]]]:
    """The companions' table, into the page."""
    companions = companion_rows()
    replace_section("close-loop-companions", "\n".join([
        markdown_table(pd.DataFrame(companions)), "",
        f"Report of gx_dps: `{REL}/companion_noise_gx_dps/report.md`."]))
    return {"companions": companions}


SECTIONS = {"synthetic": synthetic_section, "sweeps": sweeps_section,
            "axes": axes_section, "companions": companions_section}


def main() -> None:
    parts = sys.argv[sys.argv.index("--parts") + 1].split(",") if "--parts" in sys.argv \
        else list(SECTIONS)
    unknown = sorted(set(parts) - set(SECTIONS))
    if unknown:
        sys.exit(f"--parts: unknown {', '.join(unknown)}; the parts are {', '.join(SECTIONS)}")
    OUT.mkdir(parents=True, exist_ok=True)
    tasks = _tasks(parts)
    done = dict(zip((key for key, *_ in tasks),
                    in_workers(((f, a) for _, f, a in tasks), JOBS)))
    for part in parts:
        for stem, rows in SECTIONS[part](done).items():
            pd.DataFrame(rows).to_csv(OUT / f"{stem}.csv", index=False)
            print(pd.DataFrame(rows).to_string(index=False))


if __name__ == "__main__":
    main()

"""The six-axis noise model in a navigation filter: joint against per-axis, and inflated.

Six-axis records at rest: the six ADIS16405 sessions and the two MPU-6050 records with six
axes (``../shared/data``), each block-averaged to about 20 Hz (means of 5 samples) and split in
halves.  On the first half, every axis's Allan fit (:func:`fosmodel.noise.imu_noise.imu_noise`)
and the joint model of :func:`fosmodel.filter.joint_noise.joint_noise`: the same per-axis terms,
with the cross-axis correlations of the white parts and of the biases in the driving noise.

On the second half, a 3-D navigation error filter at rest: position, velocity and tilt errors
(``dv = da + f x dtheta``, ``dtheta = dw``, ``f`` the mean specific force of the training half)
driven by the six axes' error states, with simulated position updates of standard deviation
0.1 m on the three axes in update/prediction cycles of 30/30, 60/60 and 120/120 s.  The true
errors are the sensors' readings minus their training means, integrated by the same
recursion.  Four filters per record and cycle, identical but for the driving noise of the
error states:

- ``per-axis``: the axes independent (:func:`~fosmodel.filter.allan_statespace.assemble_axes`);
- ``joint``: with the cross-axis covariances;
- ``per-axis x3`` and ``per-axis x10``: every noise density inflated 3 and 10 times (``Q`` and
  the starting covariance times 9 and 100), what ``--inflate`` does to the exported values.

Per run: the RMS of the 3-D position estimation error, the RMS the filter claims (the square
root of the mean trace of its position covariance), their ratio (1 for a consistent filter,
below 1 overconfident), and the normalised estimation error squared of the position over its 3
degrees of freedom (NEES / 3: 1 when consistent).  Tables (Markdown, CSV, LaTeX) in
``studies/results/kalman_joint/``; the section ``kalman-joint`` of docs/pages/kalman.md is
rewritten from this run.

Run: ``python studies/kalman_joint.py`` (about 15 minutes on 2 cores).  It skips with one
line when ``../shared/data`` is absent.
"""

from __future__ import annotations

import time
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import pandas as pd
from doc_pages import replace_section

from fosmodel import imu_noise, joint_noise
from fosmodel.filter import JointNoise, KalmanFilter, StateSpace, initial_covariance
from fosmodel.io import Record, load_mpu6050_static, load_record, write_tables
from fosmodel.noise import Axis, to_si_scale
from fosmodel.typeset import markdown_table

REPO = Path(__file__).resolve().parents[1]
DATA = REPO.parent / "shared" / "data"
OUT = REPO / "studies" / "results" / "kalman_joint"
BLOCK = 5
SIGMA_M = 0.1
CYCLES_S = (30, 60, 120)
SEED = 0
MODELS = {"per-axis": ("independent", 1.0), "joint": ("joint", 1.0),
          "per-axis x3": ("independent", 3.0), "per-axis x10": ("independent", 10.0)}
ADIS = {"gx_dps": ("gyro", "deg/s"), "gy_dps": ("gyro", "deg/s"), "gz_dps": ("gyro", "deg/s"),
        "ax_g": ("accel", "g"), "ay_g": ("accel", "g"), "az_g": ("accel", "g")}
TOMI = {"gx": ("gyro", "deg/s"), "gy": ("gyro", "deg/s"), "gz": ("gyro", "deg/s"),
        "ax": ("accel", "g"), "ay": ("accel", "g"), "az": ("accel", "g")}
SUNSIDED = "unmoved-with-x-pointing-forward-10min.csv.gz"


@dataclass(frozen=True)
class Case:
    """One record's halves (SI, training means removed) and its models fitted on the first."""

    name: str
    rate: float
    gyro: np.ndarray  # (n, 3) rad/s, test half minus training mean
    accel: np.ndarray  # (n, 3) m/s^2
    force: np.ndarray  # mean specific force of the training half, m/s^2
    joint: JointNoise


def records() -> dict[str, tuple[Record, dict]]:
    """The six-axis records at rest, with each column's sensor and units."""
    out = {f"ADIS16405 imu{k}": (load_record(DATA / "adis16405" / f"imu{k}.csv.gz", rate=100,
                                             outliers="keep"),
                                 ADIS) for k in range(1, 7)}
    out["MPU-6050 sunsided"] = (load_record(DATA / "mpu6050_sunsided" / SUNSIDED, uniform=True,
                                                outliers="keep"),
                                ADIS)
    out["MPU-6050 tomisuarez2"] = (load_mpu6050_static(), TOMI)
    return out


def case(name: str, rec: Record, units: dict[str, tuple[str, str]]) -> Case:
    """Block means, halves, the Allan fits and the joint model of one record."""
    rate = rec.require_rate() / BLOCK
    axes = [Axis(c, s, u, "given") for c, (s, u) in units.items()]
    si = {}
    for a in axes:
        y = np.asarray(rec.column(a.column), dtype=float) * to_si_scale(a.sensor, a.units)
        n = len(y) // BLOCK * BLOCK
        si[a.column] = y[:n].reshape(-1, BLOCK).mean(axis=1)
    half = len(next(iter(si.values()))) // 2
    train = {c: y[:half] for c, y in si.items()}
    si_axes = [Axis(a.column, a.sensor, "rad/s" if a.sensor == "gyro" else "m/s^2", "SI")
               for a in axes]
    joint = joint_noise(train, imu_noise(train, si_axes, rate, name))
    test = np.column_stack([si[c][half:] - np.mean(train[c]) for c in si])
    force = np.array([np.mean(train[a.column]) for a in axes if a.sensor == "accel"])
    return Case(name, rate, test[:, :3], test[:, 3:], force, joint)


def _skew(v: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def navigation_model(error: StateSpace, force: np.ndarray, dt: float) -> StateSpace:
    """Position, velocity and tilt errors at rest driven by the six axes' error states.

    ``p += dt v``; ``v += dt (H_accel x + f x theta)``; ``theta += dt H_gyro x``; the error
    states evolve by their own model (outputs: gx, gy, gz, ax, ay, az).
    """
    m = error.n_states
    phi = np.eye(9 + m)
    phi[0:3, 3:6] = dt * np.eye(3)
    phi[3:6, 6:9] = dt * _skew(force)
    phi[3:6, 9:] = dt * error.H[3:6]
    phi[6:9, 9:] = dt * error.H[0:3]
    phi[9:, 9:] = error.Phi
    g = np.vstack([np.zeros((9, error.G.shape[1])), error.G])
    h = np.hstack([np.eye(3), np.zeros((3, 6 + m))])
    return StateSpace(Phi=phi, B=np.zeros((9 + m, 0)), G=g, H=h, Q=error.Q, mu=0.0,
                      state_names=(*(f"nav{i}" for i in range(9)), *error.state_names),
                      input_names=())


def truth(c: Case, dt: float) -> np.ndarray:
    """The true position errors: the same recursion driven by the measured errors."""
    n = len(c.accel)
    p, v, theta = np.zeros((n, 3)), np.zeros(3), np.zeros(3)
    f = _skew(c.force)
    pos = np.zeros(3)
    for k in range(1, n):
        pos = pos + dt * v
        v = v + dt * (c.accel[k - 1] + f @ theta)
        theta = theta + dt * c.gyro[k - 1]
        p[k] = pos
    return p


def run(job: tuple) -> dict[str, float]:
    """One filter run: its RMS 3-D position error, claimed RMS and NEES / 3."""
    c, model_key, inflate, cycle = job
    dt = 1.0 / c.rate
    joint = c.joint
    error = joint.model if model_key == "joint" else joint.independent
    p0_error = initial_covariance(error, joint.n_samples) * inflate**2
    error = StateSpace(Phi=error.Phi, B=error.B, G=error.G, H=error.H, Q=error.Q * inflate**2,
                       mu=0.0, state_names=error.state_names, input_names=())
    system = navigation_model(error, c.force, dt)
    n_states = system.n_states
    p0 = np.zeros((n_states, n_states))
    p0[9:, 9:] = p0_error
    kf = KalmanFilter.from_state_space(system, SIGMA_M**2 * np.eye(3), np.zeros(n_states), p0)
    true = truth(c, dt)
    rng = np.random.default_rng([SEED, len(true)])
    period = int(round(cycle / dt))
    updated = (np.arange(len(true)) // period) % 2 == 0
    errors, traces, nees = [], [], []
    settled = int(round(1.0 / dt))  # the position covariance is singular until noise reaches it
    for k in range(1, len(true)):
        kf.predict()
        if updated[k]:
            kf.update(true[k] + SIGMA_M * rng.standard_normal(3))
        if k < settled:
            continue
        e = kf.x[:3] - true[k]
        p = kf.P[:3, :3]
        errors.append(e @ e)
        traces.append(np.trace(p))
        nees.append(float(e @ np.linalg.solve(p, e)))
    rms, sigma = float(np.sqrt(np.mean(errors))), float(np.sqrt(np.mean(traces)))
    return {"RMS [m]": rms, "Filter sigma [m]": sigma, "Sigma / RMS": sigma / rms,
            "NEES / 3": float(np.mean(nees)) / 3.0}


def correlations(cases: list[Case]) -> pd.DataFrame:
    """Per record: the largest cross-axis correlations of the white parts and of the biases."""
    rows = []
    for c in cases:
        row: dict[str, object] = {"Record": c.name}
        for label, matrix in (("white", c.joint.white_correlation),
                              ("biases", c.joint.bias_correlation)):
            off = np.abs(matrix - np.eye(len(matrix)))
            i, j = np.unravel_index(int(np.argmax(off)), off.shape)
            row[f"{label}: strongest"] = (f"{matrix[i, j]:+.3f} ({c.joint.columns[i]}, "
                                          f"{c.joint.columns[j]})" if off.max() > 0 else "none")
            row[f"{label}: pairs over 0.1"] = int(np.sum(np.triu(off, 1) > 0.1))
        rows.append(row)
    return pd.DataFrame(rows)


def summarise(frame: pd.DataFrame) -> pd.DataFrame:
    """Per cycle and model, over the records: medians, and the joint model's RMS over the
    per-axis one's."""
    groups = frame.groupby(["Cycle", "Model"], sort=False)
    out = pd.DataFrame({
        "Median RMS [m]": groups["RMS [m]"].median(),
        "Median filter sigma [m]": groups["Filter sigma [m]"].median(),
        "Median sigma / RMS": groups["Sigma / RMS"].median(),
        "Sigma / RMS range": groups["Sigma / RMS"].agg(lambda r: f"{r.min():.2f}-{r.max():.2f}"),
        "Median NEES / 3": groups["NEES / 3"].median(),
    }).reset_index()
    return out


def paired(frame: pd.DataFrame) -> pd.DataFrame:
    """Per cycle, the joint model over the per-axis one, record by record."""
    wide = frame.pivot_table(index=["Record", "Cycle"], columns="Model",
                             values=["RMS [m]", "Sigma / RMS"])
    ratio = (wide["RMS [m]"]["joint"] / wide["RMS [m]"]["per-axis"]).rename("RMS joint / per-axis")
    table = ratio.reset_index().groupby("Cycle")["RMS joint / per-axis"].agg(
        median="median", min="min", max="max")
    return table.loc[[f"{c}/{c} s" for c in CYCLES_S]].reset_index()


def findings(summary: pd.DataFrame, pairs: pd.DataFrame) -> list[str]:
    """What the tables say, in sentences whose numbers come from them."""
    at = summary.set_index(["Cycle", "Model"])
    cycles = [f"{c}/{c} s" for c in CYCLES_S]
    joint = [f"{at.loc[(c, 'joint'), 'Median sigma / RMS']:.2f}" for c in cycles]
    single = [f"{at.loc[(c, 'per-axis'), 'Median sigma / RMS']:.2f}" for c in cycles]
    rms = {m: [at.loc[(c, m), "Median RMS [m]"] / at.loc[(c, "per-axis"), "Median RMS [m]"]
               for c in cycles] for m in ("per-axis x3", "per-axis x10")}
    ratio = {m: [f"{at.loc[(c, m), 'Median sigma / RMS']:.2f}" for c in cycles]
             for m in ("per-axis x3", "per-axis x10")}
    return [
        f"- Joint against per-axis: the RMS position error changes by a factor of "
        f"{pairs['min'].min():.2f}-{pairs['max'].max():.2f} record by record (medians "
        f"{', '.join(f'{v:.3f}' for v in pairs['median'])} at {', '.join(cycles)}), and the "
        f"median sigma / RMS is {', '.join(joint)} against {', '.join(single)}: with position "
        f"updates on all three axes the correlations move the RMS by at most "
        f"{100 * max(1 - pairs['min'].min(), pairs['max'].max() - 1):.0f} % on a record, and "
        "the medians by less.",
        f"- Inflated 3x and 10x on these records at rest, where the model is complete: the "
        f"filter claims {', '.join(ratio['per-axis x3'])} and {', '.join(ratio['per-axis x10'])} "
        f"times its actual error, and the actual RMS grows "
        f"{', '.join(f'{v:.2f}' for v in rms['per-axis x3'])} and "
        f"{', '.join(f'{v:.2f}' for v in rms['per-axis x10'])} times (it follows the position "
        "updates' noise and lets its bias estimates wander more). Inflation buys room for what "
        "a moving platform adds and a static record cannot show; at rest it only costs."]


def page(summary: pd.DataFrame, pairs: pd.DataFrame, corr: pd.DataFrame, seconds: float) -> str:
    return "\n".join([
        f"`python studies/kalman_joint.py` ({seconds:.0f} s): the six ADIS16405 sessions and "
        "the two six-axis MPU-6050 records at 20 Hz, fitted on their first half, filtered on "
        f"the second with position updates sigma {SIGMA_M:g} m (tables in "
        "`studies/results/kalman_joint/`).", "",
        "Correlations across axes found on the training halves (the strongest pair, and how many "
        "of the 15 pairs exceed 0.1 in magnitude; 0 for biases the record cannot tell from "
        "zero):", "",
        markdown_table(corr), "",
        "Over the records, per update/prediction cycle and model (NEES / 3 averages every "
        "sample, so the update phases weigh on it; sigma / RMS is dominated by the "
        "predictions):", "",
        markdown_table(summary, digits=3), "",
        "The joint model's RMS over the per-axis one's, record by record:", "",
        markdown_table(pairs, digits=3), "", *findings(summary, pairs)])


def main() -> None:
    if not DATA.is_dir():
        print(f"skipping: {DATA} not found (the real recordings are not part of this "
              "repository; see the README's 'Data and licences')")
        return
    start = time.perf_counter()
    cases = [case(name, rec, units) for name, (rec, units) in records().items()]
    jobs, keys = [], []
    for c in cases:
        for cycle in CYCLES_S:
            for model, (key, inflate) in MODELS.items():
                jobs.append((c, key, inflate, cycle))
                keys.append({"Record": c.name, "Cycle": f"{cycle}/{cycle} s", "Model": model})
    with ProcessPoolExecutor() as pool:
        results = list(pool.map(run, jobs))
    frame = pd.DataFrame([{**k, **r} for k, r in zip(keys, results)])
    OUT.mkdir(parents=True, exist_ok=True)
    tables = {"all_cases": frame, "summary": summarise(frame), "paired": paired(frame),
              "correlations": correlations(cases)}
    for stem, table in tables.items():
        write_tables(table, OUT, stem)
        print(f"\n## {stem}\n\n{markdown_table(table, digits=4)}")
    seconds = time.perf_counter() - start
    replace_section("kalman-joint", page(tables["summary"], tables["paired"],
                                         tables["correlations"], seconds))
    print(f"\n{seconds:.0f} s; results in {OUT}")


if __name__ == "__main__":
    main()

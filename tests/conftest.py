"""Fixtures shared by several test modules: NARX records of known terms, small record files."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel.core.candidates import Term


def _simulate_narx(truth: dict[str, float], n: int, exog: dict[str, np.ndarray], noise_sd: float,
                   seed: int, burn: int = 500) -> tuple[np.ndarray, float]:
    """Simulate ``y[n] = sum_m c_m P_m[n] + e[n]`` in raw coordinates; return y and its SNR in dB.

    ``truth`` maps term names (``"1"`` for the constant) to weights; the SNR is
    the variance of the model part over the variance of the equation error e.
    """
    rng = np.random.default_rng(seed)
    terms = [(Term.parse(k), v) for k, v in truth.items()]
    e = noise_sd * rng.standard_normal(n + burn)
    sig = {k: np.r_[np.zeros(burn), v] for k, v in exog.items()}
    y = np.zeros(n + burn)
    start = 1 + max(lag or 0 for t, _ in terms for _, lag in t.factors)
    for i in range(start, n + burn):
        v = e[i]
        for term, c in terms:
            for ch, lag in term.factors:
                c *= (y if ch == "y" else sig[ch])[i - (lag or 0)]
            v += c
        y[i] = v
    if not np.all(np.abs(y) < 1e6):
        raise RuntimeError("the NARX design diverged")
    model_part = y[burn:] - e[burn:]
    return y[burn:], float(10 * np.log10(np.var(model_part) / noise_sd**2))


@pytest.fixture
def narx() -> Callable[..., tuple[np.ndarray, float]]:
    """The simulator of records from known NARX models, for recovery tests.

    ``narx(truth, n, exog, noise_sd, seed, burn=500)`` returns the record and its SNR in dB.
    """
    return _simulate_narx


#: A readable header: spaces, parentheses and a slash in every name, the units in brackets.
READABLE = {"gx_dps": "Gyro X (deg/s)", "gy_dps": "Gyro Y (deg/s)", "gz_dps": "Gyro Z (deg/s)",
            "ax_mps2": "Accel X (g)", "ay_mps2": "Accel Y (g)", "az_mps2": "Accel Z (g)"}


@pytest.fixture(scope="session")
def readable_csv(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """Six axes (the static_imu scenario, 300 s at 100 Hz) under a header such as
    ``Gyro X (deg/s),...,Accel X (g)``, without a time column (``--rate 100``).

    Accel X follows Accel Y two samples late, so that the residual loop of Accel X, asked to
    take its companion Accel Y as an input, keeps its lags (terms named by the channel).
    """
    from data_synth import make_scenario

    rec = make_scenario("static_imu", duration=300.0, seed=5)
    frame = pd.DataFrame({READABLE[k]: v / 9.80665 if k.startswith("a") else v
                          for k, v in rec.columns.items()})
    ay = frame["Accel Y (g)"].to_numpy()
    frame["Accel X (g)"] += 0.5 * np.r_[0.0, 0.0, ay[:-2]]
    path = tmp_path_factory.mktemp("readable") / "readable.csv"
    frame.to_csv(path, index=False)
    return path


@pytest.fixture
def figure_log(tmp_path: Path,
               monkeypatch: pytest.MonkeyPatch) -> Callable[[], Callable[[], dict[str, str]]]:
    """Check every figure written from here on (also in worker processes).

    ``log = figure_log()`` sets ``FOSMODEL_FIGURE_LOG`` (:mod:`fosmodel.io.figures`);
    ``log()`` then maps each figure written, the end of its path, to what a reader could not
    read in it (empty: nothing).
    """
    def start() -> Callable[[], dict[str, str]]:
        path = tmp_path / "figures.log"
        monkeypatch.setenv("FOSMODEL_FIGURE_LOG", str(path))

        def read() -> dict[str, str]:
            lines = path.read_text().splitlines() if path.exists() else []
            return dict(line.split("\t", 1) for line in lines)

        return read

    return start


@pytest.fixture
def bursty_csv(tmp_path: Path) -> Callable[..., tuple[Path, float]]:
    """A writer of ``bursty.csv`` in the test's ``tmp_path``: 100 Hz samples received by a host
    in bursts of 5, 1 ms apart, every 50 ms.

    ``bursty_csv(n=400)`` returns the file and its effective rate in Hz.
    """
    def write(n: int = 400) -> tuple[Path, float]:
        k = np.arange(n)
        t = 0.05 * (k // 5) + 0.001 * (k % 5)
        rng = np.random.default_rng(3)
        path = tmp_path / "bursty.csv"
        pd.DataFrame({"t_s": t, "gx": rng.normal(size=n)}).to_csv(path, index=False)
        return path, (n - 1) / (t[-1] - t[0])

    return write


@pytest.fixture
def spiky_csv(tmp_path: Path) -> Callable[..., tuple[Path, np.ndarray, np.ndarray]]:
    """A writer of ``s.csv`` in the test's ``tmp_path``: columns a and b of 1000 normal samples
    with outliers at a[100], a[700] and b[700].

    ``spiky_csv(with_time)`` (a ``time`` column at 100 Hz first when true) returns the file
    and the columns a and b.
    """
    def write(with_time: bool) -> tuple[Path, np.ndarray, np.ndarray]:
        rng = np.random.default_rng(5)
        a, b = rng.normal(size=1000), rng.normal(size=1000)
        a[100], a[700], b[700] = 50.0, -60.0, 40.0
        frame = pd.DataFrame({"a": a, "b": b})
        if with_time:
            frame.insert(0, "time", np.arange(1000) / 100)
        frame.to_csv(tmp_path / "s.csv", index=False)
        return tmp_path / "s.csv", a, b

    return write



def _header(types, stamp_ns: int, seq: int):
    """A std_msgs/msg/Header stamped ``stamp_ns`` (ROS 1's with its sequence number)."""
    header = types["std_msgs/msg/Header"]
    stamp = types["builtin_interfaces/msg/Time"](sec=stamp_ns // 10**9, nanosec=stamp_ns % 10**9)
    numbered = {"seq": seq} if "seq" in header.__dataclass_fields__ else {}
    return header(**numbered, stamp=stamp, frame_id="imu_link")


def _imu_message(types, header, columns: dict[str, np.ndarray], k: int,
                 unmeasured: tuple[str, ...]):
    """Sample ``k`` of ``columns`` as a sensor_msgs/msg/Imu (no orientation, as a raw IMU)."""
    vector = types["geometry_msgs/msg/Vector3"]

    def covariance(name):
        return np.r_[-1.0 if name in unmeasured else 0.01, np.zeros(8)]

    return types["sensor_msgs/msg/Imu"](
        header=header, orientation=types["geometry_msgs/msg/Quaternion"](0.0, 0.0, 0.0, 1.0),
        orientation_covariance=np.r_[-1.0, np.zeros(8)],
        angular_velocity=vector(*(columns[c][k] for c in ("gx", "gy", "gz"))),
        angular_velocity_covariance=covariance("angular_velocity"),
        linear_acceleration=vector(*(columns[c][k] for c in ("ax", "ay", "az"))),
        linear_acceleration_covariance=covariance("linear_acceleration"))


@pytest.fixture
def imu_bag(tmp_path: Path) -> Callable[..., tuple[Path, dict[str, dict[str, np.ndarray]]]]:
    """A writer of ROS bags in the test's ``tmp_path``, with rosbags' writers, from known arrays.

    ``imu_bag(name, storage, imu={"/imu0": 400}, temperature={}, rate=200.0, zero_stamps=False,
    unmeasured=(), gap_after=None)`` writes a ROS 1 bag (storage ``"ros1"``) or a ROS 2 bag
    directory (``"sqlite3"``, ``"mcap"``) of ``sensor_msgs/msg/Imu`` topics of so many
    messages at ``rate`` and ``sensor_msgs/msg/Temperature`` topics at 10 Hz; ``zero_stamps``
    leaves the headers unstamped, ``unmeasured`` names vectors whose covariance[0] is -1, and
    ``gap_after`` delays the IMU messages after that one by 4 sample intervals.  The bag
    records each message 2 ms after its stamp.  It returns the bag and, per topic, the arrays
    written: ``stamp`` (ns, the header's), ``log_time`` (ns, when the bag recorded it) and
    the columns (``gx``.. or ``temperature``).
    """
    from rosbags.rosbag1 import Writer as Writer1
    from rosbags.rosbag2 import StoragePlugin
    from rosbags.rosbag2 import Writer as Writer2
    from rosbags.typesys import Stores, get_typestore

    def write(name: str, storage: str = "sqlite3", imu: dict[str, int] | None = None,
              temperature: dict[str, int] | None = None, rate: float = 200.0,
              zero_stamps: bool = False, unmeasured: tuple[str, ...] = (),
              gap_after: int | None = None):
        typestore = get_typestore(Stores.ROS1_NOETIC if storage == "ros1" else Stores.ROS2_HUMBLE)
        types, start = typestore.types, 1_700_000_000 * 10**9 + 123_456_789
        arrays, messages = {}, []  # messages: (log time, topic, type, message)
        for i, (topic, n) in enumerate(({"/imu0": 400} if imu is None else imu).items()):
            rng = np.random.default_rng(i)
            columns = {c: 0.01 * rng.standard_normal(n) for c in ("gx", "gy", "gz")}
            columns |= {c: mean + 0.05 * rng.standard_normal(n)
                        for c, mean in (("ax", 0.1), ("ay", -0.2), ("az", 9.81))}
            stamps = start + np.round(np.arange(n) * 1e9 / rate).astype(np.int64)
            if gap_after is not None:
                stamps[gap_after + 1:] += np.int64(round(4e9 / rate))
            arrays[topic] = {"stamp": stamps, "log_time": stamps + 2_000_000, **columns}
            messages += [(int(stamps[k]) + 2_000_000, topic, "sensor_msgs/msg/Imu", _imu_message(
                types, _header(types, 0 if zero_stamps else int(stamps[k]), k), columns, k,
                unmeasured)) for k in range(n)]
        for topic, n in (temperature or {}).items():
            stamps = start - 50_000_000 + np.arange(n, dtype=np.int64) * 100_000_000
            values = 25.0 + 0.01 * np.arange(n) ** 1.5
            arrays[topic] = {"stamp": stamps, "log_time": stamps + 2_000_000,
                             "temperature": values}
            messages += [(int(stamps[k]) + 2_000_000, topic, "sensor_msgs/msg/Temperature",
                          types["sensor_msgs/msg/Temperature"](
                              header=_header(types, 0 if zero_stamps else int(stamps[k]), k),
                              temperature=float(values[k]), variance=0.0)) for k in range(n)]
        path = tmp_path / name
        if storage == "ros1":
            writer, serialize = Writer1(path), typestore.serialize_ros1
        else:
            plugin = {"sqlite3": StoragePlugin.SQLITE3, "mcap": StoragePlugin.MCAP}[storage]
            writer = Writer2(path, version=9, storage_plugin=plugin)
            serialize = typestore.serialize_cdr
        with writer:
            connections = {}
            for log_time, topic, msgtype, message in sorted(messages, key=lambda m: m[0]):
                if topic not in connections:
                    connections[topic] = writer.add_connection(topic, msgtype,
                                                               typestore=typestore)
                writer.write(connections[topic], log_time, serialize(message, msgtype))
        return path, arrays

    return write


_MEASURED = r"""
import json, re, resource, sys
resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))  # address space (BLAS reserves)
from fosmodel.cli import main
for argv in json.loads(sys.argv[1]):
    with open("/proc/self/clear_refs", "w") as fh:  # from here, the peak is this command's
        fh.write("5")
    code = main(argv)
    # VmHWM belongs to this program's memory map; ru_maxrss would carry the forking parent's
    with open("/proc/self/status") as fh:
        peak = int(re.search(r"VmHWM:\s+(\d+)", fh.read()).group(1))
    print("\n@@ " + json.dumps([code, peak / 1024]), flush=True)
    print("@@", file=sys.stderr, flush=True)
"""


@pytest.fixture
def measured_runs() -> Callable[..., list[tuple[int, float, str]]]:
    """Run command lines one after the other in a fresh process capped at 4 GB of address space.

    Returns, for each, its exit code, the peak resident memory of that command in MB (the
    process's VmHWM, reset before each) and its stderr.
    """
    import json
    import os
    import subprocess
    import sys

    def run(commands: list[list[str]], timeout: float = 300) -> list[tuple[int, float, str]]:
        out = subprocess.run([sys.executable, "-c", _MEASURED, json.dumps(commands)],
                             capture_output=True, text=True, timeout=timeout, check=False,
                             env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
        results = [json.loads(line[3:]) for line in out.stdout.splitlines()
                   if line.startswith("@@ ")]
        errors = out.stderr.split("@@\n")
        assert len(results) == len(commands), out.stderr
        return [(code, peak, err) for (code, peak), err in zip(results, errors)]

    return run
def _loop_truth(truth: dict) -> list[tuple]:
    """The undeclared effects of a data_synth record as the residual loop names them.

    ``(effect, slow)`` per source: a temperature bias is a driver's slow part with its true
    forms and weights (its powers about the reference temperature), another channel's
    input a driver's fast part, and the rest as ``data_synth.true_effects`` maps them.
    """
    from data_synth.true_effects import true_effects
    from fosmodel.core.derived import power_name
    from fosmodel.loop.effects import make

    out = []
    temperature = {s["params"]["input"]: s["params"] for s in truth["sources"]
                   if s["kind"] == "temperature_bias" and not s["declared"]}
    for effect, slow in true_effects(truth):
        if effect.kind == "driver" and effect.channel in temperature:
            p = temperature[effect.channel]
            forms = [[power_name(effect.channel, k, p["t_ref_c"]), c]
                     for k, c in enumerate(p["coefs"]) if k and c]
            effect = make("driver", channel=effect.channel, part="slow", forms=forms)
        out.append((effect, slow))
    return out


@pytest.fixture
def loop_truth() -> Callable[[dict], list[tuple]]:
    """``loop_truth(truth)``: a data_synth record's undeclared effects as loop effects."""
    return _loop_truth


def _sweep_record(seed: int, hours: float = 6.0, rate: float = 1.0, gain: float = 0.02,
                  square: float = 0.0, lag_s: float | None = None, walk: float = 0.0,
                  still_until: float = 0.0, noise: float = 0.02,
                  lsb: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """A gyro axis at ``rate`` Hz whose bias follows a swept temperature, and the temperature.

    The temperature climbs from 5 to 20 degC in steps with flat stretches (held still over
    the first ``still_until`` of the record); the bias is ``gain (T' - 10) + square
    (T' - 10)^2`` with ``T'`` the temperature through a first-order lag of ``lag_s``, plus a
    random walk (``walk`` per sqrt(s)), AR(1) noise and a quantisation step ``lsb``.
    """
    from fosmodel.core.derived import first_order_lag

    rng = np.random.default_rng(seed)
    n = round(hours * 3600 * rate)
    t = np.arange(n) / n
    ramp = np.clip((t - still_until) / (1 - still_until), 0, 1)
    temp = 5 + 15 * (np.floor(ramp * 12) / 12 + 0.5 * np.clip(ramp * 12 % 1 * 2 - 1, 0, 1) / 12)
    temp = np.round(temp + 0.05 * rng.standard_normal(n), 2)
    lagged = temp if lag_s is None else first_order_lag(temp, lag_s, rate)
    bias = gain * (lagged - 10) + square * (lagged - 10) ** 2
    y = (bias + np.cumsum(rng.standard_normal(n)) * walk / np.sqrt(rate)
         + lfilter([1.0], [1.0, -0.5], rng.standard_normal(n)) * noise)
    if lsb:
        y = np.round(y / lsb) * lsb
    return y, temp


@pytest.fixture
def sweep_record() -> Callable[..., tuple[np.ndarray, np.ndarray]]:
    """``sweep_record(seed, **options)``: a temperature sweep and the gyro bias it drives."""
    return _sweep_record


def _thermal_group(seed: int = 0, lag_s: float = 0.0, sessions: int = 3,
                   columns: list[str] | None = None, **options):
    """Thermal-calibration sweeps of one IMU as a tempcal group, and their truth.

    ``data_synth.thermal.thermal_sessions`` draws the sessions; ``columns`` keeps some axes.
    """
    from data_synth.thermal import thermal_sessions
    from fosmodel.noise.axes import resolve_axes
    from fosmodel.workflows.tempcal import AxisGroup, TempSession

    recs = thermal_sessions(seed, lag_s=lag_s, sessions=sessions, **options)
    names = columns or [c for c in recs[0].columns if c != "temp_c"]
    runs = tuple(TempSession(f"s{k + 1}", {c: r.columns[c] for c in names}, r.columns["temp_c"],
                             r.rate) for k, r in enumerate(recs))
    return AxisGroup("imu", tuple(resolve_axes(names)), "temp_c", runs), recs[0].truth["thermal"]


@pytest.fixture(scope="session")
def thermal_group() -> Callable[..., tuple]:
    """``thermal_group(seed, lag_s=..., sessions=..., columns=...)``: sweeps and their truth."""
    return _thermal_group

"""How long a command takes to start, as a ratio to ``python -c "import numpy"``.

Every command pays for its imports before it reads a record.  Each of these runs in a fresh
interpreter, ``--repeats`` rounds timed round-robin (so that the machine's noise falls on all
of them alike), with this checkout first on the path:

* the baseline, ``python -c "import numpy"``, and a bare ``python -c pass``;
* ``fosmodel --version`` and ``fosmodel --help`` (``python -m fosmodel.cli``), which build
  the parser of every command and must not load the libraries of the commands;
* ``import fosmodel`` (the package's face, its names imported on first use).

The table gives each one's best time and its ratio to the baseline's best; the issue's target
is at most 3 for ``--version`` and ``--help``.  The script exits non-zero when either is
above it, so that a slow start is seen where it is measured, not in a timed unit test.

Run: ``python benchmarks/bench_startup.py [--repeats R] [--out PATH]``
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
from _common import machine_line

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
TARGET = 3.0
RUNS = {
    'python -c "import numpy"': ["-c", "import numpy"],
    "python -c pass": ["-c", "pass"],
    "fosmodel --version": ["-m", "fosmodel.cli", "--version"],
    "fosmodel --help": ["-m", "fosmodel.cli", "--help"],
    "import fosmodel": ["-c", "import fosmodel"],
}
BASELINE = 'python -c "import numpy"'
CHECKED = ("fosmodel --version", "fosmodel --help")


def run_once(args: list[str]) -> float:
    """Seconds of one run of ``python args`` in a fresh interpreter, this checkout first."""
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(ROOT), os.environ.get(
        "PYTHONPATH", "")]).rstrip(os.pathsep)}
    start = time.perf_counter()
    subprocess.run([sys.executable, *args], env=env, stdout=subprocess.DEVNULL, check=True)
    return time.perf_counter() - start


def measure(repeats: int) -> pd.DataFrame:
    """Best time of each run over ``repeats`` round-robin rounds, and its ratio to the baseline."""
    best = dict.fromkeys(RUNS, float("inf"))
    for _ in range(repeats):
        for name, args in RUNS.items():
            best[name] = min(best[name], run_once(args))
    return pd.DataFrame({"run": list(best), "best (s)": [round(v, 3) for v in best.values()],
                         "/ import numpy": [round(v / best[BASELINE], 2)
                                            for v in best.values()]})


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=15)
    parser.add_argument("--out", default=str(HERE / "results" / "startup.txt"))
    args = parser.parse_args()
    table = measure(args.repeats)
    over = table[table["run"].isin(CHECKED) & (table["/ import numpy"] > TARGET)]
    text = "\n".join([
        f"Start-up of a command against python -c \"import numpy\": best of {args.repeats} "
        "round-robin runs each, in fresh interpreters; target: --version and --help at most "
        f"{TARGET:g} x.", machine_line(), "", table.to_string(index=False), "",
        "over the target: " + (", ".join(over["run"]) if len(over) else "none")])
    Path(args.out).write_text(text + "\n")
    print(text)
    return 1 if len(over) else 0


if __name__ == "__main__":
    sys.exit(main())

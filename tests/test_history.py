"""The project's files speak of the project, not of its history: no session, no tracker number.

A comment or a page says why a thing is so ("the machine, not the code, moved this time"),
not when it happened ("this morning"), and names no issue of a tracker the repository does
not hold.  Every tracked text file is read: the package, its tests, studies, benchmarks,
docs, the README, the developers' guide and the configuration.
"""

import re
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
HISTORY = re.compile(r"\bissues?\s+#?\d|\b(?:this|previous|last|next)\s+session\b|"
                     r"\bthis\s+morning\b|\ba\s+week\s+ago\b|\byesterday\b|\btoday\b",
                     re.IGNORECASE)
BINARY = (".png", ".svg", ".gz", ".npy", ".parquet", ".bag", ".ulg", ".mcap", ".db3", ".zip")


def _tracked():
    try:
        listed = subprocess.run(["git", "ls-files"], cwd=ROOT, capture_output=True, text=True,
                                check=True).stdout.split()
    except (OSError, subprocess.CalledProcessError):
        pytest.skip("not a git checkout: the tracked files are unknown")
    # this file spells the phrases it looks for
    return [ROOT / name for name in listed if not name.endswith(BINARY)
            and (ROOT / name).is_file() and ROOT / name != Path(__file__).resolve()]


def test_no_session_history_or_tracker_number_in_the_project_s_files():
    found = [f"{path.relative_to(ROOT)}:{number}: {line.strip()}"
             for path in _tracked()
             for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1)
             if HISTORY.search(line)]
    assert not found, "\n".join(found)


@pytest.mark.parametrize("line", ["as issue 31 asked", "measured this session",
                                  "the previous session's runs", "a run this morning",
                                  "Today's code", "(issues 5 and 15)"])
def test_the_scan_finds_history(line):
    assert HISTORY.search(line)


@pytest.mark.parametrize("line", ["six ADIS16405 sessions", "sessions of one IMU",
                                  "an issue the reader meets", "todays_mean"])
def test_the_scan_leaves_the_project_s_own_words(line):
    assert not HISTORY.search(line)

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fosmodel.core import files
from fosmodel.core.exceptions import InputError
from fosmodel.io.output import (
    atomic_write,
    publish,
    refuse_overwrite,
    report_directory,
    same_file,
    write_text,
)


def test_write_text_replaces_the_file(tmp_path):
    p = tmp_path / "out.txt"
    write_text(p, "old")
    write_text(p, "new")
    assert p.read_text() == "new"
    assert [f.name for f in tmp_path.iterdir()] == ["out.txt"]


def test_failed_write_leaves_the_old_file_and_no_temporary(tmp_path):
    p = tmp_path / "out.txt"
    write_text(p, "old")
    with pytest.raises(RuntimeError):
        with atomic_write(p) as fh:
            fh.write("half")
            raise RuntimeError("interrupted")
    assert p.read_text() == "old"
    assert [f.name for f in tmp_path.iterdir()] == ["out.txt"]


def test_failed_first_write_creates_nothing(tmp_path):
    p = tmp_path / "new.bin"
    with pytest.raises(KeyboardInterrupt):
        with atomic_write(p, "wb") as fh:
            fh.write(b"x")
            raise KeyboardInterrupt
    assert list(tmp_path.iterdir()) == []


def test_a_report_is_moved_into_an_existing_directory(tmp_path):
    out, tmp = tmp_path / "out", tmp_path / ".out.tmp"
    (out / "imu1_gx").mkdir(parents=True)
    (out / "imu1_gx" / "report.md").write_text("old")
    (out / "notes.txt").write_text("mine")
    (tmp / "imu1_gx").mkdir(parents=True)
    (tmp / "imu1_gx" / "report.md").write_text("new")
    (tmp / "best.csv").write_text("new")
    publish(tmp, out)
    assert (out / "imu1_gx" / "report.md").read_text() == "new"
    assert (out / "best.csv").read_text() == "new" and (out / "notes.txt").read_text() == "mine"
    fresh = tmp_path / "new" / "deeper"
    publish(out, fresh)
    assert (fresh / "best.csv").exists() and not out.exists()


def test_a_report_into_directories_that_do_not_exist_yet(tmp_path):
    """Staged in the nearest existing ancestor, then moved to the new path."""
    out = tmp_path / "a" / "b" / "report"
    with report_directory(out) as tmp:
        assert tmp.parent == tmp_path
        (tmp / "report.md").write_text("new")
    assert (out / "report.md").read_text() == "new"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["a"]


def test_a_report_that_would_replace_an_input_is_refused_whole(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    record = out / "study.csv"
    record.write_text("time,gx\n")
    with pytest.raises(InputError, match=r"would replace .*study.csv, a file this command reads"):
        with report_directory(out, [record]) as tmp:
            (tmp / "report.md").write_text("new")
            (tmp / "study.csv").write_text("table")
    assert record.read_text() == "time,gx\n" and sorted(p.name for p in out.iterdir()) == [
        "study.csv"]
    assert [p.name for p in tmp_path.iterdir()] == ["out"]  # no staging directory left


def _aliases(tmp_path):
    """Ways of naming the file ``rec.csv``: itself, relative, through a symlink, a hard link."""
    record = tmp_path / "rec.csv"
    record.write_text("time,gx\n0,1\n")
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.csv").symlink_to(record)
    os.link(record, tmp_path / "hard.csv")
    return record, [record, tmp_path / "sub" / ".." / "rec.csv", tmp_path / "link.csv",
                    tmp_path / "hard.csv"]


def test_an_output_may_not_name_an_input_however_spelt(tmp_path, monkeypatch):
    record, aliases = _aliases(tmp_path)
    monkeypatch.chdir(tmp_path)
    for alias in [*aliases, Path("rec.csv"), Path("./sub/../link.csv")]:
        assert same_file(alias, record)
        with pytest.raises(InputError, match=r"^--out .* is the record .*: fosmodel never writes "
                                             r"over a file it reads; choose another output name$"):
            refuse_overwrite({"--out": alias}, {"the record": "rec.csv"})
    refuse_overwrite({"--out": tmp_path / "model.json"}, {"the record": record})
    with pytest.raises(InputError, match="--json a.json and --out ./a.json name the same file"):
        refuse_overwrite({"--json": "a.json", "--out": "./a.json"}, {})


def test_a_temporary_file_of_a_killed_run_goes_with_the_next_write(tmp_path):
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    out = tmp_path / "out.txt"
    stale = tmp_path / files._temporary_name(out, dead.pid, "0123456789ab", ".tmp")
    stale.write_text("half")
    kept = tmp_path / files._temporary_name(out, dead.pid, "0123456789ab", ".kept")  # an undo copy
    kept.write_text("old")
    live = tmp_path / files._temporary_name(out, os.getpid(), "0123456789ab", ".tmp")  # busy
    live.write_text("busy")
    unsigned = tmp_path / f".out.txt.{dead.pid}.0123456789ab.tmp"  # a user's file of that form
    unsigned.write_text("mine")
    write_text(out, "new")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted([live.name, unsigned.name,
                                                                 "out.txt"])


def test_new_files_follow_the_umask(tmp_path):
    old = os.umask(0o027)
    try:
        write_text(tmp_path / "a.txt", "x")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.txt").stat().st_mode) == 0o640


_WRITER = """
import sys
from fosmodel.io.output import write_text
path, n = sys.argv[1], int(sys.argv[2])
for i in range(n):
    write_text(path, str(i % 10) * 200_000)  # one character, the same length each time
"""


def test_killed_while_writing_leaves_the_old_or_the_new_file_whole(tmp_path):
    path = tmp_path / "out.txt"
    write_text(path, "old")
    for delay in (0.05, 0.1, 0.2, 0.3):
        proc = subprocess.Popen([sys.executable, "-c", _WRITER, str(path), "1000"])
        time.sleep(delay)
        proc.send_signal(signal.SIGKILL)
        proc.wait()
        text = path.read_text()
        assert text == "old" or (len(text) == 200_000 and len(set(text)) == 1)
    write_text(path, "done")  # the next write clears what the killed ones left
    assert [p.name for p in tmp_path.iterdir()] == ["out.txt"]


@pytest.mark.parametrize("name, file", [("gx_dps", "gx_dps"), ("Gyro X (deg/s)", "Gyro_X_deg_s_"),
                                        ("acc.x [m/s^2]", "acc.x_m_s_2_"), ("..", "column"),
                                        ("a/../b", "a_.._b")])
def test_a_column_s_name_as_a_file_name_stays_in_its_folder(name, file):
    from fosmodel.io.output import path_name

    assert path_name(name) == file

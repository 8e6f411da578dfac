"""A cleanup removes only what it proves its own, and an output replaces only a regular file.

The temporaries a write leaves when killed are removed by the next write to the same
destination; a file the command was given, or one it did not create by its own naming rule
(a signed name), is never removed, whatever its name.  An output never goes over a device, a
FIFO or a socket: one line, exit code 2, nothing written.
"""

import os
import socket
import stat
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from fosmodel import cli
from fosmodel.core import files
from fosmodel.core.exceptions import InputError
from fosmodel.io import output
from fosmodel.io.journal import all_or_nothing


def _dead_pid():
    child = subprocess.Popen([sys.executable, "-c", "pass"])
    child.wait()
    return child.pid


DEAD = _dead_pid()


def _record_text(n=3000):
    rng = np.random.default_rng(4)
    gx = 0.01 * rng.standard_normal(n)
    return "time,gx\n" + "".join(f"{k / 100!r},{g:.6f}\n" for k, g in enumerate(gx))


def _one_error_line(capsys):
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


def test_a_record_named_like_a_dead_writers_temporary_is_kept(tmp_path, capsys, monkeypatch):
    # the name of an output's temporary file as it once was: the output's name, a dead pid
    monkeypatch.chdir(tmp_path)
    record = tmp_path / ".m2.json.4194303.0123456789ab.tmp"
    record.write_text(_record_text())
    before = record.read_bytes()
    assert cli.main(["fit", record.name, "--column", "gx", "--max-lag", "2",
                     "--out", "m2.json"]) == 0
    assert record.read_bytes() == before
    assert (tmp_path / "m2.json").is_file()


def test_a_record_with_a_temporary_files_signed_name_is_kept(tmp_path, capsys, monkeypatch):
    # even a name of the writer's own rule, of a dead writer, is never removed when given
    monkeypatch.chdir(tmp_path)
    name = files._temporary_name(Path("m2.json"), DEAD, "0123456789ab", ".tmp")
    record = tmp_path / name
    record.write_text(_record_text())
    before = record.read_bytes()
    assert cli.main(["fit", name, "--column", "gx", "--max-lag", "2", "--out", "m2.json"]) == 0
    assert record.read_bytes() == before


def test_a_stale_temporary_of_the_writers_own_name_goes(tmp_path):
    out = tmp_path / "out.txt"
    stale = tmp_path / files._temporary_name(out, DEAD, "00000000abcd", ".tmp")
    stale.write_text("half")
    output.write_text(out, "new")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]


def test_the_kept_copy_of_a_writer_killed_before_its_rename_goes(tmp_path):
    out = tmp_path / "out.txt"
    out.write_text("old")
    kept = tmp_path / files._temporary_name(out, DEAD, "00000000abcd", ".kept")
    os.link(out, kept)  # the copy of the destination, which was never replaced
    other = tmp_path / files._temporary_name(out, DEAD, "00000000abce", ".kept")
    (tmp_path / "elsewhere").write_text("mine")
    os.link(tmp_path / "elsewhere", other)  # a link to another file: not provably ours
    output.write_text(out, "new")
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(["elsewhere", other.name,
                                                                 "out.txt"])
    assert out.read_text() == "new" and (tmp_path / "elsewhere").read_text() == "mine"


#: What a file beside the output is: a user's file of any name, one of the old unsigned
#: pattern, a forged signature, a dead writer's temporary (as a file, a hard link of another
#: file, a symbolic link, a directory), a live writer's.
KINDS = ("user", "unsigned", "forged", "stale", "stale-link", "stale-symlink", "stale-dir",
         "live")
SUFFIXES = (".tmp", ".kept", ".tmpdir")
names = st.text(st.characters(codec="ascii", categories=("L", "N"), include_characters="._-"),
                min_size=1, max_size=12).filter(lambda s: s not in (".", ".."))


def _make(folder, out, kind, suffix, pid, token, user_name):
    """Create a file of ``kind`` beside ``out``; return its path."""
    if kind == "user":
        path = folder / user_name
    elif kind == "unsigned":
        path = folder / f".{out.name}.{pid}.{token}{suffix}"
    elif kind == "forged":
        path = folder / f".{out.name}.{pid}.{token}{'0' * 16}{suffix}"
    else:
        path = folder / files._temporary_name(out, os.getpid() if kind == "live" else pid,
                                              token, suffix)
    if path.exists() or path.is_symlink() or path == out:
        return None
    if kind == "stale-dir":
        path.mkdir()
        (path / "part.md").write_text("part")
    elif kind == "stale-link":
        other = folder / f"other-{token}"
        other.write_text("linked")
        os.link(other, path)
    elif kind == "stale-symlink":
        path.symlink_to(folder / "target-of-a-link")
    else:
        path.write_text(f"{kind} {token}")
    return path


def _state(folder):
    out = {}
    for p in folder.rglob("*"):
        if p.is_symlink():
            out[str(p)] = ("link", os.readlink(p))
        elif p.is_file():
            out[str(p)] = ("file", p.read_bytes())
        else:
            out[str(p)] = ("dir", None)
    return out


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(out_name=names,
       siblings=st.lists(st.tuples(st.sampled_from(KINDS), st.sampled_from(SUFFIXES),
                                   st.sampled_from([DEAD, 1, 4194303, 2**40]),
                                   st.text("0123456789abcdef", min_size=12, max_size=12),
                                   names, st.booleans()), max_size=8),
       report=st.booleans())
def test_no_given_file_is_ever_touched_whatever_the_names(out_name, siblings, report):
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        out = folder / out_name
        made = [(kind, path, suffix, pid, is_given) for kind, suffix, pid, token, user, is_given
                in siblings
                if (path := _make(folder, out, kind, suffix, pid, token, user)) is not None]
        inputs = {f"the record {i}": path for i, (_, path, _, _, is_given) in enumerate(made)
                  if is_given}
        before = _state(folder)
        with all_or_nothing():
            output.refuse_overwrite({}, inputs)
            if report:
                with output.report_directory(out) as staging:
                    (staging / "a.md").write_text("report")
            else:
                output.write_text(out, "new")
        after = _state(folder)
        suffix_of_write = (".tmpdir",) if report else (".tmp", ".kept")
        for kind, path, suffix, pid, is_given in made:
            removable = (kind in ("stale", "stale-dir") and not is_given
                         and suffix in suffix_of_write and not files._alive(pid))
            if removable:
                assert str(path) not in after, path  # the cleanup does its work
            else:  # every other file stays byte for byte, given or not
                assert after.get(str(path)) == before[str(path)], (kind, path)
                if kind == "stale-dir":
                    assert after[str(path / "part.md")] == before[str(path / "part.md")]


def _private_null(path):
    os.mknod(path, stat.S_IFCHR | 0o666, os.makedev(1, 3))


def _fifo(path):
    os.mkfifo(path)


def _socket(path):
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(path))
    return sock


@pytest.mark.skipif(os.geteuid() != 0, reason="making a device node needs root")
def test_an_output_over_a_device_node_is_refused(tmp_path, capsys):
    record = tmp_path / "rec.csv"
    record.write_text(_record_text())
    node = tmp_path / "mynull"
    _private_null(node)
    assert cli.main(["fit", str(record), "--column", "gx", "--out", str(node)]) == 2
    assert _one_error_line(capsys) == (
        f"fosmodel: error: cannot write {node}: a device, not a regular file; fosmodel "
        "writes outputs only to regular files or new paths")
    assert stat.S_ISCHR(node.lstat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mynull", "rec.csv"]


def test_the_system_null_device_is_never_an_output(tmp_path, capsys):
    record = tmp_path / "rec.csv"
    record.write_text(_record_text())
    assert cli.main(["fit", str(record), "--column", "gx", "--out", "/dev/null"]) == 2
    assert _one_error_line(capsys) == (
        "fosmodel: error: cannot write /dev/null: a device, not a regular file; fosmodel "
        "writes outputs only to regular files or new paths")
    assert stat.S_ISCHR(os.stat("/dev/null").st_mode)


@pytest.mark.parametrize("make, kind", [(_fifo, "a FIFO"), (_socket, "a socket")])
@pytest.mark.parametrize("option", ["--out", "--json"])
def test_an_output_over_a_fifo_or_socket_is_refused(tmp_path, capsys, make, kind, option):
    record = tmp_path / "rec.csv"
    record.write_text(_record_text())
    special = tmp_path / "special"
    keep = make(special)
    link = tmp_path / "link"
    link.symlink_to(special)
    try:
        for target, shown in ((special, f"{special}"), (link, f"{link} ({special})")):
            argv = (["fit", str(record), "--column", "gx", "--out", str(target)]
                    if option == "--out" else
                    ["allan", str(record), "--column", "gx", "--out", str(tmp_path / "r"),
                     "--json", str(target)])
            assert cli.main(argv) == 2
            assert _one_error_line(capsys) == (
                f"fosmodel: error: cannot write {shown}: {kind}, not a regular file; "
                "fosmodel writes outputs only to regular files or new paths")
            assert sorted(p.name for p in tmp_path.iterdir()) == ["link", "rec.csv", "special"]
    finally:
        if keep is not None:
            keep.close()


def test_a_report_directory_that_is_a_fifo_is_refused(tmp_path, capsys):
    record = tmp_path / "rec.csv"
    record.write_text(_record_text())
    _fifo(tmp_path / "report")
    assert cli.main(["allan", str(record), "--column", "gx", "--out",
                     str(tmp_path / "report")]) == 2
    assert _one_error_line(capsys) == (
        f"fosmodel: error: cannot write a report into {tmp_path / 'report'}: it is a FIFO, "
        "not a directory")


def test_a_fifo_inside_a_report_directory_is_not_replaced(tmp_path):
    out = tmp_path / "report"
    out.mkdir()
    _fifo(out / "a.md")
    with pytest.raises(InputError, match=r"a\.md: a FIFO, not a regular file"), \
            output.report_directory(out) as staging:
        (staging / "a.md").write_text("report")
    assert stat.S_ISFIFO((out / "a.md").lstat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["report"]


def test_a_device_swapped_in_after_the_checks_is_not_replaced(tmp_path):
    # the check again at the rename: a path that became a FIFO while the command ran
    out = tmp_path / "out.txt"
    with pytest.raises(InputError, match="a FIFO, not a regular file"), \
            output.atomic_write(out) as fh:
        fh.write("new")
        _fifo(out)
    assert stat.S_ISFIFO(out.lstat().st_mode)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.txt"]

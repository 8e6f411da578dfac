"""Nothing lost, nothing silently wrong: outputs never over inputs, bounded reads, and
refusals where a result would mean nothing."""

import errno
import gzip
import json
import os
import shutil
import signal
import subprocess
import sys
import warnings

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel, FOSRegressor, cli, fos
from fosmodel.core.exceptions import FitWarning, InputError
from fosmodel.io.loader import load_record


@pytest.fixture
def folder(tmp_path):
    rng = np.random.default_rng(0)
    n = 30_000
    gx = lfilter([1.0], [1.0, -0.7], rng.standard_normal(n)) * 0.1
    pd.DataFrame({"time": np.arange(n) / 100.0, "gx": gx,
                  "temp": 20 + np.arange(n) / 1e4}).to_csv(tmp_path / "rec.csv", index=False)
    (tmp_path / "sub").mkdir()
    (tmp_path / "link.csv").symlink_to(tmp_path / "rec.csv")
    os.link(tmp_path / "rec.csv", tmp_path / "hard.csv")
    assert cli.main(["fit", str(tmp_path / "rec.csv"), "--column", "gx", "--max-lag", "2",
                     "--out", str(tmp_path / "model.json")]) == 0
    return tmp_path


def _aliases(folder, name):
    """Every way of naming ``folder/name`` used here: itself, relative with '..', a symlink,
    a hard link (for the record)."""
    out = [folder / name, folder / "sub" / ".." / name]
    if name == "rec.csv":
        out += [folder / "link.csv", folder / "hard.csv"]
    return out


def _commands(folder, out):
    """Each command with ``out`` in each of its output options that names a file."""
    rec = str(folder / "rec.csv")
    loop = ["close-loop", rec, "--column", "gx", "--out", str(folder / "report")]
    study = ["study", rec, "--column", "gx", "--sensor", "gyro", "--units", "deg/s",
             "--orders", "1", "--degrees", "1", "--methods", "burg", "--protocol", "fair",
             "--split", "30s,20s", "--no-levels", "--out", str(folder / "report")]
    allan = ["allan", rec, "--column", "gx", "--out", str(folder / "report")]
    return [
        ["fit", rec, "--column", "gx", "--out", out],
        ["predict", rec, "--model", str(folder / "model.json"), "--out", out],
        [*study, "--json", out],
        [*loop, "--json", out], [*loop, "--model", out],
        [*allan, "--json", out],
    ]


def _snapshot(folder):
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file()}


@pytest.mark.parametrize("target", ["rec.csv", "model.json"])
def test_no_command_writes_over_a_file_it_reads(folder, capsys, monkeypatch, target):
    monkeypatch.chdir(folder)
    before = _snapshot(folder)
    runs = 0
    for alias in [*_aliases(folder, target), target]:
        for argv in _commands(folder, str(alias)):
            if target == "model.json" and argv[0] != "predict":
                continue  # only predict reads the model
            assert cli.main([str(a) for a in argv]) == 2, argv
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and "fosmodel never writes over a file it reads" in err[0], err
            runs += 1
    assert runs == (6 * 5 if target == "rec.csv" else 3)
    assert _snapshot(folder) == before and not (folder / "report").exists()


def test_two_outputs_may_not_name_one_file(folder, capsys):
    argv = ["close-loop", str(folder / "rec.csv"), "--column", "gx", "--out",
            str(folder / "report"), "--json", str(folder / "o.json"), "--model",
            str(folder / "sub" / ".." / "o.json")]
    assert cli.main(argv) == 2
    assert "name the same file; give each output its own name" in capsys.readouterr().err
    assert not (folder / "o.json").exists() and not (folder / "report").exists()


def test_a_report_that_would_replace_an_input_changes_nothing(folder, capsys):
    study = folder / "data" / "study.csv"
    study.parent.mkdir()
    study.write_bytes((folder / "rec.csv").read_bytes())
    before = _snapshot(folder)
    argv = ["study", str(study), "--column", "gx", "--sensor", "gyro", "--units", "deg/s",
            "--orders", "1", "--degrees", "1", "--methods", "burg", "--protocol", "fair",
            "--split", "30s,20s", "--no-levels", "--out", str(study.parent)]
    assert cli.main(argv) == 2
    assert "would replace" in capsys.readouterr().err
    assert _snapshot(folder) == before
    assert sorted(p.name for p in folder.iterdir() if p.name.startswith(".")) == []


_CAPPED = r"""
import re, resource, sys
resource.setrlimit(resource.RLIMIT_AS, (4 * 2**30, 4 * 2**30))  # address space (BLAS reserves)
from fosmodel.cli import main
code = main(sys.argv[1:])
# VmHWM belongs to this program's memory map; ru_maxrss would carry the forking parent's peak
with open("/proc/self/status") as fh:
    print("peak", re.search(r"VmHWM:\s+(\d+)", fh.read()).group(1), flush=True)
sys.exit(code)
"""


@pytest.mark.slow
def test_a_file_that_expands_far_is_refused_within_a_memory_cap(tmp_path):
    """300 MB of one line in a 300 kB file: refused after 64 MB, in well under 1 GB."""
    path = tmp_path / "bomb.csv.gz"
    with gzip.open(path, "wb", compresslevel=9) as fh:
        fh.write(b"gx\n")
        chunk = b"0\n" * 5_000_000
        for _ in range(30):
            fh.write(chunk)
    assert path.stat().st_size < 2_000_000
    out = subprocess.run([sys.executable, "-c", _CAPPED, "fit", str(path), "--column", "gx",
                          "--rate", "100", "--out", str(tmp_path / "m.json")],
                         capture_output=True, text=True, timeout=120, check=False,
                         env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert out.returncode == 2, out.stderr
    assert "decompresses to more than 100 times its size" in out.stderr
    peak_mb = int(out.stdout.split()[-1]) / 1024
    assert peak_mb < 1024 and not (tmp_path / "m.json").exists()


def test_a_time_that_stands_still_fails_on_the_first_block(tmp_path, capsys):
    path = tmp_path / "still.csv.gz"
    with gzip.open(path, "wb", compresslevel=1) as fh:  # 20 million rows of "0,0"
        fh.write(b"time,gx\n" + b"0,0\n" * 20_000_000)
    with pytest.raises(InputError, match=r"line 3: time repeats \(0.0 then 0.0\) and does not "
                                          r"advance over 500,000 rows"):
        load_record(path)


def test_a_backward_time_fails_in_its_block_with_its_line(tmp_path, monkeypatch):
    """Across a block boundary and inside a later block, the line named is the file's."""
    monkeypatch.setattr("fosmodel.io.loader.CHUNK_ROWS", 1000)
    calls = []
    monkeypatch.setattr("fosmodel.io.values._check_finite",
                        lambda *a, **k: calls.append(a))  # reached only after every block
    for bad_row in (1000, 2500):  # the first row of block 2, and one inside block 3
        time = np.arange(5000) / 100.0
        time[bad_row] = time[bad_row - 1] - 0.5
        path = tmp_path / f"back{bad_row}.csv"
        pd.DataFrame({"time": time, "gx": 0.0}).to_csv(path, index=False)
        with pytest.raises(InputError, match=rf"line {bad_row + 2}: time goes backwards"):
            load_record(path)
    assert calls == []


def test_devices_fifos_and_directories_are_not_records(tmp_path):
    fifo = tmp_path / "pipe.csv"
    os.mkfifo(fifo)
    (tmp_path / "zero.csv").symlink_to("/dev/zero")
    (tmp_path / "broken.csv").symlink_to(tmp_path / "none.csv")
    for path, message in ((fifo, "a FIFO, not a regular file"),
                          (tmp_path / "zero.csv", "(/dev/zero): a device, not a regular file"),
                          (tmp_path, "a directory, not a record"),
                          (tmp_path / "broken.csv", "no such file (a broken symbolic link)")):
        with pytest.raises(InputError, match=message.replace("(", r"\(").replace(")", r"\)")):
            load_record(path, rate=100)


def test_constant_tiny_and_complex_records_are_refused():
    with pytest.raises(InputError, match=r"y is constant \(1\): there is nothing to model"):
        FOSModel(max_lag=2).fit(np.ones(100))
    with pytest.raises(InputError, match=r"8 samples leave 4 in the fitting window \(after the "
                                         r"lag window of 4\) for 5 candidates; FOS needs at "
                                         "least 7"):
        FOSModel(max_lag=4).fit(np.arange(8.0) ** 2 % 5)
    with pytest.raises(InputError, match="no longer than the lag window of 1000000 samples"):
        FOSModel(max_lag=10**6).fit(np.random.default_rng(0).standard_normal(5000))
    y = np.random.default_rng(1).standard_normal(500)
    for fit in (lambda: FOSModel(max_lag=2).fit(y.astype(complex)),
                lambda: fos(np.c_[y, y].astype(complex), y),
                lambda: FOSModel(max_lag=2, exog_lags={"x": 0}).fit(y, {"x": y * 1j})):
        with pytest.raises(InputError, match="is complex"):
            fit()
    with pytest.raises(ValueError, match="[Cc]omplex"):
        FOSRegressor().fit(np.c_[y, y].astype(complex), y)


def test_a_thin_fit_warns_and_says_so_in_its_summary():
    y = lfilter([1.0], [1.0, -0.8], np.random.default_rng(2).standard_normal(12))
    with pytest.warns(FitWarning, match="only 10 samples for 2 weights"):
        model = FOSModel(max_lag=2, max_terms=1, stop="max_terms").fit(y)
    assert "the weights are rough" in str(model.summary())
    with warnings.catch_warnings():
        warnings.simplefilter("error", FitWarning)
        FOSModel(max_lag=2, max_terms=1, stop="max_terms").fit(np.tile(y, 3))


@pytest.mark.parametrize("stop", ["korenberg", "max_terms", "variance", "mean_square", "aic",
                                  "bic", "fpe", "mdl"])
def test_a_noise_free_target_selects_only_its_terms(stop):
    x = np.random.default_rng(3).standard_normal((400, 20))
    y = 2.0 * x[:, 3] - x[:, 7] + 0.5
    kw = {"tol": 1e-30} if stop in ("variance", "mean_square") else {}
    result = fos(x, y, stop=stop, max_terms=20 if stop == "max_terms" else None, **kw)
    assert sorted(result.support.tolist()) == [3, 7]
    assert result.stop_reason in ("rounding", stop, "no_reduction")
    np.testing.assert_allclose(sorted(result.coef), [-1.0, 2.0], atol=1e-9)
    model = FOSModel(max_lag=3, stop=stop, tol=kw.get("tol"),
                     max_terms=10 if stop == "max_terms" else None)
    z = lfilter([1.0], [1.0, -1.2, 0.5], np.r_[1.0, np.zeros(999)])  # an exact AR(2) decay
    assert sorted(model.fit(z).terms_) == ["y[n-1]", "y[n-2]"]


def test_a_thin_fit_on_the_command_line_warns_in_one_line(tmp_path):
    pd.DataFrame({"time": np.arange(12) / 100, "gx": np.random.default_rng(4).standard_normal(12)}
                 ).to_csv(tmp_path / "r.csv", index=False)
    out = subprocess.run([sys.executable, "-m", "fosmodel.cli", "fit", str(tmp_path / "r.csv"),
                          "--column", "gx", "--max-lag", "1", "--stop", "max_terms",
                          "--max-terms", "1", "--out", str(tmp_path / "m.json")],
                         capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    err = out.stderr.splitlines()
    assert len(err) == 1 and err[0].startswith("fosmodel: warning: only 11 samples for 2 weights")
    assert json.loads((tmp_path / "m.json").read_text())["format"] == "fosmodel.FOSModel"


def _interrupted_commands(folder):
    rec = str(folder / "rec.csv")
    out = str(folder / "out")
    report = ["--out", out]
    return {
        "fit": ["fit", rec, "--column", "gx", "--out", out],
        "predict": ["predict", rec, "--model", str(folder / "model.json"), "--out", out],
        "study": ["study", rec, "--column", "gx", "--sensor", "gyro", "--units", "deg/s",
                  "--orders", "1", "--degrees", "1", "--methods", "burg", "--protocol", "fair",
                  "--split", "30s,20s", "--no-levels", *report, "--json", str(folder / "o.json")],
        "close-loop": ["close-loop", rec, "--column", "gx", *report, "--json",
                       str(folder / "o.json"), "--model", str(folder / "m.json")],
        "allan": ["allan", rec, "--column", "gx", *report, "--json", str(folder / "o.json")],
        "synth": ["synth", "clean", "--duration", "10", "--out", out],
        "demo": ["demo", *report],
    }


@pytest.mark.slow
@pytest.mark.parametrize("command", ["fit", "predict", "study", "close-loop", "allan", "synth",
                                     "demo"])
def test_an_interrupted_command_exits_130_and_writes_nothing(folder, capsys, monkeypatch,
                                                            command):
    """Ctrl-C arriving as the first output file is about to be renamed into place."""
    before = _snapshot(folder)
    calls = []

    def interrupted(fd):
        calls.append(fd)
        raise KeyboardInterrupt

    monkeypatch.setattr("fosmodel.io.output.os.fsync", interrupted)
    if command == "demo":  # interrupt the demo's long first part at once
        monkeypatch.setattr("fosmodel.demo.run_paper_records",
                            lambda out: (_ for _ in ()).throw(KeyboardInterrupt))
    assert cli.main(_interrupted_commands(folder)[command]) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "fosmodel: interrupted"
    assert calls or command == "demo"
    assert _snapshot(folder) == before  # no output, no temporary file, no staging directory
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]


@pytest.fixture
def sigint_handled():
    """Let a child process receive Ctrl-C as a terminal's user would send it.

    A shell starting the tests in the background (``cmd &``) sets SIGINT to ignored, and an
    ignored signal stays ignored through ``exec``: the command under test would run to its
    end.  A handled one is reset to the default there, and Python installs its own.
    """
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, previous)


@pytest.mark.slow
@pytest.mark.usefixtures("sigint_handled")
def test_ctrl_c_on_a_running_loop(tmp_path):
    """The real signal: SIGINT while the loop runs, then the same command to its end."""
    rng = np.random.default_rng(5)
    n = 400_000
    gx = lfilter([1.0], [1.0, -0.7], rng.standard_normal(n)) + np.cumsum(
        rng.standard_normal(n)) * 0.002
    pd.DataFrame({"time": np.arange(n) / 100.0, "gx": gx}).to_csv(tmp_path / "r.csv",
                                                                  index=False)
    argv = [sys.executable, "-m", "fosmodel.cli", "close-loop", str(tmp_path / "r.csv"),
            "--column", "gx", "--out", str(tmp_path / "loop"), "--json", str(tmp_path / "l.json")]
    with subprocess.Popen(argv, stderr=subprocess.PIPE, text=True) as proc:
        for line in proc.stderr:  # wait for the loop to be under way
            if "round 1" in line:
                break
        proc.send_signal(signal.SIGINT)
        err = proc.stderr.read()
        assert proc.wait(timeout=60) == 130 and "fosmodel: interrupted" in err
        assert "Traceback" not in err and "KeyboardInterrupt" not in err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]


# --- the operating system's refusals of an output: one line, exit 2, nothing changed ---------

_LAST = {"fit": "out", "predict": "out", "study": "o.json", "close-loop": "o.json",
         "allan": "o.json", "synth": "out.truth.json"}  # the last file each command writes


def _failing_at(name, error):
    """An ``os.fsync`` that raises ``error`` on the temporary file of output ``name``."""
    real = os.fsync

    def fsync(fd):
        if os.path.basename(os.readlink(f"/proc/self/fd/{fd}")).startswith(f".{name}."):
            raise error
        return real(fd)
    return fsync


@pytest.mark.slow
@pytest.mark.parametrize("command", sorted(_LAST))
def test_a_full_disk_or_ctrl_c_at_the_last_output_undoes_the_first(folder, capsys, monkeypatch,
                                                                   command):
    """The outputs a command put in place before its last one failed are taken back: removed
    when new, restored byte for byte when they replaced earlier ones."""
    argv = _interrupted_commands(folder)[command]
    fresh = _snapshot(folder)
    full = OSError(errno.ENOSPC, "No space left on device")
    with monkeypatch.context() as patch:
        patch.setattr("fosmodel.io.output.os.fsync", _failing_at(_LAST[command], full))
        assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == (f"fosmodel: error: cannot write {folder / _LAST[command]}: No space left "
                       "on device")
    assert _snapshot(folder) == fresh and not [p for p in folder.rglob(".*")]
    assert cli.main(argv) == 0
    written = _snapshot(folder)
    assert len(written) > len(fresh)
    with monkeypatch.context() as patch:
        patch.setattr("fosmodel.io.output.os.fsync", _failing_at(_LAST[command],
                                                                  KeyboardInterrupt()))
        assert cli.main(argv) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == "fosmodel: interrupted"
    assert _snapshot(folder) == written and not [p for p in folder.rglob(".*")]


@pytest.mark.parametrize("command", ["fit", "predict", "study", "close-loop", "allan"])
def test_a_folder_the_process_may_not_write_is_refused_before_any_work(folder, capsys,
                                                                       monkeypatch, command):
    """A read-only output folder was a PermissionError, an internal error, after the work."""
    argv = _interrupted_commands(folder)[command]
    before = _snapshot(folder)
    monkeypatch.setattr("fosmodel.io.output.os.access", lambda path, mode: False)
    monkeypatch.setattr("fosmodel.cli.commands.load_record",
                        lambda *a, **k: pytest.fail("read the record"))
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("fosmodel: error: cannot write ")
    assert err[0].endswith(f": permission denied on directory {folder}"), err
    assert _snapshot(folder) == before


@pytest.mark.parametrize("error, said", [
    (PermissionError(errno.EACCES, "Permission denied"), "Permission denied"),
    (OSError(errno.EROFS, "Read-only file system"), "Read-only file system"),
    (IsADirectoryError(errno.EISDIR, "Is a directory"), "Is a directory"),
])
def test_a_write_the_system_refuses_after_the_checks_is_one_line(folder, capsys, monkeypatch,
                                                                 error, said):
    """The folder changed between the check and the write: the refusal names the output."""
    before = _snapshot(folder)
    real = os.open

    def refused(path, *args, **kwargs):
        if os.path.basename(path).startswith(".model2.json."):
            raise error
        return real(path, *args, **kwargs)
    monkeypatch.setattr("fosmodel.io.output.os.open", refused)
    argv = ["fit", str(folder / "rec.csv"), "--column", "gx", "--out", str(folder / "model2.json")]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == f"fosmodel: error: cannot write {folder / 'model2.json'}: {said}"
    assert _snapshot(folder) == before


def test_a_folder_named_like_a_report_file_changes_nothing(folder, capsys):
    """It was an IsADirectoryError, an internal error, once the report's first files had moved."""
    report = folder / "report"
    (report / "allan.md").mkdir(parents=True)
    (report / "noise.csv").write_text("earlier\n")
    before = _snapshot(folder)
    assert cli.main(["allan", str(folder / "rec.csv"), "--column", "gx", "--out",
                     str(report)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"fosmodel: error: cannot write the report into {report}: {report}/allan.md "
                   "is a directory, where the report has a file of that name"]
    assert _snapshot(folder) == before and (report / "allan.md").is_dir()
    assert not [p for p in folder.rglob(".*")]


def _in_a_mount(tmp_path, options):
    """A command prefix that runs in a private mount namespace with a tmpfs on ``tmp_path/mnt``
    (``options``), then prints what the command left in it; or a skip where this process may
    not mount."""
    mnt = tmp_path / "mnt"
    mnt.mkdir()
    prefix = ["unshare", "--mount", "--propagation", "private", "sh", "-c",
              f'mount -t tmpfs -o {options} tmpfs "$0" || exit 99; "$@"; code=$?; '
              'echo "left:" $(ls -A "$0"); exit $code', str(mnt)]
    if shutil.which("unshare") is None or subprocess.run(
            [*prefix, "true"], capture_output=True, check=False).returncode != 0:
        pytest.skip("no private mount namespace here (unshare --mount needs privileges)")
    return prefix, mnt


@pytest.mark.slow
@pytest.mark.parametrize("options, said", [
    ("size=64k", "No space left on device"),
    ("ro", "is on a read-only file system"),
])
def test_a_real_full_disk_and_a_real_read_only_folder(tmp_path, options, said):
    prefix, mnt = _in_a_mount(tmp_path, options)
    y = lfilter([1.0], [1.0, -0.7], np.random.default_rng(6).standard_normal(5000))
    pd.DataFrame({"time": np.arange(5000) / 100.0, "gx": y}).to_csv(tmp_path / "r.csv",
                                                                    index=False)
    for argv in (["allan", str(tmp_path / "r.csv"), "--column", "gx", "--out", str(mnt / "a")],
                 ["fit", str(tmp_path / "r.csv"), "--column", "gx", "--out", str(mnt / "m.json")]):
        out = subprocess.run([*prefix, sys.executable, "-m", "fosmodel.cli", *argv],
                             capture_output=True, text=True, timeout=120, check=False)
        err = out.stderr.strip().splitlines()
        if argv[0] == "fit" and options.startswith("size"):
            assert out.returncode == 0, out.stderr  # a model file fits in 64 kB
            continue
        assert out.returncode == 2 and len(err) == 1, out.stderr
        assert err[0].startswith(f"fosmodel: error: cannot write {argv[-1]}: ") and said in err[0]
        assert out.stdout.splitlines()[-1] == "left:"  # nothing in the mount


@pytest.mark.usefixtures("sigint_handled")
def test_ctrl_c_while_the_libraries_load_is_one_line(tmp_path):
    """Ctrl-C in the first seconds (numpy, pandas and scikit-learn loading) printed a traceback."""
    # a record the loop takes seconds over: a signal the loaded machine delivers late still
    # lands in the command, not in the interpreter's shutdown after a quick refusal
    n = 30_000
    pd.DataFrame({"time": np.arange(n) / 100.0,
                  "gx": np.random.default_rng(0).standard_normal(n)}).to_csv(
        tmp_path / "r.csv", index=False)
    argv = [sys.executable, "-X", "importtime", "-m", "fosmodel.cli", "close-loop",
            str(tmp_path / "r.csv"), "--column", "gx", "--out", str(tmp_path / "loop")]
    with subprocess.Popen(argv, stderr=subprocess.PIPE, text=True) as proc:
        for line in proc.stderr:  # the command line's guard is in place once numpy loads
            if line.split("|")[-1].strip() == "numpy":
                break
        proc.send_signal(signal.SIGINT)
        err = [line for line in proc.stderr.read().splitlines()
               if not line.startswith("import time:")]
        assert proc.wait(timeout=60) == 130
    assert err == ["fosmodel: interrupted"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["r.csv"]

"""Every check guarded for the records it can meet: shorter than one window, at a low rate,
long enough that a figure's ticks are computed to their last digits."""

import math

import numpy as np
import pytest
from matplotlib.figure import Figure
from scipy.signal import lfilter

from fosmodel import cli
from fosmodel.loop.loop_figure import _frame
from fosmodel.noise.axes import Axis
from fosmodel.noise.checks import stillness

SIX = "gx=deg/s,gy=deg/s,gz=deg/s,ax=m/s^2,ay=m/s^2,az=m/s^2"


def _two_rows(tmp_path):
    path = tmp_path / "two.csv"
    path.write_text("time,gx,gy,gz,ax,ay,az\n0,0.1,0.2,0.1,0.01,0.02,9.8\n"
                    "0.01,0.2,0.1,0.3,0.02,0.03,9.81\n")
    return path


@pytest.mark.parametrize("command, said", [
    (["allan", "{rec}", "--column", "gx", "--out", "{out}"],
     "record too short for an Allan variance: 2 samples, need at least 100"),
    (["imu", "{rec}", "--units", SIX, "--out", "{out}"],
     "the record has 2 samples (0.02 s at 100 Hz), too short for these settings"),
    (["fleet", "{rec}", "--units", SIX, "--steps", "allan", "--out", "{out}"],
     "record too short for an Allan variance: 2 samples"),
])
def test_a_record_shorter_than_one_window_is_refused_in_one_line(tmp_path, capsys, command,
                                                                 said):
    rec = _two_rows(tmp_path)
    argv = [a.format(rec=rec, out=tmp_path / "out") for a in command]
    assert cli.main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("fosmodel: error: ") and said in err[-1], err
    assert not any("internal error" in line for line in err)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["two.csv"]


@pytest.mark.parametrize("n", [1, 2, 15, 150])
def test_the_stillness_of_a_record_shorter_than_two_windows_is_left_to_the_length_checks(n):
    x = np.random.default_rng(0).standard_normal(n)
    found = stillness({"gx": x}, [Axis("gx", "gyro", "deg/s", "")], 100.0)
    assert found.still.all() and found.n_samples == n


def _wandering_gyro(n, seed=3):
    """A static gyro whose bias wanders over about ten samples: AR(1), 0.9, 0.2 deg/s."""
    e = np.random.default_rng(seed).standard_normal(n)
    return 0.2 * math.sqrt(1 - 0.81) * lfilter([1.0], [1.0, -0.9], e)


def _write(path, gx, rate):
    t = np.arange(len(gx)) / rate
    path.write_text("time,gx\n" + "".join(f"{a:.6f},{b:.6f}\n" for a, b in zip(t, gx)))
    return path


@pytest.mark.parametrize("rate", [1.0, 100.0])
def test_a_static_record_at_a_low_rate_is_static(tmp_path, capsys, rate):
    # Two hours at 1 Hz: a window is 10 samples (10 s), the minute around it 7 windows, and
    # the noise of its median read off the medians (at 1 Hz neighbouring samples wander
    # together); the same samples at 100 Hz pass as they did.
    rec = _write(tmp_path / "rec.csv", _wandering_gyro(7200), rate)
    argv = ["allan", str(rec), "--column", "gx", "--units", "deg/s", "--out",
            str(tmp_path / "report")]
    if rate < 1.5:
        argv += ["--rate", "1"]
    assert cli.main(argv) == 0, capsys.readouterr().err
    assert (tmp_path / "report").is_dir()


def test_a_turn_at_a_low_rate_is_still_motion_in_its_own_window_length(tmp_path, capsys):
    gx = _wandering_gyro(7200)
    gx[3000:3020] += 5.0  # a 20 s turn at 5 deg/s
    rec = _write(tmp_path / "rec.csv", gx, 1.0)
    assert cli.main(["allan", str(rec), "--column", "gx", "--units", "deg/s", "--rate", "1",
                     "--out", str(tmp_path / "report")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert "the record is not static: it moves for" in err[0]
    assert "(10 s medians)" in err[0]
    assert not (tmp_path / "report").exists()


@pytest.mark.parametrize("low, high", [
    (19565.682440956938, 19565.682440957145),  # no tick of the locator reaches either end
    (1734348.405267763, 1734348.4052682933),
    (0.0, 19999.99),  # the time axis of 2,000,000 samples at 100 Hz
    (5.0, 5.0),
])
def test_a_panel_frames_values_whatever_their_last_digits(low, high):
    ax = Figure().add_subplot()
    ax.plot([0, 1, 2], [low, (low + high) / 2, high])
    _frame(ax, "y")
    bottom, top = ax.get_ylim()
    assert bottom <= low and top >= high
    assert len(ax.yaxis.get_major_locator().tick_values(bottom, top)) >= 2


def test_the_notes_after_the_stillness_check_name_command_line_flags(tmp_path, capsys):
    counts = np.random.default_rng(5).integers(-40, 40, 6000)  # raw counts, not yet scaled
    path = tmp_path / "rec.csv"
    path.write_text("time,gx\n" + "".join(f"{k / 100:.2f},{c}\n" for k, c in enumerate(counts)))
    assert cli.main(["allan", str(path), "--column", "gx", "--units", "deg/s", "--out",
                     str(tmp_path / "report")]) == 0
    err = capsys.readouterr().err
    assert "fosmodel: note: column(s) gx hold only integers: if they are raw counts, scale " \
           "them, e.g. --scale gx=1/16384" in err
    assert "scale={" not in err


@pytest.mark.slow
def test_close_loop_on_two_million_samples_draws_its_figures(tmp_path, capsys):
    # the figure's frame, where no tick of the locator reached the data's maximum
    n = 2_000_000
    rng = np.random.default_rng(0)
    gx = 0.05 * lfilter([1.0], [1.0, -0.5], rng.standard_normal(n))
    path = tmp_path / "rec.npy"
    np.save(path, np.rec.fromarrays([np.arange(n) / 100.0, np.round(gx, 6),
                                     np.round(0.05 * rng.standard_normal(n), 6)],
                                    names="time,gx,gy"))
    out = tmp_path / "report"
    assert cli.main(["close-loop", str(path), "--column", "gx", "--out", str(out)]) == 0, \
        capsys.readouterr().err
    assert (out / "report.md").is_file()

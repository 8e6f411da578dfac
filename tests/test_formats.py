"""The format registry: the loader, the logs, the fleet and the command line read the same table."""

import re
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from fosmodel import cli
from fosmodel.io.formats import COMPRESSED, CSV, FORMATS, LOGS, SUFFIXES, TABLES, table_format
from fosmodel.io.loader import load_record
from fosmodel.io.topics import is_sensor_log
from fosmodel.workflows.fleet_record import record_name

ROOT = Path(__file__).resolve().parents[1]
COMMANDS = ["fit", "predict", "study", "close-loop", "allan", "imu", "fleet"]


def _help(command, capsys):
    with pytest.raises(SystemExit) as done:
        cli.main([command, "--help"])
    assert done.value.code == 0
    return " ".join(capsys.readouterr().out.split())  # argparse wraps the lines


@pytest.mark.parametrize("command", COMMANDS)
def test_the_help_of_every_record_argument_names_every_format(command, capsys):
    text = _help(command, capsys)
    wanted = ", ".join(f.help for f in FORMATS[:-1]) + f" or {FORMATS[-1].help}"
    assert wanted in text


@pytest.mark.parametrize("suffix", sorted(SUFFIXES))
def test_the_fleet_leaves_every_format_and_compression_suffix_out_of_a_name(suffix):
    assert record_name(f"runs/imu1{suffix}") == "imu1"
    assert record_name(f"runs/imu1{suffix.upper()}") == "imu1"


def test_the_fleet_knows_exactly_the_registry_suffixes():
    every = {s for f in FORMATS for s in f.suffixes} | set(COMPRESSED)
    assert SUFFIXES == every
    assert record_name("imu1.csv.gz") == "imu1" and record_name("imu1.dat") == "imu1.dat"


def _write(path, frame):
    if path.suffix == ".npy":
        np.save(path, frame.to_records(index=False))
    elif path.suffix == ".parquet":
        pytest.importorskip("pyarrow", reason="Parquet needs the 'parquet' extra")
        frame.to_parquet(path)
    else:
        frame.to_csv(path, index=False)


@pytest.mark.parametrize("fmt, suffix", [(f, s) for f in TABLES for s in f.suffixes])
def test_the_loader_reads_each_table_suffix_with_its_format(tmp_path, fmt, suffix):
    frame = pd.DataFrame({"time": np.arange(200) / 100.0, "gx": np.sin(np.arange(200.0))})
    path = tmp_path / f"rec{suffix}"
    _write(path, frame)
    assert table_format(path) is fmt
    assert table_format(path.with_name(f"rec{suffix.upper()}")) is fmt
    record = load_record(path)
    assert record.rate == pytest.approx(100.0)
    np.testing.assert_array_equal(record.column("gx"), frame["gx"].to_numpy())


def test_a_name_of_no_format_is_read_as_csv(tmp_path):
    assert table_format(tmp_path / "rec.dat") is CSV
    assert table_format(tmp_path / "rec.npy.gz") is CSV


@pytest.mark.parametrize("fmt, suffix", [(f, s) for f in LOGS for s in f.suffixes])
def test_every_log_suffix_is_a_log_and_no_table_suffix_is(tmp_path, fmt, suffix):
    assert is_sensor_log(tmp_path / f"flight{suffix}")
    assert fmt.recognises(tmp_path / f"flight{suffix}")
    assert not any(is_sensor_log(tmp_path / f"rec{s}") for f in TABLES for s in f.suffixes)


def test_every_extra_the_registry_names_is_one_of_the_package():
    pyproject = (ROOT / "pyproject.toml").read_text()
    extras = pyproject.split("[project.optional-dependencies]")[1].split("\n[")[0]
    named = {f.extra for f in FORMATS if f.extra}
    assert named and all(re.search(rf"^{extra} = \[", extras, re.M) for extra in named)
    readme = (ROOT / "README.md").read_text()
    assert all(re.search(rf"`\[{extra}\]`", readme) for extra in named)

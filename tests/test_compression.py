"""Compressed records read bounded while they stream: the limit holds, and so does the memory.

The files are bombs of the two kinds a hostile or damaged file can be: one endless line (a
megabyte of gzip expanding to a gibibyte of zeros, 8 GiB as gzip members one after the other)
and rows that go on far beyond the file's size.  Each is read the way the loader reads (the
head where the header is looked for, then the rows through pandas), in a fresh process whose
peak memory (VmHWM) is measured.
"""

import gzip
import io
import json
import os
import subprocess
import sys

import pandas as pd
import pytest

from fosmodel.core.exceptions import InputError
from fosmodel.io.compression import (
    EXPANSION_FLOOR,
    HEAD_BYTES,
    MAX_LINE,
    BoundedStream,
    capped_source,
    head_lines,
)

PEAK_MB = 1024


@pytest.fixture(scope="module")
def bombs(tmp_path_factory):
    """A gibibyte of zeros in a megabyte of gzip; 8 GiB as eight such members; 600 MB of rows."""
    folder = tmp_path_factory.mktemp("bombs")
    chunk = b"0" * 2**24
    with gzip.open(folder / "zeros.csv.gz", "wb", compresslevel=9) as fh:
        for _ in range(64):
            fh.write(chunk)
    member = (folder / "zeros.csv.gz").read_bytes()
    (folder / "eight.csv.gz").write_bytes(member * 8)  # gzip reads members one after another
    with gzip.open(folder / "rows.csv.gz", "wb", compresslevel=9) as fh:
        fh.write(b"gx\n")
        for _ in range(40):
            fh.write(b"0\n" * 7_500_000)
    return folder


_READ = r"""
import json, re, sys
from pathlib import Path
import pandas as pd
from fosmodel.core.exceptions import InputError
from fosmodel.io.compression import capped_source, head_lines

def peak():
    with open("/proc/self/status") as fh:
        return int(re.search(r"VmHWM:\s+(\d+)", fh.read()).group(1)) / 1024

out = {}
for name in sys.argv[1:]:
    path = Path(name)
    with open("/proc/self/clear_refs", "w") as fh:
        fh.write("5")
    head = sum(map(len, head_lines(path, 51)))
    try:
        with capped_source(path) as source:
            for block in pd.read_csv(source, chunksize=500_000, low_memory=False):
                pass
        error = None
    except InputError as exc:
        error = str(exc)
    out[path.name] = [head, error, peak()]
print(json.dumps(out))
"""


@pytest.mark.slow
def test_bombs_are_refused_while_they_stream_within_a_gigabyte(bombs):
    names = ["zeros.csv.gz", "eight.csv.gz", "rows.csv.gz"]
    out = subprocess.run([sys.executable, "-c", _READ, *(str(bombs / n) for n in names)],
                         capture_output=True, text=True, timeout=300, check=False,
                         env={**os.environ, "OPENBLAS_NUM_THREADS": "1"})
    assert out.returncode == 0, out.stderr
    runs = json.loads(out.stdout)
    size = (bombs / "rows.csv.gz").stat().st_size
    expected = {
        "zeros.csv.gz": (HEAD_BYTES, f"{bombs}/zeros.csv.gz: line 1 is longer than 16 MiB once "
                                     "decompressed: fosmodel stops there"),
        "eight.csv.gz": (HEAD_BYTES, f"{bombs}/eight.csv.gz: line 1 is longer than 16 MiB once "
                                     "decompressed: fosmodel stops there"),
        "rows.csv.gz": (3 + 50 * 2, f"{bombs}/rows.csv.gz: decompresses to more than 100 times "
                                    f"its size ({size:,} bytes): fosmodel stops at "
                                    f"{max(100 * size, EXPANSION_FLOOR):,} bytes"),
    }
    for name, (head, error) in expected.items():
        read, said, peak = runs[name]
        assert read == head and said.startswith(error), (name, read, said)
        assert peak < PEAK_MB, (name, peak)


def test_a_record_reads_whole_through_the_stream(tmp_path):
    frame = pd.DataFrame({"time": [0.0, 0.01, 0.02], "gx": [1.5, -2.0, 3.25]})
    path = tmp_path / "r.csv.gz"
    with gzip.open(path, "wt") as fh:
        fh.write("Fs,100\n" + frame.to_csv(index=False))
    with capped_source(path) as source:
        pd.testing.assert_frame_equal(pd.read_csv(source, skiprows=1), frame)
    assert head_lines(path, 2) == ["Fs,100\n", "time,gx\n"]
    plain = tmp_path / "r.csv"
    plain.write_bytes(b"a\r\nb\rc\n")
    assert head_lines(plain, 5) == ["a\r\n", "b\r", "c\n"]
    with capped_source(plain) as source:
        assert source == plain


def test_the_stream_never_gives_more_than_its_limit(tmp_path):
    path = tmp_path / "r.csv.gz"
    path.write_bytes(b"x" * 20)  # its size, for the message
    stream = BoundedStream(io.BytesIO(b"0,1\n" * 1000), path, limit=2000)
    with pytest.raises(InputError, match=r"\(20 bytes\): fosmodel stops at 2,000 bytes"):
        while stream.read(300):
            pass
    assert stream.given == 2001  # one byte over, to know it is over


def test_a_line_over_the_longest_is_refused_where_it_is(tmp_path):
    path = tmp_path / "r.csv.gz"
    path.write_bytes(b"x")
    data = b"gx\n1\n" + b"7" * (MAX_LINE + 1)
    stream = BoundedStream(io.BytesIO(data), path, limit=10 * MAX_LINE)
    with pytest.raises(InputError, match="line 3 is longer than 16 MiB"):
        while stream.read(2**20):
            pass

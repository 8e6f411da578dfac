"""Reading a model file: bounded before parsing, refused in one line when it is no model file.

A model path is read only when it is a regular file of at most ``MAX_BYTES``: a FIFO is
refused without waiting for a writer, ``/dev/zero`` without reading it, an 8 GiB file from its
size.  The peak memory of every refusal is measured in a fresh process (VmHWM) and must stay
under 1 GB, as the records' refusals do (``tests/test_guards.py``).
"""

import json
import os

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel
from fosmodel.core.exceptions import InputError
from fosmodel.io.model_file import read_model, write_model
from fosmodel.models.model_file import MAX_BYTES, MAX_DEPTH

PEAK_MB = 1024


@pytest.fixture
def files(tmp_path):
    """A record and a model fitted on it (``fosmodel fit --max-lag 3``)."""
    y = lfilter([1.0], [1.0, -0.7], np.random.default_rng(0).standard_normal(3000)) * 0.1
    pd.DataFrame({"time": np.arange(3000) / 100.0, "gx": y}).to_csv(tmp_path / "rec.csv",
                                                                      index=False)
    model = FOSModel(max_lag=3).fit(pd.Series(y, name="gx"))
    write_model(tmp_path / "model.json", model, {"column": "gx", "rate_hz": 100.0})
    return tmp_path


def _predict(folder, model):
    return ["predict", str(folder / "rec.csv"), "--model", str(model), "--out",
            str(folder / "pred.csv")]


def _edited(folder, name, edit):
    data = json.loads((folder / "model.json").read_text())
    edit(data)
    path = folder / name
    path.write_text(json.dumps(data))
    return path


def test_a_model_file_round_trips(files):
    model = read_model(files / "model.json")
    assert model.terms_ == ["y[n-1]"] and model.meta_["column"] == "gx"


def test_what_is_no_regular_file_is_refused_without_reading_it(files, measured_runs):
    """/dev/zero reached 6.8 GB and a MemoryError; a FIFO hung until killed."""
    (files / "zero.json").symlink_to("/dev/zero")
    os.mkfifo(files / "fifo.json")
    (files / "sub").mkdir()
    with open(files / "huge.json", "wb") as fh:  # 8 GiB, sparse: nothing to read but its size
        fh.truncate(8 * 2**30)
    cases = {"zero.json": "cannot read model {}/zero.json (/dev/zero): a device, not a model file",
             "fifo.json": "cannot read model {}/fifo.json: a FIFO, not a model file",
             "sub": "cannot read model {}/sub: a directory, not a model file",
             "huge.json": "{}/huge.json: not a model file (8,589,934,592 bytes; a model file "
                          "holds at most 16 MiB)"}
    runs = measured_runs([_predict(files, files / name) for name in cases], timeout=120)
    for (name, message), (code, peak, err) in zip(cases.items(), runs):
        assert code == 2 and err.strip() == f"fosmodel: error: {message.format(files)}", err
        assert peak < PEAK_MB, (name, peak)
    assert not (files / "pred.csv").exists()


def test_a_file_that_grows_past_the_limit_while_read_is_refused(files, monkeypatch):
    path = files / "model.json"
    monkeypatch.setattr("fosmodel.models.model_file.MAX_BYTES", path.stat().st_size - 1)
    with pytest.raises(InputError, match="not a model file"):
        read_model(path)
    assert MAX_BYTES == 16 * 2**20


@pytest.mark.parametrize("text, message", [
    ("[" * 100_000 + "]" * 100_000, f"not a model file (JSON nested more than {MAX_DEPTH} deep)"),
    ('{"a": ' + "[" * 20 + "]" * 20 + "}", f"JSON nested more than {MAX_DEPTH} deep"),
    ('{"format": ' + "9" * 4000 + "}", "not a model file (an integer of 4,000 digits)"),
    ('{"format": -' + "9" * 21 + "}", "not a model file (an integer of 21 digits)"),
    ("{", "not a model file (invalid JSON at line 1)"),
])
def test_json_nesting_and_integers_are_bounded(files, text, message):
    path = files / "m.json"
    path.write_text(text)
    with pytest.raises(InputError) as caught:
        read_model(path)
    assert str(caught.value) == f"{path}: {message}" or message in str(caught.value)


def test_forged_models_are_refused_naming_the_field(files, measured_runs):
    """What ``predict`` accepted (absurd weights, a term twice, hundreds of terms) or ended in
    MemoryError on (a lag of 10^12, a power of 10^9): one line each, under 1 GB."""
    def hundreds(d):
        d["fitted"]["terms"] = [f"y[n-{k}]" for k in range(1, 301)]
        for key in ("coef", "coef_se", "q", "mse_path"):
            d["fitted"][key] = [0.001] * 300

    def twice(d):
        d["fitted"]["terms"] *= 2
        for key in ("coef", "coef_se", "q", "mse_path"):
            d["fitted"][key] *= 2

    edits = {
        "absurd": (lambda d: d["fitted"].update(coef=[1e300]),
                   "fitted.coef[0]: 1e+300 is over 1e+30 in magnitude"),
        "large": (lambda d: d["fitted"].update(coef=[5e8]),
                  "fitted.coef[0]: the weight 5e+08 of 'y[n-1]' is beyond any fit's: abs(w) "
                  "s^(d-1) = 5e+08, with s = "),
        "twice": (twice, "fitted.terms[1]: 'y[n-1]' repeats fitted.terms[0]"),
        "hundreds": (hundreds, "fitted.terms: 300 terms, but the params make 4 candidates, the "
                               "constant among them"),
        "lag": (lambda d: d["fitted"].update(terms=["y[n-1000000000000]"]),
                "fitted.terms[0]: 'y[n-1000000000000]' lags the output by 1000000000000 "
                "samples, outside 1 to params.max_lag 3"),
        "lag-params": (lambda d: (d["params"].update(max_lag=10**12),
                                  d["fitted"].update(terms=["y[n-1000000000000]"])),
                       "params.max_lag: 1000000000000 is not an integer from 0 to 10,000,000"),
        "power": (lambda d: d["fitted"].update(terms=["y[n-1]^1000000000"]),
                  "fitted.terms[0]: term 'y[n-1]^1000000000' is a product of more than 1 "
                  "factor(s) (params.degree 1)"),
        "degree": (lambda d: (d["params"].update(degree=10**9),
                              d["fitted"].update(terms=["y[n-1]^1000000000"])),
                   "params.degree: 1000000000 is not an integer from 1 to 32"),
    }
    paths = {name: _edited(files, f"{name}.json", edit) for name, (edit, _) in edits.items()}
    runs = measured_runs([_predict(files, path) for path in paths.values()])
    for (name, (_, message)), (code, peak, err) in zip(edits.items(), runs):
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1, (name, err)
        assert lines[0].startswith(f"fosmodel: error: {paths[name]}: corrupted model file: "
                                   f"{message}"), (name, lines[0])
        assert peak < PEAK_MB, (name, peak)
    assert not (files / "pred.csv").exists()

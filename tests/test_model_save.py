"""Model files: FOSModel.save and load, the JSON `fosmodel fit` writes, checked on reading."""

import json
import os

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel, cli
from fosmodel.core.exceptions import InputError
from fosmodel.io.model_file import read_model, write_model


@pytest.fixture(scope="module")
def fitted():
    y = lfilter([1.0], [1.0, -1.2, 0.5], np.random.default_rng(3).standard_normal(4000))
    return FOSModel(max_lag=4, degree=2).fit(y), y


def test_save_then_load_predicts_the_same(fitted, tmp_path):
    model, y = fitted
    model.save(tmp_path / "m.json", {"column": "gyro_x", "rate_hz": 100.0})
    again = FOSModel.load(tmp_path / "m.json")
    np.testing.assert_array_equal(again.predict(y), model.predict(y))
    assert again.meta_ == {"column": "gyro_x", "rate_hz": 100.0}
    assert json.loads((tmp_path / "m.json").read_text()) == model.to_dict(again.meta_)


def test_a_file_of_fosmodel_fit_loads_and_the_commands_read_what_save_writes(tmp_path, capsys):
    import pandas as pd

    y = lfilter([1.0], [1.0, -0.9], np.random.default_rng(5).standard_normal(3000))
    pd.DataFrame({"gyro_x": y}).to_csv(tmp_path / "r.csv", index=False)
    assert cli.main(["fit", str(tmp_path / "r.csv"), "--column", "gyro_x", "--rate", "100",
                     "--max-lag", "3", "--out", str(tmp_path / "fit.json")]) == 0
    model = FOSModel.load(tmp_path / "fit.json")
    assert model.meta_["column"] == "gyro_x"
    model.save(tmp_path / "saved.json", model.meta_)
    assert read_model(tmp_path / "saved.json").terms_ == model.terms_
    write_model(tmp_path / "written.json", model, model.meta_)
    assert (tmp_path / "written.json").read_text() == (tmp_path / "saved.json").read_text()
    capsys.readouterr()


@pytest.mark.parametrize("content, message", [
    (b"\xff\xfe", "not a model file (not UTF-8 text)"),
    (b"{", "not a model file (invalid JSON at line 1)"),
    (b'{"format": "other"}', "not a fosmodel FOSModel file (missing or wrong 'format')"),
])
def test_a_file_that_is_not_a_model_is_refused_in_one_line_naming_it(content, message, tmp_path):
    path = tmp_path / "bad.json"
    path.write_bytes(content)
    with pytest.raises(InputError) as error:
        FOSModel.load(path)
    assert str(error.value) == f"{path}: {message}"
    with pytest.raises(InputError, match=r"^cannot read model .*missing\.json: No such file"):
        FOSModel.load(tmp_path / "missing.json")


def test_weights_that_are_not_finite_are_refused(fitted, tmp_path):
    model, _ = fitted
    data = model.to_dict()
    data["fitted"]["coef"][0] = float("nan")
    (tmp_path / "nan.json").write_text(json.dumps(data))
    with pytest.raises(InputError, match=r"fitted\.coef\[0\]: nan is not a finite number"):
        FOSModel.load(tmp_path / "nan.json")


def _refusals(path):
    """The messages of ``FOSModel.load`` and the commands' ``read_model`` refusing ``path``."""
    messages = []
    for read in (FOSModel.load, read_model):
        with pytest.raises(InputError) as error:
            read(path)
        messages.append(str(error.value))
    return messages


def test_load_refuses_a_fifo_and_dev_zero_unread_as_the_commands_do(tmp_path):
    """A FIFO would block ``open`` until a writer came; /dev/zero would be read without end."""
    os.mkfifo(tmp_path / "fifo.json")
    (tmp_path / "zero.json").symlink_to("/dev/zero")
    assert _refusals(tmp_path / "fifo.json") == [
        f"cannot read model {tmp_path}/fifo.json: a FIFO, not a model file"] * 2
    assert _refusals(tmp_path / "zero.json") == [
        f"cannot read model {tmp_path}/zero.json (/dev/zero): a device, not a model file"] * 2


@pytest.mark.parametrize("edit, problem", [
    (lambda f: f.update(terms=["y[n-1000000000000]"]),
     "fitted.terms[0]: 'y[n-1000000000000]' lags the output by 1000000000000 samples, outside "
     "1 to params.max_lag 4"),
    (lambda f: f["coef"].__setitem__(0, 1e300),
     "fitted.coef[0]: 1e+300 is over 1e+30 in magnitude"),
    (lambda f: f.update(terms=[f["terms"][0]] * len(f["terms"])),
     "fitted.terms[1]: 'y[n-1]' repeats fitted.terms[0]"),
])
def test_load_refuses_a_forged_model_in_the_commands_line(fitted, tmp_path, edit, problem):
    model, _ = fitted
    data = model.to_dict()
    edit(data["fitted"])
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(data))
    assert _refusals(path) == [f"{path}: corrupted model file: {problem}"] * 2


def test_an_unfitted_model_is_not_saved(tmp_path):
    with pytest.raises(InputError, match="not fitted"):
        FOSModel(max_lag=2).save(tmp_path / "m.json")
    assert not (tmp_path / "m.json").exists()

"""Fuzzing the model file schema (hypothesis): any edit of a valid model file is refused in one
line or read as a model that predicts finite numbers; never another exception, never a warning.

Beside the record fuzzer (``tests/test_fuzz_cli.py``), which feeds a fixed list of damaged
files to every command, this one draws its damage: a JSON value of any type put in place of any
field of a real model file, or term names drawn with lags and powers up to 10^15.  The examples
are derandomized and few (a few seconds in CI); a failure prints the edit.
"""

import copy
import json
import warnings

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from scipy.signal import lfilter

from fosmodel import FOSModel, Term
from fosmodel.core.exceptions import InputError
from fosmodel.io.model_file import read_model

SETTINGS = settings(max_examples=100, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])
N = 400
_Y = lfilter([1.0], [1.0, -1.2, 0.5], np.random.default_rng(0).standard_normal(N))
_TEMP = 20 + np.cumsum(np.random.default_rng(1).standard_normal(N)) * 0.01
_T = np.arange(N) / 100.0
_COS = np.cos(2 * np.pi * 7.3 * _T)


def _model_dicts():
    models = [
        FOSModel(max_lag=3, degree=2, exog_lags={"temp": 2}).fit(_Y, {"temp": _TEMP}),
        FOSModel(max_lag=2, levels=[0.5], rate=100.0, columns=["cos@7.3Hz"]).fit(
            _Y + _COS, {"cos@7.3Hz": _COS}),
    ]
    return [json.loads(json.dumps(m.to_dict({"column": "gx"}))) for m in models]


MODEL_DICTS = _model_dicts()


def _paths(value, prefix=()):
    """Every path to a value inside a JSON value (the root excluded)."""
    items = (value.items() if isinstance(value, dict) else
             enumerate(value) if isinstance(value, list) else ())
    for key, item in items:
        yield (*prefix, key)
        yield from _paths(item, (*prefix, key))


JSON = st.recursive(
    st.none() | st.booleans() | st.integers(-2**70, 2**70)
    | st.floats(allow_nan=True, allow_infinity=True) | st.text(max_size=12),
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=6), inner,
                                                                max_size=4),
    max_leaves=8)

FACTORS = st.one_of(
    st.builds(lambda ch, lag: f"{ch}[n-{lag}]", st.sampled_from(["y", "temp", "x"]),
              st.integers(0, 10**15) | st.integers(0, 4)),
    st.sampled_from(["level@0.5s", "level@3s", "cos@7.3Hz", "sin@1Hz"]))
TERMS = st.lists(st.builds(lambda f, p: f if p == 1 else f"{f}^{p}", FACTORS,
                           st.integers(1, 3) | st.integers(1, 10**12)),
                 min_size=1, max_size=3).map("*".join)


SCALES = (0.0, -1.0, 1e-300, 1e-30, 1e30, 1e300, float("inf"))
PER_TERM = ("terms", "coef", "coef_se", "q", "mse_path")


def _field(data, path):
    *parents, last = path
    for key in parents:
        data = data[key]
    return data, last


@st.composite
def edits(draw):
    """A valid model dict with one edit: a field replaced by any JSON value or a number scaled
    by up to 10^308, a term renamed (lags and powers up to 10^15), a term repeated, a parameter
    set to any integer."""
    data = copy.deepcopy(draw(st.sampled_from(MODEL_DICTS)))
    fitted = data["fitted"]
    kind = draw(st.sampled_from(["any", "scale", "term", "repeat", "param"]))
    if kind == "any":
        parent, key = _field(data, draw(st.sampled_from(sorted(_paths(data), key=str))))
        parent[key] = draw(JSON)
    elif kind == "scale":
        numbers = [p for p in sorted(_paths(data), key=str)
                   if isinstance(_field(data, p)[0][_field(data, p)[1]], float)]
        parent, key = _field(data, draw(st.sampled_from(numbers)))
        parent[key] = parent[key] * draw(st.sampled_from(SCALES)) * 10.0 ** draw(st.integers(-8, 8))
    elif kind == "term":
        fitted["terms"][draw(st.integers(0, len(fitted["terms"]) - 1))] = draw(TERMS)
    elif kind == "repeat":
        i = draw(st.integers(0, len(fitted["terms"]) - 1))
        for key in PER_TERM:
            fitted[key].append(fitted[key][i])
    else:
        key = draw(st.sampled_from(["max_lag", "degree", "max_candidates", "product_lags",
                                    "max_terms"]))
        data["params"][key] = draw(st.integers(-2, 10**15) | st.integers(0, 6))
    return data


@pytest.fixture(scope="module")
def model_path(tmp_path_factory):
    return tmp_path_factory.mktemp("schema") / "model.json"


@SETTINGS
@given(data=edits())
def test_an_edited_model_file_is_refused_in_one_line_or_read_as_a_fit_writes_it(data,
                                                                                 model_path):
    """Refused: one line naming the file.  Read: distinct terms, and a prediction on the
    record whose residual mean square is a finite number, without a warning."""
    model_path.write_text(json.dumps(data))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        try:
            model = read_model(model_path)
        except InputError as exc:
            assert str(exc).startswith(f"{model_path}: ") and "\n" not in str(exc)
            return
        assert len({Term.parse(name) for name in model.terms_}) == len(model.terms_)
        channels = {"temp": _TEMP, "cos@7.3Hz": _COS, "x": _TEMP}
        try:
            pred = model.predict(_Y, {k: channels[k] for k in model.input_columns()})
        except InputError:
            return
        assert np.isfinite(np.mean((_Y - pred)[model.lag_window_:] ** 2))

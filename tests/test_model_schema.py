"""The model file schema: every model a fit writes passes it; each forged field is named.

The cases edit the dict of a real fitted model, one field at a time, and expect the one line
that names the field.  A fuzz test over the same schema is in ``tests/test_fuzz_schema.py``.
"""

import copy
import json
import math

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel import FOSModel
from fosmodel.core.exceptions import InputError
from fosmodel.models.model_schema import MAX_CANDIDATES, check_model_dict


def _signal(n=3000, seed=0):
    return lfilter([1.0], [1.0, -1.2, 0.5], np.random.default_rng(seed).standard_normal(n))


def _models():
    """Models of every kind a fit writes: products, inputs, levels, columns, no centring."""
    y = _signal()
    temp = 20 + np.cumsum(np.random.default_rng(1).standard_normal(3000)) * 0.01
    t = np.arange(3000) / 100.0
    return {
        "lags": FOSModel(max_lag=4).fit(y),
        "products": FOSModel(max_lag=3, degree=3, exog_lags={"temp": 2}).fit(
            y + 0.3 * np.r_[0, y[:-1]] ** 2, {"temp": temp}),
        "product-lags": FOSModel(max_lag=4, degree=2, product_lags=2, exog_lags={"temp": 1}).fit(
            y, {"temp": temp}),
        "levels-columns": FOSModel(max_lag=2, levels=[0.5, 5.0], rate=100.0,
                                   columns=["cos@7.3Hz", "step@12s"]).fit(
            y + np.cos(2 * np.pi * 7.3 * t) + (t >= 12),
            {"cos@7.3Hz": np.cos(2 * np.pi * 7.3 * t), "step@12s": (t >= 12) * 1.0}),
        "columns-products": FOSModel(max_lag=2, degree=2, rate=100.0, columns=["step@12s"]).fit(
            y + (t >= 12), {"step@12s": (t >= 12) * 1.0}),
        "uncentred": FOSModel(max_lag=2, center=False).fit(y + 100.0),
        "max-terms": FOSModel(max_lag=5, max_terms=1, stop="max_terms").fit(y),
    }


MODELS = {name: json.loads(json.dumps(model.to_dict({"column": "gx"})))
          for name, model in _models().items()}


@pytest.mark.parametrize("name", sorted(MODELS))
def test_every_kind_of_fitted_model_passes(name):
    check_model_dict(MODELS[name])
    back = FOSModel.from_dict(MODELS[name])
    assert back.terms_ == MODELS[name]["fitted"]["terms"]


def test_a_format_1_file_without_standard_errors_passes():
    data = copy.deepcopy(MODELS["lags"])
    data["format_version"] = 1
    for key in ("coef_se", "intercept_se"):
        del data["fitted"][key]
    check_model_dict(data)
    assert math.isnan(FOSModel.from_dict(data).intercept_se_)


def _with(path, value):
    """An edit setting ``path`` (keys separated by '/') of a model dict to ``value``."""
    def edit(data):
        *parents, last = path.split("/")
        for key in parents:
            data = data[int(key) if isinstance(data, list) else key]
        if value is _DELETE:
            del data[last]
        else:
            data[int(last) if isinstance(data, list) else last] = value
    return edit


_DELETE = object()

# (model, edit, the message after "corrupted model file: ")
CASES = {
    "version-text": ("lags", _with("format_version", "2"),
                     "format_version: '2' is not a format version"),
    "version-zero": ("lags", _with("format_version", 0), "format_version: 0 is not"),
    "params-unknown": ("lags", _with("params/alpha", 1),
                       "params.'alpha': not a parameter of FOSModel"),
    "params-lag-negative": ("lags", _with("params/max_lag", -1),
                            "params.max_lag: -1 is not an integer from 0 to 10,000,000"),
    "params-lag-float": ("lags", _with("params/max_lag", 4.0), "params.max_lag: 4.0 is not"),
    "params-degree-bool": ("lags", _with("params/degree", True), "params.degree: True is not"),
    "params-exog-lag": ("products", _with("params/exog_lags/temp", -2),
                        "params.exog_lags: {'temp': -2} gives channel 'temp' the lag -2"),
    "params-levels": ("levels-columns", _with("params/levels", [0.5, -1]),
                      "params.levels: [0.5, -1] is not a list of time constants"),
    "params-columns": ("levels-columns", _with("params/columns", ["cos@7.3Hz", 3]),
                       "params.columns: ['cos@7.3Hz', 3] is not a list of column names"),
    "params-rate": ("levels-columns", _with("params/rate", 0), "params.rate: 0 is not a number"),
    "params-stop": ("lags", _with("params/stop", "never"), "params.stop: 'never' is not a stop"),
    "params-tol": ("lags", _with("params/tol", float("nan")), "params.tol: nan is not a number"),
    "params-center": ("lags", _with("params/center", "yes"), "params.center: 'yes' is not true"),
    "params-too-many": ("lags", _with("params/max_candidates", 10**8),
                        "params.max_candidates: 100000000 is not an integer"),
    "candidates-over-max": ("products", _with("params/max_candidates", 50),
                            "params: max_lag 3, degree 3 and the channels make more than 50 "
                            "candidates"),
    "n-candidates": ("lags", _with("fitted/n_candidates", 100),
                     "fitted.n_candidates: 100, but the params make 5 candidates"),
    "terms-missing": ("lags", _with("fitted/terms", _DELETE), "fitted.terms: missing"),
    "term-number": ("lags", _with("fitted/terms/0", 5), "fitted.terms[0]: 5 is not a term name"),
    "term-garbage": ("lags", _with("fitted/terms/0", "y[n-1]+y"), "fitted.terms[0]: cannot parse"),
    "term-constant": ("lags", _with("fitted/terms/0", "1"),
                      "fitted.terms[0]: the constant is the intercept, not a term"),
    "term-lag-zero": ("lags", _with("fitted/terms/0", "y[n-0]"),
                      "fitted.terms[0]: 'y[n-0]' lags the output by 0 samples, outside 1 to "
                      "params.max_lag 4"),
    "term-exog-unknown": ("lags", _with("fitted/terms/0", "x[n-0]"),
                          "fitted.terms[0]: 'x[n-0]' reads channel 'x', which params.exog_lags "
                          "does not list"),
    "term-exog-lag": ("products", _with("fitted/terms/0", "temp[n-3]"),
                      "fitted.terms[0]: 'temp[n-3]' lags 'temp' by 3 samples, beyond "
                      "params.exog_lags.temp 2"),
    "term-level": ("levels-columns", _with("fitted/terms/0", "level@2s"),
                   "fitted.terms[0]: 'level@2s' reads level@2s, which params.levels does not "
                   "offer"),
    "term-column": ("levels-columns", _with("fitted/terms/0", "sin@1Hz"),
                    "fitted.terms[0]: 'sin@1Hz' reads column 'sin@1Hz', which params.columns "
                    "does not list"),
    "term-column-product": ("levels-columns", _with("fitted/terms/0", "y[n-1]*cos@7.3Hz"),
                            "fitted.terms[0]: term 'y[n-1]*cos@7.3Hz' is a product of more than "
                            "1 factor(s) (params.degree 1)"),
    "term-column-in-product": ("columns-products", _with("fitted/terms/0", "y[n-1]*step@12s"),
                              "fitted.terms[0]: 'y[n-1]*step@12s' multiplies column 'step@12s', "
                              "which enters only alone"),
    "term-degree": ("products", _with("fitted/terms/0", "y[n-1]^2*y[n-2]^2"),
                    "fitted.terms[0]: term 'y[n-1]^2*y[n-2]^2' is a product of more than 3 "
                    "factor(s) (params.degree 3)"),
    "term-product-lags": ("product-lags", _with("fitted/terms/0", "y[n-3]*y[n-1]"),
                          "fitted.terms[0]: 'y[n-3]*y[n-1]' multiplies y[n-3], but "
                          "params.product_lags 2 keeps products to the output lags 1 to 2"),
    "term-product-input": ("product-lags", _with("fitted/terms/0", "y[n-1]*temp[n-0]"),
                           "fitted.terms[0]: 'y[n-1]*temp[n-0]' multiplies temp[n-0], but "
                           "params.product_lags 2"),
    "term-repeated-spelling": ("products", lambda d: d["fitted"]["terms"].__setitem__(
        1, "*".join(reversed(d["fitted"]["terms"][0].split("*")))), "fitted.terms[1]: "),
    "max-terms": ("max-terms", _with("params/max_terms", 0), "params.max_terms: 0 is not"),
    "coef-count": ("lags", lambda d: d["fitted"]["coef"].append(0.1),
                   "fitted.coef: 3 values for 2 terms"),
    "coef-text": ("lags", _with("fitted/coef/1", "0.5"), "fitted.coef[1]: '0.5' is not a number"),
    "coef-nan": ("lags", _with("fitted/coef/0", float("nan")),
                 "fitted.coef[0]: nan is not a finite number"),
    "coef-gain": ("lags", _with("fitted/coef/0", 2e6),
                  "fitted.coef[0]: the weight 2e+06 of 'y[n-1]' is beyond any fit's: "
                  "abs(w) s^(d-1) = 2e+06"),
    "intercept-inf": ("lags", _with("fitted/intercept", float("inf")),
                      "fitted.intercept: inf is not a finite number"),
    "se-count": ("lags", lambda d: d["fitted"]["coef_se"].pop(), "fitted.coef_se: 1 values"),
    "se-missing": ("lags", _with("fitted/coef_se", _DELETE), "fitted.coef_se: missing"),
    "mse-null-zero": ("lags", _with("fitted/mse_null", 0.0), "fitted.mse_null: 0 is not positive"),
    "n-samples": ("lags", _with("fitted/n_samples", 3), "fitted.n_samples: 3 is not an integer "
                                                        "from 4"),
    "offsets-extra": ("lags", _with("fitted/offsets/temp", 20.0),
                      "fitted.offsets: has 'temp', which the model does not read"),
    "offsets-missing": ("products", _with("fitted/offsets", {"y": 0.0}),
                        "fitted.offsets: lacks 'temp'"),
    "offsets-huge": ("lags", _with("fitted/offsets/y", 1e31),
                     "fitted.offsets.y: 1e+31 is over 1e+30 in magnitude"),
    "stop-reason": ("lags", _with("fitted/stop_reason", ["x"]), "fitted.stop_reason: ['x'] is not"),
    "meta-column": ("lags", _with("meta/column", 5), "meta.column: 5 is not a column name"),
    "meta-list": ("lags", _with("meta", [1]), "meta: not an object"),
    "fitted-list": ("lags", _with("fitted", [1]), "fitted: not an object"),
}


@pytest.mark.parametrize("case", sorted(CASES))
def test_a_forged_field_is_named(case):
    name, edit, message = CASES[case]
    data = copy.deepcopy(MODELS[name])
    edit(data)
    with pytest.raises(InputError) as caught:
        check_model_dict(data)
    assert str(caught.value).startswith(f"corrupted model file: {message}"), str(caught.value)


def test_the_candidate_count_is_that_of_the_spec_without_building_it():
    """Counted from the sizes: the same number as count_candidates, in no time for any size."""
    from fosmodel.core.candidates import count_candidates
    for name, data in MODELS.items():
        spec = FOSModel(**data["params"]).candidate_spec()
        assert data["fitted"]["n_candidates"] == count_candidates(spec), name
    data = copy.deepcopy(MODELS["lags"])
    data["params"].update(max_lag=MAX_CANDIDATES, degree=32, max_candidates=MAX_CANDIDATES)
    with pytest.raises(InputError, match="make more than 10,000,000 candidates"):
        check_model_dict(data)


def test_a_newer_format_is_left_to_say_its_version():
    data = {**MODELS["lags"], "format_version": 99, "params": "anything"}
    check_model_dict(data)
    with pytest.raises(InputError, match="format version 99 is newer"):
        FOSModel.from_dict(data)


def test_a_refused_model_predicts_nothing_different_from_a_valid_one(tmp_path):
    """The forged files predict didn't refuse predicted something else than the valid model."""
    from fosmodel import cli
    y = _signal(2000, seed=4)
    pd.DataFrame({"time": np.arange(2000) / 100, "gx": y}).to_csv(tmp_path / "r.csv", index=False)
    valid = MODELS["lags"]
    (tmp_path / "valid.json").write_text(json.dumps(valid))
    twice = copy.deepcopy(valid)
    for key in ("terms", "coef", "coef_se", "q", "mse_path"):
        twice["fitted"][key] = twice["fitted"][key] * 2
    (tmp_path / "twice.json").write_text(json.dumps(twice))
    argv = ["predict", str(tmp_path / "r.csv"), "--out", str(tmp_path / "p.csv"), "--model"]
    assert cli.main([*argv, str(tmp_path / "valid.json")]) == 0
    assert cli.main([*argv, str(tmp_path / "twice.json")]) == 2

import math

import numpy as np
import pytest

from fosmodel.core.candidates import (
    CandidateSpec,
    Term,
    check_terms_fit_spec,
    count_candidates,
    evaluate_sum,
    evaluate_terms,
    generate_terms,
)
from fosmodel.core.exceptions import InputError


@pytest.mark.parametrize(
    "name",
    ["1", "y[n-1]", "temp[n-0]", "y[n-1]*y[n-3]", "y[n-2]^2", "y[n-1]*temp[n-0]",
     "y[n-2]^2*temp[n-1]", "y[n-1]^3", "sin@0.5Hz", "exp(-t/300)"],
)
def test_names_parse_back(name):
    assert Term.parse(name).name == name


def test_factors_are_canonical():
    assert Term((("temp", 0), ("y", 3), ("y", 1))).name == "y[n-1]*y[n-3]*temp[n-0]"
    assert Term.parse("temp[n-0]*y[n-1]") == Term.parse("y[n-1]*temp[n-0]")
    assert Term.parse("y[n-2]*y[n-2]").name == "y[n-2]^2"


@pytest.mark.parametrize("bad", ["", "y[n-]", "y[n+1]", "y[n-1]**2", "a b", "y[n-1]^x"])
def test_bad_names_are_rejected(bad):
    with pytest.raises(InputError):
        Term.parse(bad)


def test_eq15_candidate_set_linear_and_exog_lag_zero():
    spec = CandidateSpec(max_lag=3, degree=1, exog_lags={"temp": 2})
    names = [t.name for t in generate_terms(spec)]
    assert names == ["1", "y[n-1]", "y[n-2]", "y[n-3]", "temp[n-0]", "temp[n-1]", "temp[n-2]"]
    assert spec.lag_window == 3


def test_cross_products_up_to_degree():
    spec = CandidateSpec(max_lag=2, degree=2)
    names = [t.name for t in generate_terms(spec)]
    assert names == ["1", "y[n-1]", "y[n-2]", "y[n-1]^2", "y[n-1]*y[n-2]", "y[n-2]^2"]


@pytest.mark.parametrize(
    "spec",
    [CandidateSpec(10, 1), CandidateSpec(10, 2), CandidateSpec(5, 3, {"a": 2, "b": 0}),
     CandidateSpec(50, 2), CandidateSpec(4, 2, {"temp": 1}, columns=["sin@1Hz", "trend"])],
)
def test_count_matches_generated_set_without_duplicates(spec):
    terms = generate_terms(spec)
    assert count_candidates(spec) == len(terms) == len({t.name for t in terms})


def test_count_closed_form_paper_sizes():
    # L = 50, CP = 2: 1 + 50 + 50*51/2 = 1326; L = 20, CP = 3: C(23, 3) = 1771
    assert count_candidates(CandidateSpec(50, 2)) == 1326
    assert count_candidates(CandidateSpec(20, 3)) == math.comb(23, 3)


def test_user_columns_are_linear_candidates():
    spec = CandidateSpec(1, 2, columns=["sin@1Hz"])
    names = [t.name for t in generate_terms(spec)]
    assert names[-1] == "sin@1Hz" and "y[n-1]*sin@1Hz" not in names


@pytest.mark.parametrize(
    "kwargs",
    [{"max_lag": -1}, {"degree": 0}, {"max_lag": 2.5}, {"exog_lags": {"y": 2}},
     {"exog_lags": {"temp c": 1}}, {"exog_lags": {"temp": -1}}, {"columns": ["a*b"]},
     {"columns": ["x", "x"]}, {"exog_lags": {"t": 1}, "columns": ["t"]}],
)
def test_bad_specs_are_rejected(kwargs):
    with pytest.raises(InputError):
        CandidateSpec(**kwargs)


def test_evaluate_terms_point_by_point():
    y = np.arange(10.0)
    x = np.arange(10.0) * 10
    terms = [Term.parse(n) for n in ["1", "y[n-1]", "y[n-2]^2", "y[n-1]*x[n-0]"]]
    out = evaluate_terms(terms, {"y": y, "x": x}, 2)
    n = np.arange(2, 10)
    np.testing.assert_array_equal(out[:, 0], 1.0)
    np.testing.assert_array_equal(out[:, 1], y[n - 1])
    np.testing.assert_array_equal(out[:, 2], y[n - 2] ** 2)
    np.testing.assert_array_equal(out[:, 3], y[n - 1] * x[n])


def test_evaluate_sum_equals_the_matrix_times_the_weights():
    rng = np.random.default_rng(4)
    signals = {"y": rng.standard_normal(500), "x": rng.standard_normal(500), "c": np.ones(500)}
    names = ["1", "y[n-1]", "y[n-2]^2", "y[n-1]*x[n-0]", "x[n-3]*y[n-3]^2", "c"]
    terms = [Term.parse(n) for n in names]
    w = rng.standard_normal(len(terms))
    want = evaluate_terms(terms, signals, 3) @ w
    np.testing.assert_allclose(evaluate_sum(terms, w, signals, 3), want, rtol=1e-13, atol=1e-13)
    assert evaluate_sum([], [], signals, 3).tolist() == [0.0] * 497
    with pytest.raises(InputError, match="needs 3 past samples, only 2"):
        evaluate_sum(terms, w, signals, 2)


def test_terms_outside_spec_are_rejected():
    spec = CandidateSpec(2, 1, {"temp": 1})
    check_terms_fit_spec([Term.parse("y[n-2]"), Term.parse("temp[n-1]")], spec)
    for bad in ["y[n-3]", "temp[n-2]", "other[n-0]", "col"]:
        with pytest.raises(InputError):
            check_terms_fit_spec([Term.parse(bad)], spec)

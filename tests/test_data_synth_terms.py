"""Term names in fosmodel's grammar and exact models of sums (data_synth.terms)."""

import numpy as np
import pytest

from data_synth.terms import Representation, add_term, evaluate, exact_model, shift, terms_json
from fosmodel.core.candidates import Term
from fosmodel.core.exceptions import InputError


@pytest.mark.parametrize(
    "factors, name",
    [
        ((), "1"),
        ((("y", 1),), "y[n-1]"),
        ((("y", 3), ("y", 1)), "y[n-1]*y[n-3]"),
        ((("y", 2), ("y", 2)), "y[n-2]^2"),
        ((("temp_c", 0), ("y", 1)), "y[n-1]*temp_c[n-0]"),
        ((("temp_c", 0), ("temp_c", 0)), "temp_c[n-0]^2"),
        ((("temp_c", 0), ("accel_x", 3)), "accel_x[n-3]*temp_c[n-0]"),
        ((("b", 2), ("a", 5), ("b", 1), ("y", 4)), "y[n-4]*a[n-5]*b[n-1]*b[n-2]"),
    ],
)
def test_term_names_follow_grammar(factors, name):
    assert Term(factors).name == name
    assert Term.parse(name) == Term(factors)


def test_parse_rejects_bad_terms():
    for bad in ("y[n+1]", "y[1]", "2*y[n-1]", "y[n-1]^"):
        with pytest.raises(InputError):
            Term.parse(bad)


def test_add_shift_and_json():
    terms = {}
    add_term(terms, [("y", 2), ("y", 1)], 0.5)
    add_term(terms, [("y", 1), ("y", 2)], 0.25)
    add_term(terms, [], 0.0)
    assert terms == {(("y", 1), ("y", 2)): 0.75, (): 0.0}
    assert terms_json(terms) == [{"term": "y[n-1]*y[n-2]", "coef": 0.75}]
    assert shift((("temp_c", 0), ("temp_c", 0)), 2) == (("temp_c", 2), ("temp_c", 2))


def test_exact_model_of_exogenous_and_white_parts():
    white = Representation({}, 0.3)
    white2 = Representation({}, 0.4)
    bias = Representation({(): 2.0})
    temp = Representation({(("temp_c", 0),): 0.1})
    m = exact_model([white, white2, bias, temp])
    assert m.terms == {(): 2.0, (("temp_c", 0),): 0.1}
    assert m.innovation_std == pytest.approx(0.5)


def test_exact_model_filters_exogenous_terms_through_ar():
    ar = Representation({(("y", 1),): 0.5, (("y", 2),): -0.2}, 1.0)
    m = exact_model([ar, Representation({(): 1.0, (("u", 3),): 2.0})])
    assert m.innovation_std == 1.0
    assert m.terms == pytest.approx(
        {
            (("y", 1),): 0.5,
            (("y", 2),): -0.2,
            (): 1.0 * (1 - 0.5 + 0.2),
            (("u", 3),): 2.0,
            (("u", 4),): -1.0,
            (("u", 5),): 0.4,
        }
    )


def test_exact_model_none_cases():
    ar = Representation({(("y", 1),): 0.5}, 1.0)
    nonlinear = Representation({(("y", 1),): 0.5, (("y", 1), ("y", 2)): 0.1}, 1.0)
    assert exact_model([ar, Representation({}, 0.2)]) is None  # AR + white = ARMA
    assert exact_model([ar, ar]) is None
    assert exact_model([nonlinear, Representation({(): 1.0})]) is None
    assert exact_model([ar, None]) is None
    assert exact_model([nonlinear]).terms == nonlinear.terms


def test_evaluate_computes_lagged_products():
    y = np.arange(1.0, 7.0)
    u = np.arange(10.0, 16.0)
    pred = evaluate(
        [
            {"term": "1", "coef": 1.0},
            {"term": "y[n-1]*u[n-2]", "coef": 2.0},
            {"term": "u[n-0]^2", "coef": 0.5},
        ],
        {"gyro": y, "u": u},
        "gyro",
    )
    assert np.all(np.isnan(pred[:2]))
    n = np.arange(2, 6)
    np.testing.assert_allclose(pred[2:], 1 + 2 * y[n - 1] * u[n - 2] + 0.5 * u[n] ** 2)


def test_truth_terms_are_fosmodel_term_names():
    from data_synth.scenarios import SCENARIOS, make_sessions
    from fosmodel.core.candidates import Term

    names = set()
    for truth in (rec.truth for scenario in SCENARIOS
                  for rec in make_sessions(scenario, duration=5.0, seed=1)):
        for entry in truth["sources"] + ([truth["model"]] if truth["model"] else []):
            names.update(t["term"] for t in entry["terms"] or [])
    assert {"y[n-1]*y[n-2]", "temp_c[n-0]^2", "accel_x[n-3]", "rate_ref[n-0]", "1"} <= names
    for name in names:
        assert Term.parse(name).name == name

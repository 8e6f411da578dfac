import json
import math

import numpy as np
import pytest
from scipy.signal import lfilter
from statsmodels.tsa.arima_process import arma_acf, arma_acovf
from statsmodels.tsa.stattools import acf

from fosmodel import FOSModel, InputError
from fosmodel.filter.statespace import (
    NonlinearStateSpace,
    StateSpace,
    position_velocity_error_model,
    to_nonlinear_state_space,
    to_state_space,
)
from fosmodel.models.baselines import ARModel, GaussMarkovModel

RNG = np.random.default_rng(11)
AR2 = lfilter([1.0], [1.0, -1.5, 0.7], RNG.standard_normal(20_000)) + 3.0


def _sparse_record(n=20_000, seed=2):
    """AR with lags 1 and 3 only, offset 5."""
    e = np.random.default_rng(seed).standard_normal(n)
    return lfilter([1.0], [1.0, -0.6, 0.0, -0.3], e) + 5.0


def _exog_record(narx):
    """Output lags 1-2, input lags 0 and 2 (input offset 25) and a trend column, offset 3."""
    rng = np.random.default_rng(4)
    n = 20_000
    exog = {"temp": 25.0 + rng.standard_normal(n), "trend": np.linspace(0.0, 1.0, n)}
    truth = {"1": 3.0, "y[n-1]": 0.6, "y[n-2]": -0.2, "temp[n-0]": 0.5, "temp[n-2]": -0.3,
             "trend": 0.8}
    y, _ = narx(truth, n, exog, 0.1, seed=5)
    return y, exog


def _nonlinear_record(narx):
    rng = np.random.default_rng(6)
    exog = {"u": rng.uniform(-1.0, 1.0, 20_000)}
    truth = {"y[n-1]": 0.5, "y[n-2]": -0.2, "y[n-1]*y[n-2]": 0.1,
             "y[n-1]*u[n-1]": 0.3, "u[n-0]": 0.7, "u[n-1]^2": -0.4}
    y, _ = narx(truth, 20_000, exog, 0.1, seed=7)
    return y, exog


def _fitted_nonlinear(narx):
    y, exog = _nonlinear_record(narx)
    return FOSModel(max_lag=3, degree=2, exog_lags={"u": 2}, max_terms=8,
                    stop="max_terms").fit(y, exog), y, exog


def _state_space_predictions(ss, y, start, inputs=None, transition=None):
    """One-step predictions of y[n] from the true past through the exported filter."""
    transition = transition or ss.step
    out = np.full(len(y), np.nan)
    for n in range(start, len(y)):
        u = None if inputs is None else inputs[n]
        out[n] = ss.predict_measurement(transition(ss.state_from(y[:n]), u))
    return out


def _theoretical_acf(ss, n_lags):
    """``H Phi^k P H' / H P H'`` from the stationary covariance P."""
    p = ss.stationary_covariance()
    cov = [(ss.H @ np.linalg.matrix_power(ss.Phi, k) @ p @ ss.H.T).item()
           for k in range(n_lags + 1)]
    return np.array(cov) / cov[0], cov[0]


# -- one-step predictions equal the model's ------------------------------------------------


@pytest.mark.parametrize("method", ["burg", "yule_walker", "covariance"])
def test_ar_state_space_predicts_like_the_model(method):
    model = ARModel(3, method).fit(AR2)
    ss = to_state_space(model)
    y = AR2[:400]
    np.testing.assert_allclose(_state_space_predictions(ss, y, 3), model.predict(y),
                               rtol=0, atol=1e-10)
    assert ss.Phi.shape == (3, 3) and ss.n_inputs == 0
    np.testing.assert_array_equal(ss.Phi[0], model.coef_)
    np.testing.assert_array_equal(ss.Phi[1:], np.eye(3)[:2])
    assert ss.Q[0, 0] == model.sigma2_ and ss.mu == model.mean_


def test_gauss_markov_is_the_one_state_special_case():
    model = GaussMarkovModel(rate=20.0).fit(AR2)
    ss = to_state_space(model)
    assert ss.state_names == ("y[n]",)
    assert ss.Phi[0, 0] == pytest.approx(math.exp(-model.beta_ / 20.0), rel=1e-14)
    assert ss.stationary_covariance()[0, 0] == pytest.approx(model.process_var_, rel=1e-12)
    y = AR2[:300]
    np.testing.assert_allclose(_state_space_predictions(ss, y, 1), model.predict(y),
                               rtol=0, atol=1e-10)


def test_sparse_fos_keeps_the_selected_lags_in_a_companion_matrix():
    y = _sparse_record()
    model = FOSModel(max_lag=6).fit(y)
    assert sorted(model.terms_) == ["y[n-1]", "y[n-3]"]
    ss = to_state_space(model)
    assert ss.state_names == ("y[n]", "y[n-1]", "y[n-2]")
    assert ss.Phi[0, 1] == 0.0 and ss.input_names == ("1",)
    assert ss.B[0, 0] == model.intercept_
    np.testing.assert_allclose(_state_space_predictions(ss, y[:500], 6, np.ones((500, 1))),
                               model.predict(y[:500]), rtol=0, atol=1e-10)


def test_fos_with_inputs_and_offsets_predicts_like_the_model(narx):
    y, exog = _exog_record(narx)
    model = FOSModel(max_lag=3, exog_lags={"temp": 3}, columns=["trend"]).fit(y, exog)
    assert {"temp[n-0]", "temp[n-2]", "trend"} <= set(model.terms_)
    ss = to_state_space(model)
    inputs = ss.input_matrix(exog, len(y))
    assert ss.input_names[0] == "1" and "temp[n-2]" in ss.input_names
    assert np.isnan(inputs[1, ss.input_names.index("temp[n-2]")])
    np.testing.assert_allclose(_state_space_predictions(ss, y[:600], 3, inputs),
                               model.predict(y[:600], {k: v[:600] for k, v in exog.items()}),
                               rtol=0, atol=1e-10)


def test_nonlinear_fos_predicts_through_f(narx):
    model, y, exog = _fitted_nonlinear(narx)
    assert any("*" in t or "^" in t for t in model.terms_)
    ss = to_nonlinear_state_space(model)
    inputs = ss.input_matrix(exog, len(y))
    pred = _state_space_predictions(ss, y[:500], 3, inputs, transition=ss.f)
    np.testing.assert_allclose(pred, model.predict(y[:500], {"u": exog["u"][:500]}),
                               rtol=0, atol=1e-10)


def test_linear_models_give_the_same_transition_both_ways():
    model = FOSModel(max_lag=4).fit(_sparse_record())
    lin, nonlin = to_state_space(model), to_nonlinear_state_space(model)
    x = np.array([0.3, -1.2, 0.7])
    np.testing.assert_allclose(nonlin.f(x, [1.0]), lin.step(x, [1.0]), rtol=0, atol=1e-14)
    np.testing.assert_allclose(nonlin.jacobian(x, [1.0]), lin.Phi, rtol=0, atol=1e-14)


# -- free runs, autocorrelation ------------------------------------------------------------


def test_simulation_with_noise_equals_the_model_free_run():
    model = ARModel(4, "burg").fit(AR2)
    ss = to_state_space(model)
    noise = RNG.standard_normal(300)
    np.testing.assert_allclose(
        ss.simulate(300, x0=ss.state_from(AR2[:50]), noise=noise),
        model.simulate(AR2[:50], 300, noise=noise), rtol=0, atol=1e-10)


def test_nonlinear_simulation_equals_the_model_free_run(narx):
    model, y, exog = _fitted_nonlinear(narx)
    ss = to_nonlinear_state_space(model)
    n0, steps = 50, 200
    noise = 0.1 * RNG.standard_normal(steps)
    inputs = ss.input_matrix(exog, len(y))[n0:n0 + steps]
    expected = model.simulate(y[:n0], steps, {"u": exog["u"][:n0 + steps]}, noise)
    np.testing.assert_allclose(ss.simulate(steps, ss.state_from(y[:n0]), inputs, noise),
                               expected, rtol=0, atol=1e-10)


@pytest.mark.parametrize("kind", ["ar", "fos"])
def test_output_autocorrelation_matches_the_model(kind):
    if kind == "ar":
        model = ARModel(2, "burg").fit(AR2)
        ar = model.coef_
    else:
        model = FOSModel(max_lag=6).fit(_sparse_record())
        ar = model.ar_coefficients()
    ss = to_state_space(model)
    n_lags, n = 20, 100_000
    rho, var = _theoretical_acf(ss, n_lags)
    np.testing.assert_allclose(rho, arma_acf(np.r_[1.0, -ar], [1.0], n_lags + 1), atol=1e-10)
    assert var == pytest.approx(arma_acovf(np.r_[1.0, -ar], [1.0], 1, ss.Q[0, 0])[0], rel=1e-10)

    noise = math.sqrt(ss.Q[0, 0]) * np.random.default_rng(3).standard_normal(n)
    u = None if kind == "ar" else np.zeros((n, 1))  # the mean-free drive, without a0
    out = ss.simulate(n, inputs=u, noise=noise)
    # Bartlett's bound on the standard error of a sample autocorrelation, 4 of them
    tol = 4 * math.sqrt((1 + 2 * np.sum(rho[1:] ** 2)) / n)
    np.testing.assert_allclose(acf(out, nlags=n_lags, fft=True), rho, rtol=0, atol=tol)
    assert np.var(out) == pytest.approx(var, rel=0.1)


# -- Jacobian ------------------------------------------------------------------------------


def test_jacobian_matches_finite_differences(narx):
    model, _, _ = _fitted_nonlinear(narx)
    ss = to_nonlinear_state_space(model)
    rng = np.random.default_rng(8)
    h = 1e-6
    for _ in range(5):
        x, u = rng.normal(size=ss.n_states), np.r_[1.0, rng.uniform(-1, 1, ss.n_inputs - 1)]
        numeric = np.column_stack([(ss.f(x + h * e, u) - ss.f(x - h * e, u)) / (2 * h)
                                   for e in np.eye(ss.n_states)])
        np.testing.assert_allclose(ss.jacobian(x, u), numeric, rtol=0, atol=1e-8)


def test_jacobian_of_a_power_uses_the_product_rule():
    ss = NonlinearStateSpace(coef=np.array([2.0]), factors=((0, 0, 1),), term_names=("t",),
                             input_offsets=np.zeros(0), G=np.eye(2)[:, :1], H=np.eye(1, 2),
                             Q=np.eye(1), mu=0.0, state_names=("a", "b"), input_names=())
    x = np.array([3.0, 5.0])  # f0 = 2 a^2 b
    np.testing.assert_allclose(ss.jacobian(x), [[2 * 2 * 3 * 5, 2 * 9], [1.0, 0.0]])


# -- augmentation, serialisation, refusals -------------------------------------------------


def test_position_velocity_augmentation_is_park_2004_eq_5_7():
    model = ARModel(4, "burg").fit(AR2)
    dt = 0.05
    system = position_velocity_error_model(to_state_space(model), dt)
    a = model.coef_
    expected = np.array([
        [1, dt, 0, 0, 0, 0],
        [0, 1, dt, 0, 0, 0],
        [0, 0, a[0], a[1], a[2], a[3]],
        [0, 0, 1, 0, 0, 0],
        [0, 0, 0, 1, 0, 0],
        [0, 0, 0, 0, 1, 0],
    ])
    np.testing.assert_array_equal(system.Phi, expected)
    np.testing.assert_array_equal(system.G[:, 0], [0, 0, 1, 0, 0, 0])
    np.testing.assert_array_equal(system.H, [[1, 0, 0, 0, 0, 0]])
    assert system.state_names[:3] == ("dp", "dv", "da y[n]") and system.B.shape == (6, 0)


def test_a_vector_driving_noise_enters_through_every_column_of_g():
    """One noise per column of G, and an output that sums states (the Allan models' form)."""
    ss = StateSpace(Phi=np.diag([0.5, 1.0]), B=np.zeros((2, 0)), G=np.array([[1.0, 0.0],
                    [0.5, 2.0]]), H=np.ones((1, 2)), Q=np.diag([0.1, 0.2]), mu=3.0,
                    state_names=("a", "b"), input_names=())
    np.testing.assert_allclose(ss.step([1.0, 1.0], w=[1.0, 2.0]), [1.5, 5.5])
    w = np.random.default_rng(8).standard_normal((20, 2))
    x, expected = np.zeros(2), []
    for wk in w:
        x = ss.Phi @ x + ss.G @ wk
        expected.append(x.sum() + 3.0)
    np.testing.assert_allclose(ss.simulate(20, noise=w), expected, rtol=1e-14)
    with pytest.raises(InputError, match="driving noise has 2 entries; got 1"):
        ss.step([0.0, 0.0], w=1.0)
    with pytest.raises(InputError, match=r"noise must be a finite \(n_steps, 2\) array"):
        ss.simulate(3, noise=np.zeros(3))
    system = position_velocity_error_model(ss, 0.1)
    np.testing.assert_array_equal(system.G, np.vstack([np.zeros((2, 2)), ss.G]))
    np.testing.assert_array_equal(system.Phi[1, 2:], [0.1, 0.1])
    np.testing.assert_array_equal(system.Q, ss.Q)


def test_to_dict_is_json_and_complete(narx):
    lin = to_state_space(FOSModel(max_lag=3).fit(AR2)).to_dict()
    non = to_nonlinear_state_space(_fitted_nonlinear(narx)[0]).to_dict()
    for d in (lin, non):
        assert json.loads(json.dumps(d)) == d
    assert lin["kind"] == "linear" and len(lin["Phi"]) == len(lin["state_names"])
    assert non["kind"] == "nonlinear" and non["terms"][0]["name"] == "1"


def test_refusals_name_the_problem(narx):
    with pytest.raises(InputError, match="ARModel is not fitted"):
        to_state_space(ARModel(2))
    with pytest.raises(InputError, match="FOSModel is not fitted"):
        to_nonlinear_state_space(FOSModel())
    with pytest.raises(InputError, match="cannot export a list"):
        to_state_space([0.5])
    model = _fitted_nonlinear(narx)[0]
    with pytest.raises(InputError, match=r"nonlinear term\(s\).*to_nonlinear_state_space"):
        to_state_space(model)
    ss = to_state_space(FOSModel(max_lag=2).fit(AR2))
    with pytest.raises(InputError, match="u must hold the 1 input"):
        ss.step(np.zeros(2))
    with pytest.raises(InputError, match="the state needs 2"):
        ss.state_from([1.0])
    with pytest.raises(InputError, match="state has 2 entries"):
        ss.predict_measurement(np.zeros(3))


def test_unstable_model_has_no_stationary_covariance():
    ss = StateSpace(Phi=np.array([[1.01]]), B=np.zeros((1, 0)), G=np.ones((1, 1)),
                    H=np.ones((1, 1)), Q=np.ones((1, 1)), mu=0.0, state_names=("y[n]",),
                    input_names=())
    with pytest.raises(InputError, match="unstable"):
        ss.stationary_covariance()

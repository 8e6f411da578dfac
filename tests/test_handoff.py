"""The loop's final model handed to a filter: refitted on all the data, judged against the
Allan model in the aided position filter, recommended by a stated rule, written as JSON."""

import json

import numpy as np
import pytest
from scipy.signal import lfilter

from data_synth import make_scenario
from fosmodel.filter import read_filter_file
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.handoff import FilterScore, _recommend, _why, hand_off, refit_on_all

RATE, N = 10.0, 30_000


def _driven_accel(seed=0):
    """An accelerometer (m/s^2) whose bias follows a temperature swinging over 700 s."""
    rng = np.random.default_rng(seed)
    t = np.arange(N) / RATE
    temp = 25 + 5 * np.sin(2 * np.pi * t / 700) + 0.01 * rng.standard_normal(N)
    y = (0.01 + 0.003 * (temp - 25)
         + lfilter([1.0], [1.0, -0.5], rng.standard_normal(N)) * 2e-3)
    return y, {"temp_c": temp}


@pytest.fixture(scope="module")
def driven():
    y, channels = _driven_accel()
    result = close_loop(y, channels, LoopConfig(rate=RATE, sensor="accel", units="m/s^2"))
    return y, channels, result


def test_the_final_model_is_refitted_on_all_the_data_with_the_loop_s_structure(driven):
    y, _, result = driven
    final = refit_on_all(result, y)
    loop = result.final_model.model
    assert final.terms_ == loop.terms_ and final.compensation == loop.compensation
    expected = loop.refit_weights(y, result.final_model.inputs)
    np.testing.assert_array_equal(final.coef_, expected.coef_)
    assert not np.allclose(final.coef_, loop.coef_, rtol=1e-6, atol=0)  # fitted anew


def test_a_driven_record_recommends_the_loop_model_and_writes_both_files(driven, tmp_path):
    y, channels, result = driven
    assert result.final_model.model.compensation  # the driver is a compensation: D u
    handoff = hand_off(result, y, channels, sensor="accel", units="m/s^2", column="ax")
    loop, allan = handoff.scores["loop final model"], handoff.scores["Allan model"]
    # the driver the loop found cuts the position error ten-fold, and its filter says so
    assert loop.rms_m < 0.2 * allan.rms_m
    assert 0.7 <= loop.ratio <= 1.5
    assert handoff.recommended == "loop final model"
    assert handoff.why.startswith("The loop final model has the lowest RMS position error")
    paths = handoff.write(tmp_path / "filter", {"column": "ax"})
    assert [p.name for p in paths] == ["loop_model.json", "allan_model.json"]
    back = read_filter_file(paths[0])
    ss = handoff.final_system()
    np.testing.assert_array_equal(back.system.D, ss.D)
    assert back.system.D[0, back.system.input_names.index("pow(temp_c,1,25.14)")] \
        == pytest.approx(0.003, rel=0.01)
    data = json.loads(paths[0].read_text())
    assert data["fitted_on"] == f"all {N} samples" and data["kind"] == "linear"
    inputs = {i["name"]: i for i in data["inputs"]}
    assert inputs["pow(temp_c,1,25.14)"]["unit"] == "([temp_c])^1"
    assert json.loads(paths[1].read_text())["state_names"][-1] == "random-walk bias"
    entry = handoff.to_dict()
    assert entry["recommended"] == "loop final model" and entry["cycle_s"] == 60.0
    assert "weights were refitted on all the data given (30000 samples)" in handoff.text()


def test_the_rule_is_the_lowest_rms_among_consistent_filters():
    scores = {"a": FilterScore(1.0, 0.5), "b": FilterScore(2.0, 1.6), "c": FilterScore(3.0, 3.0)}
    assert _recommend(scores) == "b"  # a is overconfident (0.5)
    # none consistent: the one that comes nearest, and the reason says so
    overconfident = {"a": FilterScore(1.0, 0.5), "b": FilterScore(2.0, 1.2)}
    assert _recommend(overconfident) == "b"
    assert _why(overconfident, "b") == ("No model's filter claims 0.7 of its actual error; "
                                        "the b comes nearest (sigma / RMS 0.60).")


def test_without_units_nothing_is_judged_and_the_report_says_why(driven):
    y, channels, result = driven
    handoff = hand_off(result, y, channels, sensor=None, units=None)
    assert handoff.scores == {} and handoff.recommended is None and handoff.allan is None
    assert handoff.why == ("Not judged: the column's sensor and units are not known, so the "
                           "filter's position error cannot be put in metres.")


def test_a_nonlinear_final_model_is_written_for_an_ekf_and_not_judged(tmp_path):
    import dataclasses

    from fosmodel import FOSModel
    from fosmodel.models.bound import BoundModel

    rec = make_scenario("undeclared_nonlinear", seed=0)
    y = rec.columns[rec.target]
    channels = {k: v for k, v in rec.columns.items() if k != rec.target}
    units = rec.truth["units"]
    result = close_loop(y, channels, LoopConfig(rate=rec.rate, sensor="gyro", units=units))
    # the loop's judge refuses this record's cross-products on its outage biases: a final
    # model that holds them is put in its place, as a loop that kept them would hand it on
    half = len(y) // 2
    model = FOSModel(max_lag=4, degree=2, product_lags=4, rate=rec.rate).fit(y[:half])
    assert any("*" in t for t in model.terms_), model.terms_  # a cross-product was chosen
    result = dataclasses.replace(result, final_model=BoundModel(model, {}))
    handoff = hand_off(result, y, channels, sensor="gyro", units=units)
    assert not handoff.linear and handoff.scores == {}
    assert handoff.recommended == "Allan model"
    assert "nonlinear terms: its filter JSON is for an extended Kalman filter" in handoff.why
    path = handoff.write(tmp_path, {})[0]
    back = read_filter_file(path)
    assert json.loads(path.read_text())["kind"] == "nonlinear"
    assert np.all(np.linalg.eigvalsh(back.P0) > 0)


def test_close_loop_writes_the_filter_files_and_the_model_refitted_on_all(tmp_path, capsys):
    import pandas as pd

    from fosmodel import FOSModel, cli

    y, channels = _driven_accel()
    rec = tmp_path / "rec.csv"
    pd.DataFrame({"time": np.arange(N) / RATE, "ax_mps2": y, **channels}).to_csv(rec,
                                                                                index=False)
    out, js, model = tmp_path / "loop", tmp_path / "loop.json", tmp_path / "final.json"
    code = cli.main([str(a) for a in ["close-loop", rec, "--column", "ax_mps2", "--units",
                                      "m/s^2", "--out", out, "--json", js, "--model", model]])
    _, err = capsys.readouterr()
    assert code == 0, err
    data = json.loads(js.read_text())
    assert data["filter"]["recommended"] == "loop final model"
    assert data["filter"]["files"] == {"loop final model": "loop_model.json",
                                       "Allan model": "allan_model.json"}
    for name in data["filter"]["files"].values():
        assert read_filter_file(out / "filter" / name).system.rate == RATE
    report = (out / "report.md").read_text()
    assert "## The filter" in report and "Recommended: loop final model." in report
    assert ("its terms' weights were refitted on all the data given (30000 samples), its "
            "compensation's weights kept from the loop's fitting segment") in report
    saved = json.loads(model.read_text())
    assert saved["meta"]["fitted_on"] == ("all the record; structure chosen on the close-loop "
                                          "segments")
    written = read_filter_file(out / "filter" / "loop_model.json").system
    refit = FOSModel.from_dict(saved)
    from fosmodel.filter import to_state_space

    np.testing.assert_allclose(written.Phi, to_state_space(refit).Phi, rtol=1e-12)


def test_imu_writes_each_axis_s_filter_models_and_a_section(tmp_path, capsys):
    import pandas as pd

    from fosmodel import cli

    rec = make_scenario("static_imu", duration=300.0, seed=5)
    path = tmp_path / "imu.csv"
    pd.DataFrame({"time": np.arange(30_000) / 100.0, **rec.columns}).to_csv(path, index=False)
    out, js = tmp_path / "report", tmp_path / "imu.json"
    code = cli.main([str(a) for a in [
        "imu", path, "--columns", "gx_dps,ax_mps2", "--split", "60s,60s", "--orders", "1-2",
        "--methods", "fos,burg", "--jobs", "1", "--out", out, "--json", js]])
    _, err = capsys.readouterr()
    assert code == 0, err
    data = json.loads(js.read_text())
    assert set(data["filter"]) == {"gx_dps", "ax_mps2"}
    page = (out / "report.md").read_text()
    assert "## Filter models per axis" in page
    for column, entry in data["filter"].items():
        for name in ("loop_model.json", "allan_model.json"):
            back = read_filter_file(out / "filter" / column / name)
            assert back.system.rate == 100.0 and np.all(np.isfinite(back.P0))
        scores = entry["scores"]
        assert set(scores) == {"loop final model", "Allan model"}
        consistent = {k: s["rms_m"] for k, s in scores.items() if s["sigma_over_rms"] >= 0.7}
        if consistent:  # the stated rule, on the numbers the JSON gives
            assert entry["recommended"] == min(consistent, key=consistent.get)
        assert f"- {column}: {entry['why']}" in page


@pytest.mark.slow
def test_a_final_model_with_a_level_and_a_driver_converts_exactly():
    """The loop's level (a state) and its temperature compensation (D) in the state space."""
    from fosmodel.filter import initial_covariance, to_state_space

    rec = make_scenario("slow_random_walk_temperature", seed=0)
    y = rec.columns[rec.target]
    channels = {k: v for k, v in rec.columns.items() if k != rec.target}
    result = close_loop(y, channels, LoopConfig(rate=rec.rate, sensor="gyro", units="deg/s"))
    bound = result.final_model
    assert bound.model.compensation and bound.model.spec_.levels
    ss = to_state_space(bound.model)
    assert ss.state_names[-1].startswith("level@") and np.any(ss.D)
    u = ss.input_matrix(channels, len(y))  # the raw temperature only
    pred = bound.predict(y)
    for n in (2000, 30_000, 89_000):
        x = ss.state_from(y[:n], u[:n])
        assert ss.predict_measurement(ss.step(x, u[n]), u[n]) == pytest.approx(pred[n],
                                                                               abs=1e-12)
    assert np.all(np.linalg.eigvalsh(initial_covariance(ss, len(y) // 2)) > 0)


def test_the_judging_filter_s_settled_gains_reproduce_run_filter():
    """The periodic fast path against run_filter itself, with inputs and unit roots."""
    from fosmodel import FOSModel
    from fosmodel.filter import (
        KalmanFilter,
        initial_covariance,
        position_velocity_error_model,
        run_filter,
        to_state_space,
    )
    from fosmodel.loop.handoff import _periodic_filter

    y, _ = _driven_accel(4)
    model = FOSModel(max_lag=3, levels=[30.0], rate=RATE).fit(y[:10_000])
    error = to_state_space(model.refit_weights(y[:10_000], hold=True))
    system = position_velocity_error_model(error, 1 / RATE)
    p0 = np.zeros((system.n_states,) * 2)
    p0[2:, 2:] = initial_covariance(error, 10_000)
    rng = np.random.default_rng(0)
    m, period = 20_000, 600
    z = np.cumsum(np.cumsum(rng.standard_normal(m))) * 1e-4 + 0.1 * rng.standard_normal(m)
    z[np.arange(m) % period >= period // 2] = np.nan
    inputs = np.ones((m, 1))

    def fresh():
        return KalmanFilter.from_state_space(system, [[0.01]], np.zeros(system.n_states), p0)

    reference = run_filter(fresh(), z, inputs)
    position, variance = _periodic_filter(fresh(), z, inputs, period)
    np.testing.assert_allclose(position, reference.x[:, 0], rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(variance, reference.variance[:, 0], rtol=1e-8)
    # a pattern that does not repeat is run_filter all along
    z[12_345] = np.nan
    position, _ = _periodic_filter(fresh(), z, inputs, period)
    np.testing.assert_allclose(position, run_filter(fresh(), z, inputs).x[:, 0], rtol=1e-12,
                               atol=1e-12)

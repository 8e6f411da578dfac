import time

import numpy as np
import pytest
from scipy.signal import lfilter
from statsmodels.tsa.arima_process import ArmaProcess

from fosmodel.core.exceptions import InputError
from fosmodel.io.split import Split
from fosmodel.models.dynamics import ar_free_run, ar_one_step
from fosmodel.noise.denoise import denoise
from fosmodel.study import harness
from fosmodel.study.harness import StudyConfig
from fosmodel.study.runner import run_study

RATE = 10.0


AR3 = [1.0, -0.9, 0.5, -0.3]


def _ar3(n=30000, seed=0):
    e = np.random.default_rng(seed).standard_normal(n + 1000)
    return lfilter([1.0], AR3, e)[1000:] * 1e-3 + 2e-3  # m/s^2


def _config(**kw):
    base = dict(rate=RATE, sensor="accel", units="m/s^2", orders=(1, 2, 3, 4, 5, 6),
                degrees=(1,), train_s=600.0, evaluate_s=300.0, horizon_s=30.0, n_starts=10,
                levels=False)
    return StudyConfig(**{**base, **kw})


def test_split_by_duration():
    split = Split.by_duration(10000, 10.0, 180, 180, min_predict=300)
    assert (split.train, split.evaluate, split.predict) == (
        slice(0, 1800), slice(1800, 3600), slice(3600, 10000))
    with pytest.raises(InputError, match="leaves 0 samples to predict, 301 are needed"):
        Split.by_duration(3600, 10.0, 180, 180, min_predict=301)
    with pytest.raises(InputError, match="empty training or evaluation segment"):
        Split.by_duration(3600, 10.0, 0, 180)


def test_ar_study_levels_off_at_the_true_order():
    """One-step MSE falls by 1 - pacf(k)^2 from order k-1 to k, then stays flat after p = 3."""
    pacf = ArmaProcess(ar=AR3).pacf(7)
    result = run_study(_ar3(), _config(protocols=("fair",)))
    rows = result.rows.set_index(["method", "order"])["mse"]
    n_train = 6000
    for method in ("fos", "yw", "cov", "burg"):
        mse = rows[method]
        for order in (2, 3):
            assert mse[order] / mse[order - 1] == pytest.approx(1 - pacf[order] ** 2, abs=0.01)
        for order in (4, 5, 6):  # beyond p = 3 flat, within the cost of extra estimates
            assert abs(mse[order] - mse[3]) / mse[3] < 5 * (order - 3) / n_train + 2e-3
    best = result.best().set_index("method")
    assert set(best.index) == {"fos", "yw", "cov", "burg", "gm"}
    assert all(best.loc[m, "order"] >= 3 for m in ("yw", "cov", "burg"))


class _Spy:
    """A model that records what it is fit on and takes known time to fit and to predict."""

    seen: list = []

    def __init__(self, fit_s=0.0, predict_s=0.0):
        self.fit_s, self.predict_s = fit_s, predict_s
        self.lag_window_, self.n_terms_ = 1, 1

    def fit(self, y):
        _Spy.seen.append(np.array(y))
        time.sleep(self.fit_s)
        self.mu = float(np.mean(y))
        return self

    def predict(self, y):
        time.sleep(self.predict_s)
        return ar_one_step(np.array([0.5]), self.mu, y)

    def simulate(self, y_init, n_steps, noise=None):
        return self.mu + ar_free_run(np.array([0.5]), y_init - self.mu, np.zeros(n_steps))

    def is_stable(self):
        return True


def test_fit_sees_only_training_samples(monkeypatch):
    _Spy.seen = []
    monkeypatch.setattr(harness, "make_model", lambda *a, **k: _Spy())
    y = _ar3()
    config = _config(orders=(2,), methods=("fos", "burg"))
    run_study(y, config)
    train = slice(0, round(config.train_s * RATE))
    fitted = {arr.tobytes() for arr in _Spy.seen}
    assert fitted == {y[train].tobytes(), denoise(y[train], RATE, "wavelet").tobytes()}
    # changing every later sample changes nothing that was fit
    _Spy.seen = []
    z = y.copy()
    z[train.stop:] += 1.0
    run_study(z, config)
    assert {arr.tobytes() for arr in _Spy.seen} == fitted


def test_runtime_is_measured_around_fit_only(monkeypatch):
    monkeypatch.setattr(harness, "make_model", lambda *a, **k: _Spy(fit_s=0.05, predict_s=0.3))
    result = run_study(_ar3(12000), _config(orders=(1,), methods=("burg",),
                                           protocols=("fair",), n_starts=2))
    assert 0.05 <= result.rows["runtime_s"].iloc[0] < 0.25


def test_fos_is_fit_once_for_both_protocols():
    result = run_study(_ar3(12000), _config(orders=(2,), methods=("fos", "yw")))
    fos = result.rows[result.rows["method"] == "fos"]
    assert list(fos["protocol"]) == ["paper", "fair"] and fos["runtime_s"].nunique() == 1
    yw = result.rows[result.rows["method"] == "yw"].set_index("protocol")
    assert yw.loc["paper", "data"] == "wavelet" and yw.loc["fair", "data"] == "raw"


def test_unstable_baseline_is_reported_not_simulated_silently():
    rng = np.random.default_rng(3)
    y = np.cumsum(np.cumsum(rng.standard_normal(12000))) * 1e-6  # integrated twice
    result = run_study(y, _config(orders=(3,), methods=("cov",), protocols=("fair",)))
    row = result.rows.iloc[0]
    if not row["stable"]:
        assert np.isnan(row["outage_mse"]) and any("unstable" in w for w in result.warnings)
    else:
        assert np.isfinite(row["outage_mse"])


def test_json_rows_have_the_documented_keys():
    result = run_study(_ar3(12000), _config(orders=(1, 2), methods=("fos", "gm")))
    data = result.to_json_dict()
    keys = {"method", "order", "degree", "mse", "position_error_m", "outage_mse", "bias_rms",
            "outage_position_error_m", "runtime_s", "n_terms", "protocol"}
    assert all(keys <= set(row) for row in data["rows"] + data["best"])
    assert set(data["rows"][0]["bias_rms"]) == {"1", "10", "30"}
    assert len(data["best"]) == 4  # fos and gm under two protocols


def test_every_method_is_also_fit_about_the_local_level():
    """On a wandering bias, each method gains from the level; FOS weighs it freely."""
    rng = np.random.default_rng(6)
    n = 30000
    y = _ar3(n, seed=6) + np.cumsum(rng.standard_normal(n)) * 2e-5
    config = _config(orders=(3,), levels=True)
    result = run_study(y, config)
    rows = result.rows
    assert set(rows[rows["protocol"] == "paper"]["method"]) == {"fos", "yw", "cov", "burg", "gm"}
    fair = rows[rows["protocol"] == "fair"]
    assert {m + "+level" for m in ("fos", "yw", "cov", "burg", "gm")} <= set(fair["method"])
    taus = sorted(fair.loc[fair["method"] == "burg+level", "level_tau_s"])
    assert len(taus) == 4 and all(np.isnan(fair.loc[fair["method"] == "fos+level",
                                                    "level_tau_s"]))
    best = result.best().query("protocol == 'fair'").set_index("method")
    assert best.loc["burg+level", "label"] == "Burg + level"
    assert best.loc["fos+level", "label"] == "FOS CP=1 + level"
    for method in ("fos", "burg"):
        assert (best.loc[method + "+level", "outage_position_error_m"]
                < best.loc[method, "outage_position_error_m"])


@pytest.mark.parametrize(
    "y, kw, message",
    [(np.zeros(0), {}, "leaves 0 samples to predict"),
     (np.zeros(5000), {}, "leaves 0 samples to predict"),
     (np.zeros(9100), {}, "leaves 100 samples to predict, 600 are needed"),
     (np.zeros(20000), {"methods": ("fos", "arima")}, "unknown method 'arima'"),
     (np.zeros(20000), {"units": "deg/s"}, "units"),
     (np.zeros(20000), {"orders": (0, 1)}, "every order must be an integer >= 1")],
)
def test_bad_input(y, kw, message):
    with pytest.raises(InputError, match=message):
        run_study(y, _config(**kw))


def test_a_baseline_about_the_level_needs_its_time_constant():
    config = _config()
    assert harness.make_model("burg+level", 2, 1, config, level_tau=20.0).tau_s == 20.0
    with pytest.raises(InputError, match=r"^burg\+level needs the time constant of its level "
                                         r"\(level_tau=\.\.\.\)$"):
        harness.make_model("burg+level", 2, 1, config)

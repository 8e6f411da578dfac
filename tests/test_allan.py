"""Allan variance analysis against synthetic records with known noise coefficients.

Tolerances come from the statistics of the estimates, not from guesses: a
squared coefficient read off at one tau, where its term has the share ``s`` of
the Allan variance estimated with ``edf`` equivalent degrees of freedom, is
chi-square distributed with ``edf * s^2`` degrees of freedom (relative
standard deviation ``sqrt(2/edf)/s``).  The truth must lie in the 99.73 %
chi-square interval of the best such single-tau read-off, computed here from
the true model and Greenhall's edf of the true noise type.  The fit combines
many strongly correlated taus and has its own standard errors; the truth must
also lie in the fit's 99.73 % interval, and a Monte Carlo test checks that
those standard errors are calibrated.
"""

import json
import math
from dataclasses import replace

import allantools
import numpy as np
import pandas as pd
import pytest

from data_synth import BiasInstability, Drift, RandomWalk, WhiteNoise, compose, make_scenario
from data_synth.scenarios import ARRAY_TYPICAL
from data_synth.units import (
    arw_to_density,
    density_to_arw,
    density_to_vrw,
    rrw_to_density,
    vrw_to_density,
)
from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.noise.allan import FLICKER_FLOOR, allan_deviation, readoff
from fosmodel.noise.allan_fit import TERMS, fit_noise
from fosmodel.noise.allan_report import allan_figure

THREE_SIGMA = 0.9973


def _record(sources, seconds, rate, seed, units="deg/s"):
    rec = compose(sources, duration=seconds, rate=rate, seed=seed, units=units)
    return rec.columns[rec.target]


def _truth_interval(result, true_avar, term, alpha, estimate):
    """99.73 % chi-square interval of the truth around ``estimate`` from the best single tau.

    ``true_avar`` maps each term to its true Allan variance at ``result.taus``;
    ``alpha`` is the true noise type where ``term`` dominates.
    """
    m = np.round(result.taus * result.rate).astype(int)
    edf = np.array([allantools.edf_greenhall(alpha, 2, int(k), result.n_samples + 1,
                                             overlapping=True) for k in m])
    share = true_avar[term] / sum(true_avar.values())
    dof = float(np.max(edf * share**2))
    return allantools.confidence_interval(estimate, dof, THREE_SIGMA)


def _inside(fit, term, truth):
    lo, hi = fit.interval(term, THREE_SIGMA)
    return lo <= truth <= hi


# -- the Allan deviation and its confidence intervals ---------------------------------------


def test_adev_matches_the_overlapping_definition():
    """El-Diasty et al. (2007) eq. (1): sigma^2 = mean of (ybar[n+m] - ybar[n])^2 / 2 over all n."""
    y = np.random.default_rng(4).normal(size=3000) + np.linspace(0, 1, 3000)
    rate = 50.0
    result = allan_deviation(y, rate, taus=[1 / rate, 7 / rate, 50 / rate, 333 / rate])
    for tau, adev, count in zip(result.taus, result.adev, result.counts):
        m = round(tau * rate)
        c = np.r_[0.0, np.cumsum(y)]
        means = (c[m:] - c[:-m]) / m
        diffs = means[m:] - means[:-m]
        assert adev == pytest.approx(np.sqrt(np.mean(diffs**2) / 2), rel=1e-10)
        assert count == len(diffs)


def test_long_records_blocked_sums_match_allantools(monkeypatch):
    # records over BLOCKED_SAMPLES are summed in blocks: force it on a short one, with blocks
    # shorter than the longest 2 m so that second differences straddle block edges
    from fosmodel.noise import allan

    y = np.random.default_rng(6).normal(size=5000) + np.linspace(0, 2, 5000)
    rate = 100.0
    reference = allan_deviation(y, rate)
    monkeypatch.setattr(allan, "BLOCKED_SAMPLES", 0)
    monkeypatch.setattr(allan, "BLOCK", 97)
    blocked = allan_deviation(y, rate)
    np.testing.assert_array_equal(blocked.taus, reference.taus)
    np.testing.assert_array_equal(blocked.counts, reference.counts)
    np.testing.assert_allclose(blocked.adev, reference.adev, rtol=1e-12)
    np.testing.assert_allclose(blocked.lower, reference.lower, rtol=1e-12)


def test_default_taus_span_one_sample_to_nine_clusters():
    result = allan_deviation(np.random.default_rng(0).normal(size=9000), 100.0)
    m = np.round(result.taus * 100).astype(int)
    assert m[0] == 1 and m[-1] == 9000 // 9
    per_decade = len(m) / math.log10(m[-1])
    assert 8 <= per_decade <= 11 and np.all(np.diff(m) > 0)
    assert np.all(result.lower < result.adev) and np.all(result.adev < result.upper)


def test_white_noise_edf_is_greenhalls_for_white_fm():
    n = 20000
    result = allan_deviation(np.random.default_rng(1).normal(size=n), 1.0)
    assert np.all(result.alpha == 0)
    m = np.round(result.taus).astype(int)
    expected = [allantools.edf_greenhall(0, 2, int(k), n + 1, overlapping=True) for k in m]
    np.testing.assert_allclose(result.edf, expected, rtol=1e-12)


def test_ci_covers_the_true_adev_of_white_noise_about_68_percent():
    """Each 68 % interval holds the true N/sqrt(tau) with probability 0.68.

    Over 20 records x 32 taus (correlated along tau, about 150 independent
    draws) the coverage has a standard deviation of about 0.04: 0.55-0.81
    is a 3-sigma band around 0.68.
    """
    hits = []
    for seed in range(20):
        result = allan_deviation(np.random.default_rng(seed).normal(size=20000), 1.0)
        true = 1.0 / np.sqrt(result.taus)
        hits.append((result.lower <= true) & (true <= result.upper))
    coverage = float(np.mean(hits))
    assert 0.55 < coverage < 0.81, coverage


# -- noise coefficients ----------------------------------------------------------------------


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_white_noise_arw_recovered(seed):
    """El-Diasty et al. (2007) Table 1 gyro ARW 2.8946 deg/sqrt(h), 100 Hz, 200 s."""
    density = arw_to_density(2.8946)
    result = allan_deviation(_record([WhiteNoise(density)], 200, 100.0, seed), 100.0,
                             units="deg/s", sensor="gyro")
    fit = fit_noise(result)
    n_hat = fit.coefficients["N"]
    lo, hi = _truth_interval(result, {"N": density**2 / result.taus}, "N", 0, n_hat)
    assert abs(n_hat / density - 1) < 0.05 and lo <= density <= hi
    assert abs(n_hat - density) < 3 * fit.stderr["N"]
    assert _inside(fit, "N", density)
    assert fit.resolved["N"] and all(fit.dominant(t) == "N" for t in result.taus)
    assert fit.navigation("N") == (pytest.approx(density_to_arw(n_hat)), "deg/sqrt(h)")


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_white_noise_slope_and_classic_readoff(seed):
    """The measured slope is -1/2 and the -1/2 line read at 1 s is N.

    The slope from tau = 1/rate to the tau with 100 clusters has the standard
    deviation sqrt(1/(2 edf_1) + 1/(2 edf_2))/ln(tau_2/tau_1) (the two
    deviations are positively correlated, so this is an upper bound); the
    read-off goes through one point, whose 99.73 % interval must hold N.
    """
    density = 0.05
    result = allan_deviation(_record([WhiteNoise(density)], 200, 100.0, seed), 100.0)
    i = int(np.argmin(np.abs(result.n_samples / np.round(result.taus * 100) - 100)))
    slope = math.log(result.adev[i] / result.adev[0]) / math.log(result.taus[i] / result.taus[0])
    sd = math.sqrt(0.5 / result.edf[0] + 0.5 / result.edf[i]) / math.log(result.taus[i]
                                                                          / result.taus[0])
    assert abs(slope + 0.5) < 3 * sd < 0.05
    n_read = readoff(result)["N"]
    j = int(np.argmin(np.abs(result.adev * np.sqrt(result.taus) - n_read)))
    assert n_read == pytest.approx(result.adev[j] * math.sqrt(result.taus[j]), rel=1e-12)
    lo, hi = allantools.confidence_interval(n_read, result.edf[j], THREE_SIGMA)
    assert lo <= density <= hi


@pytest.mark.slow
def test_standard_errors_are_calibrated():
    """Over 40 white-noise records the z-scores of N^2 have unit spread.

    The sample standard deviation of 40 z-scores has a relative standard error
    of 1/sqrt(78) = 0.11, so 0.67-1.33 is a 3-sigma band; the coverage of the
    68 % interval, 0.68 +- 0.074, gets the band 0.46-0.90.
    """
    z, inside = [], []
    for seed in range(40):
        fit = fit_noise(allan_deviation(_record([WhiteNoise(0.05)], 50, 100.0, seed), 100.0))
        z.append((fit.coefficients["N"] ** 2 - 0.05**2) / fit.squared_stderr["N"])
        lo, hi = fit.interval("N")
        inside.append(lo <= 0.05 <= hi)
    assert 0.67 < np.std(z) < 1.33 and abs(np.mean(z)) < 0.5
    assert 0.46 < np.mean(inside) < 0.90


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_rate_random_walk_recovered(seed):
    """White 0.01 deg/sqrt(s) + RRW 0.001 deg/s/sqrt(s) at 10 Hz for 2 h.

    RRW dominates from tau = sqrt(3) N/K = 17 s up to 800 s, where few
    clusters remain; the best single-tau read-off (about 28 s) has about 120
    degrees of freedom, so the 99.73 % interval is about -16 %/+23 %.
    """
    white, rrw = 0.01, 0.001
    y = _record([WhiteNoise(white), RandomWalk(rrw)], 7200, 10.0, seed)
    result = allan_deviation(y, 10.0)
    fit = fit_noise(result, terms=("N", "K"))
    true = {"N": white**2 / result.taus, "K": rrw**2 * result.taus / 3}
    lo, hi = _truth_interval(result, true, "K", -2, fit.coefficients["K"])
    assert lo <= rrw <= hi and 0.8 < hi / lo < 1.8
    assert _inside(fit, "K", rrw) and _inside(fit, "N", white)
    assert fit.dominant(result.taus[0]) == "N" and fit.dominant(result.taus[-1]) == "K"
    assert result.alpha[0] == 0 and result.alpha[-1] == -2


@pytest.mark.slow
def test_koldbaek_totu_2011_gyro_arw_and_rrw_recovered():
    """Koldbæk and Totu (2011) eq. 5.4: ARW 0.068 deg/sqrt(s), RRW 0.00029 deg/sqrt(s^3), 102.4 Hz.

    RRW overtakes ARW at tau = sqrt(3) N/K = 406 s, so the record must be long
    against that: 12 h leaves 106 clusters at the crossover and RRW dominates
    for a decade above it (the best single-tau read-off of K, at 760 s with 57
    clusters, has about 31 degrees of freedom: a 99.73 % interval of about
    -28 %/+57 %).  All five terms are fitted, as on real data.
    """
    rec = make_scenario("gyro_array_8", duration=12 * 3600.0, seed=0, typical=True)
    arw = rec.truth["sources"][0]["params"]["densities"][0]
    rrw = rec.truth["sources"][1]["params"]["densities"][0]
    assert (arw, rrw) == ARRAY_TYPICAL and rec.rate == 102.4
    result = allan_deviation(rec.columns["gyro_1"], rec.rate, units="deg/s", sensor="gyro")
    fit = fit_noise(result)
    true = {"N": arw**2 / result.taus, "K": rrw**2 * result.taus / 3}
    k_hat, n_hat = fit.coefficients["K"], fit.coefficients["N"]
    lo, hi = _truth_interval(result, true, "K", -2, k_hat)
    assert lo <= rrw <= hi and _inside(fit, "K", rrw)
    assert abs(n_hat / arw - 1) < 0.05 and _inside(fit, "N", arw)
    assert {k for k in TERMS if fit.resolved[k]} == {"N", "K"}
    assert fit.dominant(result.taus[0]) == "N" and fit.dominant(result.taus[-1]) == "K"
    k_nav, k_units = fit.navigation("K")
    assert k_units == "deg/h/sqrt(h)"
    assert rrw_to_density(k_nav, per="h/sqrt(h)") == pytest.approx(k_hat, rel=1e-12)
    assert fit.navigation("N")[0] == pytest.approx(density_to_arw(n_hat), rel=1e-12)


def test_quantization_recovered_and_dominant_at_short_tau():
    """IEEE Std 952 quantization: a white angle error, uniform over one LSB (Q = LSB/sqrt(12)).

    0.02 deg LSB (Q = 0.0058 deg) on 0.01 deg/sqrt(s) white rate noise at
    100 Hz: Q dominates up to tau = 3Q^2/N^2 = 1 s.  The uniform error is
    platykurtic, so the Gaussian edf make the interval conservative.
    """
    rate, white, lsb = 100.0, 0.01, 0.02
    q = lsb / math.sqrt(12.0)
    angle_error = np.random.default_rng(7).uniform(-lsb / 2, lsb / 2, 100_001)
    y = _record([WhiteNoise(white)], 1000, rate, 7) + np.diff(angle_error) * rate
    result = allan_deviation(y, rate)
    fit = fit_noise(result)
    true = {"Q": 3 * q**2 / result.taus**2, "N": white**2 / result.taus}
    lo, hi = _truth_interval(result, true, "Q", 2, fit.coefficients["Q"])
    assert lo <= q <= hi and _inside(fit, "Q", q) and _inside(fit, "N", white)
    assert fit.dominant(result.taus[0]) == "Q" and fit.dominant(result.taus[-1]) == "N"
    assert result.alpha[0] == 2


def test_rate_ramp_recovered_and_dominant_at_long_tau():
    """A deterministic 0.57 deg/s per hour ramp (R = 1.58e-4 deg/s^2) on white noise, 10 Hz, 1 h."""
    white, ramp = 0.01, 1.58e-4
    y = _record([WhiteNoise(white), Drift(slope_per_h=ramp * 3600)], 3600, 10.0, 3)
    fit = fit_noise(allan_deviation(y, 10.0))
    assert _inside(fit, "R", ramp) and _inside(fit, "N", white)
    assert abs(fit.coefficients["R"] - ramp) < 3 * fit.stderr["R"]
    assert fit.dominant(1.0) == "N" and fit.dominant(300.0) == "R"


def test_bias_instability_recovered_on_its_floor():
    """Flicker B = 0.002 deg/s (floor 0.664 B) under 0.002 deg/sqrt(s) white noise, 10 Hz, 1 h."""
    white, b = 0.002, 0.002
    source = BiasInstability(b, tau_min_s=0.01, tau_max_s=1e5)
    result = allan_deviation(_record([WhiteNoise(white), source], 3600, 10.0, 2), 10.0)
    fit = fit_noise(result)
    assert _inside(fit, "B", b) and fit.resolved["B"]
    assert fit.dominant(result.taus[-1]) == "B"
    assert fit.term_adev("B", [1.0])[0] == pytest.approx(FLICKER_FLOOR * fit.coefficients["B"])


def test_accelerometer_vrw_in_navigation_units_independent_of_record_units():
    """El-Diasty et al. (2007) Table 1 accelerometer VRW 0.2797 m/s/sqrt(h); the record in mg."""
    density = vrw_to_density(0.2797)
    y = _record([WhiteNoise(density)], 300, 100.0, 5, units="m/s^2")
    fit = fit_noise(allan_deviation(y, 100.0, units="m/s^2", sensor="accel"))
    vrw, units = fit.navigation("N")
    assert units == "m/s/sqrt(h)" and vrw == pytest.approx(density_to_vrw(fit.coefficients["N"]))
    assert vrw == pytest.approx(0.2797, rel=0.05)
    in_mg = fit_noise(allan_deviation(y / 9.80665e-3, 100.0, units="mg", sensor="accel"))
    for k in TERMS:
        assert in_mg.navigation(k)[0] == pytest.approx(fit.navigation(k)[0], rel=1e-6, abs=1e-15)
    assert in_mg.navigation("B")[1] == "mg" and fit.name("N") == "velocity random walk"


def test_gyro_in_deg_per_hour_gives_the_same_navigation_values():
    y = _record([WhiteNoise(0.01), RandomWalk(0.002)], 1800, 10.0, 4)
    deg_s = fit_noise(allan_deviation(y, 10.0, units="deg/s", sensor="gyro"))
    deg_h = fit_noise(allan_deviation(y * 3600, 10.0, units="deg/h", sensor="gyro"))
    for k in ("N", "K"):
        assert deg_h.navigation(k)[0] == pytest.approx(deg_s.navigation(k)[0], rel=1e-6)
    assert deg_s.navigation("B")[1] == "deg/h" and deg_s.navigation("R")[1] == "deg/h^2"


def test_without_units_coefficients_stay_in_record_units():
    fit = fit_noise(allan_deviation(np.random.default_rng(0).normal(size=2000), 10.0))
    assert fit.navigation("N") is None and fit.units("N") == "units*sqrt(s)"
    assert "Navigation" not in fit.summary().to_frame().columns


def test_fit_restricted_to_terms_and_unresolved_terms_reported():
    y = _record([WhiteNoise(0.01)], 600, 10.0, 8)
    fit = fit_noise(allan_deviation(y, 10.0), terms=("N", "K", "Q"))
    assert fit.terms == ("Q", "N", "K")
    table = fit.summary().to_frame()
    assert list(table["Term"]) == ["Q", "N", "K"]
    unresolved = table[table["Resolved"] == "no"]
    assert set(unresolved["Term"]) == {k for k in fit.terms if not fit.resolved[k]}
    assert unresolved["Coefficient"].isna().all()
    assert not fit.resolved["K"] and "Not resolved" in str(fit.summary())


def test_summary_figure_and_json():
    y = _record([WhiteNoise(0.068), RandomWalk(0.00029)], 3600, 102.4, 1)
    result = allan_deviation(y, 102.4, units="deg/s", sensor="gyro")
    fit = fit_noise(result)
    text = str(fit.summary())
    assert "angle random walk" in text and "deg/sqrt(h)" in text and "Classic read-offs" in text
    data = json.loads(json.dumps({"allan": result.to_dict(), "noise": fit.to_dict()},
                                 allow_nan=False))
    assert data["noise"]["navigation"]["N"]["units"] == "deg/sqrt(h)"
    assert len(data["allan"]["taus_s"]) == len(result.taus)
    fig = allan_figure(result, fit, "gyro")
    labels = fig.axes[0].get_legend_handles_labels()[1]
    arw = fit.navigation("N")[0]
    assert abs(arw - 4.08) < 3 * fit.stderr["N"] * 60  # 0.068 deg/sqrt(s) is 4.08 deg/sqrt(h)
    assert f"N angle random walk = {arw:.3g} deg/$\\sqrt{{\\mathrm{{h}}}}$" in labels
    assert len(fig.axes) == 2 and fig.axes[1].get_ylabel() == "fit / data"
    assert "fitted sum" in labels
    frame = result.to_frame()
    assert list(frame.columns[:4]) == ["tau (s)", "ADEV (deg/s)", "lower 68 %", "upper 68 %"]


def test_readoff_b_is_the_minimum_over_0664():
    y = _record([WhiteNoise(0.01), RandomWalk(0.002)], 3600, 10.0, 6)
    result = allan_deviation(y, 10.0)
    assert readoff(result)["B"] == pytest.approx(result.adev.min() / FLICKER_FLOOR)
    assert math.isnan(readoff(allan_deviation(_record([WhiteNoise(0.01)], 600, 10.0, 6),
                                              10.0))["B"])


# -- errors ------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "kwargs, message",
    [
        ({"y": np.ones(99) + np.arange(99)}, "record too short"),
        ({"y": np.r_[np.zeros(200), np.nan]}, "non-finite"),
        ({"y": np.full(500, 3.0)}, "constant"),
        ({"rate": 0.0}, "rate must be a finite number > 0"),
        ({"sensor": "gyro"}, "need the units of the record"),
        ({"sensor": "gyro", "units": "deg/min"}, "unknown gyro units"),
        ({"taus": [100.0]}, "taus must lie between"),
        ({"taus": [0.001]}, "taus must lie between"),
    ],
)
def test_bad_input_raises_input_error(kwargs, message):
    args = {"y": np.random.default_rng(0).normal(size=500), "rate": 10.0, **kwargs}
    with pytest.raises(InputError, match=message):
        allan_deviation(args.pop("y"), args.pop("rate"), **args)


@pytest.mark.parametrize(
    "terms, message",
    [(("N", "X"), "unknown noise term 'X'"), (("N", "N"), "distinct"), ((), "distinct"),
     (("NN",), "did you mean 'N'")],
)
def test_bad_terms_raise_input_error(terms, message):
    result = allan_deviation(np.random.default_rng(0).normal(size=500), 10.0)
    with pytest.raises(InputError, match=message):
        fit_noise(result, terms=terms)


# -- command line ------------------------------------------------------------------------------


def _csv(tmp_path, seconds=600.0, name="gyro.csv"):
    rec = compose([WhiteNoise(0.068), RandomWalk(0.00029)], duration=seconds, rate=102.4, seed=2)
    path = tmp_path / name
    rec.to_frame().to_csv(path, index=False)
    return path


def _run(args, capsys):
    code = cli.main([str(a) for a in args])
    out, err = capsys.readouterr()
    return code, out, err


def test_cli_writes_figure_tables_and_json(tmp_path, capsys):
    out_dir, json_path = tmp_path / "allan", tmp_path / "allan.json"
    code, out, err = _run(["allan", _csv(tmp_path), "--column", "gyro_y", "--sensor", "gyro",
                           "--units", "deg/s", "--out", out_dir, "--json", json_path], capsys)
    assert code == 0, err
    for name in ("allan.png", "allan.svg", "allan.md", "allan.csv", "allan.tex", "noise.md",
                 "noise.csv", "noise.tex"):
        assert (out_dir / name).stat().st_size > 0, name
    assert "Allan variance noise coefficients" in out and "angle random walk" in out
    noise = pd.read_csv(out_dir / "noise.csv")
    row = noise[noise["Term"] == "N"].iloc[0]
    assert row["Resolved"] == "yes" and row["Navigation units"] == "deg/sqrt(h)"
    assert row["Navigation"] == pytest.approx(4.08, rel=0.05)
    data = json.loads(json_path.read_text(), parse_constant=lambda c: pytest.fail(c))
    assert data["column"] == "gyro_y" and data["allan"]["rate_hz"] == pytest.approx(102.4)
    adev = pd.read_csv(out_dir / "allan.csv")
    assert len(adev) == len(data["allan"]["taus_s"]) and "edf" in adev.columns
    # the fitted curve at every measured tau, and the datasheet's number the measured minimum
    assert len(data["noise"]["fit_adev"]) == len(data["allan"]["taus_s"])
    sheet = data["noise"]["datasheet"]
    if sheet["in_run_bias_stability"] is not None:
        assert sheet["in_run_bias_stability"] == min(data["allan"]["adev"])


def test_cli_without_units_uses_record_units(tmp_path, capsys):
    code, out, err = _run(["allan", _csv(tmp_path), "--column", "gyro_y", "--out",
                           tmp_path / "o"], capsys)
    assert code == 0, err
    assert "units*sqrt(s)" in out and "Navigation" not in out


@pytest.mark.parametrize(
    "extra, seconds, message",
    [
        ([], 0.5, "record too short"),
        (["--sensor", "gyro"], 600.0, "column 'gyro_y': a gyro, but the name does not tell "
                                      "its units; give them as gyro_y=UNITS (e.g. gyro_y=deg/s)"),
        (["--sensor", "accel", "--units", "deg/s"], 600.0,
         "column 'gyro_y': deg/s is a unit of a gyro, not of an accelerometer"),
    ],
)
def test_cli_bad_input_exit_2_one_line_no_output(tmp_path, capsys, extra, seconds, message):
    out_dir = tmp_path / "o"
    code, _, err = _run(["allan", _csv(tmp_path, seconds), "--column", "gyro_y",
                         "--out", out_dir, *extra], capsys)
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("fosmodel: error: ") and message in err
    assert not out_dir.exists()


def test_cli_unknown_column_exit_2(tmp_path, capsys):
    code, _, err = _run(["allan", _csv(tmp_path), "--column", "gyro", "--out", tmp_path / "o"],
                        capsys)
    assert code == 2 and "did you mean 'gyro_y'" in err


def test_step_record_with_undefined_noise_id_still_gives_adev_and_fit():
    # constant stretches leave the lag-1 autocorrelation undefined (allantools raises on it):
    # the noise id falls back to white FM and the analysis completes
    y = np.r_[np.zeros(1500), np.ones(1500)]
    result = allan_deviation(y, 100.0)
    assert np.isfinite(result.adev).all() and np.isfinite(result.lower).all()
    assert fit_noise(result).coefficients["K"] > 0  # a step looks like a rate random walk


def test_cli_reads_the_units_in_a_column_s_name(tmp_path, capsys):
    """``allan --column "Accel X (g)"``: the units from the name, as every command reads them."""
    rng = np.random.default_rng(4)
    path = tmp_path / "a.csv"
    pd.DataFrame({"Accel X (g)": rng.normal(0.0, 1e-3, 20_000)}).to_csv(path, index=False)
    assert cli.main(["allan", str(path), "--column", "Accel X (g)", "--rate", "100", "--out",
                     str(tmp_path / "allan")]) == 0
    out = capsys.readouterr().out
    assert "Units:                              g" in out
    assert "Sensor:                         accel" in out


@pytest.mark.parametrize(("n", "seed"), [(20_000, 2), (216_000, 5), (60_000, 0)])
def test_no_minimum_on_a_curve_that_only_falls(n, seed):
    """White noise alone: the curve's lowest point, among its last noisy taus, is no minimum
    (these draws put it at 177 s of 222 s and 1210 s of 2400 s)."""
    read = readoff(allan_deviation(np.random.default_rng(seed).normal(size=n), 10.0))
    assert math.isnan(read["min_adev"]) and math.isnan(read["min_tau_s"])
    assert math.isnan(read["B"]) and math.isnan(read["K"])


def test_a_wiggle_of_the_last_taus_is_no_k_line():
    """A -1/2 curve whose last point jumps up (few clusters there): its two-point slope is
    +1/2, but over half a decade the curve falls, so there is no K read-off."""
    res = allan_deviation(np.random.default_rng(1).normal(size=60_000), 10.0)
    log_t = np.log10(res.taus)
    adev = 10 ** (-0.5 * log_t)
    adev[-1] = adev[-2] * 10 ** (0.5 * (log_t[-1] - log_t[-2]))
    read = readoff(replace(res, adev=adev))
    assert math.isnan(read["K"])
    assert read["N"] == pytest.approx(1.0)


def test_a_flat_floor_is_a_minimum_and_a_rise_makes_one():
    """White noise and a random walk: the curve falls, floors and rises, and the minimum is
    read where it is; the K read-off is on the +1/2 stretch."""
    rng = np.random.default_rng(3)
    x = rng.normal(size=200_000) + np.cumsum(0.003 * rng.normal(size=200_000))
    res = allan_deviation(x, 10.0)
    read = readoff(res)
    i = int(np.argmin(res.adev))
    assert read["min_adev"] == res.adev[i] and 0 < i < len(res.taus) - 2
    assert read["K"] == pytest.approx(0.003 * math.sqrt(10.0), rel=0.3)

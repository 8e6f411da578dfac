"""The residual loop over sessions of one sensor: shared effects, a constant each."""

import json

import numpy as np
import pytest

from data_synth import make_sessions, write_record
from fosmodel import cli
from fosmodel.core.exceptions import InputError
from fosmodel.core.levels import level_series
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.effects import CandidateFamily, make
from fosmodel.loop.judge import verdict
from fosmodel.loop.sessions import (
    Session,
    SessionFitter,
    SessionJudge,
    _ahead,
    _parts,
    _record,
    close_sessions,
    score_sessions,
)

HOURS = 12


@pytest.fixture(scope="module")
def sweeps():
    """Three half-day sessions of the temperature_sessions IMU (seed 0)."""
    return make_sessions("temperature_sessions", seed=0, duration=HOURS * 3600.0)


def _sessions(records, column="gx_dps"):
    return [Session(r.columns[column], {k: v for k, v in r.columns.items() if k != column},
                    f"s{i + 1}") for i, r in enumerate(records)]


CONFIG = LoopConfig(rate=1.0, sensor="gyro", units="deg/s")


@pytest.fixture(scope="module")
def result(sweeps):
    return close_sessions(_sessions(sweeps), CONFIG)


def test_the_shared_temperature_sensitivity_is_named_and_recovered(result, sweeps):
    (step,) = [s for s in result.steps if s.effect.kind == "driver"]
    assert step.effect.channel == "temp_c" and step.effect.part == "slow"
    truth = sweeps[0].truth["shared"]["temperature_bias"]["gx_dps"]
    centre = float(next(iter(step.effect.forms))[0].split(",")[-1].rstrip(")"))
    slope = truth["coefs"][1] + 2 * truth["coefs"][2] * (centre - truth["t_ref_c"])
    weights = dict(step.effect.forms)
    assert weights[f"pow(temp_c,1,{centre:.8g})"] == pytest.approx(slope, rel=0.2)
    # judged on every session held out, the comparisons pooled
    assert len(step.judgement.sessions) == 3 and step.judgement.origins_s == ()
    assert result.after.bias_rms[1800] < 0.5 * result.before.bias_rms[1800]
    assert not result.worse()


def test_each_session_keeps_its_own_constant(result):
    model = result.final_model.model
    assert len(result.constants) == 3 and abs(np.mean(result.constants)) < 1e-9
    data = result.to_json_dict()
    assert [s["name"] for s in data["sessions"]] == ["s1", "s2", "s3"]
    assert [s["constant"] for s in data["sessions"]] == result.constants
    assert {"before", "after", "ratios", "worse"} <= set(data["sessions"][0])
    assert model.compensation and data["effects"][0]["evaluation"]["sessions"]


def test_the_predicted_parts_never_decide(sweeps, result):
    changed = _sessions(sweeps)
    for session in changed:
        n = len(session.y)
        y = np.array(session.y, dtype=float)
        y[round(0.7 * n):] += 3 * np.sin(np.arange(n - round(0.7 * n)) * 0.37)
        session.channels["temp_c"][round(0.7 * n):] += 5.0  # a new effect, and a new sweep
        object.__setattr__(session, "y", y)
    other = close_sessions(changed, CONFIG)
    assert [s.effect for s in other.steps] == [s.effect for s in result.steps]
    assert [s.judgement for s in other.steps] == [s.judgement for s in result.steps]


def test_a_held_out_session_s_constant_comes_from_its_head_only(sweeps):
    """Its first head_s seconds give the constant; what follows is judged, and never read."""
    from fosmodel.loop.effects import CandidateFamily
    from fosmodel.loop.record import LoopRecord
    from fosmodel.loop.sessions import SessionFitter

    ys = [r.columns["gx_dps"] for r in sweeps]
    bounds = np.cumsum([0, *map(len, ys)])
    spans = tuple(slice(a, b) for a, b in zip(bounds[:-1], bounds[1:]))
    record = LoopRecord(np.concatenate(ys), {}, 1.0, spans)
    decide = tuple(slice(s.start, s.start + round(0.7 * (s.stop - s.start))) for s in spans)
    fitter = SessionFitter(record, decide, CONFIG)
    model = fitter.fit(CandidateFamily(10), [1, 2])
    head = fitter.session(model, 0, slice(0, 600))
    y = record.y[spans[0]].copy()
    y[600:] += 10.0  # all that is judged moves: the constant does not
    record_moved = LoopRecord(np.concatenate([y, *ys[1:]]), {}, 1.0, spans)
    moved = SessionFitter(record_moved, decide, CONFIG).session(model, 0, slice(0, 600))
    assert moved.model.intercept_ == head.model.intercept_


def test_sessions_are_refused_in_one_line(sweeps):
    sessions = _sessions(sweeps)
    with pytest.raises(InputError, match="a loop over sessions needs two or more, got 1"):
        close_sessions(sessions[:1], CONFIG)
    odd = Session(sessions[1].y, {"temp_c": sessions[1].channels["temp_c"]}, "odd")
    with pytest.raises(InputError, match=r"^odd: its channels \(temp_c\) are not those of s1 "):
        close_sessions([sessions[0], odd], CONFIG)
    short = Session(sessions[1].y[:650], {k: v[:650] for k, v in sessions[1].channels.items()},
                    "short")
    with pytest.raises(InputError, match=r"^short \(650 samples, 650 s\) is too short: its "
                                         r"first 600 s give its constant"):
        close_sessions([sessions[0], short], CONFIG)
    assert isinstance(close_loop(sessions[:2], None, LoopConfig(rate=1.0, max_effects=0)),
                      type(close_sessions(sessions[:2], LoopConfig(rate=1.0, max_effects=0))))


def test_close_loop_and_fit_of_several_files(sweeps, tmp_path, capsys):
    files = []
    for i, rec in enumerate(sweeps):
        path = tmp_path / f"day{i + 1}.csv"
        write_record(rec, path)
        files.append(str(path))
    model, out = tmp_path / "shared.json", tmp_path / "loop"
    code = cli.main(["close-loop", *files, "--column", "gx_dps", "--units", "gx_dps=deg/s",
                     "--out", str(out), "--model", str(model), "--max-lag", "5"])
    stdout, err = capsys.readouterr()
    assert code == 0, err
    assert "residual loop report of 3 sessions written to" in stdout
    report = (out / "report.md").read_text()
    assert "| day1 |" in report and "| pooled |" in report
    saved = json.loads(model.read_text())
    assert [s["source"] for s in saved["meta"]["sessions"]] == files
    fitted = tmp_path / "fit.json"
    code = cli.main(["fit", *files, "--column", "gx_dps", "--exog", "temp_c:0", "--max-lag",
                     "2", "--out", str(fitted)])
    assert code == 0, capsys.readouterr().err
    meta = json.loads(fitted.read_text())["meta"]
    assert len(meta["sessions"]) == 3 and "first minutes" in meta["constant"]
    assert level_series  # the module's levels are those of each session (see the fitter)


def _drift_judged(shape):
    """A drift judged over three sessions sharing ``shape`` (of the fraction of a session)."""
    rng = np.random.default_rng(4)
    n = 20000
    sessions = [Session(c + shape(np.arange(n) / n) + 0.05 * rng.standard_normal(n), None,
                        f"s{k + 1}") for k, c in enumerate((0.3, -0.2, 0.1))]
    config = LoopConfig(rate=1.0, horizons_s=(30.0, 300.0))
    record, _ = _record(sessions, config)
    head = round(config.head_s * config.rate)
    decide, _, judged, _ = _parts(record, config, head)
    fitter = SessionFitter(record, decide, config)
    family = CandidateFamily(config.max_lag).add(make("level", taus=(10.0, 30.0)), record)
    drift = make("drift", form="trend", tau_s=5000.0)
    trial = family.add(drift, record)
    judge = SessionJudge(fitter, family, judged, head, _ahead(record, config, judged, head))
    judgement = judge(fitter.fit(trial), trial, drift)
    level = make("level", taus=(10.0, 30.0))
    alone, with_drift = (score_sessions(sessions, config, e) for e in ([level], [level, drift]))
    return judgement, config, alone["bias_rms"]["300"], with_drift["bias_rms"]["300"]


def test_a_drift_shared_by_the_deciding_hours_is_judged_ahead_in_time():
    # a rise over each session's first half that turns there: held out across sessions the
    # drift is judged on the hours it was fitted on (it passes), on the predicted part it
    # runs on and is worse; judged ahead of a fit on the first halves it loses, refused
    judgement, config, alone, with_drift = _drift_judged(lambda u: -2 * np.abs(u - 0.5))
    assert verdict(judgement.last, list(judgement.sessions), config.accept_alpha) is not None
    assert with_drift > 1.3 * alone
    assert not judgement.accepted
    assert len(judgement.earlier) == 3 and judgement.origins_s == (10000.0,) * 3
    assert all(g < 0 for g in judgement.gains("outage_300s")[:-1])


def test_a_drift_that_runs_on_is_kept_ahead_in_time():
    judgement, _, alone, with_drift = _drift_judged(lambda u: 0.5 * u)
    assert judgement.accepted and with_drift < 0.5 * alone
    assert all(g > 0 for g in judgement.gains(judgement.kept_on)[:-1])

import numpy as np
import pytest
from scipy.signal import lfilter

from fosmodel.study.harness import StudyConfig
from fosmodel.study.report import level_table, paper_table, study_table, write_study
from fosmodel.study.runner import run_study


@pytest.fixture(scope="module")
def result():
    e = np.random.default_rng(0).standard_normal(13000)
    y = lfilter([1.0], [1.0, -0.8, 0.3], e)[1000:] * 0.01
    config = StudyConfig(rate=10.0, sensor="gyro", units="deg/s", orders=(1, 2, 10),
                         degrees=(1, 2), train_s=300.0, evaluate_s=300.0, n_starts=5)
    return run_study(y, config)


def test_paper_table_layout(result):
    table = paper_table(result)
    assert list(table["Order L"].unique()) == [1, 10]
    first = table[table["Order L"] == 1]
    assert list(first["Method"]) == ["Yule-Walker", "Yule-Walker", "Covariance", "Covariance",
                                     "Burg", "Burg", "Gauss-Markov", "Gauss-Markov",
                                     "FOS CP=1", "FOS CP=2"]
    assert "Gauss-Markov" not in set(table[table["Order L"] == 10]["Method"])
    assert set(first["Data"]) == {"raw", "wavelet"}
    assert "MSE (deg/s)^2" in table.columns and "Position error (m)" in table.columns


def test_study_table_has_every_row(result):
    plain = 3 * 2 + 3 * 3 + 1  # FOS orders x degrees, three AR methods x orders, GM
    about_level = 3 * 2 + 4 * (3 * 3 + 1)  # fair only: each baseline per level time constant
    assert len(result.level_taus) == 4
    assert len(study_table(result)) == len(result.rows) == 2 * plain + about_level


def test_level_table_sets_each_method_beside_its_level_form(result):
    table = level_table(result)
    assert list(table["Method"]) == [
        "Burg", "Covariance", "FOS CP=1", "FOS CP=2", "Gauss-Markov", "Yule-Walker",
        "Burg + level", "Covariance + level", "FOS CP=1 + level", "FOS CP=2 + level",
        "Gauss-Markov + level", "Yule-Walker + level"]
    taus = table["Level tau (s)"]
    assert taus[:6].isna().all() and taus[8:10].isna().all()
    assert set(taus[[6, 7, 10, 11]]) <= set(result.level_taus)


def test_write_study_writes_tables_figures_and_report(result, tmp_path):
    paths = write_study(result, tmp_path / "out", "Test study")
    names = {p.name for p in paths}
    for stem in ("comparison", "study", "best", "level"):
        assert {f"{stem}.md", f"{stem}.csv", f"{stem}.tex"} <= names
    assert {"order_paper.png", "order_paper.svg", "order_fair.png", "order_fair.svg",
            "report.md"} <= names
    assert all(p.stat().st_size > 0 for p in paths)
    assert (tmp_path / "out" / "order_fair.png").read_bytes()[:4] == b"\x89PNG"
    assert "\\begin{tabular}" in (tmp_path / "out" / "comparison.tex").read_text()
    report = (tmp_path / "out" / "report.md").read_text()
    assert "# Test study" in report and "![fair protocol](order_fair.png)" in report
    assert "## About the local level (fair protocol)" in report
    assert not [p for p in (tmp_path / "out").iterdir() if p.name.endswith(".tmp")]


def test_the_comparison_table_takes_the_lowest_and_the_highest_order(tmp_path):
    e = np.random.default_rng(1).standard_normal(7000)
    y = lfilter([1.0], [1.0, -0.8, 0.3], e)[1000:] * 0.01
    config = StudyConfig(rate=10.0, sensor="gyro", units="deg/s", orders=(1, 2, 3, 4),
                         degrees=(1,), train_s=200.0, evaluate_s=200.0, n_starts=3, levels=False)
    result = run_study(y, config)
    table = paper_table(result)
    assert list(table["Order L"].unique()) == [1, 4]
    assert set(table[table["Order L"] == 4]["Method"]) == {
        "Yule-Walker", "Covariance", "Burg", "FOS CP=1"}
    assert "Gauss-Markov" in set(table[table["Order L"] == 1]["Method"])
    assert list(paper_table(result, orders=(2, 3))["Order L"].unique()) == [2, 3]
    write_study(result, tmp_path, "orders 1-4")
    report = (tmp_path / "report.md").read_text()
    assert "## Comparison at orders 1 and 4 (Tamazin et al. 2013" in report
    assert "at model orders 1 and 4" in (tmp_path / "comparison.tex").read_text()


def test_every_metric_of_the_report_is_defined_where_it_appears(result, tmp_path):
    """The comparison table's position error of 1e8 m says what it is: Tamazin et al.'s (2013)
    equivalent position error over T = 3600 s; the outage error its horizon and segment."""
    write_study(result, tmp_path, "defined")
    page = (tmp_path / "report.md").read_text()
    table_end = page.index("What the columns are:")
    assert page.index("| Position error (m) |") < table_end
    notes = page[table_end:page.index("## Best configuration")]
    assert ("- Position error (m): the equivalent position error of Tamazin et al. (2013), "
            "T = 3600 s: an "
            "error of constant size sqrt(MSE) integrated freely for an hour, 0.5 sqrt(MSE) T^2 "
            "for an accelerometer and g sqrt(MSE) T^3 / 6 for a gyroscope") in notes
    assert "- MSE (deg/s)^2: the mean square of the one-step prediction error on the " \
        "prediction segment (600-1200 s of the record)." in notes
    assert ("- Outage position error (m, 30 s): in each of 5 outages of 30 s spread evenly "
            "over the prediction segment (600-1200 s of the record), the model's free run") \
        in notes
    assert ("- One-step bias RMS tau s (deg/s): the RMS of the means of the one-step "
            "residual") in notes
    assert "- Evaluate MSE (deg/s)^2: the same on the evaluation segment (300-600 s" in notes
    tex = (tmp_path / "comparison.tex").read_text()
    assert "equivalent position error" in tex and "free runs of 30" in tex

"""Every LaTeX table fosmodel writes compiles.

Each kind of ``.tex`` (a study report, several studies, a residual-loop report, an Allan
report, an IMU noise report, a FOSModel summary and a table of every special character) is
made from small synthetic data and checked twice: by a strict structural check that always
runs (braces, environments, special characters outside math mode, cells per row, booktabs
rules, caption and label), and by ``pdflatex -halt-on-error`` inside a minimal document when
pdflatex is installed (``.ci/run`` installs it where it can).
"""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from scipy.signal import lfilter

from fosmodel.io.output import write_tables
from fosmodel.loop.closeloop import LoopConfig, close_loop
from fosmodel.loop.loop_report import write_loop_report
from fosmodel.models.model import FOSModel
from fosmodel.noise.allan import allan_deviation
from fosmodel.noise.allan_fit import fit_noise
from fosmodel.noise.allan_report import write_allan
from fosmodel.noise.imu_noise import Axis, imu_noise, write_imu_noise
from fosmodel.study.files import ColumnStudy, write_reports
from fosmodel.study.harness import StudyConfig, plan_study
from fosmodel.study.runner import run_study
from fosmodel.typeset.latex import latex_number, latex_text, table_label
from fosmodel.typeset.tables import latex_table

PDFLATEX = shutil.which("pdflatex")
#: A plain article with the packages fosmodel's tables name in their first line.
PREAMBLE = ("\\documentclass{article}\n\\usepackage{booktabs}\n\\usepackage{longtable}\n"
            "\\usepackage{pdflscape}\n\\usepackage{graphicx}\n\\begin{document}\n")
DOCUMENT = PREAMBLE + "%s\n\\end{document}\n"
#: Characters that mean something to LaTeX in text mode.
SPECIAL = set("&%$#_{}~^\\")
#: A title with every special character and a unit, as a user may give it.
TITLE = "gx_dps #1 (m/s^2, 5 % & $, {x} ~ back\\slash)"


# -- the strict structural check -------------------------------------------------------------


def _tokens(source: str):
    """``(token, in_math)``: a control word (``\\caption``), a control symbol (``\\&``) or a
    character, and whether it stands in math mode (between unescaped dollars)."""
    in_math, i = False, 0
    while i < len(source):
        if source[i] == "\\":
            word = re.match(r"\\([A-Za-z]+|.)", source[i:], re.DOTALL).group(0)
            yield word, in_math
            i += len(word)
            continue
        if source[i] == "$":
            in_math = not in_math
        else:
            yield source[i], in_math
        i += 1
    assert not in_math, "a math mode is not closed"


def structural_problems(source: str) -> list[str]:
    """What would stop ``source`` from compiling, or break the table (empty when none).

    Whole-line comments (the line naming the packages a table needs) are left out."""
    source = re.sub(r"(?m)^%.*\n", "", source)
    problems, depth, envs, previous = [], 0, [], ""
    for token, in_math in _tokens(source):
        if token == "{":
            # an argument's brace follows its command, or the argument before, at once
            if not (in_math or previous.startswith("\\") and previous[1:].isalpha()
                    or previous in ("}", "]")):
                problems.append(f"a bare '{{' after {previous!r}")
            depth += 1
        elif token == "}":
            depth -= 1
            if depth < 0:
                problems.append("a '}' closes nothing")
        elif token in ("%", "#", "~") or token in ("_", "^") and not in_math:
            problems.append(f"{token!r} unescaped" + (" in math mode" if in_math else ""))
        elif token == "&" and in_math:
            problems.append("'&' inside math mode")
        previous = token
    if depth:
        problems.append(f"{depth} '{{' not closed")
    for kind, name in re.findall(r"\\(begin|end)\{([^}]*)\}", source):
        if kind == "begin":
            envs.append(name)
        elif not envs or envs.pop() != name:
            problems.append(f"\\end{{{name}}} does not close the open environment")
    problems += [f"\\begin{{{name}}} not closed" for name in envs]
    return problems + _table_problems(source)


def _table_problems(source: str) -> list[str]:
    problems = []
    tables = re.findall(r"\\begin\{(table|longtable)\}(.*?)\\end\{\1\}", source, re.DOTALL)
    if not tables:
        problems.append("no table")
    for kind, table in tables:
        if not re.search(r"\\caption\{.+\}", table):
            problems.append("a table without a caption")
        if not re.search(r"\\label\{tab:fosmodel-[a-z0-9-]+\}", table):
            problems.append("a table without a tab:fosmodel- label")
        if kind == "table":
            spec, body = re.search(r"\\begin\{tabular\}\{([^}]*)\}(.*)\\end\{tabular\}", table,
                                   re.DOTALL).groups()
            expected = ["toprule", "midrule", "bottomrule"]
        else:  # heads on the first page and on the next ones, the bottom rule on the last
            spec, body = re.match(r"\{([^}]*)\}\n\\caption\{.*?\}\\label\{[^}]*\}\\\\\n(.*)",
                                  table, re.DOTALL).groups()
            body = re.sub(r"\\(endfirsthead|endhead|endlastfoot)\n", "", body)
            expected = ["toprule", "midrule", "toprule", "midrule", "bottomrule"]
        rules = re.findall(r"\\(toprule|midrule|bottomrule)", body)
        if rules != expected:
            problems.append(f"rules {rules}, not {expected}")
        columns = len(re.findall(r"[lrc]|p\{[^}]*\}", spec))
        for row in re.split(r"\\\\\s*\n", re.sub(r"\\(toprule|midrule|bottomrule)", "", body)):
            if row.strip():
                cells = 1 + sum(token == "&" for token, in_math in _tokens(row) if not in_math)
                if cells != columns:
                    problems.append(f"{cells} cells where the spec {spec!r} has {columns}: "
                                    f"{row.strip()[:60]}")
    return problems


def _compile(source: str, workdir: Path) -> None:
    tex = workdir / "check.tex"
    tex.write_text(DOCUMENT % source)
    run = subprocess.run([PDFLATEX, "-halt-on-error", "-interaction=nonstopmode", tex.name],
                         cwd=workdir, capture_output=True, text=True, timeout=120,
                         stdin=subprocess.DEVNULL)
    errors = [line for line in run.stdout.splitlines() if line.startswith("!")]
    assert run.returncode == 0 and (workdir / "check.pdf").exists(), errors or run.stdout[-800:]


# -- every kind of .tex fosmodel writes ------------------------------------------------------


def _ar(n: int, seed: int) -> np.ndarray:
    e = np.random.default_rng(seed).standard_normal(n + 500)
    return lfilter([1.0], [1.0, -0.8, 0.3], e)[500:]


def _study_config() -> StudyConfig:
    return StudyConfig(rate=10.0, sensor="accel", units="m/s^2", orders=(1, 2, 3), degrees=(1,),
                       train_s=200.0, evaluate_s=200.0, n_starts=3)


def _special_table(out: Path) -> list[Path]:
    frame = pd.DataFrame({
        "gx_dps": [1e-05, -2.5, np.nan, np.inf], "N (deg/s/sqrt(Hz))": [1, -2, 300000, 4],
        "text & more": ["a_b^c", "50 % of #1", "{braces} ~ $5", "back\\slash"],
        "mixed": [None, 0.25, "y[n-1]^2", True]})
    paths = write_tables(frame, out, "special", "Every special character: _ ^ % & # $ { } ~ \\",
                         report=TITLE)
    return [p for p in paths if p.suffix == ".tex"]


def _studies(out: Path, seeds: tuple[int, ...]) -> list[Path]:
    """The report of one study (``--columns`` of one file) or of several."""
    config, studies, results = _study_config(), [], []
    for seed in seeds:
        y = _ar(6000, seed) * 0.01
        studies.append(ColumnStudy(f"imu{seed}.csv", "ay_mps2", f"imu{seed}_ay_mps2",
                                   plan_study(y, config)))
        results.append(run_study(y, config))
    write_reports(studies, results, out, TITLE)
    return sorted(out.rglob("*.tex"))


def _loop(out: Path) -> list[Path]:
    n, rate = 12_000, 50.0
    temp = np.linspace(20.0, 30.0, n)
    y = 0.05 * _ar(n, 3) + 0.02 * (temp - 25.0) ** 2
    result = close_loop(y, {"temp_c": temp}, LoopConfig(rate=rate, sensor="gyro", units="deg/s"))
    write_loop_report(result, out, TITLE)
    return sorted(out.glob("*.tex"))


def _allan(out: Path) -> list[Path]:
    rng = np.random.default_rng(4)
    y = 0.01 * rng.standard_normal(20_000) + np.cumsum(1e-4 * rng.standard_normal(20_000))
    result = allan_deviation(y, 100.0, units="deg/s", sensor="gyro")
    write_allan(result, fit_noise(result), out, TITLE)
    return sorted(out.glob("*.tex"))


def _imu(out: Path) -> list[Path]:
    rng = np.random.default_rng(5)
    columns = {"gx_dps": 0.01 * rng.standard_normal(20_000),
               "ax_mps2": 0.002 * rng.standard_normal(20_000)}
    axes = [Axis("gx_dps", "gyro", "deg/s", "given"), Axis("ax_mps2", "accel", "m/s^2", "given")]
    write_imu_noise(imu_noise(columns, axes, 100.0, "imu.csv"), out, TITLE)
    return sorted(out.rglob("*.tex"))


def _workflow(out: Path) -> list[Path]:
    """The six-axis workflow's own tables (its axes' reports are the kinds above)."""
    from data_synth import make_scenario
    from fosmodel.workflows.imu import ImuConfig, run_imu
    from fosmodel.workflows.imu_report import write_imu_tables

    rec = make_scenario("static_imu", duration=300.0, seed=3)
    axes = [Axis("gy_dps", "gyro", "deg/s", "given"), Axis("ax_mps2", "accel", "m/s^2", "given")]
    result = run_imu(rec.columns, axes, rec.rate, "static_imu.csv", config=ImuConfig(
        orders=(1, 2), methods=("fos", "burg"), train_s=60.0, evaluate_s=60.0, n_jobs=1))
    write_imu_tables(result, out, TITLE)
    return sorted(out.glob("*.tex"))


def _summary(out: Path) -> list[Path]:
    model = FOSModel(max_lag=3, degree=2, stop="max_terms", max_terms=4).fit(_ar(3000, 6))
    path = out / "summary.tex"
    out.mkdir(parents=True, exist_ok=True)
    path.write_text(model.summary().as_latex())
    return [path]


WRITERS = {"special": _special_table, "study": lambda out: _studies(out, (0,)),
           "studies": lambda out: _studies(out, (1, 2)), "loop": _loop,
           "allan": _allan, "imu": _imu, "workflow": _workflow, "summary": _summary}
EXPECTED = {"special": {"special"}, "study": {"comparison", "study", "best", "level"},
            "studies": {"best", "comparison", "study", "level"},
            "loop": {"effects", "ratios", "diagnostics"}, "allan": {"allan", "noise"},
            "imu": {"noise", "noise_si", "allan"},
            "workflow": {"noise", "study", "loop", "timing"}, "summary": {"summary"}}


# the commands that run whole studies or analyses to write their tables are the long ones
_LONG = {"imu", "studies", "workflow"}


@pytest.fixture(scope="module", params=[pytest.param(name, marks=pytest.mark.slow)
                                        if name in _LONG else name for name in sorted(WRITERS)])
def tex_files(request, tmp_path_factory) -> list[Path]:
    out = tmp_path_factory.mktemp(request.param)
    files = WRITERS[request.param](out)
    assert {p.stem for p in files} == EXPECTED[request.param]
    return files


def test_every_table_passes_the_strict_check(tex_files):
    for path in tex_files:
        assert structural_problems(path.read_text()) == [], path


@pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed (.ci/run installs it "
                    "with apt-get where it runs as root); the strict check still ran")
def test_every_table_compiles_with_pdflatex(tex_files, tmp_path):
    for i, path in enumerate(tex_files):
        workdir = tmp_path / str(i)
        workdir.mkdir()
        _compile(path.read_text(), workdir)


# -- the check bites, and the helpers say what they do ----------------------------------------


@pytest.mark.parametrize(("broken", "problem"), [
    ("x_y", "'_' unescaped"), ("50 %", "'%' unescaped"), ("a^2", "'^' unescaped"),
    ("#1", "'#' unescaped"), ("{x}", "a bare '{'"), ("a & b", "cells where the spec"),
    ("$x", "a math mode is not closed"), ("\\begin{center}", "not closed")])
def test_the_strict_check_finds_what_would_not_compile(broken, problem):
    good = latex_table(pd.DataFrame({"a": ["x"], "b": [1.0]}), "caption", table_label("t"))
    assert structural_problems(good) == []
    bad = good.replace("x & 1", f"{broken} & 1")
    found = (structural_problems(bad) if problem != "a math mode is not closed"
             else pytest.raises(AssertionError, structural_problems, bad).value.args)
    assert any(problem in text for text in found), found


def test_units_numbers_and_labels():
    assert latex_text("MSE (m/s^2)^2") == "MSE (m/s$^{2}$)$^{2}$"
    assert latex_text("deg/h/sqrt(h)") == r"deg/h/$\sqrt{\mathrm{h}}$"
    assert latex_text("gx_dps 5 % a^b") == r"gx\_dps 5 \% a\textasciicircum{}b"
    assert [latex_number(v) for v in (1e-05, -0.25, 123456.0, 0.001234, np.nan)] == [
        r"$1\times10^{-5}$", "$-0.25$", r"$1.235\times10^{5}$", "0.001234", "--"]
    assert table_label("Table 1: accel_y (m/s^2)", "comparison") == (
        "tab:fosmodel-table-1-accel-y-m-s-2-comparison")


def test_the_tables_have_booktabs_rules_a_caption_and_the_reports_label(tmp_path):
    (path,) = _special_table(tmp_path)
    text = path.read_text()
    assert text.startswith("% a fosmodel table: \\usepackage{booktabs}\n"
                           "\\begin{table}[htbp]\n\\centering\n"
                           "\\caption{Every special character: "
                           "\\_ \\textasciicircum{} \\% \\& \\# \\$ \\{ \\} "
                           "\\textasciitilde{} \\textbackslash{}}\n"
                           "\\label{tab:fosmodel-gx-dps-1-m-s-2-5-x-back-slash-special}\n"
                           "\\begin{tabular}{rrll}\n\\toprule\n")
    # the heads over the units, in a second row
    assert ("gx\\_dps & N & text \\& more & mixed \\\\\n"
            " & (deg/s/$\\sqrt{\\mathrm{Hz}}$) &  &  \\\\\n\\midrule\n") in text
    # a column of numbers in one format: 1e-05 and -2.5 both with four significant digits
    assert "$1.000\\times10^{-5}$ & 1 & a\\_b\\textasciicircum{}c & -- \\\\" in text
    assert "$-2.500$ & $-2$ & 50 \\% of \\#1 & 0.25 \\\\" in text
    assert "-- & 300000 & \\{braces\\} \\textasciitilde{} \\$5 & y[n-1]$^{2}$ \\\\" in text
    assert "$\\infty$ & 4 & back\\textbackslash{}slash & yes \\\\\n\\bottomrule" in text

# -- tables laid out for the page --------------------------------------------------------------


def test_a_column_of_numbers_has_one_format_that_tells_its_values_apart():
    from fosmodel.typeset.tables import number_format

    def column(values, digits=4):
        fmt = number_format(values, digits)
        return [fmt(v).source for v in values]

    assert column([0.11237, 0.11239, 0.1125]) == ["0.11237", "0.11239", "0.11250"]
    assert column([15.05, 10.7, 17.6]) == ["15.05", "10.70", "17.60"]
    assert column([1.0, 10.0, 300.0]) == ["1", "10", "300"]
    assert column([4.2e-4, 0.035, 2.2e5, np.nan]) == [
        r"$4.200\times10^{-4}$", r"$3.500\times10^{-2}$", r"$2.200\times10^{5}$", "--"]
    assert column([-0.5, 0.25]) == ["$-0.5000$", "0.2500"]


def test_a_head_is_its_name_over_its_units():
    from fosmodel.typeset.tables import head_lines, split_head

    assert split_head("Outage position error (m, 30 s)") == ("Outage position error",
                                                             "(m, 30 s)")
    assert split_head("MSE (deg/s)^2") == ("MSE", "(deg/s)^2")
    assert split_head("N (deg/s/sqrt(Hz))") == ("N", "(deg/s/sqrt(Hz))")
    assert split_head("Terms") == ("Terms", "")
    assert head_lines("Outage position error", 40.0) == ["Outage", "position error"]
    assert head_lines("MSE", 40.0) == ["MSE"]


def _frame(rows: int, numbers: int, text: int = 2) -> pd.DataFrame:
    rng = np.random.default_rng(rows + numbers)
    columns = {f"Key {k}": [f"method {i % 7}" for i in range(rows)] for k in range(text)}
    columns.update({f"Outage error {k} (m, 30 s)": rng.lognormal(0.0, 0.5, rows)
                    for k in range(numbers)})
    return pd.DataFrame(columns)


@pytest.mark.parametrize(("rows", "numbers", "shape"), [
    (10, 4, dict(landscape=False, long=False, parts=1)),
    (10, 8, dict(landscape=True, long=False, parts=1)),
    (10, 16, dict(landscape=True, long=False, parts=2)),
    (120, 4, dict(landscape=False, long=True, parts=1)),
    (120, 16, dict(landscape=True, long=True, parts=2)),
])
def test_a_table_is_set_the_first_way_that_fits_the_page(rows, numbers, shape, tmp_path):
    """As it is; landscape; in parts repeating the text columns; a longtable when long."""
    from fosmodel.typeset.tables import choose_layout, columns_of

    frame = _frame(rows, numbers)
    layout = choose_layout(columns_of(frame), len(frame))
    assert (layout.landscape, layout.long, len(layout.parts)) == (
        shape["landscape"], shape["long"], shape["parts"])
    assert all(part[:2] == (0, 1) for part in layout.parts)  # the key columns in every part
    source = latex_table(frame, "A table of outages", table_label("t", str(rows)))
    assert source.count("\\begin{landscape}") == (len(layout.parts) if layout.landscape else 0)
    assert source.count("\\begin{longtable}") == (len(layout.parts) if layout.long else 0)
    assert structural_problems(source) == []
    if PDFLATEX:
        assert _page_problems({"t.tex": source}, tmp_path) == {}


def _page_problems(sources: dict[str, str], workdir: Path) -> dict[str, list[str]]:
    """Compile the tables in one plain article (twice: longtable settles its widths) and say,
    per table, what does not fit a page: an overfull line over 10 pt, a float too large."""
    body = ""
    for name, source in sources.items():
        (workdir / f"t{len(body)}.tex").write_text(source)
        body += f"\\typeout{{FOSMODEL TABLE {name}}}\n\\input{{t{len(body)}.tex}}\n\\clearpage\n"
    (workdir / "all.tex").write_text(PREAMBLE + body + "\\end{document}\n")
    for _ in range(2):
        run = subprocess.run([PDFLATEX, "-interaction=nonstopmode", "all.tex"], cwd=workdir,
                             capture_output=True, text=True, timeout=600,
                             stdin=subprocess.DEVNULL)
    assert run.returncode == 0, run.stdout[-2000:]
    found: dict[str, list[str]] = {}
    table = None
    for line in (workdir / "all.log").read_text(errors="replace").splitlines():
        if line.startswith("FOSMODEL TABLE "):
            table = line.removeprefix("FOSMODEL TABLE ")
        overfull = re.search(r"Overfull \\hbox \(([0-9.]+)pt too wide\)", line)
        if overfull and float(overfull[1]) > 10 or "Float too large for page" in line:
            found.setdefault(str(table), []).append(line.strip())
    return found


@pytest.mark.slow
@pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed (.ci/run installs it "
                    "with apt-get where it runs as root)")
def test_every_table_the_commands_write_on_a_10_minute_record_fits_a_page(tmp_path, capsys):
    """``study``, ``allan --columns``, ``close-loop`` and ``imu`` on a 10-minute six-axis record:
    each of their tables compiles in a plain article (booktabs, default margins) with no line
    overfull by more than 10 pt and no float too large for its page."""
    from fosmodel.cli import main

    record = tmp_path / "rec.csv"
    assert main(["synth", "static_imu", "--duration", "600", "--seed", "1", "--out",
                 str(record)]) == 0
    out = tmp_path / "out"
    for args in (["study", "--column", "gx_dps"],
                 ["allan", "--columns", "gx_dps,gy_dps,gz_dps,ax_mps2,ay_mps2,az_mps2"],
                 ["close-loop", "--column", "gx_dps"], ["imu"]):
        assert main([args[0], str(record), *args[1:], "--out", str(out / args[0])]) == 0
    capsys.readouterr()
    tables = sorted(out.rglob("*.tex"))
    assert len(tables) >= 70  # 74 with the effects the loop keeps on this record
    sources = {str(t.relative_to(out)): t.read_text() for t in tables}
    assert {name: p for name, s in sources.items() if (p := structural_problems(s))} == {}
    work = tmp_path / "tex"
    work.mkdir()
    assert _page_problems(sources, work) == {}


@pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed")
def test_the_page_check_finds_a_table_too_wide_and_a_float_too_long(tmp_path):
    wide = ("\\begin{table}[htbp]\n\\begin{tabular}{" + "r" * 12 + "}\n"
            + " & ".join(["1234567.89"] * 12) + " \\\\\n\\end{tabular}\n\\end{table}\n")
    long = ("\\begin{table}[htbp]\n\\begin{tabular}{r}\n" + "1 \\\\\n" * 80
            + "\\end{tabular}\n\\end{table}\n")
    found = _page_problems({"wide": wide, "long": long}, tmp_path)
    assert set(found) == {"wide", "long"}
    assert "Overfull \\hbox" in found["wide"][0]
    assert "Float too large for page" in found["long"][0]


def test_a_power_of_ten_is_estimated_as_wide_as_latex_sets_it():
    r"""pdflatex sets ``$4.456\times10^{-4}$`` 55.74 pt wide and ``$4.456\times10^{4}$``
    49.49 pt (``\settowidth``): the operator's spaces, the 7 pt power, the math minus."""
    from fosmodel.typeset.tables import _scientific, text_cell

    assert _scientific(4.456e-4).width == pytest.approx(55.74, abs=0.1)
    assert _scientific(4.456e4).width == pytest.approx(49.49, abs=0.1)
    assert text_cell(4.456e-7).width == pytest.approx(55.74, abs=0.1)  # among text


#: The noise terms of an accelerometer axis with a sinusoid (ADIS16405 session 1, az in g):
#: six scientific columns and ``acceleration random walk``, 15 pt over a landscape page when
#: a power of ten was taken for 7 pt narrower than it is.
_ACCEL_NOISE = pd.DataFrame({
    "Term": list("QNBKRS"),
    "Noise": ["quantization", "velocity random walk", "bias instability",
              "acceleration random walk", "rate ramp", "sinusoid"],
    "Coefficient": [None, 4.456e-4, 2.937e-4, 2.279e-5, None, 7.242e-4],
    "Std. error": [None, 4.769e-6, 1.823e-5, 5.542e-6, None, 1.910e-5],
    "Lower 68 %": [None, 4.409e-4, 2.771e-4, 1.882e-5, None, 7.058e-4],
    "Upper 68 %": [None, 4.504e-4, 3.138e-4, 3.121e-5, None, 7.440e-4],
    "Upper limit": [1.451e-5, None, None, None, 7.171e-7, None],
    "Read-off": [None, 6.481e-4, 3.389e-4, 3.539e-5, None, None],
    "Units": ["g*s", "g*sqrt(s)", "g", "g/sqrt(s)", "g/s", "g"],
    "Navigation": [None, 0.2622, 0.2937, 48.28, None, 0.7242],
    "Navigation upper limit": [1.423e-4, None, None, None, 91.15, None],
    "Navigation read-off": [None, 0.3814, 0.3389, 74.97, None, None],
    "Navigation units": ["m/s", "m/s/sqrt(h)", "mg", "m/s/h/sqrt(h)", "m/s/h^2", "mg"],
    "Resolved": ["no", "yes", "yes", "yes", "no", "yes"]}).astype(object)


@pytest.mark.skipif(PDFLATEX is None, reason="pdflatex is not installed")
def test_an_accelerometer_s_noise_table_fits_its_page(tmp_path):
    source = latex_table(_ACCEL_NOISE, "imu1.csv.gz: az_g: IEEE Std 952 noise terms fitted "
                         "to the Allan deviation", table_label("imu1", "az_g"))
    assert structural_problems(source) == []
    assert _page_problems({"noise.tex": source}, tmp_path) == {}

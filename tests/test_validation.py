"""The validation suite: its cases, report and ``fempipe validate``.

The quick cases run here (a few seconds each); the full suite is marked slow.
A numerics check that fails is a bug in fempipe, so every quick case must pass
all of them; paper checks may legitimately fail (findings), and the ones whose
outcome is known are asserted explicitly.
"""

from __future__ import annotations

import functools
import json
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from fempipe.cli import main
from fempipe.validation import CASES, load_case, load_references
from fempipe.validation.case import Case, alpha_name
from fempipe.validation.checks import CaseResult, Check, Table, merge_results
from fempipe.validation.report import render_report
from fempipe.validation.suite import CaseOutcome, SuiteResult, run_case, run_suite

ROOT = Path(__file__).resolve().parents[1]

#: Quick cases run by the default tests (about a minute together); the
#: quick Figs. 7 and 8-10 (~15-20 CPU-s each) run only in ``fempipe validate --quick``
#: (a stage of CI) and the slow full-suite test.
CHEAP = [
    "fig02a",
    "fig02b",
    "fig03",
    "fig04",
    "symmetry",
    "convergence",
    "fig05",
    "fig06",
    "fig11",
    "fig12",
    "end_mass",
    "external_damping",
    "hysteretic",
    "springs",
    "out_of_plane",
    "parametric",
]

#: The quick 3-D cases (about 50 CPU-s together): their numerics run by default too, so
#: that ``fempipe validate --quick`` cannot fail unnoticed.
SPACE_QUICK = ["space_onset", "space_convergence", "space_whirl"]


#: Citations a reader of the repository cannot resolve (written so that a
#: search of the repository for them finds none).
_UNRESOLVABLE = re.compile(r"S[P]EC|[Ii]ssue \d|the tas[k]")


@functools.cache
def quick_result(name: str) -> CaseResult:
    """The quick run of a case, computed once per test session."""
    return load_case(name).run(quick=True)


@pytest.mark.parametrize("name", CHEAP + SPACE_QUICK)
def test_quick_case_numerics_pass(name):
    res = quick_result(name)
    assert isinstance(res, CaseResult)
    failed = [
        (c.name, c.measured, c.tolerance)
        for c in res.checks
        if c.category == "numerics" and not c.passed
    ]
    assert not failed, failed


#: The paper's statements that the quick runs do NOT reproduce, case by case (every
#: other paper check of the case passes).  A change detector, on purpose: a statement
#: of the paper that stops, or starts, being reproduced must be a visible change of
#: this table (and of the report's findings), never a silent one.  The reasons are in
#: the report (e.g. alpha -> alpha - pi is not a symmetry; the paper's N = 3 is not
#: converged for the shapes of Fig. 3).
PAPER_NOT_REPRODUCED_QUICK = {
    "fig02a": set(),
    "fig02b": set(),
    "fig03": {"modal_3_shape", "modal_4_shape"},
    "fig04": set(),
    "symmetry": {"paper_alpha_minus_pi"},
    "convergence": set(),
    "fig05": {"pi_no_hysteresis"},
    "fig06": {"falls_with_alpha_b0.142", "falls_with_alpha_g30", "flutter", "out_of_plane_first"},
    "fig11": {"period_π/2_3", "range_π/2_3", "range_π/2_4"},
    "fig12": set(),
    "end_mass": set(),
    "external_damping": set(),
    "hysteretic": {"omega_cf_b0.23_muh", "u_cf_b0.23_mu0", "u_cf_b0.23_muh"},
    "springs": set(),
    "out_of_plane": {"planar_v_cr_is_first"},
    "parametric": {"table45_mode3"},
}

#: The same for the full runs (``fempipe validate``, the committed report).
PAPER_NOT_REPRODUCED_FULL = {
    **{name: set() for name in ("fig02a", "fig02b", "fig12", "convergence", "end_mass")},
    **{name: set() for name in ("external_damping", "springs")},
    **{name: set() for name in ("space_onset", "space_convergence", "space_whirl")},
    "fig03": {"modal_3_shape", "modal_4_shape"},
    "fig04": {"modal_3_shape"},
    "fig05": {"pi_no_hysteresis"},
    "fig06": {
        "flutter",
        "falls_with_alpha_b0.1",
        "falls_with_alpha_b0.142",
        "falls_with_alpha_g30",
    },
    "fig07": {"n3_vs_fe", "n4_vs_fe"},
    "fig08_10": {"paper_bracket_π/4"}
    | {f"n{n}_vs_fe_{a}" for n in (3, 4) for a in ("π/4", "π/2", "3π/4", "π")},
    "fig11": {f"{q}_{a}_3" for q in ("period", "range") for a in ("π/4", "π/2", "3π/4", "π")}
    | {"range_π/2_4", "range_3π/4_4", "period_π_4"},
    "symmetry": {"paper_alpha_minus_pi"},
    "hysteretic": {"u_cf_b0.23_mu0", "u_cf_b0.23_muh", "omega_cf_b0.23_muh"},
    "out_of_plane": {"planar_v_cr_is_first"},
    "parametric": {"table45_mode3"},
}


def _paper_not_reproduced(res: CaseResult) -> set[str]:
    return {c.name for c in res.checks if c.category == "paper" and not c.passed}


@pytest.mark.parametrize("name", CHEAP)
def test_which_paper_statements_are_reproduced(name):
    """Which of the paper's statements the quick run reproduces: exactly the known ones."""
    assert _paper_not_reproduced(quick_result(name)) == PAPER_NOT_REPRODUCED_QUICK[name]


@pytest.mark.parametrize("name", CHEAP)
def test_every_check_states_tolerance_and_source(name):
    """Each check says its tolerance and a source a reader of the repository can look up."""
    res = quick_result(name)
    assert res.paper_shows, "a case must say what the paper shows"
    assert res.checks
    for c in res.checks:
        assert c.tolerance.strip() and c.source.strip() and c.claim.strip(), c
        assert not _UNRESOLVABLE.search(f"{c.claim} {c.tolerance} {c.source}"), c
    json.dumps(res.to_dict(), allow_nan=False)  # strict JSON


@pytest.mark.parametrize("name", CHEAP)
def test_case_draws_its_figure(name):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig = load_case(name).plot(quick_result(name))
    assert fig.axes and any(ax.lines for ax in fig.axes)
    plt.close(fig)


@pytest.mark.parametrize("name", CASES)
def test_reference_files_have_sources(name):
    """Every case has its reference file; every number in it has a resolvable source."""
    refs = load_references(name)
    assert refs.about.strip() and not _UNRESOLVABLE.search(refs.about)
    for key, entry in refs.entries.items():
        assert entry["source"].strip(), key
        assert not _UNRESOLVABLE.search(entry["source"]), (key, entry["source"])


@pytest.mark.parametrize("name", CASES)
def test_every_case_declares_itself(name):
    """Each case module declares one Case named after it, and its entry points."""
    module = load_case(name)
    assert isinstance(module.CASE, Case) and module.CASE.name == name
    assert callable(module.run) and callable(module.plot)


def test_import_error_fails_the_case(monkeypatch):
    """A module that does not import is an error of the case, never a skipped case."""
    monkeypatch.setitem(sys.modules, "fempipe.analyses.stability", None)
    monkeypatch.delitem(sys.modules, "fempipe.validation.fig05", raising=False)
    outcome = run_case("fig05", quick=True)
    assert outcome.status == "error"
    assert "ModuleNotFoundError" in outcome.error and "fempipe.analyses.stability" in outcome.error
    assert not outcome.ok


def test_check_to_dict_is_strict_json():
    """Non-finite numbers, also inside arrays, become null (strict JSON)."""
    c = Check("x", "x", "numerics", False, np.array([1.0, np.nan]), np.float64(np.inf), "t", "s")
    d = c.to_dict()
    assert d["measured"] == [1.0, None] and d["reference"] is None
    json.dumps(d, allow_nan=False)


def test_alpha_name():
    """Inclinations print as multiples of π (the check names and tables use them)."""
    cases = {0.0: "0", np.pi / 4: "π/4", np.pi: "π", 3 * np.pi / 4: "3π/4", -2 * np.pi / 3: "-2π/3"}
    cases[9 * np.pi / 10] = "9π/10"
    cases[1.0] = "1.0000"
    for a, name in cases.items():
        assert alpha_name(a) == name


def test_alpha_minus_pi_is_not_a_symmetry():
    """The paper's closing remark of Sec. 5 is wrong; the true symmetry holds."""
    res = quick_result("symmetry")
    checks = {c.name: c for c in res.checks}
    assert checks["mirror_symmetry"].passed
    assert not checks["paper_alpha_minus_pi"].passed
    assert res.findings


def test_static_convergence_orders():
    """FE tip values converge as h^(2k); independent of the checks' own tolerance."""
    study = quick_result("convergence").data["studies"][0]
    orders = {k: s.order for k, s in study.series.items()}
    assert orders["FE P1"] == pytest.approx(2.0, abs=0.3)
    assert orders["FE P2"] == pytest.approx(4.0, abs=0.3)
    assert orders["FE P3"] == pytest.approx(6.0, abs=0.3)
    # The paper's N = 4 is worse than P3 on 16 elements by orders of magnitude.
    assert abs(study.paper_modes[4] - study.reference) > 1e-6


def test_fig02b_eq29():
    names = {c.name: c.passed for c in quick_result("fig02b").checks}
    assert names["beta"] and names["gamma"] and names["v_over_U"]


def test_check_category_is_checked():
    with pytest.raises(ValueError, match="category"):
        Check("x", "x", "wrong", True, 1, 1, "t", "s")


def test_merge_results_of_parts():
    """Parts of a split case merge into one result: checks, table rows, data, runtime."""

    def part(k):
        c = Check(f"c{k}", "claim", "numerics", True, k, k, "t", "s")
        t = Table("T", ("a",), ((k,),))
        return CaseResult("x", "Fig", "t", ("s",), (c,), (t,), data={"panels": {k: k}}, runtime=1.0)

    m = merge_results([part(1), part(2)])
    assert [c.name for c in m.checks] == ["c1", "c2"]
    assert m.tables[0].rows == ((1,), (2,)) and m.data["panels"] == {1: 1, 2: 2}
    assert m.runtime == 2.0


def _fake_suite(passed: bool) -> SuiteResult:
    check = Check("c", "a claim", "numerics", passed, 1.0, 2.0, "tol", "src")
    finding = Check("p", "a paper claim", "paper", False, 3.0, 4.0, "tol", "paper Fig. 9")
    res = CaseResult(
        "fake",
        "Fig. 0",
        "fake case",
        ("it shows",),
        (check, finding),
        tables=(Table("t", ("a", "b|c"), ((1.0, "x|y"),)),),
    )
    return _one_case_suite("fake", res)


def _one_case_suite(name: str, res: CaseResult) -> SuiteResult:
    """A quick suite of the one case ``name`` that returned ``res``."""
    return SuiteResult(
        (CaseOutcome(name, "ok", result=res),),
        quick=True,
        workers=1,
        wall_time=1.5,
        started="now",
        environment={"workers": 1},
    )


def test_report_marks_failures_and_findings():
    bad = render_report(_fake_suite(False))
    assert "**FAIL**" in bad and "❌ FAIL" in bad
    good = render_report(_fake_suite(True))
    assert "**PASS**" in good and "❌" not in good
    # the failed paper check is listed as a finding with its measurement
    assert "a paper claim" in good.split("## Findings")[1].split("<a id")[0]
    assert "b\\|c" in good  # table cells are escaped


def test_run_suite_records_errors(monkeypatch, tmp_path):
    """A case that raises is recorded, the suite goes on and is not ok."""
    import fempipe.validation.fig02b as case

    def boom(quick=False):
        raise RuntimeError("boom")

    monkeypatch.setattr(case, "run", boom)
    suite = run_suite(quick=True, cases=["fig02b", "symmetry"], out=tmp_path)
    status = {o.name: o.status for o in suite.outcomes}
    assert status == {"fig02b": "error", "symmetry": "ok"}
    assert not suite.ok
    assert (tmp_path / "symmetry.png").exists()


def test_cli_validate_quick_subset(tmp_path, capsys):
    code = main(
        [
            "validate",
            "--quick",
            "--case",
            "fig02b,symmetry",
            "--out",
            str(tmp_path),
            "--workers",
            "2",
            "--json",
            "--quiet",
        ]
    )
    out = json.loads(capsys.readouterr().out)
    assert code == 0
    assert out["ok"] is True and [c["name"] for c in out["cases"]] == ["fig02b", "symmetry"]
    report = (tmp_path / "REPORT.md").read_text()
    assert "Runtime:" in report and "fig02b.png" in report
    assert (tmp_path / "fig02b.png").stat().st_size > 1000
    assert json.loads((tmp_path / "results.json").read_text())["quick"] is True


@pytest.mark.parametrize(
    "argv, option",
    [
        (["--workers", "0"], "--workers"),
        (["--workers", "two"], "--workers"),
        (["--case", "fig99"], "--case"),
    ],
)
def test_cli_validate_bad_input(argv, option, capsys, tmp_path):
    code = main(["validate", "--out", str(tmp_path), *argv])
    err = capsys.readouterr().err.strip()
    assert code == 2
    assert (
        len(err.splitlines()) == 1 and option in err and err.startswith("fempipe validate: error:")
    )


def test_cli_validate_list(capsys):
    assert main(["validate", "--list"]) == 0
    assert "fig02b" in capsys.readouterr().out


def test_tutorial_runs(tmp_path):
    """The literate tutorial runs top to bottom and writes its plot."""
    script = ROOT / "validation" / "tutorial.py"
    proc = subprocess.run(
        [sys.executable, str(script), "--out", str(tmp_path)],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr
    assert (tmp_path / "tutorial_convergence.png").exists()
    orders = [float(line.split("p =")[1]) for line in proc.stdout.splitlines() if "p =" in line]
    assert np.allclose(orders[:3], [2, 4, 6], atol=0.3)
    # Section 9: the API study of the same case, sine and beam modes included.
    api = {
        line.split()[0]: float(line.split("observed order")[1].split()[0])
        for line in proc.stdout.splitlines()
        if "observed order" in line and line.split()[0].startswith(("fe-", "modal-"))
    }
    expected = {"fe-P1": 2, "fe-P2": 4, "fe-P3": 6, "modal-sine": 3, "modal-beam": 4}
    assert api == pytest.approx(expected, abs=0.3)


@pytest.mark.slow
def test_full_suite(tmp_path):
    """The whole suite, full versions: every case runs and passes its numerics."""
    suite = run_suite(quick=False, out=tmp_path, workers=2)
    bad = [
        (o.name, o.status, o.error[-300:])
        for o in suite.outcomes
        if o.status == "error" or (o.result is not None and not o.result.numerics_passed)
    ]
    assert not bad, bad
    assert {o.name for o in suite.outcomes if o.status == "ok"} == set(CASES)
    assert {
        o.name: _paper_not_reproduced(o.result) for o in suite.outcomes
    } == PAPER_NOT_REPRODUCED_FULL


def _truncation_suite() -> SuiteResult:
    """A fake case with one real finding, the paper's truncations and a long table."""
    checks = (
        Check("x", "v_cr falls as α grows", "paper", False, "rises by 0.01", "falls", "tol", "s"),
        Check("m3", "N = 3 reproduces the converged period", "paper", False, 0.03, 0.02, "t", "s"),
        Check("m4", "N = 4 reproduces the converged period", "paper", True, 0.01, 0.02, "t", "s"),
    )
    res = CaseResult(
        "fake",
        "Fig. 0",
        "fake case",
        ("it shows",),
        checks,
        tables=(Table("long", ("i",), tuple((i,) for i in range(100))),),
        caption="a caption",
        not_checked=("an experiment",),
    )
    return SuiteResult(
        (CaseOutcome("fake", "ok", result=res, figure="a.png", figures=("a.png", "b.png")),),
        quick=True,
        workers=1,
        wall_time=1.5,
        started="now",
        environment={"workers": 1},
    )


def test_report_findings_first_and_truncations_in_one_table(tmp_path):
    text = render_report(_truncation_suite(), tables_dir=tmp_path)
    findings = text.split("## Findings")[1].split("## Summary")[0]
    assert text.index("## Findings") < text.index("## Summary")
    # the real finding is numbered, the truncation checks are one table row
    assert "1. **Fig. 0** (fake): “v_cr falls as α grows”" in findings
    assert "2. " not in findings
    assert "| Fig. 0 | the converged period | 0.03 ⚠️ | 0.01 | t |" in findings
    # statements not checked are said so, and counted nowhere
    assert "Not checked" in text and "an experiment" in text
    # every figure embedded, with its caption; a long table goes to a linked CSV
    assert "![Fig. 0](a.png)" in text and "![Fig. 0](b.png)" in text
    assert "*Fig. 0.* a caption" in text
    assert "[fake_table1.csv](fake_table1.csv)" in text
    rows = (tmp_path / "fake_table1.csv").read_text().splitlines()
    assert rows[0] == "i" and len(rows) == 101
    # a source cited by three checks is defined once and cited by its label
    assert "- **S1**: s" in text and text.count("[S1](#sources)") == 3


def test_a_case_section_stays_within_its_budget(tmp_path):
    """A case with 25 short tables of 20 rows (each inline on its own) and 40 checks with long
    reasons: its section takes at most CASE_BUDGET bytes; the largest tables, then the checks'
    reasons and sources, go to linked CSV files that keep every row and every reason."""
    import csv
    import re

    from fempipe.validation.report import CASE_BUDGET

    why = "a reason of some length, " * 8
    checks = tuple(
        Check(f"c{k}", f"claim {k}", "numerics", True, 1e-9 * k, 1e-6, f"≤ 1e-06; {why}", f"s{k}")
        for k in range(40)
    )
    tables = tuple(
        Table(f"t{j}", ("a", "b"), tuple((i, 0.5 * i) for i in range(20))) for j in range(25)
    )
    res = CaseResult("big", "Fig. 9", "big case", ("it shows",), checks, tables=tables)
    text = render_report(_one_case_suite("big", res), tables_dir=tmp_path)
    section = re.split(r"\n(?=## )", text)
    (big,) = [s for s in section if s.startswith("## Fig. 9")]
    assert len(big.encode()) <= CASE_BUDGET
    assert "[big_checks.csv](big_checks.csv)" in big and "| ≤ 1e-06 |" in big
    with open(tmp_path / "big_checks.csv", newline="") as f:
        rows = list(csv.reader(f))
    assert len(rows) == 41 and all(why in r[6] for r in rows[1:])
    linked = re.findall(r"\[(big_table\d+\.csv)\]", big)
    assert linked and all(len((tmp_path / n).read_text().splitlines()) == 21 for n in linked)
    assert len(linked) + big.count("| a | b |") == 25  # every table, inline or linked

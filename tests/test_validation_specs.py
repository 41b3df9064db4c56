"""The check specs of the validation cases: the evaluator's verdicts and the reference files.

Every check of a case is data in ``fempipe/validation/references/<case>.json`` (claim,
limit or reference, tolerance, why, source) judged by :func:`fempipe.validation.evaluate.
evaluate`; the case only measures.  Here: the verdicts on values just inside and just outside
a tolerance, the templates, the required checks, and that the files and the cases agree
(no spec that no run uses, no check without a spec).
"""

from __future__ import annotations

import functools
import json
import math
import re

import pytest
from test_validation import CHEAP, ROOT, SPACE_QUICK, quick_result

from fempipe.validation import CASES
from fempipe.validation import case as case_module
from fempipe.validation.case import Case, References, load_references
from fempipe.validation.evaluate import Measured, evaluate, fill, measure

REFS = References(
    "demo",
    "demo references",
    {
        "tol": {"value": 1e-6, "source": "why the tolerance is 1e-6"},
        "printed": {"value": 20.05, "source": "the paper, Table 1"},
        "v": {"value": [0.0, 2.0, 4.0], "source": "chosen"},
        "v_quick": {"value": [0.0, 4.0], "source": "chosen for the quick suite"},
    },
)


def _check(spec: dict, m: Measured, quick: bool = False):
    return evaluate(spec, m, REFS.names(quick))


BELOW = {"kind": "below", "claim": "x", "limit": "{tol}", "why": "{sources[tol]}", "source": "s"}


@pytest.mark.parametrize(("value", "passed"), [(1e-6, True), (0.99e-6, True), (1.01e-6, False)])
def test_below_just_inside_and_outside(value, passed):
    c = _check(BELOW, measure("x", value))
    assert c.passed is passed
    assert c.reference == 1e-6 and c.measured == value
    assert c.tolerance == "≤ 1e-06; why the tolerance is 1e-6" and c.category == "numerics"


@pytest.mark.parametrize(
    ("spec", "value", "passed"),
    [
        ({"atol": 0.005}, 20.0549, True),
        ({"atol": 0.005}, 20.0551, False),
        ({"atol": 0.005}, 20.0451, True),
        ({"atol": 0.005}, 20.0449, False),
        ({"rtol": 1e-3}, 20.05 * (1 + 0.99e-3), True),
        ({"rtol": 1e-3}, 20.05 * (1 + 1.01e-3), False),
    ],
)
def test_close_just_inside_and_outside(spec, value, passed):
    base = {"kind": "close", "claim": "v² = {reference}", "reference": "{printed}", "why": "w"}
    c = _check(
        {**base, **spec, "source": "{sources[printed]}", "category": "paper"}, measure("x", value)
    )
    assert c.passed is passed
    assert (c.claim, c.reference, c.source) == ("v² = 20.05", 20.05, "the paper, Table 1")
    assert c.tolerance.startswith("|Δ| ≤ ") and c.category == "paper"


def test_holds_takes_the_case_verdict_and_a_measured_template():
    spec = {"kind": "holds", "claim": "grows", "measured": "values {v:.1f}", "source": "s"}
    ok = _check(spec, measure("x", ok=True, v=[1.0, 2.0]))
    assert ok.passed and ok.measured == "values 1.0, 2.0" and ok.reference is True
    assert ok.tolerance == "qualitative statement" and ok.category == "paper"
    bad = _check({**spec, "reference": "> {tol:g}"}, measure("x", ok=False, v=[]))
    assert not bad.passed and bad.reference == "> 1e-06"


def test_numbers_from_the_measurement_and_family_names():
    spec = {"kind": "below", "claim": "α = {alpha:π}: {n} modes", "why": "w", "source": "s"}
    c = _check(spec, Measured("err_{n}", 0.5, None, {"limit": 1.0, "n": 3, "alpha": math.pi / 4}))
    assert (c.name, c.claim, c.passed, c.reference) == ("err_3", "α = π/4: 3 modes", True, 1.0)
    with pytest.raises(KeyError, match="limit"):
        _check(spec, measure("err_{n}", 0.5, n=3, alpha=0.0))


def test_templates_read_the_quick_values_in_the_quick_suite():
    assert fill("v = {v:g}", REFS.names(quick=False)) == "v = 0, 2, 4"
    assert fill("v = {v:g}; {sources[v]}", REFS.names(quick=True)) == (
        "v = 0, 4; chosen for the quick suite"
    )
    assert fill("{{literal}} {x!r}", {"x": [1]}) == "{literal} [1]"


def _write(tmp_path, monkeypatch, checks: dict) -> Case:
    data = {"_about": "demo", "caption": "v = {v:g}", "v": {"value": [1.0, 2.5], "source": "s"}}
    (tmp_path / "demo.json").write_text(json.dumps({**data, "checks": checks}), encoding="utf-8")
    monkeypatch.setattr(case_module, "_REFERENCE_DIR", tmp_path)
    return Case("demo", "Fig. 0", "demo", ("it shows",))


def test_required_check_not_measured_fails_the_case(tmp_path, monkeypatch):
    """A check of the file (or a member of a family the run names) that a run does not
    measure becomes a failed numerics check; ``"required": "full"`` only in the full suite."""
    spec = {"kind": "holds", "claim": "c", "source": "s"}
    checks = {n: spec for n in ("a", "b", "c_{k}")} | {"d": spec | {"required": "full"}}
    case = _write(tmp_path, monkeypatch, checks)
    res = case.result([measure("a", 1, ok=True)], quick=True, requires=("c_1",))
    assert [c.name for c in res.checks] == ["a", "b", "c_1"]
    assert [c.passed for c in res.checks] == [True, False, False]
    assert all(c.category == "numerics" for c in res.checks[1:]) and not res.numerics_passed
    assert res.caption == "v = 1, 2.5"
    full = case.result(
        [measure(n, 1, ok=True, k=1) for n in ("a", "b", "c_{k}", "d")],
        quick=False,
        requires=("c_1",),
    )
    assert full.numerics_passed and [c.name for c in full.checks] == ["a", "b", "c_1", "d"]
    assert [c.name for c in case.result([], quick=False).checks] == ["a", "b", "d"]


def test_invalid_specs_are_refused(tmp_path, monkeypatch):
    for bad in (
        {"kind": "below", "claim": "c", "limit": 1, "source": "s"},  # no why
        {"kind": "nearly", "claim": "c", "why": "w", "source": "s"},  # no such kind
        {"kind": "holds", "claim": "c", "source": "s", "limit": 1},  # not a number of holds
    ):
        _write(tmp_path, monkeypatch, {"x": bad})
        with pytest.raises(ValueError, match="check 'x'"):
            load_references("demo")
    case = _write(tmp_path, monkeypatch, {})
    with pytest.raises(KeyError, match="no check 'x'"):
        case.result([measure("x", 1.0)], quick=True)


def _pattern(key: str) -> re.Pattern:
    """A spec's key as a pattern of check names: each ``{placeholder}`` stands for any text."""
    return re.compile(".+".join(re.escape(p) for p in re.split(r"\{[^{}]*\}", key)))


@functools.cache
def _report_names() -> dict[str, set[str]]:
    """The check names of every case in the committed report (a full run)."""
    report = json.loads((ROOT / "validation" / "report" / "results.json").read_text("utf-8"))
    return {
        c["name"]: {k["name"] for k in (c["result"] or {}).get("checks", [])}
        for c in report["cases"]
    }


@pytest.mark.parametrize("name", CASES)
def test_every_spec_is_used_and_every_check_has_one(name):
    """No spec of ``references/<case>.json`` that no run measures (a full run: the committed
    report; a quick run of the cheap cases), no check that has no spec, and every name a
    family's ``"required"`` lists is one of its members."""
    names = set(_report_names().get(name, ()))
    if name in CHEAP + SPACE_QUICK:
        names |= {c.name for c in quick_result(name).checks}
    assert names, name
    patterns = {key: _pattern(key) for key in load_references(name).checks}
    unmatched = sorted(n for n in names if not any(p.fullmatch(n) for p in patterns.values()))
    dead = sorted(k for k, p in patterns.items() if not any(p.fullmatch(n) for n in names))
    assert not unmatched, f"checks without a spec: {unmatched}"
    assert not dead, f"specs that no run measures: {dead}"
    for key, spec in load_references(name).checks.items():
        required = spec.get("required")
        for member in required if isinstance(required, list) else []:
            assert patterns[key].fullmatch(member), (key, member)

"""validation/compare_results.py: the leaf-by-leaf comparison of two validation results."""

from __future__ import annotations

import copy
import importlib.util
import json
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location(
    "compare_results", ROOT / "validation" / "compare_results.py"
)
cr = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(cr)

RESULTS = {
    "quick": False,
    "wall_time": 12.0,
    "environment": {"numpy": "2"},
    "cases": [
        {
            "name": "fig04",
            "wall_time": 1.3,
            "result": {
                "checks": [
                    {"name": "a", "passed": True, "measured": 1.5e-10, "reference": 1e-8},
                    {"name": "b", "passed": False, "measured": 0.25, "reference": 0.2},
                ],
                "tables": [{"rows": [[1.0, 2.0], [3.0, float("nan")]]}],
            },
        },
        {"name": "fig05", "result": {"checks": [{"name": "a", "passed": True, "measured": 3}]}},
    ],
}


def test_identical_results_and_what_the_machine_changes():
    after = copy.deepcopy(RESULTS)
    after["wall_time"] = 99.0
    after["environment"] = {"numpy": "3"}
    after["cases"][0]["wall_time"] = 5.0
    after["cases"].reverse()  # cases and checks are paired by name, not position
    diff = cr.compare(RESULTS, after)
    assert diff["changed"] == diff["missing"] == diff["added"] == []
    assert diff["compared"] == 18


def test_every_kind_of_difference_is_reported(tmp_path, capsys):
    after = copy.deepcopy(RESULTS)
    checks = after["cases"][0]["result"]["checks"]
    checks[0]["measured"] *= 1 + 1e-12  # round-off: the same number
    checks[1]["measured"] = 0.25 + 1e-6  # a number that moved
    checks[1]["passed"] = True  # a verdict flipped
    after["cases"][0]["result"]["tables"][0]["rows"][1][1] = 4.0  # nan -> a number
    del after["cases"][1]
    after["cases"].append({"name": "fig06", "result": {}})
    diff = cr.compare(RESULTS, after)
    paths = [c["path"] for c in diff["changed"]]
    assert paths == [
        "/cases[fig04]/result/checks[b]/passed",
        "/cases[fig04]/result/checks[b]/measured",
        "/cases[fig04]/result/tables[0]/rows[1][1]",
    ]
    assert [c["path"] for c in diff["verdict_flips"]] == [paths[0]]
    assert diff["missing"] == [
        "/cases[fig05]/name",
        "/cases[fig05]/result/checks[a]/name",
        "/cases[fig05]/result/checks[a]/passed",
        "/cases[fig05]/result/checks[a]/measured",
    ]
    assert diff["added"] == ["/cases[fig06]/name"]
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    a.write_text(json.dumps(RESULTS))
    b.write_text(json.dumps(after))
    assert cr.main([str(a), str(b)]) == 1
    out = capsys.readouterr().out
    assert "3 changed (1 verdicts flipped), 4 missing, 1 added" in out
    assert cr.main([str(a), str(a)]) == 0
    assert cr.main([str(a), str(b), "--rtol", "1e-3"]) == 1  # the verdict still differs
    assert cr.main([str(a), str(tmp_path / "none.json")]) == 2

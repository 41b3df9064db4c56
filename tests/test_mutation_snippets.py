"""The mutation check's snippets are where it looks for them (tests/mutation_check.py).

The check itself runs in CI only (minutes); this fast test fails as soon as an edit or a
rename of the model moves a term's snippet, so that the check never tests nothing, and
each guard file it runs exists.
"""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
_spec = importlib.util.spec_from_file_location(
    "mutation_check", ROOT / "tests" / "mutation_check.py"
)
mutation_check = importlib.util.module_from_spec(_spec)
sys.modules[_spec.name] = mutation_check  # its dataclasses look their module up
_spec.loader.exec_module(mutation_check)


def test_every_snippet_occurs_exactly_once_and_every_guard_exists():
    mutations = mutation_check.MUTATIONS
    assert len(mutations) >= 79
    for m in mutations:
        text = (ROOT / m.path).read_text(encoding="utf-8")
        assert text.count(m.old) == 1, (m.model, m.term, m.change, m.path)
        assert m.old != m.new
        for guard in m.tests:
            assert (ROOT / guard.split("::")[0]).is_file(), guard

"""The glossary (docs/glossary.md) against the package: one word per concept.

Every public name of :mod:`fempipe` is in the glossary, every name, option and command the
glossary lists exists, every JSON key it lists is written by the package, and no public name
uses one of the words the vocabulary replaced ("spatial", "space", "three_dimensional").
"""

from __future__ import annotations

import argparse
import ast
import importlib
import re
from pathlib import Path

import pytest

import fempipe
from fempipe.cli import SUBCOMMANDS, build_parser

ROOT = Path(__file__).resolve().parents[1]
GLOSSARY = ROOT / "docs" / "glossary.md"
COLUMNS = ("concept", "cli", "json", "python")


def _rows(text: str) -> list[dict[str, list[str]]]:
    """The table rows of the glossary, each column's backticked words."""
    rows = []
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if not line.startswith("|") or len(cells) != 4 or set(cells[0]) <= {"-"}:
            continue
        if cells[0] == "concept":
            continue
        rows.append({k: re.findall(r"`([^`]+)`", c) for k, c in zip(COLUMNS, cells, strict=True)})
    return rows


ROWS = _rows(GLOSSARY.read_text(encoding="utf-8"))


def _column(name: str) -> list[str]:
    return [w for row in ROWS for w in row[name]]


def _options() -> set[str]:
    options: set[str] = set()
    parser = build_parser()
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for sub in action.choices.values():
                for a in sub._actions:
                    options.update(a.option_strings)
    return options


def _string_literals() -> set[str]:
    found: set[str] = set()
    for path in (ROOT / "fempipe").rglob("*.py"):
        for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
            if isinstance(node, ast.Constant) and isinstance(node.value, str):
                found.add(node.value)
    return found


def test_the_table_is_read():
    assert len(ROWS) > 40
    assert all(row["python"] or row["cli"] for row in ROWS)


def test_every_public_name_is_in_the_glossary():
    listed = set(_column("python"))
    missing = sorted(set(fempipe.__all__) - listed)
    assert not missing, f"public names missing from docs/glossary.md: {missing}"


def test_every_python_name_in_the_glossary_exists():
    for name in _column("python"):
        assert name in fempipe.__all__, f"docs/glossary.md lists {name}, not a public name"
        assert getattr(fempipe, name) is not None


def test_every_command_and_option_in_the_glossary_exists():
    options = _options()
    for word in _column("cli"):
        if word.startswith("fempipe "):
            assert word.split()[1] in SUBCOMMANDS, word
        for token in word.split():
            if token.startswith("--"):
                assert token in options, f"docs/glossary.md lists {token}, no command has it"


def test_every_json_key_in_the_glossary_is_written_by_the_package():
    literals = _string_literals()
    for key in _column("json"):
        assert key in literals, f"docs/glossary.md lists the JSON key {key!r}, not in fempipe/"


REPLACED = re.compile(r"spatial|^space|_space|Space|three_dimensional", re.IGNORECASE)


def _module_public_names() -> list[tuple[str, str]]:
    names = [("fempipe", n) for n in fempipe.__all__]
    for path in sorted((ROOT / "fempipe").rglob("*.py")):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts)
        module = module.removesuffix(".__init__")
        if module.startswith(("fempipe.cli", "fempipe.validation", "fempipe.bench")):
            continue
        tree = ast.parse(path.read_text(encoding="utf-8"))
        for node in tree.body:
            if isinstance(node, ast.Assign) and any(
                isinstance(t, ast.Name) and t.id == "__all__" for t in node.targets
            ):
                names += [(module, e.value) for e in node.value.elts]  # type: ignore[attr-defined]
    return names


def test_no_public_name_uses_a_replaced_word():
    bad = [f"{m}.{n}" for m, n in _module_public_names() if REPLACED.search(n)]
    assert not bad, f"public names with a replaced word (see docs/glossary.md): {bad}"


@pytest.mark.parametrize("word", ["spatial_critical_velocity", "spaceModel", "three_dimensional"])
def test_the_replaced_words_are_caught(word):
    assert REPLACED.search(word)


def test_the_glossary_is_in_the_docs_tree():
    index = (ROOT / "docs" / "index.rst").read_text(encoding="utf-8")
    assert "glossary" in index
    importlib.import_module("fempipe.cli")

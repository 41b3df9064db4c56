"""The README and the documentation sources: the README's Python example runs and
prints the right numbers, the README stays short, the API reference lists every
public name, and the CLI reference is generated from the command's own parser.

No Sphinx build runs in the default suite; ``test_docs_build`` (slow) builds the
site with warnings as errors.
"""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _readme() -> str:
    return (ROOT / "README.md").read_text(encoding="utf-8")


def _between(text: str, marker: str) -> str:
    """The text between ``<!-- marker -->`` and ``<!-- /marker -->``."""
    return text.split(f"<!-- {marker} -->\n", 1)[1].split(f"<!-- /{marker} -->", 1)[0]


def _static_tip_bvp(gamma: float, alpha: float, v: float) -> tuple[float, float]:
    """theta(1) and X_g(1) of Eq. (31a) by collocation, independent of fempipe.

    The strong form theta'' = gamma (1 - xi) sin(theta + alpha) + v^2 sin(theta(1) - theta),
    theta(0) = 0, theta'(1) = 0, with theta(1) as an unknown parameter p (the follower
    force is nonlocal) and X_g' = cos(theta + alpha), X_g(0) = 0 (Eq. (28)).
    """
    from scipy.integrate import solve_bvp

    def rhs(xi, y, p):
        th, dth, _ = y
        return np.vstack(
            [
                dth,
                gamma * (1 - xi) * np.sin(th + alpha) + v**2 * np.sin(p[0] - th),
                np.cos(th + alpha),
            ]
        )

    def bc(ya, yb, p):
        return np.array([ya[0], yb[1], ya[2], yb[0] - p[0]])

    xi = np.linspace(0.0, 1.0, 201)
    guess = np.vstack([-0.5 * xi * (2 - xi), -(1 - xi), xi])  # sagging under gravity
    sol = solve_bvp(rhs, bc, xi, guess, p=[-0.5], tol=1e-10, max_nodes=100000)
    assert sol.status == 0, sol.message
    return float(sol.y[0, -1]), float(sol.y[2, -1])


def test_readme_python_example_matches_an_independent_solution(capsys):
    """The README's example against solve_bvp of the strong form, the groups of Eq. (19)
    computed here from the SI pipe (so PipeSI's conversion is checked too)."""
    code = _between(_readme(), "python-example").split("```python\n", 1)[1].split("```", 1)[0]
    exec(compile(code, "README.md", "exec"), {"__name__": "readme_example"})
    lines = capsys.readouterr().out.splitlines()
    L, EI, m, M, g = 0.094, 1.8e-5, 0.0159, 0.0058, 9.8
    gamma = (m + M) * g * L**3 / EI
    pattern = re.compile(r"U = ([\d.]+) m/s: theta_tip = (\S+) rad, X_tip = (\S+)$")
    parsed = [pattern.match(line) for line in lines]
    assert len(parsed) == 3 and all(parsed), lines
    for match in parsed:
        U, theta_tip, X_tip = (float(s) for s in match.groups())
        v = np.sqrt(M / EI) * U * L
        theta_ref, X_ref = _static_tip_bvp(gamma, np.pi / 2, v)
        # P3:16's tip error is O(h^6) ~ 1e-8 here, the BVP's 1e-10; 8 printed digits
        assert theta_tip == pytest.approx(theta_ref, abs=2e-8), U
        assert X_tip == pytest.approx(X_ref, abs=2e-8), U
    # the flow straightens the sagging pipe: the example shows something
    assert float(parsed[2].group(3)) < float(parsed[0].group(3)) - 0.3


def test_readme_is_short_and_keeps_its_commands():
    text = _readme()
    assert len(text.splitlines()) <= 300
    for marker in ("main-command", "test-command", "docs-command"):
        lines = [
            s for s in _between(text, marker).splitlines() if s.strip() and not s.startswith("```")
        ]
        assert len(lines) == 1, marker  # .ci/run's extract() wants exactly one line
        assert lines[0].startswith("python3 -m venv .venv && . .venv/bin/activate && pip install")
    docs_cmd = _between(text, "docs-command")
    assert "'.[docs]'" in docs_cmd and "sphinx -W -b html docs docs/_build/html" in docs_cmd


def test_readme_links_into_the_docs_exist():
    for target in re.findall(r"\]\((docs/[^)#\s]+)", _readme()):
        assert (ROOT / target).is_file(), target


def test_docs_extra_has_what_conf_py_loads():
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    extra = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    names = {
        re.split(r"[<>=\[ ]", req, maxsplit=1)[0].lower()
        for req in extra["project"]["optional-dependencies"]["docs"]
    }
    assert {"sphinx", "numpydoc", "sphinx-gallery", "sphinx-argparse"} <= names
    assert {"pydata-sphinx-theme", "myst-parser", "sphinx-mathjax-offline"} <= names


def test_every_public_name_is_in_the_api_reference():
    import fempipe

    source = (DOCS / "api" / "index.rst").read_text(encoding="utf-8")
    listed = []
    for block in source.split(".. autosummary::")[1:]:
        for line in block.splitlines()[1:]:
            if line and not line.startswith(" "):
                break  # the end of the directive
            listed += re.findall(r"^   (\w+)$", line)
    assert sorted(listed) == sorted(fempipe._LAZY), set(listed) ^ set(fempipe._LAZY)
    assert len(listed) == len(set(listed))  # each name once
    assert ".. currentmodule:: fempipe" in source


def test_cli_reference_is_generated_from_the_real_parser():
    import argparse
    import importlib

    source = (DOCS / "cli" / "reference.rst").read_text(encoding="utf-8")
    options = dict(re.findall(r"^   :(\w+): (\S+)$", source, flags=re.MULTILINE))
    assert ".. argparse::" in source
    parser = getattr(importlib.import_module(options["module"]), options["func"])()
    from fempipe.cli import SUBCOMMANDS, build_parser

    assert isinstance(parser, argparse.ArgumentParser) and options["prog"] == parser.prog
    assert options["module"] == "fempipe.cli" and options["func"] == build_parser.__name__
    # the full parser: every subcommand has its options (not the bare subparsers of main())
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert set(sub.choices) == set(SUBCOMMANDS)
    assert "--alpha" in sub.choices["static"].format_help()


def test_validation_report_splits_into_one_page_per_case(tmp_path):
    """The docs extension that turns the committed report into pages, on a copy."""
    import json
    import shutil

    sys.path.insert(0, str(DOCS / "_ext"))
    try:
        import validation_report
    finally:
        sys.path.remove(str(DOCS / "_ext"))
    shutil.copytree(ROOT / "validation" / "report", tmp_path / "validation" / "report")
    (tmp_path / "docs").mkdir()
    cases = validation_report.generate(tmp_path / "docs", tmp_path)
    results = json.loads((ROOT / "validation" / "report" / "results.json").read_text("utf-8"))
    assert cases == [c["name"] for c in results["cases"]]
    out = tmp_path / "docs" / "report"
    for case in results["cases"]:
        page = (out / f"{case['name']}.md").read_text(encoding="utf-8")
        assert sum(line.startswith("# ") for line in page.splitlines()) == 1, case["name"]
        for fig in case.get("figures", []):
            assert f"]({fig})" in page and (out / fig).is_file(), fig
    index = (out / "index.md").read_text(encoding="utf-8")
    assert "(#" not in index.replace("(#report-sources)", "")  # every in-page link rewritten
    assert "## Reproduce" in index and "{toctree}" in index


@pytest.mark.slow
def test_docs_build(tmp_path):
    """The whole site with warnings as errors (the README's docs command, minus the install;
    CI runs it after that command, which installs the docs extra)."""
    pytest.importorskip("sphinx", reason="the docs extra: pip install '.[docs]'")
    cmd = [sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html", "docs", str(tmp_path)]
    subprocess.run(cmd, cwd=ROOT, check=True)
    assert (tmp_path / "index.html").is_file()
    assert (tmp_path / "cli" / "reference.html").is_file()
    # getting started shows the main job's figure, made by the README's main command
    html = (tmp_path / "getting_started.html").read_text(encoding="utf-8")
    assert re.search(r'<img [^>]*src="_images/shapes\.png"', html)
    assert (tmp_path / "_images" / "shapes.png").stat().st_size > 10_000
    # options printed as typed: "--alpha", never an en or em dash a shell rejects
    for page in ("cli/reference.html", "cli/options.html", "getting_started.html"):
        html = (tmp_path / page).read_text(encoding="utf-8")
        assert "--alpha" in html, page
        assert not re.search("[\u2013\u2014](alpha|U|basis|json|out|planar)\\b", html), page
    # equations render offline: MathJax from the site itself, no page loads a script or a
    # style sheet from another host, and no page has an empty navigation box
    assert (tmp_path / "_static" / "mathjax" / "tex-chtml.js").is_file()
    pages = sorted(tmp_path.rglob("*.html"))
    assert len(pages) > 50
    for path in pages:
        html = path.read_text(encoding="utf-8")
        page = path.relative_to(tmp_path)
        assert not re.search(r'<(script|link)[^>]*(src|href)="(https?:)?//', html), page
        assert '<div class="bd-toc-item navbar-nav"></div>' not in html, page
    html = (tmp_path / "theory" / "model.html").read_text(encoding="utf-8")
    assert re.search(r'<script[^>]*src="\.\./_static/mathjax/tex-chtml\.js"', html)


def test_api_summaries_are_whole_sentences():
    """The API reference's summaries are the docstrings' first sentences as autosummary cuts
    them: at the first period followed by white space.  "Solve Eq. (31a) ..." became "Solve
    Eq."; no first sentence may end on an abbreviation."""
    import inspect

    import fempipe

    cut = []
    for name in sorted(fempipe._LAZY):
        para = " ".join((inspect.getdoc(getattr(fempipe, name)) or "").split("\n\n")[0].split())
        first = re.split(r"\.\s+", para)[0]
        if re.search(r"\b(Eq|Eqs|Fig|Figs|Ref|Sec|cf|vs|al)$", first):
            cut.append((name, first))
    assert not cut, cut


def _literal_blocks(text: str) -> list[str]:
    """The literal blocks of a Markdown page: fenced ones and those indented by four spaces
    after a blank line (outside lists)."""
    blocks = re.findall(r"^```[^\n]*\n(.*?)^```", text, flags=re.S | re.M)
    blocks += re.findall(r"(?:(?<=\n\n)|^)((?:    [^ \-*\d].*\n)+)", text)
    return blocks


def test_equations_are_typeset_not_literal_blocks():
    """Display equations are LaTeX (``$$ ... $$``, rendered by the site's own MathJax), never
    a code block of Unicode: one notation on every page."""
    symbols = re.compile("[\u222b\u03b8\u03be\u03c6\u03c8\u03c7\u03a3\u221a\u2032\u2033]")
    pages = sorted((ROOT / "docs").rglob("*.md"))
    pages = [p for p in pages if "_build" not in p.parts and "_generated" not in p.parts]
    assert len(pages) >= 10
    for page in pages:
        for block in _literal_blocks(page.read_text(encoding="utf-8")):
            assert not symbols.search(block), f"{page.relative_to(ROOT)}: {block[:60]!r}"
    model = (ROOT / "docs" / "theory" / "model.md").read_text(encoding="utf-8")
    assert "$$\n-\\theta''" in model

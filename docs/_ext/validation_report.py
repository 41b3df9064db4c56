"""Sphinx extension: one docs page per case of the committed validation report.

``fempipe validate --out validation/report`` writes ``REPORT.md`` (one ``##``
section per case, each after an ``<a id="CASE"></a>`` anchor), ``results.json``
and the figures and tables the sections link to.  At ``builder-inited`` this
extension splits ``REPORT.md`` into ``docs/report/index.md`` (the overview:
headline, findings, summary table, sources, how to reproduce) and
``docs/report/CASE.md`` (one page per case), rewrites the report's in-page
links into links between those pages, and copies the figures and CSV tables
next to them.  Nothing is recomputed: the pages show the committed numbers.
Files are rewritten only when their content changes, so an incremental build
stays incremental.
"""

from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

#: the report, relative to the repository root
REPORT_DIR = Path("validation") / "report"
#: the generated pages, relative to the docs source folder
OUT_DIR = Path("report")

_ANCHOR = re.compile(r'^<a id="([A-Za-z0-9_]+)"></a>\s*$')
_HEADING = re.compile(r"^(#{1,6}) ")


def _write_if_changed(path: Path, text: str) -> None:
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.write_text(text, encoding="utf-8")


def _copy_if_changed(src: Path, dst: Path) -> None:
    if not dst.exists() or dst.read_bytes() != src.read_bytes():
        shutil.copyfile(src, dst)


def _promote(lines: list[str]) -> list[str]:
    """One heading level up (``##`` -> ``#``), outside code fences."""
    out, fenced = [], False
    for line in lines:
        if line.startswith("```"):
            fenced = not fenced
        m = _HEADING.match(line)
        if m and not fenced and len(m.group(1)) > 1:
            line = line[1:]
        out.append(line)
    return out


def split_report(text: str, cases: list[str]) -> tuple[list[str], dict[str, list[str]]]:
    """Split REPORT.md into the overview's lines and each case's lines.

    Parameters
    ----------
    text : str
        The report's Markdown.
    cases : list of str
        The case names, in the order of ``results.json``.

    Returns
    -------
    overview : list of str
        Everything outside the case sections (the ``## Reproduce`` tail included).
    sections : dict
        Case name -> the lines of its section, its anchor line excluded.
    """
    overview: list[str] = []
    sections: dict[str, list[str]] = {}
    current: list[str] = overview
    titled = False  # whether the current case's own ``##`` title has been read
    for line in text.splitlines():
        m = _ANCHOR.match(line)
        if m and m.group(1) in cases:
            current, titled = sections.setdefault(m.group(1), []), False
            continue
        if line.startswith("## ") and current is not overview:
            if titled:  # the next level-2 heading after a case's title ends the case
                current = overview
            titled = True
        current.append(line)
    missing = [c for c in cases if c not in sections]
    if missing:
        raise ValueError(f"validation report: no section for the cases {missing}")
    return overview, sections


def _links(line: str, cases: list[str]) -> str:
    """The report's in-page links as links between the generated pages."""
    line = re.sub(r"\[(S\d+)\]\(#sources\)", r"{ref}`\1 <report-sources>`", line)
    for case in cases:
        line = line.replace(f"](#{case})", f"]({case}.md)")
    return line


def generate(docs_dir: Path, root: Path) -> list[str]:
    """Write ``docs/report/``; return the case names, in the report's order."""
    report = root / REPORT_DIR
    results = json.loads((report / "results.json").read_text(encoding="utf-8"))
    cases = [c["name"] for c in results["cases"]]
    overview, sections = split_report((report / "REPORT.md").read_text(encoding="utf-8"), cases)
    out = docs_dir / OUT_DIR
    out.mkdir(exist_ok=True)

    lines = []
    for line in overview:
        if line.strip() == '<a id="sources"></a>':
            lines.append("(report-sources)=")
            continue
        lines.append(_links(line, cases))
    toc = ["", "```{toctree}", ":maxdepth: 1", ":caption: One page per case", ""]
    toc += cases + ["```", ""]
    header = [
        "<!-- generated from validation/report/REPORT.md by docs/_ext/validation_report.py -->",
        "",
    ]
    _write_if_changed(out / "index.md", "\n".join(header + lines + toc))

    for case in cases:
        body = [_links(line, cases) for line in _promote(sections[case])]
        _write_if_changed(out / f"{case}.md", "\n".join(header + body).rstrip() + "\n")

    for f in sorted(report.iterdir()):
        if f.suffix in {".png", ".csv"}:
            _copy_if_changed(f, out / f.name)
    return cases


def _builder_inited(app) -> None:
    docs_dir = Path(app.srcdir)
    generate(docs_dir, docs_dir.parent)


def setup(app) -> dict:
    app.connect("builder-inited", _builder_inited)
    return {"version": "1", "parallel_read_safe": True, "parallel_write_safe": True}

"""The Markdown validation report (``REPORT.md``) and ``results.json``, made by the run alone."""

from __future__ import annotations

import json
import os
import re
from pathlib import Path

from ..io import write_json, write_text
from .checks import Check, Table, format_cell
from .suite import CaseOutcome, SuiteResult

__all__ = ["render_report", "write_report"]


#: The report's prose: paragraphs as ``str.format`` templates, by section.
_TEXT = json.loads(
    Path(__file__).with_name("references").joinpath("report.json").read_text("utf-8")
)


def _paragraphs(section: str, **values) -> list[str]:
    """The paragraphs of ``section``, filled from ``values``, each followed by a blank line."""
    return [line for par in _TEXT[section] for line in (par.format(**values), "")]


def _source_labels(suite: SuiteResult) -> dict[str, str]:
    """Sources cited by three or more checks, each defined once as [S1], [S2], ..."""
    count: dict[str, int] = {}
    for _, c in suite.checks():
        count[c.source] = count.get(c.source, 0) + 1
    repeated = [src for src, n in count.items() if n >= 3]
    return {src: f"S{k}" for k, src in enumerate(repeated, start=1)}


def _check_row(c: Check, sources: dict[str, str] | None = None, short: bool = False) -> str:
    """One check as a table row (``short``: no reason, no source)."""
    mark = "✅ pass" if c.passed else ("❌ FAIL" if c.category == "numerics" else "⚠️ differs")
    cells = [mark, c.category, c.claim, format_cell(c.measured), format_cell(c.reference)]
    if short:
        cells.append(c.tolerance.split(";")[0])
    else:
        cells += [
            c.tolerance,
            f"[{sources[c.source]}](#sources)" if sources and c.source in sources else c.source,
        ]
    return "| " + " | ".join(format_cell(x) for x in cells) + " |"


def _minutes(t: float) -> str:
    return f"{t:.1f} s" if t < 120 else f"{t / 60:.1f} min ({t:.0f} s)"


#: A paper check on the paper's modal truncation: "[α = ..: ]N = 3 [(the
#: paper's truncation) ]reproduces <quantity>".
_TRUNCATION = re.compile(
    r"^(?P<pre>.*?)N = (?P<n>\d+)(?: \(the paper's truncation\))? reproduces (?P<what>.*)$"
)


def _truncation(c: Check) -> re.Match | None:
    return _TRUNCATION.match(c.claim) if c.category == "paper" else None


def _headline(suite: SuiteResult) -> list[str]:
    """The round pipe's first instability, from the out-of-plane case and Fig. 6 (if run)."""
    parts = [
        o.result.data["headline"]
        for o in suite.outcomes
        if o.result is not None and o.result.data.get("headline")
    ]
    if not parts:
        return []
    return _paragraphs("headline", parts="; ".join(parts))


def _findings(suite: SuiteResult) -> list[str]:
    """The disagreements with the paper first, then one table of the truncation errors."""
    lines = ["## Findings: where the converged model and the paper disagree", ""]
    k = 0
    rows: dict = {}
    for o in suite.outcomes:
        if o.result is None:
            continue
        for f in o.result.findings:
            k += 1
            lines.append(f"{k}. **{o.result.figure}** ({o.name}): {f}")
        for c in o.result.checks:
            m = _truncation(c)
            if m is not None:
                key = (o.result.figure, f"{m['pre']}{m['what']}")
                row = rows.setdefault(key, {"tolerance": format_cell(c.tolerance.split(";")[0])})
                row[m["n"]] = format_cell(c.measured) + ("" if c.passed else " ⚠️")
                continue
            if c.category == "paper" and not c.passed and c.name not in o.result.explained:
                k += 1
                lines.append(
                    f"{k}. **{o.result.figure}** ({o.name}): “{c.claim}” does not hold for the "
                    f"converged model: measured {format_cell(c.measured)}; criterion "
                    f"{format_cell(c.reference)} ({c.tolerance}). Reference: {c.source}."
                )
    if k == 0:
        lines.append("None.")
    if rows:
        over = sum(v.endswith("⚠️") for r in rows.values() for v in r.values())
        lines += [
            "",
            *_paragraphs("truncations", over=over),
            "| figure | quantity | N = 3 | N = 4 | tolerance |",
            "|---|---|---|---|---|",
        ]
        lines += [
            f"| {fig} | {format_cell(what)} | {r.get('3', '')} | {r.get('4', '')} | "
            f"{r['tolerance']} |"
            for (fig, what), r in rows.items()
        ]
    return [*lines, ""]


#: Tables longer than this go to a CSV file beside the report, linked.
MAX_INLINE_ROWS = 30
#: The most bytes a case's section of REPORT.md may take: past it, its longest tables go to
#: CSV files beside the report (linked), then its checks' reasons and sources (the checks
#: stay inline with their verdicts and numbers; results.json holds everything).
CASE_BUDGET = 8192


def _linked(t, tables_dir: Path | None, inline: bool) -> bool:
    """Whether a table goes to a CSV file: long or not ``inline``, and ``tables_dir`` given."""
    return tables_dir is not None and (not inline or len(t.rows) > MAX_INLINE_ROWS)


def _table(t, case: str, k: int, linked: bool) -> list[str]:
    """A table in Markdown, or a link to its CSV file ``<case>_table<k>.csv``."""
    if not linked:
        return ["", t.to_markdown()]
    name = f"{case}_table{k}.csv"
    out = ["", f"**{t.title}**: {len(t.rows)} rows in [{name}]({name}) (CSV)."]
    if t.note:
        out += ["", t.note]
    return out


def _write_csv(path: Path, t) -> None:
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(t.columns)
    w.writerows(t.rows)
    write_text(path, buf.getvalue())


def render_report(
    suite: SuiteResult, figures_dir: str = ".", tables_dir: str | os.PathLike | None = None
) -> str:
    """The report as Markdown (figure links relative to ``figures_dir``); long tables, and those
    past a case's :data:`CASE_BUDGET`, go to CSV files in ``tables_dir`` when given.
    """
    tables_path = None if tables_dir is None else Path(tables_dir)
    cmd = "fempipe validate" + (" --quick" if suite.quick else "")
    lines = [*_introduction(suite, cmd), *_headline(suite), *_findings(suite), *_summary(suite)]
    sources = _source_labels(suite)
    if sources:
        lines += [
            "",
            '<a id="sources"></a>',
            "",
            "### Sources cited by several checks",
            "",
            *[f"- **{label}**: {src}" for src, label in sources.items()],
        ]
    for o in suite.outcomes:
        lines += _case_section(o, sources, figures_dir, tables_path)
    return "\n".join([*lines, "", *_paragraphs("reproduce", cmd=cmd)])


def _introduction(suite: SuiteResult, cmd: str) -> list[str]:
    """The title, the paper, how the report was generated and how to read it."""
    env = suite.environment
    return _paragraphs(
        "introduction",
        cmd=cmd,
        mode="quick" if suite.quick else "full",
        started=suite.started,
        runtime=_minutes(suite.wall_time),
        git=f" (git {env['git_commit']})" if env.get("git_commit") else "",
        skfem=env.get("scikit-fem"),
        **{k: env.get(k) for k in ("workers", "cpu_count", "fempipe", "python", "numpy", "scipy")},
    )


def _summary(suite: SuiteResult) -> list[str]:
    """The counts of passed checks, the table of cases and the failed numerics checks."""
    num = [c for _, c in suite.checks("numerics")]
    pap = [c for _, c in suite.checks("paper")]
    lines = [
        "## Summary",
        "",
        f"- numerics checks passed: **{sum(c.passed for c in num)} / {len(num)}**",
        f"- paper statements reproduced: **{sum(c.passed for c in pap)} / {len(pap)}**",
        f"- overall: **{'PASS' if suite.ok else 'FAIL'}** (PASS = every case ran and every "
        "numerics check passed; paper findings do not fail the suite)",
        "",
        "| case | paper figure | what | status | numerics | paper | compute time |",
        "|---|---|---|---|---|---|---|",
    ]
    for o in suite.outcomes:
        r = o.result
        if r is None:
            lines.append(
                f"| [{o.name}](#{o.name}) | | | {o.status}: {format_cell(o.error.splitlines()[-1] if o.error else '')} | | | |"
            )
            continue
        n_ok = sum(c.passed for c in r.checks if c.category == "numerics")
        n_all = sum(c.category == "numerics" for c in r.checks)
        p_ok = sum(c.passed for c in r.checks if c.category == "paper")
        p_all = sum(c.category == "paper" for c in r.checks)
        status = o.status if o.status != "ok" else ("ok" if r.numerics_passed else "FAIL")
        lines.append(
            f"| [{o.name}](#{o.name}) | {r.figure} | {format_cell(r.title)} | {status} | "
            f"{n_ok}/{n_all} | {p_ok}/{p_all} | {r.runtime:.1f} s |"
        )
    failed = [(n, c) for n, c in suite.checks("numerics") if not c.passed]
    if failed:
        lines += ["", "### Failed numerics checks (bugs or unconverged settings in fempipe)", ""]
        lines += [
            f"- {n}: {c.claim}: measured {format_cell(c.measured)}; {c.tolerance}"
            for n, c in failed
        ]
    return lines


def _size(lines: list[str]) -> int:
    return len("\n".join(lines).encode())


def _case_section(
    o: CaseOutcome, sources: dict[str, str], figures_dir: str, tables_path: Path | None
) -> list[str]:
    """One case's section within :data:`CASE_BUDGET`; writes the CSV files it links."""
    r = o.result
    if r is None or tables_path is None:
        return _case_lines(o, sources, figures_dir, tables_path, set(), 0)
    outside: set[int] = set()
    by_size = sorted(range(len(r.tables)), key=lambda k: -len(r.tables[k].to_markdown()))
    level = 0
    lines = _case_lines(o, sources, figures_dir, tables_path, outside, level)
    for k in by_size:
        if _size(lines) <= CASE_BUDGET:
            break
        outside.add(k)
        lines = _case_lines(o, sources, figures_dir, tables_path, outside, level)
    while _size(lines) > CASE_BUDGET and level < 2:
        level += 1
        lines = _case_lines(o, sources, figures_dir, tables_path, outside, level)
    for k, t in enumerate(r.tables, start=1):
        if _linked(t, tables_path, k - 1 not in outside):
            _write_csv(tables_path / f"{o.name}_table{k}.csv", t)
    if level:
        _checks_csv(tables_path / f"{o.name}_checks.csv", r.checks)
    return lines


def _checks_csv(path: Path, checks) -> None:
    """Every check of a case, with the reason for its tolerance and its source, as CSV."""
    columns = ("passed", "category", "name", "claim", "measured", "reference", "tolerance",
               "source")  # fmt: skip
    rows = tuple(tuple(getattr(c, k) for k in columns) for c in checks)
    _write_csv(path, Table("checks", columns, rows))


def _case_lines(
    o: CaseOutcome,
    sources: dict[str, str],
    figures_dir: str,
    tables_path: Path | None,
    outside: set[int],
    checks_level: int,
) -> list[str]:
    """One case's section; ``checks_level`` 0: checks with reasons, 1: without, 2: failed only."""
    lines = ["", f'<a id="{o.name}"></a>', ""]
    r = o.result
    if r is None:
        return lines + [f"## {o.name}: {o.status}", "", "```", o.error.strip(), "```"]
    lines += [f"## {r.figure}: {r.title}", ""]
    lines += [
        f"Case `fempipe.validation.{o.name}` ({'quick' if r.quick else 'full'}), "
        f"compute time {r.runtime:.1f} s."
    ]
    if o.status == "error":
        lines += ["", "**Error:**", "", "```", o.error.strip(), "```"]
    lines += ["", "What the paper shows, checked here:", ""]
    lines += [f"- {s}" for s in r.paper_shows]
    if r.not_checked:
        lines += ["", "Not checked (neither reproduced nor contradicted):", ""]
        lines += [f"- {s}" for s in r.not_checked]
    for fig in o.figures or ((o.figure,) if o.figure else ()):
        lines += ["", f"![{r.figure}]({Path(figures_dir, fig).as_posix()})"]
    if r.caption and (o.figures or o.figure):
        lines += ["", f"*{r.figure}.* {r.caption}"]
    if checks_level:
        name = f"{o.name}_checks.csv"
        shown = r.checks if checks_level == 1 else [c for c in r.checks if not c.passed]
        n_pass = sum(c.passed for c in r.checks)
        lines += [
            "",
            f"{n_pass} of {len(r.checks)} checks pass; every check with the reason for its "
            f"tolerance and its source: [{name}]({name}) (CSV)."
            + ("" if checks_level == 1 else " Below: the checks that do not pass."),
        ]
        if shown:
            lines += [
                "",
                "| result | category | check | measured | reference | tolerance |",
                "|---|---|---|---|---|---|",
                *[_check_row(c, short=True) for c in shown],
            ]
    else:
        lines += [
            "",
            "| result | category | check | measured | reference | tolerance (why) | source |",
            "|---|---|---|---|---|---|---|",
            *[_check_row(c, sources) for c in r.checks],
        ]
    for k, t in enumerate(r.tables, start=1):
        lines += _table(t, o.name, k, _linked(t, tables_path, k - 1 not in outside))
    return lines


def write_report(suite: SuiteResult, out: str | os.PathLike) -> Path:
    """Write ``REPORT.md`` and ``results.json`` into ``out`` (atomically); return the report path."""

    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    write_json(out / "results.json", suite.to_dict())
    return write_text(out / "REPORT.md", render_report(suite, tables_dir=out))

"""Checks, tables and case results: the vocabulary of the validation suite.

Every comparison is a :class:`Check` carrying its tolerance, why it has that size and the
source of the reference, so the report can be judged without the code.  Two categories:
``numerics`` (fempipe against an independent computation: refined mesh, other
discretization, ODE solver, symmetry, classical value; must pass) and ``paper`` (a statement
of Chen, Hu, Dai & Wang 2020 against fempipe's converged answer; a failure is a *finding*).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from ..io import to_jsonable

__all__ = ["CATEGORIES", "CaseResult", "Check", "Table", "format_cell", "merge_results"]

CATEGORIES = ("numerics", "paper")


@dataclass(frozen=True)
class Check:
    """One comparison with a verdict: ``name`` (unique in its case), ``claim`` in words,
    ``category`` (``numerics``, ``paper``), ``passed``, ``measured``, ``reference``,
    ``tolerance`` (the criterion and why) and ``source`` of the reference.
    """

    name: str
    claim: str
    category: str
    passed: bool
    measured: Any
    reference: Any
    tolerance: str
    source: str

    def __post_init__(self) -> None:
        if self.category not in CATEGORIES:
            raise ValueError(f"category must be one of {CATEGORIES}, got {self.category!r}")
        object.__setattr__(self, "passed", bool(self.passed))

    def to_dict(self) -> dict:
        return to_jsonable(asdict(self))


def format_cell(x: Any) -> str:
    """A value as a Markdown table cell: floats to 8 significant digits, ``|`` escaped."""
    if isinstance(x, (bool, np.bool_)):
        return "true" if x else "false"
    if isinstance(x, (float, np.floating)):
        return f"{float(x):.8g}"
    return str(x).replace("|", "\\|").replace("\n", " ")


@dataclass(frozen=True)
class Table:
    """A small table for the report: a title, column names (a tuple, or one string
    ``"a | b | c"``) and rows of cells."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]
    note: str = ""

    def __post_init__(self) -> None:
        if isinstance(self.columns, str):
            object.__setattr__(self, "columns", tuple(self.columns.split(" | ")))
        object.__setattr__(self, "rows", tuple(self.rows))

    def to_markdown(self) -> str:
        head = "| " + " | ".join(format_cell(c) for c in self.columns) + " |"
        sep = "|" + "|".join("---" for _ in self.columns) + "|"
        body = ["| " + " | ".join(format_cell(c) for c in row) + " |" for row in self.rows]
        out = [f"**{self.title}**", "", head, sep, *body]
        if self.note:
            out += ["", self.note]
        return "\n".join(out)

    def to_dict(self) -> dict:
        return to_jsonable(asdict(self))


@dataclass(frozen=True)
class CaseResult:
    """What one case returns: ``explained``, failed paper checks a finding already states;
    ``data``, the figure's arrays (not serialised); ``runtime``, wall time of ``run`` in s."""

    case: str
    figure: str
    title: str
    paper_shows: tuple[str, ...]
    checks: tuple[Check, ...]
    tables: tuple[Table, ...] = ()
    findings: tuple[str, ...] = ()
    data: dict = field(default_factory=dict, compare=False, repr=False)
    explained: tuple[str, ...] = ()
    quick: bool = False
    runtime: float = 0.0
    caption: str = ""
    not_checked: tuple[str, ...] = ()

    @property
    def numerics_passed(self) -> bool:
        """All numerics checks passed (fempipe is right)."""
        return all(c.passed for c in self.checks if c.category == "numerics")

    @property
    def failed(self) -> tuple[Check, ...]:
        return tuple(c for c in self.checks if not c.passed)

    def to_dict(self) -> dict:
        out = {k: getattr(self, k) for k in ("case", "figure", "title")}
        out.update(paper_shows=list(self.paper_shows), quick=self.quick, runtime=self.runtime)
        out.update(
            checks=[c.to_dict() for c in self.checks], tables=[t.to_dict() for t in self.tables]
        )
        out.update(
            findings=list(self.findings), caption=self.caption, not_checked=list(self.not_checked)
        )
        return out


def merge_results(results: list[CaseResult]) -> CaseResult:
    """One CaseResult from the parts of a case run separately: checks, findings and same-titled
    tables concatenated, ``data`` merged key by key, runtimes summed.
    """
    if not results:
        raise ValueError("nothing to merge")
    first = results[0]
    tables: dict[str, Table] = {}
    for r in results:
        for t in r.tables:
            old = tables.get(t.title)
            tables[t.title] = t if old is None else replace(t, rows=old.rows + t.rows)
    data: dict = {}
    for r in results:
        for k, v in r.data.items():
            if isinstance(v, dict) and isinstance(data.get(k), dict):
                data[k] = {**data[k], **v}
            else:
                data.setdefault(k, v)
    joined = {k: tuple(x for r in results for x in getattr(r, k)) for k in _JOINED}
    tables = tuple(tables.values())
    return replace(
        first, **joined, tables=tables, data=data, runtime=sum(r.runtime for r in results)
    )


#: The fields of the parts of a case that :func:`merge_results` concatenates.
_JOINED = ("checks", "findings", "explained")

"""Checks, tables and case results: the vocabulary of the validation suite.

A validation case compares what fempipe computes with a reference and says
whether they agree.  Every comparison is a :class:`Check` that carries its own
tolerance, the reason for that tolerance and the source of the reference
number, so a reader of the report can judge it without reading the code.

Checks come in two categories:

``numerics``
    fempipe against an independent computation (a refined mesh, the other
    discretization, an independent ODE boundary-value solver, a symmetry, a
    classical value).  These must pass; a failure is a bug in fempipe.
``paper``
    a statement or number of the paper (Chen, Hu, Dai & Wang 2020) against
    fempipe's mesh-converged answer.  A failure here is a *finding*: the
    paper and the converged model disagree, and the report says by how much.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from ..io import to_jsonable

__all__ = ["CATEGORIES", "CaseResult", "Check", "Table", "format_cell", "merge_results"]

CATEGORIES = ("numerics", "paper")


@dataclass(frozen=True)
class Check:
    """One comparison with a pass/fail verdict.

    Attributes
    ----------
    name : str
        Short identifier, unique within its case.
    claim : str
        The statement checked, in words ("flutter in the second mode").
    category : {'numerics', 'paper'}
        See the module docstring.
    passed : bool
    measured : float or str
        What fempipe computed.
    reference : float or str or None
        The number or statement it is compared with.
    tolerance : str
        The acceptance criterion, with why it has that size.
    source : str
        Where the reference comes from (paper section/figure/equation, a
        classical result with its citation, or the independent computation).
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
    """A small table for the report: a title, column names and rows of cells."""

    title: str
    columns: tuple[str, ...]
    rows: tuple[tuple[Any, ...], ...]
    note: str = ""

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
    """What one validation case returns.

    Attributes
    ----------
    case : str
        Module name (``fig02b``).
    figure : str
        The paper's figure it reproduces (``Fig. 2(b)``).
    title : str
    paper_shows : tuple of str
        What the paper shows there, in words; each is checked below.
    checks : tuple of Check
    tables : tuple of Table
    findings : tuple of str
        Disagreements with the paper, with the measurement.
    explained : tuple of str
        Names of failed paper checks that a finding already explains (the
        report lists them once, by the finding's text).
    data : dict
        Arrays the figure is drawn from (not serialised by ``to_dict``).
    quick : bool
        Whether the quick (coarser) version ran.
    runtime : float
        Wall time of ``run``, s (measured by :mod:`fempipe.validation.suite`).
    caption : str
        The figure's caption (see :class:`fempipe.validation.case.Case`).
    not_checked : tuple of str
        Statements of the paper the case cannot check.
    """

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
        return {
            "case": self.case,
            "figure": self.figure,
            "title": self.title,
            "paper_shows": list(self.paper_shows),
            "quick": self.quick,
            "runtime": self.runtime,
            "checks": [c.to_dict() for c in self.checks],
            "tables": [t.to_dict() for t in self.tables],
            "findings": list(self.findings),
            "caption": self.caption,
            "not_checked": list(self.not_checked),
        }


def merge_results(results: list[CaseResult]) -> CaseResult:
    """One CaseResult from the parts of a case run separately (in order).

    Checks and findings are concatenated, tables with the same title get their
    rows concatenated, ``data`` dicts are merged (dict values merged key by
    key), runtimes are summed (the compute time of the case, whatever ran in
    parallel).
    """
    if not results:
        raise ValueError("nothing to merge")
    first = results[0]
    tables: dict[str, Table] = {}
    for r in results:
        for t in r.tables:
            old = tables.get(t.title)
            tables[t.title] = (
                t if old is None else Table(t.title, t.columns, old.rows + t.rows, t.note)
            )
    data: dict = {}
    for r in results:
        for k, v in r.data.items():
            if isinstance(v, dict) and isinstance(data.get(k), dict):
                data[k] = {**data[k], **v}
            else:
                data.setdefault(k, v)
    return CaseResult(
        case=first.case,
        figure=first.figure,
        title=first.title,
        paper_shows=first.paper_shows,
        checks=tuple(c for r in results for c in r.checks),
        tables=tuple(tables.values()),
        findings=tuple(f for r in results for f in r.findings),
        data=data,
        quick=first.quick,
        runtime=sum(r.runtime for r in results),
        explained=tuple(e for r in results for e in r.explained),
        caption=first.caption,
        not_checked=first.not_checked,
    )

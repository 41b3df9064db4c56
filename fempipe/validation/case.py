"""A validation case, declared once: what it reproduces, its references, its result.

Every case module of :mod:`fempipe.validation` declares one :class:`Case`:
its name, the paper's figure, a title, what the paper shows there (each
statement is checked) and the names of the checks every run must emit.  The
case reads its reference numbers through :attr:`Case.references`
(``references/<name>.json``, each entry a value with its source), builds
checks against them with :meth:`References.close` and
:meth:`References.below` (value and source taken from the file, never
restated), and returns :meth:`Case.result`.

A declared check that a run did not emit is a failed numerics check in that
result: a code path that silently skipped a comparison fails the case
instead of shrinking the report.
"""

from __future__ import annotations

import json
import time
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path
from typing import Any

import numpy as np

from .checks import CaseResult, Check, Table, below, close

__all__ = ["Case", "References", "alpha_name", "label_tag", "load_references"]

_REFERENCE_DIR = Path(__file__).with_name("references")


@dataclass(frozen=True)
class References:
    """The reference numbers of one case, from ``references/<case>.json``.

    Each entry is ``{"value": ..., "source": "..."}``; ``about`` is the file's
    ``"_about"`` text (where the numbers come from as a whole).
    """

    case: str
    about: str
    entries: Mapping[str, Mapping[str, Any]]

    def value(self, key: str, quick: bool = False) -> Any:
        """The value of ``key``; with ``quick``, that of ``key + "_quick"`` (which must exist)."""
        return self.entries[f"{key}_quick" if quick else key]["value"]

    def source(self, key: str) -> str:
        """Where the value of ``key`` comes from (for a tolerance: why it has that size)."""
        return self.entries[key]["source"]

    def close(
        self,
        name: str,
        claim: str,
        measured: float,
        *,
        key: str | None = None,
        atol: float = 0.0,
        rtol: float = 0.0,
        why: str,
        category: str = "numerics",
    ) -> Check:
        """``measured`` against the file's value of ``key`` (default ``name``), citing its source."""
        key = key or name
        return close(
            name,
            claim,
            measured,
            self.value(key),
            atol=atol,
            rtol=rtol,
            why=why,
            source=self.source(key),
            category=category,
        )

    def below(
        self,
        name: str,
        claim: str,
        measured: float,
        key: str,
        *,
        source: str,
        category: str = "numerics",
    ) -> Check:
        """``measured <= `` the file's tolerance ``key``; the file's source says why it has that size."""
        return below(
            name,
            claim,
            measured,
            self.value(key),
            why=self.source(key),
            source=source,
            category=category,
        )


def load_references(case: str) -> References:
    """The reference numbers of ``case`` from ``references/<case>.json``.

    Raises
    ------
    ValueError
        If the file has no ``"_about"`` or an entry lacks ``value`` or ``source``.
    """
    path = _REFERENCE_DIR / f"{case}.json"
    with path.open(encoding="utf-8") as fh:
        data = json.load(fh)
    if not isinstance(data.get("_about"), str):
        raise ValueError(f"{path}: needs an '_about' text")
    for key, entry in data.items():
        if key.startswith("_"):
            continue
        if not isinstance(entry, dict) or "value" not in entry or "source" not in entry:
            raise ValueError(f"{path}: entry {key!r} needs 'value' and 'source'")
    entries = {k: v for k, v in data.items() if not k.startswith("_")}
    return References(case, data["_about"], entries)


def not_emitted(name: str, case: str) -> Check:
    """The failed numerics check standing for a declared check that a run did not emit."""
    return Check(
        name,
        f"the declared check {name!r} is computed",
        "numerics",
        False,
        "not computed",
        "computed",
        "every check a case declares must be emitted by each run",
        f"the declaration of fempipe.validation.{case}",
    )


@dataclass(frozen=True)
class Case:
    """One validation case: a figure of the paper (or a study) and its checks.

    Attributes
    ----------
    name : str
        Module name (``fig02b``), also the reference file's name.
    figure : str
        The paper's figure it reproduces (``Fig. 2(b)``).
    title : str
    paper_shows : tuple of str
        What the paper shows there, in words; each is checked.
    requires : tuple of str
        Names of checks every run must emit; checks that depend on the run
        (one per inclination, the full suite only) are passed to
        :meth:`result` by the run that knows them.
    not_checked : tuple of str
        Statements of the paper this case cannot check (said so in the
        report, never counted as reproduced).
    caption : str
        The figure's caption in the report: parameters, flow velocities,
        discretizations in words, the key of colors, line styles and
        markers, which shapes are static and which oscillate.
    """

    name: str
    figure: str
    title: str
    paper_shows: tuple[str, ...]
    requires: tuple[str, ...] = ()
    caption: str = ""
    not_checked: tuple[str, ...] = ()

    @property
    def references(self) -> References:
        """The case's reference numbers (``references/<name>.json``)."""
        return load_references(self.name)

    def result(
        self,
        checks: Iterable[Check],
        *,
        quick: bool,
        started: float,
        tables: Iterable[Table] = (),
        findings: Iterable[str] = (),
        data: dict | None = None,
        explained: Iterable[str] = (),
        requires: Iterable[str] = (),
    ) -> CaseResult:
        """The case's result; every declared check that is missing is added as failed.

        Parameters
        ----------
        checks : iterable of Check
        quick : bool
            Whether the quick version ran.
        started : float
            ``time.perf_counter()`` when the run started (the runtime is measured from it).
        tables, findings, data, explained
            As :class:`~fempipe.validation.checks.CaseResult`.
        requires : iterable of str
            Check names this run must emit besides :attr:`requires`.
        """
        checks = tuple(checks)
        emitted = {c.name for c in checks}
        declared = dict.fromkeys((*self.requires, *requires))
        missing = tuple(not_emitted(n, self.name) for n in declared if n not in emitted)
        return CaseResult(
            case=self.name,
            figure=self.figure,
            title=self.title,
            paper_shows=self.paper_shows,
            caption=self.caption,
            not_checked=self.not_checked,
            checks=checks + missing,
            tables=tuple(tables),
            findings=tuple(findings),
            data={} if data is None else data,
            explained=tuple(explained),
            quick=quick,
            runtime=time.perf_counter() - started,
        )


def alpha_name(alpha: float) -> str:
    """The inclination as a multiple of pi (``π/4``, ``3π/4``, ``-2π/3``, ``0``) when it is one.

    Denominators up to 12; any other angle is printed with 4 decimals.
    """
    k = Fraction(alpha / np.pi).limit_denominator(12)
    if abs(float(k) * np.pi - alpha) > 1e-12:
        return f"{alpha:.4f}"
    if k == 0:
        return "0"
    sign = "-" if k < 0 else ""
    num, den = abs(k.numerator), k.denominator
    return f"{sign}{'' if num == 1 else num}π{'' if den == 1 else f'/{den}'}"


def label_tag(label: str) -> str:
    """A discretization label as it appears in check names: ``"FE P3:8"`` → ``"FEP3:8"``, ``"N = 3"`` → ``"N3"``."""
    return label.replace(" ", "").replace("=", "")

"""A validation case, declared once: what it reproduces, its references, its result.

``references/<name>.json`` (:func:`load_references`) holds a case's declaration (``"case"``:
the paper's figure, title, what the paper shows; :meth:`Case.load`), its reference numbers
with their sources, the caption template and the check specs
(:mod:`fempipe.validation.evaluate`).  A run returns :meth:`Case.result`, which judges every
measurement by its spec.  A check without placeholders must be measured by every run
(``"required": "full"``: every full run; ``false``: when it applies): a required check a run
did not measure fails the case.
"""

from __future__ import annotations

import json
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from .checks import CaseResult, Check, Table
from .evaluate import KINDS, SPEC_KEYS, Measured, alpha_name, evaluate, fill

__all__ = ["Case", "References", "alpha_name", "label_tag", "load_references"]

_REFERENCE_DIR = Path(__file__).with_name("references")


@dataclass(frozen=True)
class References:
    """``references/<case>.json``: ``entries`` ``{"value", "source"}`` by name, ``about``
    its ``"_about"`` text, ``caption`` the caption template, ``checks`` the specs by name."""

    case: str
    about: str
    entries: Mapping[str, Mapping[str, Any]]
    caption: str = ""
    checks: Mapping[str, Mapping[str, Any]] = field(default_factory=dict)
    declaration: Mapping[str, Any] = field(default_factory=dict)
    tables: Mapping[str, Mapping[str, str]] = field(default_factory=dict)

    def value(self, key: str, quick: bool = False) -> Any:
        """The value of ``key``; with ``quick``, that of ``key + "_quick"`` (which must exist)."""
        return self.entries[f"{key}_quick" if quick else key]["value"]

    def source(self, key: str) -> str:
        """Where the value of ``key`` comes from (for a tolerance: why it has that size)."""
        return self.entries[key]["source"]

    def table(self, name: str, rows: Iterable, **values: Any) -> Table:
        """The table ``name`` of the ``"tables"`` section: its title, columns (``"a | b"``) and
        note templates filled from ``values`` (``str.format``), and ``rows``."""
        t = self.tables[name]
        title, columns, note = (t.get(k, "").format(**values) for k in ("title", "columns", "note"))
        return Table(title, columns, tuple(rows), note)

    def names(self, quick: bool) -> dict:
        """The values the templates name (quick: the ``_quick`` variants) and ``"sources"``."""
        key = {
            k: f"{k}_quick" if quick and f"{k}_quick" in self.entries else k for k in self.entries
        }
        out = {k: self.entries[q]["value"] for k, q in key.items()}
        out["sources"] = {k: self.entries[q]["source"] for k, q in key.items()}
        return out


def _check_spec(path: Path, name: str, spec: Any) -> None:
    """Raise ValueError unless ``spec`` is a valid check spec."""
    if not isinstance(spec, dict) or spec.get("kind") not in KINDS:
        raise ValueError(f"{path}: check {name!r} needs a kind, one of {', '.join(KINDS)}")
    missing = {"claim", "source"} | ({"why"} if spec["kind"] != "holds" else set())
    unknown = set(spec) - SPEC_KEYS - set(KINDS[spec["kind"]])
    req = spec.get("required", True)
    if not (isinstance(req, list) or req in (True, False, "full")):
        unknown.add("required")
    if missing - set(spec) or unknown:
        raise ValueError(
            f"{path}: check {name!r}: missing {missing - set(spec)}, unknown {unknown}"
        )


def load_references(case: str) -> References:
    """The reference file ``references/<case>.json``; ValueError if it is malformed."""
    path = _REFERENCE_DIR / f"{case}.json"
    with path.open(encoding="utf-8") as fh:
        data = json.load(fh)
    if not isinstance(data.get("_about"), str):
        raise ValueError(f"{path}: needs an '_about' text")
    checks = data.get("checks", {})
    for name, spec in checks.items():
        _check_spec(path, name, spec)
    entries = {k: v for k, v in data.items() if not k.startswith("_") and k not in _META}
    for key, entry in entries.items():
        if not isinstance(entry, dict) or "value" not in entry or "source" not in entry:
            raise ValueError(f"{path}: entry {key!r} needs 'value' and 'source'")
    meta = (data.get("caption", ""), checks, data.get("case", {}), data.get("tables", {}))
    return References(case, data["_about"], entries, *meta)


#: The keys of a reference file that are not reference numbers.
_META = ("caption", "checks", "case", "tables")


def not_emitted(name: str, case: str) -> Check:
    """The failed numerics check standing for a required check that a run did not measure."""
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


def required(checks: Mapping[str, Mapping], quick: bool) -> list[str]:
    """The checks every run must measure (module docstring) and the listed family members."""
    names = []
    for name, spec in checks.items():
        want = spec.get("required", True)
        if isinstance(want, list):
            names += want
        elif "{" not in name and (want is True or (want == "full" and not quick)):
            names.append(name)
    return names


@dataclass(frozen=True)
class Case:
    """One validation case: module ``name`` (also its reference file's), the paper's
    ``figure``, ``title``, ``paper_shows`` (each checked) and ``not_checked`` (statements
    it cannot check, said so in the report)."""

    name: str
    figure: str
    title: str
    paper_shows: tuple[str, ...]
    not_checked: tuple[str, ...] = ()

    @classmethod
    def load(cls, name: str) -> Case:
        """The case ``name`` as its reference file's ``"case"`` section declares it."""
        d = load_references(name).declaration
        shows, skipped = tuple(d["paper_shows"]), tuple(d.get("not_checked", ()))
        return cls(name, d["figure"], d["title"], shows, skipped)

    @property
    def references(self) -> References:
        """The case's reference file (``references/<name>.json``)."""
        return load_references(self.name)

    @property
    def caption(self) -> str:
        """The figure's caption, filled from the full suite's reference values."""
        refs = self.references
        return fill(refs.caption, refs.names(quick=False))

    def check(self, m: Measured, quick: bool) -> Check:
        """The check of one measurement (a case that needs a verdict to write a finding)."""
        refs = self.references
        return evaluate(_spec(refs, m.spec), m, refs.names(quick))

    def result(
        self,
        measured: Iterable[Measured],
        *,
        quick: bool,
        tables: Iterable[Table] = (),
        findings: Iterable[str] = (),
        data: dict | None = None,
        explained: Iterable[str] = (),
        requires: Iterable[str] = (),
    ) -> CaseResult:
        """Every measurement judged by its spec, every missing required check added as
        failed; ``requires``: checks this run must measure besides the file's required ones
        (the other arguments as :class:`~fempipe.validation.checks.CaseResult`)."""
        refs = self.references
        names = refs.names(quick)
        checks = tuple(evaluate(_spec(refs, m.spec), m, names) for m in measured)
        emitted = {c.name for c in checks}
        declared = dict.fromkeys((*required(refs.checks, quick), *requires))
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
        )


def _spec(refs: References, key: str) -> Mapping:
    try:
        return refs.checks[key]
    except KeyError:
        raise KeyError(f"{refs.case}: no check {key!r} in references/{refs.case}.json") from None


def label_tag(label: str) -> str:
    """A discretization label as it appears in check names: ``"FE P3:8"`` → ``"FEP3:8"``, ``"N = 3"`` → ``"N3"``."""
    return label.replace(" ", "").replace("=", "")

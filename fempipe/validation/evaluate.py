"""Checks from data: what a case measured, judged by the check specs of its reference file.

``references/<case>.json`` holds a ``"checks"`` section: per check its kind (``below``: the
measured value at most a limit; ``close``: within a tolerance of a reference; ``holds``: a
statement the case judges), claim, limit or reference and tolerance, why and source.  A case
only measures: it returns one :class:`Measured` per check (:func:`measure`), and
:func:`evaluate` builds the :class:`~fempipe.validation.checks.Check` from it and its spec.

Texts are templates (:func:`fill`): ``{x}`` is the measurement's field ``x``, else the
reference value ``x`` (in the quick suite ``x_quick`` where there is one); ``{sources[x]}``
is the source of ``x``; ``{limit}``, ``{reference}``, ``{atol}``, ``{rtol}`` the check's own
numbers.  A list is formatted item by item and joined by ", "; the format ``π`` writes an
angle as a multiple of π.  A number of a spec is a number or a template that fills to one;
one the spec leaves out is the measurement's field of that name.  The spec's key is the
check's name, itself a template for a family of checks (one per inclination, say).
docs/verification.md describes the format.
"""

from __future__ import annotations

import string
from collections.abc import Mapping
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from .checks import Check

__all__ = ["KINDS", "Measured", "alpha_name", "evaluate", "fill", "measure"]

#: The kinds of check, with the numbers each takes (and their defaults; None: required).
KINDS: dict[str, dict[str, float | None]] = {
    "below": {"limit": None},
    "close": {"reference": None, "atol": 0.0, "rtol": 0.0},
    "holds": {},
}
#: The keys a check spec may have besides its numbers.
SPEC_KEYS = {"kind", "claim", "why", "source", "category", "reference", "measured", "required"}


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


class _Template(string.Formatter):
    """``str.format`` with lists joined by ", " and the format ``π`` (:func:`alpha_name`)."""

    def format_field(self, value: Any, format_spec: str) -> str:
        if isinstance(value, (list, tuple, np.ndarray)):
            return ", ".join(self.format_field(v, format_spec) for v in value)
        if format_spec == "π":
            return alpha_name(float(value))
        return format(value, format_spec)


_TEMPLATE = _Template()


def fill(template: str, names: Mapping[str, Any]) -> str:
    """``template`` with its ``{placeholders}`` filled from ``names`` (module docstring)."""
    return _TEMPLATE.vformat(template, (), names)


@dataclass(frozen=True)
class Measured:
    """What a case measured for the check ``spec`` of its reference file.

    ``value`` is the measured number (``below``, ``close``) or text (``holds``), ``ok``
    whether a ``holds`` statement holds, ``fields`` the values of the spec's placeholders.
    """

    spec: str
    value: Any = None
    ok: bool | None = None
    fields: Mapping[str, Any] = field(default_factory=dict)


def measure(spec: str, value: Any = None, *, ok: bool | None = None, **fields: Any) -> Measured:
    """``Measured(spec, value, ok, fields)``: ``measure("fe_mesh", err, mesh="P3:16")``."""
    return Measured(spec, value, ok, fields)


def _number(spec: Mapping, key: str, default: float | None, m: Measured, names: Mapping):
    """A number of the spec: a number, a template filled to one, or the measurement's field."""
    if key in spec:
        v = spec[key]
        return float(fill(v, names)) if isinstance(v, str) else v
    if key in m.fields:
        return m.fields[key]
    if default is None:
        raise KeyError(f"check {m.spec!r}: {key!r} is neither in its spec nor measured")
    return default


def evaluate(spec: Mapping, m: Measured, names: Mapping[str, Any]) -> Check:
    """The check of the measurement ``m`` by its ``spec`` (``names``: the reference values).

    ``names`` maps the references' names to their values and ``"sources"`` to their
    sources (:meth:`fempipe.validation.case.References.names`); the measurement's fields
    and the check's numbers are added to it for the templates.  ``below``: ``measured <=
    limit``; ``close``: ``|measured - reference| <= atol + rtol |reference|``; ``holds``:
    the case's verdict ``ok``.
    """
    kind = spec["kind"]
    names = {**names, **m.fields}
    nums = {k: _number(spec, k, d, m, names) for k, d in KINDS[kind].items()}
    names.update(nums)
    name, claim, source = (fill(t, names) for t in (m.spec, spec["claim"], spec["source"]))
    why = fill(spec.get("why", "qualitative statement"), names)
    category = spec.get("category", "paper" if kind == "holds" else "numerics")
    if kind == "holds":
        reference = spec.get("reference", m.fields.get("reference", True))
        if isinstance(reference, str):
            reference = fill(reference, names)
        value = fill(spec["measured"], names) if "measured" in spec else m.value
        return Check(name, claim, category, bool(m.ok), value, reference, why, source)
    value = float(m.value)
    if kind == "below":
        limit = nums["limit"]
        tol = f"≤ {limit:.3g}; {why}"
        return Check(name, claim, category, value <= limit, value, float(limit), tol, source)
    ref, atol, rtol = float(nums["reference"]), nums["atol"], nums["rtol"]
    err = abs(value - ref)
    bound = " + ".join([f"{atol:.3g}"] * bool(atol) + [f"{rtol:.3g}·|ref|"] * bool(rtol))
    tol = f"|Δ| ≤ {bound or '0'} (|Δ| = {err:.3g}); {why}"
    return Check(name, claim, category, err <= atol + rtol * abs(ref), value, ref, tol, source)

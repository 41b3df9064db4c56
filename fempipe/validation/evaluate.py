"""Checks from data: what a case measured, judged by the check specs of its reference file.

``references/<case>.json`` has a ``"checks"`` section: per check its kind (``below`` a
limit, ``close`` to a reference, ``holds``: a verdict of the case), claim, numbers, why and
source.  A case returns one :class:`Measured` per check (:func:`measure`); :func:`evaluate`
builds the :class:`~fempipe.validation.checks.Check`.  Texts are templates (:func:`fill`):
``{x}`` is the measurement's field ``x``, else the reference value ``x`` (quick suite:
``x_quick`` if any), ``{sources[x]}`` its source, ``{limit}`` etc. the check's numbers; lists
are joined by ", ", the format ``π`` writes an angle as a multiple of π.  A spec's key is
the check's name, itself a template for a family.  Format: docs/verification.md.
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
    """The angle as a multiple of π (``π/4``, ``-2π/3``, ``0``; denominators <= 12), else 4 decimals."""
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
    """What a case measured for check ``spec``: ``value``, ``ok`` (``holds``), template ``fields``."""

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
    """The check of ``m`` by ``spec`` (``below``: measured <= limit; ``close``: |measured -
    reference| <= atol + rtol |reference|; ``holds``: verdict ``ok``); ``names``: references."""
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

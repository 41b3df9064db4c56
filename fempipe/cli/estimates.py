"""``--error-estimate``: the option and the shapes it adds to a command's output.

With ``--error-estimate`` a command (``static``, ``critical``, ``simulate``)
reruns its computation on the refined discretisation of
:func:`fempipe.studies.error_estimate.refine` and reports, beside each number ``Q``
of its JSON, ``Q_error`` (the estimate of
:func:`fempipe.studies.error_estimate.estimate`) and ``Q_refined`` (the refined
value), plus a top-level ``"error_estimate"`` describing the method
(:class:`fempipe.studies.error_estimate.ErrorEstimate`) with the ``notes`` of the
comparison (an event found on one discretisation only, attractors of
different kinds, a refined solve that failed).  CSV files gain only the
``Q_error`` columns, after the existing ones.  The text output shows
``value ± error``.  Without the option nothing of this is computed or shown.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable, Mapping

from fempipe.studies.error_estimate import RATIO, ErrorEstimate, estimate

__all__ = [
    "ERROR",
    "REFINED",
    "add_argument",
    "beside",
    "error_columns",
    "header",
    "pm",
    "with_estimate",
]

#: Suffixes of the keys added beside a reported key.
ERROR, REFINED = "_error", "_refined"


def add_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--error-estimate`` in its own group; ``what`` names the numbers it covers."""
    g = parser.add_argument_group("error estimate")
    g.add_argument(
        "--error-estimate",
        action="store_true",
        help=f"also run on the refined discretisation (FE: every element halved; modal: twice "
        f"the modes) and report beside {what} its error estimate KEY_error = "
        "max(3 |Q - Q_refined| 2^p / (2^p - 1), solver tolerance) (Roache's Grid Convergence "
        "Index; p = 2k for Pk, 3 for sine modes, 4 for beam modes) and KEY_refined; costs about "
        "the refined run",
    )


def beside(d: Mapping, key: str, extra: Mapping) -> dict:
    """A copy of ``d`` with the items of ``extra`` inserted right after ``key``.

    Keeps the JSON readable: ``v_cr``, ``v_cr_error``, ``v_cr_refined``.  If
    ``key`` is absent the items are appended.
    """
    if key not in d:
        return {**d, **extra}
    out: dict = {}
    for k, val in d.items():
        out[k] = val
        if k == key:
            out.update(extra)
    return out


def with_estimate(
    d: Mapping,
    key: str,
    refined: float | None,
    order: float | None,
    floor: float,
    scale: float = 1.0,
    ratio: float = RATIO,
) -> dict:
    """``d`` with ``key_error`` and ``key_refined`` beside ``key``.

    The error is :func:`~fempipe.studies.error_estimate.estimate` of ``d[key]``
    against ``refined`` with the floor ``floor * max(1, |d[key]|)`` (a
    relative solver tolerance); None when either value is None.  ``scale``
    converts a derived quantity (an SI value, ``scale`` times a
    dimensionless one whose values are given).
    """
    coarse = d.get(key)
    if coarse is None or refined is None:
        err = None
    else:
        err = estimate(coarse, refined, order, ratio, floor=floor * max(1.0, abs(coarse)))
    return beside(d, key, _pair(key, err, refined, scale))


def _pair(key: str, err: float | None, refined: float | None, scale: float) -> dict:
    return {
        key + ERROR: None if err is None else err * scale,
        key + REFINED: None if refined is None else refined * scale,
    }


def error_columns(rows: Iterable[Mapping]) -> list[str]:
    """The CSV columns of ``rows``: every key but ``*_refined`` and notes, errors last.

    The existing columns keep their order and position; the ``*_error``
    columns follow them.
    """
    keys: list[str] = []
    for row in rows:
        keys.extend(k for k in row if k not in keys)
    errors = [k for k in keys if k.endswith(ERROR)]
    plain = [k for k in keys if not k.endswith((ERROR, REFINED)) and k != "error_note"]
    return plain + errors


def header(info: ErrorEstimate, notes: list[str]) -> dict:
    """The top-level ``"error_estimate"`` entry: the method and the notes."""
    return {**info.to_dict(), "notes": list(notes)}


def print_footer(est: Mapping, where: str = "") -> None:
    """The text output's last lines: how the estimates were formed, then the notes.

    ``where`` is added after the refined discretisation (e.g. the attractor found there).
    """
    print(
        f"± error estimate: {est['method']} to {est['refined']}{where}, {est['formula']} "
        f"(floor: {est['floor']})"
    )
    for note in est["notes"]:
        print(f"note: {note}")


def pm(value, error, spec: str = "{:+.6f}") -> str:
    """``"value ± error"`` (the error with two digits); ``"value ± ?"`` without an error."""
    text = spec.format(value)
    if error is None:
        return f"{text} ± ?"
    return f"{text} ± {error:.1e}"

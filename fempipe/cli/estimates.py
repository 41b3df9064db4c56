"""``--error-estimate``: the option, and how a command shows the estimates.

With ``--error-estimate`` a command (``static``, ``critical``, ``simulate``)
reruns its computation on the refined discretization of
:func:`fempipe.studies.error_estimate.refine` and reports, beside each number ``Q``
of its JSON, ``Q_error`` (the estimate of
:func:`fempipe.studies.error_estimate.estimate`) and ``Q_refined`` (the refined
value), plus a top-level ``"error_estimate"`` describing the method
(:class:`fempipe.studies.error_estimate.ErrorEstimate`) with the ``notes`` of the
comparison (an event found on one discretization only, attractors of
different kinds, a refined solve that failed).  The library attaches them
(:mod:`fempipe.studies.estimates`); this module holds the option and the
shapes of the other outputs: CSV files gain only the ``Q_error`` columns,
after the existing ones (:func:`error_columns`), and the text output shows
``value ± error`` (:func:`pm`, :func:`print_footer`).  Without the option
nothing of this is computed or shown.
"""

from __future__ import annotations

import argparse
from collections.abc import Iterable, Mapping

from fempipe.studies.estimates import ERROR, REFINED

__all__ = [
    "ERROR",
    "REFINED",
    "add_argument",
    "error_columns",
    "pm",
    "print_footer",
]


def add_argument(parser: argparse.ArgumentParser, what: str) -> None:
    """``--error-estimate`` in its own group; ``what`` names the numbers it covers."""
    g = parser.add_argument_group("error estimate")
    g.add_argument(
        "--error-estimate",
        action="store_true",
        help=f"also run on the refined discretization (FE: every element halved; modal: twice "
        f"the modes) and report beside {what} its error estimate KEY_error = "
        "max(3 abs(Q - Q_refined) 2^p / (2^p - 1), solver tolerance) (Roache's Grid Convergence "
        "Index; p = 2k for Pk, 3 for sine modes, 4 for beam modes) and KEY_refined; costs about "
        "the refined run",
    )


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


def print_footer(est: Mapping, where: str = "") -> None:
    """The text output's last lines: how the estimates were formed, then the notes.

    ``where`` is added after the refined discretization (e.g. the attractor found there).
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

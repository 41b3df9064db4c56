"""The shape of the estimates in a result: ``Q_error`` and ``Q_refined`` beside ``Q``.

The keys are inserted right after the reported key (:func:`beside`), so that
the JSON reads ``v_cr``, ``v_cr_error``, ``v_cr_refined``; the top-level
``"error_estimate"`` entry is :func:`header`.  :class:`Refined` is what every
refined run of :mod:`fempipe.studies.estimates` returns.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

from fempipe.studies.error_estimate import RATIO, ErrorEstimate, estimate

__all__ = ["ERROR", "REFINED", "Refined", "beside", "header", "with_estimate"]

#: Suffixes of the keys added beside a reported key.
ERROR, REFINED = "_error", "_refined"


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


def header(info: ErrorEstimate, notes: Sequence[str]) -> dict:
    """The top-level ``"error_estimate"`` entry: the method and the notes."""
    return {**info.to_dict(), "notes": list(notes)}


@dataclass(frozen=True)
class Refined:
    """A computation repeated on the refined discretization.

    Attributes
    ----------
    discretization : FiniteElement or Modal
        The refined discretization, :func:`~fempipe.studies.error_estimate.refine`
        of the reported one.
    info : ErrorEstimate
        How the estimates are formed (order, ratio, the floor's origin).
    notes : tuple of str
        What the refined run could not do (a refined solve that failed, ...).
    """

    discretization: object
    info: ErrorEstimate
    notes: tuple[str, ...]

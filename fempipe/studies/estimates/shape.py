"""The shape of the estimates in a result: ``Q_error`` and ``Q_refined`` right after ``Q``.

So the JSON reads ``v_cr``, ``v_cr_error``, ``v_cr_refined``; the top-level
``"error_estimate"`` entry is :func:`header`.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

from fempipe.studies.error_estimate import ERROR, RATIO, REFINED, ErrorEstimate, estimate

__all__ = ["beside", "header", "pair", "with_estimate"]


def beside(d: Mapping, key: str, extra: Mapping) -> dict:
    """A copy of ``d`` with the items of ``extra`` right after ``key`` (appended if absent)."""
    if key not in d:
        return {**d, **extra}
    out: dict = {}
    for k, val in d.items():
        out[k] = val
        if k == key:
            out.update(extra)
    return out


def pair(key: str, err, refined, scale: float = 1.0) -> dict:
    """``{key_error: err * scale, key_refined: refined * scale}``, None kept."""
    return {
        key + ERROR: None if err is None else err * scale,
        key + REFINED: None if refined is None else refined * scale,
    }


def with_estimate(
    d: Mapping,
    key: str,
    refined: float | None,
    order: float | None,
    floor: float,
    ratio: float = RATIO,
) -> dict:
    """``d`` with ``key_error`` (floor ``floor * max(1, |d[key]|)``) and ``key_refined``
    beside ``key``; the error None when either value is None."""
    coarse = d.get(key)
    if coarse is None or refined is None:
        err = None
    else:
        err = estimate(coarse, refined, order, ratio, floor=floor * max(1.0, abs(coarse)))
    return beside(d, key, pair(key, err, refined))


def header(info: ErrorEstimate, notes: Sequence[str]) -> dict:
    """The top-level ``"error_estimate"`` entry: the method and the notes."""
    return {**info.to_dict(), "notes": list(notes)}

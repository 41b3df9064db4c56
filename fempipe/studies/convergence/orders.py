"""Observed orders of convergence and Richardson extrapolation."""

from __future__ import annotations

import math

import numpy as np

__all__ = ["estimate_order", "extrapolate_richardson", "local_orders", "extrapolate"]


def estimate_order(
    dofs: np.ndarray, errors: np.ndarray, floor: float, n_points: int = 3
) -> tuple[float, tuple[int, ...]]:
    """Slope of log(err) against log(dofs) over the finest ``n_points`` points with err > floor.

    Returns ``(order, indices)``; order is positive for a decaying error and
    NaN if fewer than two usable points exist.
    """
    dofs, errors = np.asarray(dofs, dtype=float), np.asarray(errors, dtype=float)
    ok = np.flatnonzero(np.isfinite(errors) & (errors > floor))
    # The finest usable points are consecutive refinements: the asymptotic range.
    idx = tuple(int(i) for i in ok[-n_points:])
    if len(idx) < 2:
        return float("nan"), idx
    slope = np.polyfit(np.log(dofs[list(idx)]), np.log(errors[list(idx)]), 1)[0]
    return float(-slope), idx


def extrapolate_richardson(
    coarse: complex, fine: complex, order: float, ratio: float = 2.0
) -> tuple[complex, float]:
    """Richardson extrapolation and its error estimate (the size of the correction)."""
    corr = (fine - coarse) / (ratio**order - 1.0)
    return fine + corr, float(abs(corr))


def local_orders(sizes: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Orders from three consecutive members: log(|d_1| / |d_2|) / log(r), d the differences."""
    sizes = np.asarray(sizes, dtype=float)
    values = np.asarray(values)
    out = np.full(max(0, sizes.size - 2), np.nan)
    for i in range(out.size):
        d1 = abs(values[i + 1] - values[i])
        d2 = abs(values[i + 2] - values[i + 1])
        r = sizes[i + 2] / sizes[i + 1]
        if d1 > 0 and d2 > 0 and np.isfinite(d1 + d2):
            out[i] = math.log(d1 / d2) / math.log(r)
    return out


def extrapolate(f, values: np.ndarray, tol: float, p: float | None):
    """``(value, error_estimate, how, raw)`` from the two finest usable members, or None.

    Parameters
    ----------
    f : Family
        The family (its ``sizes``) the values belong to.
    values : ndarray
        One value per member, NaN where the member failed.
    tol : float
        Relative accuracy of the solver: the floor of the error estimate.
    p : float or None
        Theoretical order (None: the observed local order of the last three members).

    Returns
    -------
    tuple or None
        ``raw`` is the estimate before it is raised to the solver tolerance.
    """
    sizes = np.array(f.sizes, dtype=float)
    ok = np.flatnonzero(np.isfinite(values))
    if ok.size < 2 or ok[-1] != ok[-2] + 1:
        return None
    i, j = int(ok[-2]), int(ok[-1])
    r = sizes[j] / sizes[i]
    floor = tol * max(1.0, abs(values[j]))
    lo = local_orders(sizes[: j + 1], values[: j + 1])
    if p is None:
        if lo.size == 0 or not np.isfinite(lo[-1]) or lo[-1] <= 0:
            # No theory and no measured order: the last difference is the estimate.
            raw = float(abs(values[j] - values[i]))
            value = complex(values[j]) if np.iscomplexobj(values) else float(values[j])
            n_i, n_j = f.sizes[i], f.sizes[j]
            how = f"finest member n = {n_j}, estimate |Q(n={n_j}) - Q(n={n_i})| (no order known)"
            return value, max(raw, floor), how, raw
        p = float(lo[-1])
        source = f"observed local order {p:.2f}"
    else:
        source = f"theoretical order {p:g}"
    val, corr = extrapolate_richardson(values[i], values[j], p, r)
    raw = corr
    err = max(corr, floor)
    how = (
        f"n = {f.sizes[i]}, {f.sizes[j]} with the {source} (ratio {r:g}); error estimate "
        f"|correction| = {corr:.2e}"
        + (f", raised to the solver tolerance {floor:.1e}" if floor > corr else "")
    )
    if lo.size and np.isfinite(lo[-1]) and abs(lo[-1] - p) > 0.5 * p and corr > floor:
        # Not yet asymptotic: the correction is no measure of the error; use
        # the last difference itself, a safer bound.
        raw = float(abs(values[j] - values[i]))
        err = max(raw, floor)
        how += (
            f"; the last local order {lo[-1]:.2f} is far from {p:g} (not asymptotic), so the "
            f"estimate is the last difference {err:.2e}"
        )
    return val, err, how, raw

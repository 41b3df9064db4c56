"""Bifurcations of periodic orbits found on a finished branch: folds, period doublings,
Neimark-Sacker points, located between consecutive points.

Method: docs/theory/numerics.md, "Branches of periodic orbits".
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from .results import (
    CycleBranch,
    CyclePoint,
    CycleSpecialPoint,
    HopfPoint,
    nontrivial_multipliers,
    swing,
)

__all__ = ["NEAR_ONE", "cycle_branch", "special_points"]

#: Non-real multipliers this close to +1 are not counted as a complex pair.
NEAR_ONE = 0.1


def cycle_branch(
    name: str,
    hopf: HopfPoint,
    points: Sequence[CyclePoint],
    reason: str,
    steps: int,
    rejected: int,
    its: int,
    wall: float,
) -> CycleBranch:
    """The :class:`CycleBranch` of ``points`` with its special points."""
    return CycleBranch(
        name=name,
        hopf=hopf,
        points=tuple(points),
        special_points=tuple(special_points(points)),
        end_reason=reason,
        steps=steps,
        rejected_steps=rejected,
        newton_iterations=its,
        wall_time=wall,
    )


def _tests(pt: CyclePoint) -> tuple[int, int, float, float]:
    """(real multipliers below -1, complex ones outside the unit circle,
    the most negative real multiplier + 1, the largest complex modulus - 1)."""
    mu = nontrivial_multipliers(pt.multipliers)
    real = np.abs(mu.imag) <= 1e-10 * np.maximum(1.0, np.abs(mu))
    neg = mu[real & (mu.real < 0)].real
    # A "complex pair" within NEAR_ONE of +1 is two real multipliers near 1 (the
    # trivial one and the one through +1 near a Hopf point or a fold) that the
    # eigensolver splits into a pair: no Neimark-Sacker point.
    cplx = np.abs(mu[~real & (np.abs(mu - 1.0) > NEAR_ONE)])
    return (
        int(np.sum(neg < -1.0)),
        int(np.sum(cplx > 1.0)),
        float(neg.min() + 1.0) if neg.size else math.nan,
        float(cplx.max() - 1.0) if cplx.size else math.nan,
    )


def special_points(points: Sequence[CyclePoint]) -> list[CycleSpecialPoint]:
    """Folds, period doublings and Neimark-Sacker points between consecutive points."""
    out = []
    for k in range(1, len(points)):
        a, b = points[k - 1], points[k]
        if k >= 2:
            p0 = points[k - 2]
            if (a.v - p0.v) * (b.v - a.v) < 0:
                out.append(_fold(p0, a, b, k - 1))
        ta, tb = _tests(a), _tests(b)
        for count, value, kind in ((0, 2, "period_doubling"), (1, 3, "neimark_sacker")):
            if ta[count] != tb[count]:
                fa, fb = ta[value], tb[value]
                if kind == "period_doubling":
                    fa, fb = -fa, -fb  # > 0 outside
                w = fa / (fa - fb) if math.isfinite(fa) and math.isfinite(fb) and fa != fb else 0.5
                w = min(1.0, max(0.0, w))
                out.append(
                    CycleSpecialPoint(
                        v=float(a.v + w * (b.v - a.v)),
                        type=kind,
                        period=float(a.period + w * (b.period - a.period)),
                        index=k - 1,
                    )
                )
    return out


def _fold(p0: CyclePoint, a: CyclePoint, b: CyclePoint, index: int) -> CycleSpecialPoint:
    """Vertex of the parabola v(s) through three points (s: chord length in (v, T, swing))."""

    def dist(p, q):
        return math.hypot(p.v - q.v, p.period - q.period, swing(p) - swing(q))

    s = np.array([0.0, dist(p0, a), dist(p0, a) + dist(a, b)])
    c = np.polyfit(s, np.array([p0.v, a.v, b.v]), 2)
    if c[0] == 0:
        return CycleSpecialPoint(float(a.v), "fold", float(a.period), index)
    s_star = float(np.clip(-c[1] / (2 * c[0]), s[0], s[-1]))
    return CycleSpecialPoint(
        v=float(np.polyval(c, s_star)),
        type="fold",
        period=float(
            np.polyval(np.polyfit(s, np.array([p0.period, a.period, b.period]), 2), s_star)
        ),
        index=index,
    )

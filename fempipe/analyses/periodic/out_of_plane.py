"""Do the planar orbits and equilibria of a bifurcation diagram survive in 3-D?

A planar orbit is one of the 3-D model too (mirror symmetry), observed only when stable out
of the plane as well: an orbit's out-of-plane Floquet multipliers, an equilibrium's
out-of-plane spectrum decide.  :class:`VerdictStore` keeps them in the point store;
:func:`locate_change` finds where the largest out-of-plane multiplier crosses 1.
Theory: docs/theory/space.md.
"""

from __future__ import annotations

import json
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fempipe.analyses.limit_cycle import LimitCycle, ShootingError, shoot
from fempipe.analyses.three_d import compute_out_of_plane_floquet
from fempipe.analyses.three_d.verdict import cycle_entries, equilibrium_verdict
from fempipe.core.errors import SolverError
from fempipe.core.files import write_text
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.plane.operators import PipeModel

from .results import CyclePoint, nontrivial_multipliers

__all__ = [
    "VerdictStore",
    "as_limit_cycle",
    "cycle_verdict",
    "equilibrium_verdict",
    "locate_change",
    "EveryKth",
    "Spread",
    "branch_verdicts",
]


def as_limit_cycle(pt: CyclePoint) -> LimitCycle:
    """The orbit of a continued point as a :class:`LimitCycle` (its state, period,
    tip and multipliers; no trajectory): what the out-of-plane monodromy needs."""
    return LimitCycle(
        period=float(pt.period),
        q0=np.asarray(pt.q0, dtype=float),
        qdot0=np.asarray(pt.qdot0, dtype=float),
        tip=dict(pt.tip),
        floquet_multipliers=np.asarray(pt.multipliers),
        stable=bool(pt.stable),
        iterations=pt.iterations,
        residual=pt.residual,
    )


def cycle_verdict(model: PipeModel, cycle: LimitCycle, stable_in_plane: bool) -> dict:
    """The out-of-plane multipliers of a planar orbit and ``stable_3d``: the keys of
    :func:`fempipe.analyses.three_d.verdict.cycle_entries` and ``planar_block_max_multiplier``
    (the planar multipliers again: evidence)."""
    oop = compute_out_of_plane_floquet(model, cycle)
    out = cycle_entries(model, oop, stable_in_plane)
    # Evidence to check the verdict by: the out-of-plane run's planar block (the
    # planar model's multipliers, recomputed) and, at an axisymmetric alpha,
    # the neutral multiplier of the rotation about the vertical (1 exactly).
    mu = nontrivial_multipliers(np.asarray(oop.planar_multipliers))
    out["planar_block_max_multiplier"] = float(np.max(np.abs(mu))) if mu.size else None
    return out


@dataclass(frozen=True)
class EveryKth:
    """Branch points for the verdict (picklable): every ``k``-th, the last, those at ``v_keep``."""

    k: int
    v_keep: tuple = ()

    def __call__(self, points: Sequence[CyclePoint]) -> list[int]:
        keep = set(range(0, len(points), max(int(self.k), 1)))
        if points:
            keep.add(len(points) - 1)
        keep |= {i for i, p in enumerate(points) if any(abs(p.v - w) < 1e-9 for w in self.v_keep)}
        return sorted(keep)


@dataclass(frozen=True)
class Spread:
    """About ``n`` branch points spread evenly (picklable), the last, those at ``v_keep``."""

    n: int
    v_keep: tuple = ()

    def __call__(self, points: Sequence[CyclePoint]) -> list[int]:
        k = max(1, math.ceil(len(points) / max(int(self.n), 1)))
        return EveryKth(k, self.v_keep)(points)


class VerdictStore:
    """The 3-D verdicts of one branch's points: ``{"points": {"<index>": {"v", ...}}}``,
    rewritten atomically after each; one of another v is recomputed; no path: in memory."""

    def __init__(self, path: str | Path | None) -> None:
        self.path = None if path is None else Path(path)
        self.data: dict = {}
        if self.path is not None and self.path.exists():
            self.data = json.loads(self.path.read_text()).get("points", {})

    def get(self, index: int, v: float) -> dict | None:
        d = self.data.get(str(index))
        if d is None or abs(d["v"] - v) > 1e-12:
            return None
        return {k: x for k, x in d.items() if k != "v"}

    def put(self, index: int, v: float, verdict: dict) -> None:
        self.data[str(index)] = {"v": float(v), **verdict}
        if self.path is not None:
            write_text(self.path, json.dumps({"points": self.data}))


def branch_verdicts(
    model: PipeModel,
    points: Sequence[CyclePoint],
    indices: Sequence[int],
    store: VerdictStore,
    on_point: Callable[[], None] | None = None,
) -> dict[int, dict]:
    """The verdicts of ``points[i]`` for i in ``indices``, from ``store`` or computed
    (and stored); keyed by index."""
    out = {}
    for i in indices:
        pt = points[i]
        got = store.get(i, pt.v)
        if got is None:
            m = model.with_params(replace(model.params, v=float(pt.v)))
            try:
                got = cycle_verdict(m, as_limit_cycle(pt), pt.stable)
            except SolverError as exc:
                # Reported with the point, not fatal for the diagram.
                got = {"stable_3d": None, "out_of_plane_error": str(exc)}
            store.put(i, pt.v, got)
            if on_point is not None:
                on_point()
        out[i] = got
    return out


def locate_change(
    model: PipeModel,
    a: CyclePoint,
    b: CyclePoint,
    mu_a: float,
    mu_b: float,
    *,
    tol: float = 1e-3,
    max_iter: int = 6,
) -> dict | None:
    """The v between two orbits where the largest non-trivial out-of-plane multiplier crosses 1:
    regula falsi (Illinois) on ``mu - 1`` until the bracket is shorter than ``tol``.

    Returns ``{"v", "v_bracket", "iterations", "cpu_time"}``, or None without a bracketed
    crossing or when an orbit cannot be shot.
    """
    t0 = time.process_time()
    if (mu_a - 1.0) * (mu_b - 1.0) > 0:
        return None
    # Bracket ends [v, mu - 1]; Illinois: the end kept twice in a row has its value halved.
    lo, hi = [a.v, mu_a - 1.0], [b.v, mu_b - 1.0]
    side = it = 0
    while it < max_iter and abs(hi[0] - lo[0]) >= tol:
        it += 1
        v = lo[0] - lo[1] * (hi[0] - lo[0]) / (hi[1] - lo[1])
        w = (v - a.v) / (b.v - a.v)
        q, qd, T = (
            (1 - w) * np.asarray(getattr(a, k)) + w * np.asarray(getattr(b, k))
            for k in ("q0", "qdot0", "period")
        )
        m = model.with_params(replace(model.params, v=float(v)))
        try:
            cyc = shoot(PipeDynamics(m), q, qd, float(T))
        except ShootingError:
            return None
        f = compute_out_of_plane_floquet(m, cyc).max_nontrivial - 1.0
        if f * lo[1] > 0:
            lo = [float(v), f]
            if side == 1:
                hi[1] *= 0.5
            side = 1
        else:
            hi = [float(v), f]
            if side == -1:
                lo[1] *= 0.5
            side = -1
    v_root = lo[0] - lo[1] * (hi[0] - lo[0]) / (hi[1] - lo[1])
    return {
        "v": float(v_root),
        "v_bracket": sorted([float(lo[0]), float(hi[0])]),
        "iterations": it,
        "cpu_time": time.process_time() - t0,
    }

"""Do the planar orbits and equilibria of a bifurcation diagram survive in 3-D?

The planar states are states of the 3-D model (:mod:`fempipe.model.space`)
and stay planar by the mirror symmetry, so a planar periodic orbit of the
paper's Eq. (20) is a periodic orbit in 3-D as well; it is observed in 3-D
only when it is stable in the plane and against out-of-plane perturbations.
For an orbit the out-of-plane Floquet multipliers decide
(:func:`fempipe.analyses.space.out_of_plane_floquet`), for an equilibrium the
out-of-plane spectrum (:mod:`fempipe.model.out_of_plane`), as the planar
``simulate`` reports them (:func:`fempipe.analyses.space.three_dimensional_verdict`).

:class:`VerdictStore` keeps the verdicts of a branch in the point store of a
diagram, beside the branch, so that a rerun computes only the missing ones;
:func:`locate_change` bisects between two orbits of a branch for the v where
the largest out-of-plane multiplier crosses the unit circle.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from fempipe.analyses.limit_cycle import LimitCycle, ShootingError, shoot
from fempipe.analyses.space import out_of_plane_floquet
from fempipe.analyses.space.verdict import cycle_entries, equilibrium_verdict
from fempipe.core.errors import SolverError
from fempipe.core.files import write_text
from fempipe.model.operators import PipeModel

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
    empty = np.zeros(0)
    return LimitCycle(
        period=float(pt.period),
        q0=np.asarray(pt.q0, dtype=float),
        qdot0=np.asarray(pt.qdot0, dtype=float),
        level=math.nan,
        tip=dict(pt.tip),
        floquet_multipliers=np.asarray(pt.multipliers),
        stable=bool(pt.stable),
        iterations=pt.iterations,
        residual=pt.residual,
        orbit_t=empty,
        orbit_q=empty,
        orbit_qdot=empty,
    )


def cycle_verdict(model: PipeModel, cycle: LimitCycle, stable_in_plane: bool) -> dict:
    """The out-of-plane multipliers of a planar orbit and ``stable_3d``.

    Parameters
    ----------
    model : PipeModel
        At the orbit's v.
    cycle : LimitCycle
    stable_in_plane : bool
        The orbit's planar verdict (its in-plane Floquet multipliers).

    Returns
    -------
    dict
        ``out_of_plane_floquet_multipliers`` (six largest, ``[re, im]``),
        ``max_nontrivial_out_of_plane_multiplier``, ``stable_out_of_plane``,
        ``stable_3d`` (stable in the plane and out of it),
        ``out_of_plane_cpu_time`` (CPU seconds), ``planar_block_max_multiplier``
        (the largest non-trivial modulus of the out-of-plane run's planar block: the
        planar multipliers again), ``neutral_out_of_plane_multiplier`` (``[re, im]``,
        the rotation about the vertical, left out of the verdict; None unless
        sin(alpha) = 0) with ``out_of_plane_symmetry_defect`` (its distance from 1),
        and ``stable_3d_note`` where the verdict is rough
        (:func:`~fempipe.analyses.space.verdict.rough_verdict_note`).
    """
    oop = out_of_plane_floquet(model, cycle)
    out = cycle_entries(model, oop, stable_in_plane)
    # Evidence to check the verdict by: the out-of-plane run's planar block (the
    # planar model's multipliers, recomputed) and, at an axisymmetric alpha,
    # the neutral multiplier of the rotation about the vertical (1 exactly).
    mu = nontrivial_multipliers(np.asarray(oop.planar_multipliers))
    out["planar_block_max_multiplier"] = float(np.max(np.abs(mu))) if mu.size else None
    return out


@dataclass(frozen=True)
class EveryKth:
    """A selection of branch points for the verdict (picklable, for worker
    processes): every ``k``-th one, the last one, and those at the velocities
    ``v_keep`` (to 1e-9)."""

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
    """A selection of about ``n`` branch points spread evenly by index (picklable),
    with the last one and those at the velocities ``v_keep`` (to 1e-9)."""

    n: int
    v_keep: tuple = ()

    def __call__(self, points: Sequence[CyclePoint]) -> list[int]:
        k = max(1, math.ceil(len(points) / max(int(self.n), 1)))
        return EveryKth(k, self.v_keep)(points)


class VerdictStore:
    """The 3-D verdicts of one branch's points, one JSON file in the point store.

    ``{"points": {"<index>": {"v": ..., <verdict keys>}}}``, rewritten atomically
    after every new verdict; a verdict whose v is not the point's is ignored
    (recomputed).  Without a path the verdicts live in memory only.
    """

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
    """The v between two orbits of a branch where the largest non-trivial
    out-of-plane multiplier crosses 1, by regula falsi (Illinois) on
    ``mu - 1``.

    The orbit at an intermediate v is shot (:func:`fempipe.analyses.limit_cycle.shoot`)
    from the state interpolated linearly between the two orbits in v; the
    interval shrinks until it is shorter than ``tol`` or ``max_iter``
    orbits have been computed.

    Returns
    -------
    dict or None
        ``{"v", "v_bracket": [lo, hi], "iterations", "cpu_time"}`` (v: the secant's root in the last bracket), or
        None when the two do not bracket a crossing or an orbit cannot be shot.
    """
    import time

    t0 = time.process_time()
    if (mu_a - 1.0) * (mu_b - 1.0) > 0:
        return None
    # Bracket ends [v, mu - 1]; Illinois: the end kept twice in a row has its value halved.
    lo, hi = [a.v, mu_a - 1.0], [b.v, mu_b - 1.0]
    side = 0
    it = 0
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
            cyc = shoot(m, q, qd, float(T))
        except ShootingError:
            return None
        f = out_of_plane_floquet(m, cyc).max_nontrivial - 1.0
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

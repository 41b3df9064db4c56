"""Bifurcation diagrams of the 3-D model: its attractors against v, by resumable sweeps.

At each v the 3-D model is integrated until its attractor is recognized
(:func:`~fempipe.analyses.three_d.motion.simulate_3d`); the point records its kind
(equilibrium, periodic, whirl, quasi-periodic, non-periodic), whether the motion is planar,
the tip's [min, max] in the plane and out of it (Y_tip), the period and the whirl rate.  Each
point starts from the state the previous one ended on; after an equilibrium, and at the first
point, from the static state of its own v perturbed in the plane and out of it (``started``).
Points, store and sweep driver: :mod:`fempipe.analyses.periodic.points`.
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.three_d.motion import Motion3D, simulate_3d
from fempipe.model.plane.operators import PipeModel

from ..limit_cycle import TIP_KEYS_3D
from ..periodic.points import (
    BifurcationPoint,
    PointStore,
    diagram_manifest,
    ordered,
    run_diagram,
    sweep_points,
)

__all__ = ["Diagram3D", "compute_diagram_3d", "sweep_3d"]


def _point(motion: Motion3D, m: PipeModel, direction, index, v, started) -> BifurcationPoint:
    """The point of the motion found at v; its state: on the shot orbit, else the last one."""
    if motion.cycle is not None:
        U, Ud = motion.cycle.q0, motion.cycle.qdot0
    else:
        U, Ud = motion.U[-1], motion.Udot[-1]
    return BifurcationPoint(
        v=float(v),
        direction=direction,
        index=index,
        alpha=float(m.params.alpha),
        attractor=motion.kind,
        motion=motion.motion,
        **{k: [float(x) for x in motion.tip[k]] for k in TIP_KEYS_3D},
        period=None if motion.period is None else float(motion.period),
        period_n=motion.period_n,
        whirl_rate=motion.whirl_rate,
        planarity=float(motion.planarity),
        stable=None if motion.cycle is None else bool(motion.cycle.stable),
        started=started,
        steps=int(motion.steps),
        rejected_steps=int(motion.rejected_steps),
        t_end=float(motion.t_end),
        cpu_time=float(motion.cpu_time),
        q=np.asarray(U, dtype=float),
        qdot=np.asarray(Ud, dtype=float),
    )


def sweep_3d(
    model: PipeModel,
    values: Sequence[float],
    direction: str = "up",
    *,
    store: PointStore | None = None,
    progress: Callable[[BifurcationPoint], None] | None = None,
    **motion_options,
) -> list[BifurcationPoint]:
    """Sweep the flow velocity in 3-D, each point from the previous attractor.

    As :func:`fempipe.analyses.bifurcation.sweep`: ``model`` the planar model; ``store``
    read and written (resume); ``progress(point)``; ``**motion_options`` passed to
    :func:`simulate_3d` (``out_of_plane_amplitude``, ``t_max``, ``rtol`` ...).
    """

    def step(i: int, v: float, prev: BifurcationPoint | None) -> BifurcationPoint:
        m = model.with_params(replace(model.params, v=v))
        options = dict(motion_options)
        started = "static state"
        if prev is not None and prev.attractor != "equilibrium":
            options["initial"] = (prev.q, prev.qdot)
            started = "previous attractor"
        return _point(simulate_3d(m, **options), m, direction, i, v, started)

    return sweep_points(values, direction, step, store=store, sweep="space", progress=progress)


def _sweep_task(model, values, direction, options, store, on_point) -> list[BifurcationPoint]:
    """One sweep of :func:`compute_diagram_3d`."""
    return sweep_3d(model, values, direction, store=store, progress=on_point, **options)


@dataclass(frozen=True)
class Diagram3D:
    """The attractors of the 3-D model against v: the points (dicts, by direction and sweep
    order), the run's wall time, the sum of the points' CPU times, the manifest."""

    points: list
    wall_time: float
    cpu_time: float
    manifest: dict

    def to_dict(self) -> dict:
        return {
            "points": list(self.points),
            "wall_time": self.wall_time,
            "cpu_time": self.cpu_time,
            "manifest": self.manifest,
        }


def compute_diagram_3d(
    model: PipeModel,
    values: Sequence[float],
    directions: Sequence[str] = ("up",),
    *,
    store_dir: str | os.PathLike | None = None,
    progress: Callable[[int, int], None] | None = None,
    **motion_options,
) -> Diagram3D:
    """The 3-D attractors against v by sweeps (:func:`sweep_3d`), resumable.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
    directions : sequence of {"up", "down"}
    store_dir, progress
        As :func:`fempipe.analyses.periodic.points.run_diagram`.
    **motion_options
        Passed to :func:`simulate_3d`; part of the store's manifest.
    """
    t0 = time.perf_counter()
    for d in directions:
        ordered(values, d)
    manifest = diagram_manifest(
        model, values, motion_options, head={"model": "3d"}, directions=directions
    )
    results = run_diagram(
        _sweep_task,
        [(model, values, d, dict(motion_options)) for d in directions],
        manifest,
        store_dir=store_dir,
        progress=progress,
        total=len(values) * len(directions),
    )
    points = [p for r in results for p in r]
    cpu = math.fsum(p.cpu_time for p in points)
    return Diagram3D([p.to_dict() for p in points], time.perf_counter() - t0, cpu, manifest)

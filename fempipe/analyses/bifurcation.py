"""Bifurcation diagrams of the tip response against the flow velocity by sweeps (Figs. 7-10).

:func:`sweep` steps v up or down, each point starting from the previous attractor;
:func:`compute_bifurcation_diagram` runs sweeps (up, down, several alpha) in parallel,
resumable.  Details: docs/theory/numerics.md, "Bifurcation sweeps".
"""

from __future__ import annotations

import logging
import math
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.periodic.out_of_plane import cycle_verdict, equilibrium_verdict
from fempipe.core.errors import SolverError
from fempipe.model.dynamics_problem import PipeDynamics, refuse_hysteretic
from fempipe.model.plane.operators import PipeModel

from .dynamics import IntegrationError, make_initial_state
from .limit_cycle import TIP_KEYS, Attractor, LimitCycle, ShootingError, find_attractor, shoot
from .periodic.points import (
    DIRECTIONS,
    BifurcationPoint,
    PointStore,
    diagram_manifest,
    ordered,
    run_diagram,
    sweep_points,
)

__all__ = [
    "BifurcationPoint",
    "PointStore",
    "sweep",
    "compute_bifurcation_diagram",
    "DIRECTIONS",
    "BifurcationDiagram",
]

log = logging.getLogger(__name__)


def sweep(
    model: PipeModel,
    values: Sequence[float],
    direction: str = "up",
    *,
    q0: np.ndarray | None = None,
    qdot0: np.ndarray | None = None,
    perturbation: float = 0.01,
    store: PointStore | None = None,
    alpha_index: int = 0,
    progress: Callable[[BifurcationPoint], None] | None = None,
    continue_cycles: bool = True,
    out_of_plane: bool = False,
    **attractor_options,
) -> list[BifurcationPoint]:
    """Sweep the flow velocity, each point starting from the previous attractor.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
    direction : {"up", "down"}
    q0, qdot0 : ndarray, optional
        Start of the first point (default: static state + perturbation).
    perturbation : float
        Rotation (rad, first sine mode) added after an equilibrium.
    store, alpha_index : PointStore, optional; int
        Finished points are read from and written to it (file names by alpha index).
    progress : callable, optional
        Called with each finished (or loaded) point.
    continue_cycles : bool
        After a stable cycle, first shoot from it.
    out_of_plane : bool
        Also each attractor's 3-D verdict (a stored point gains it on a rerun).
    **attractor_options
        Passed to :func:`fempipe.analyses.limit_cycle.find_attractor`.

    Returns
    -------
    list of BifurcationPoint
    """
    refuse_hysteretic(model.params, "sweep")

    def at(v: float) -> PipeModel:
        return model.with_params(model.params.with_flow(v))

    def step(i: int, v: float, prev: BifurcationPoint | None) -> BifurcationPoint:
        m = at(v)
        if prev is None:
            q, p, after_equilibrium, cycle = q0, qdot0, q0 is None, None
        else:
            q, p = prev.q, prev.qdot
            after_equilibrium = prev.attractor == "equilibrium"
            cycle = (prev.period, prev.period_n) if prev.attractor == "periodic" else None
        q, p = _start_state(m, q, p, after_equilibrium, perturbation)
        t0 = time.perf_counter()
        att = None
        if continue_cycles and cycle is not None and attractor_options.get("use_shooting", True):
            att = _continue_cycle(m, q, p, cycle, attractor_options)
        if att is None:
            att = find_attractor(m, q, p, perturbation=perturbation, **attractor_options)
        point = _new_point(att, m, direction, i, v, t0)
        if out_of_plane:
            point = replace(point, three_d=_three_d_verdict(m, point, att.cycle))
        return point

    def amend(v: float, point: BifurcationPoint) -> BifurcationPoint:
        if out_of_plane and point.three_d is None:
            return replace(point, three_d=_three_d_verdict(at(v), point))
        return point

    return sweep_points(
        values,
        direction,
        step,
        store=store,
        sweep=f"a{alpha_index:02d}",
        progress=progress,
        amend=amend,
    )


def _three_d_verdict(m: PipeModel, point: BifurcationPoint, cycle=None) -> dict:
    """``stable_3d`` and its evidence: a cycle's out-of-plane multipliers (of ``cycle``, or
    the stored point's state and period), an equilibrium's out-of-plane spectrum."""
    if point.attractor == "equilibrium":
        return equilibrium_verdict(m, point.q, True)
    if point.attractor != "periodic" or point.period is None:
        return {"stable_3d": None}
    if cycle is None:
        cycle = LimitCycle(float(point.period), point.q, point.qdot)  # what the monodromy needs
    stable = point.max_multiplier is None or point.max_multiplier < 1.0
    try:
        return cycle_verdict(m, cycle, stable)
    except SolverError as exc:
        return {"stable_3d": None, "out_of_plane_error": str(exc)}


def _start_state(m: PipeModel, q, p, after_equilibrium: bool, perturbation: float):
    """``(q, p)``, perturbed after an equilibrium; none: the static state, perturbed."""
    if q is None:
        q, p = make_initial_state(m, 1, perturbation)
    elif after_equilibrium:
        dq, _ = make_initial_state(m, 1, perturbation, q_static=np.zeros(m.n))
        q, p = np.asarray(q) + dq, np.zeros(m.n)
    return q, p


def _new_point(
    att: Attractor, m: PipeModel, direction: str, index: int, v: float, t0: float
) -> BifurcationPoint:
    """The point of an attractor found at v (``t0``: when its computation began); logged."""
    tip = att.tip or dict.fromkeys(TIP_KEYS, [math.nan, math.nan])
    point = BifurcationPoint(
        v=float(v),
        direction=direction,
        index=index,
        alpha=float(m.params.alpha),
        attractor=att.kind,
        **{k: tip[k] for k in TIP_KEYS},
        period=att.period,
        period_n=att.period_n,
        max_multiplier=(att.cycle.max_nontrivial_multiplier if att.cycle else None),
        steps=att.stats["steps"],
        rejected_steps=att.stats["rejected_steps"],
        wall_time=time.perf_counter() - t0,
        q=np.asarray(att.q, dtype=float),
        qdot=np.asarray(att.qdot, dtype=float),
    )
    log.info(
        "%s v=%.4g: %s, eta_tip [%.4g, %.4g] (%.1f s)",
        direction,
        v,
        att.kind,
        point.eta_tip[0],
        point.eta_tip[1],
        point.wall_time,
    )
    return point


def _continue_cycle(model, q, p, prev_cycle, options) -> Attractor | None:
    """Shoot from the previous point's cycle; None if that does not give a stable cycle."""
    period, period_n = prev_cycle
    try:
        # A tenth of the shooting tolerance: the residual understates the orbit's error
        # by 1 / (1 - mu) for a multiplier mu near 1 (near the Hopf point).
        cyc = shoot(
            PipeDynamics(model),
            q,
            p,
            period,
            rtol=options.get("shoot_rtol", 1e-7),
            tol=0.1 * options.get("shoot_tol", 1e-6),
            max_iter=8,
            reuse_monodromy=True,
        )
    except (ShootingError, IntegrationError) as exc:
        log.info("cycle continuation failed at v = %.6g (%s); integrating", model.params.v, exc)
        return None
    if not cyc.stable:
        log.info("continued cycle unstable at v = %.6g; integrating", model.params.v)
        return None
    return Attractor(
        kind="periodic",
        period=cyc.period,
        period_n=period_n,
        tip=cyc.tip,
        cycle=cyc,
        q=cyc.q0.copy(),
        qdot=cyc.qdot0.copy(),
        params=model.params,
        t_end=0.0,
        stats={
            "steps": cyc.total_steps,
            "rejected_steps": cyc.rejected_steps,
            "wall_time": cyc.wall_time,
        },
        message="continued from the previous cycle by shooting",
    )


def _sweep_task(
    model: PipeModel,
    values: list,
    direction: str,
    alpha_index: int,
    options: dict,
    out_of_plane: bool,
    store: PointStore,
    on_point: Callable[[BifurcationPoint], None] | None,
) -> list[dict]:
    """One sweep of :func:`compute_bifurcation_diagram`: its points without their states."""
    pts = sweep(
        model,
        values,
        direction,
        store=store,
        alpha_index=alpha_index,
        progress=on_point,
        out_of_plane=out_of_plane,
        **options,
    )
    return [pt.to_dict(state=False) for pt in pts]


@dataclass(frozen=True)
class BifurcationDiagram:
    """All points of a set of sweeps (dicts, by alpha, direction, sweep order), the run's
    wall time and its manifest (``run.json``)."""

    points: list
    wall_time: float
    manifest: dict

    def to_dict(self) -> dict:
        return {
            "points": list(self.points),
            "wall_time": self.wall_time,
            "discretization": self.manifest["discretization"],
            "params": self.manifest["params"],
        }


def compute_bifurcation_diagram(
    model: PipeModel,
    values: Sequence[float],
    directions: Sequence[str] = DIRECTIONS,
    *,
    alphas: Sequence[float] | None = None,
    store_dir: str | os.PathLike | None = None,
    executor: Executor | None = None,
    workers: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    out_of_plane: bool = False,
    **attractor_options,
) -> BifurcationDiagram:
    """Sweeps up and/or down (for one or several alpha), in parallel, resumable.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
    directions : sequence of {"up", "down"}
    alphas : sequence of float, optional
        Inclinations; default ``[model.params.alpha]``.
    store_dir, executor, workers, progress
        As :func:`fempipe.analyses.periodic.points.run_diagram`.
    out_of_plane : bool
        Each point's 3-D verdict (:func:`sweep`).
    **attractor_options
        Passed to :func:`fempipe.analyses.limit_cycle.find_attractor`.

    Returns
    -------
    BifurcationDiagram

    Raises
    ------
    ValueError
        Hysteretic damping, no values, a bad direction or worker count
        (PointStoreMismatchError for a store of another run).
    """
    refuse_hysteretic(model.params, "compute_bifurcation_diagram")
    t0 = time.perf_counter()
    directions = list(directions)
    for d in directions:
        ordered(values, d)
    alphas = [model.params.alpha] if alphas is None else [float(a) for a in alphas]
    manifest = diagram_manifest(
        model, values, attractor_options, alphas=alphas, directions=directions
    )
    tasks = [
        (
            model.with_params(replace(model.params, alpha=float(a))),
            list(values),
            d,
            ia,
            dict(attractor_options),
            out_of_plane,
        )
        for ia, a in enumerate(alphas)
        for d in directions
    ]
    results = run_diagram(
        _sweep_task,
        tasks,
        manifest,
        store_dir=store_dir,
        executor=executor,
        workers=workers,
        progress=progress,
        total=len(values) * len(tasks),
    )
    points = [pt for r in results for pt in r]
    return BifurcationDiagram(points=points, wall_time=time.perf_counter() - t0, manifest=manifest)

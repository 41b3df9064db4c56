"""Bifurcation diagrams of the tip response against the flow velocity (Figs. 7-10) by sweeps.

:func:`sweep` steps v up (or down) through a list of values; each point starts from the
attractor of the previous one and records, with
:func:`fempipe.analyses.limit_cycle.find_attractor`, the kind of attractor, its period and the
extrema of eta(1), X_g(1), Z_g(1); a stable cycle is first continued by shooting directly
from the previous one.  Sweeping up and down shows hysteresis where a stable equilibrium and
a stable cycle coexist (subcritical Hopf).  :func:`bifurcation_diagram` runs independent
sweeps (up and down, several alpha) in parallel through
:func:`fempipe.core.parallel.run_tasks`, writing every finished point at once to a point
store, from which a rerun resumes with the same results as an uninterrupted run.

How a point starts and how the store resumes: docs/theory/numerics.md, "Bifurcation sweeps".
"""

from __future__ import annotations

import logging
import math
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.periodic.out_of_plane import cycle_verdict, equilibrium_verdict
from fempipe.core.errors import SolverError
from fempipe.core.parallel import run_tasks
from fempipe.model.dynamics_problem import refuse_hysteretic
from fempipe.model.operators import PipeModel

from .dynamics import IntegrationError, make_initial_state
from .limit_cycle import Attractor, LimitCycle, ShootingError, find_attractor, shoot
from .periodic.points import BifurcationPoint, PointStore

__all__ = [
    "BifurcationPoint",
    "PointStore",
    "sweep",
    "bifurcation_diagram",
    "DIRECTIONS",
    "BifurcationDiagram",
]

log = logging.getLogger(__name__)

DIRECTIONS = ("up", "down")


def _ordered(values: Sequence[float], direction: str) -> list[float]:
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be 'up' or 'down', got {direction!r}")
    vals = sorted(float(v) for v in values)
    return vals if direction == "up" else vals[::-1]


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
        Its ``params.v`` is replaced by each value.
    values : sequence of float
        Flow velocities (sorted up or down according to ``direction``).
    direction : {"up", "down"}
    q0, qdot0 : ndarray, optional
        Start of the first point (default: static state + perturbation).
    perturbation : float
        Amplitude (rad, first sine mode) added when the previous attractor is
        an equilibrium.
    store : PointStore, optional
        Finished points are read from and written to it (resume).
    alpha_index : int
        Index of this sweep's alpha in the store's file names.
    progress : callable, optional
        Called with each finished (or loaded) point.
    continue_cycles : bool
        When the previous attractor is a stable cycle, first shoot directly
        from it with its period (natural-parameter continuation of the periodic
        orbit, no transient); accepted only if Newton converges to a stable
        cycle of non-zero amplitude, else the point falls back to
        :func:`~fempipe.analyses.limit_cycle.find_attractor` from the same state.
    out_of_plane : bool
        Also decide whether each attractor survives in 3-D (:func:`_three_d_verdict`:
        the out-of-plane Floquet multipliers of a cycle, the out-of-plane
        spectrum of an equilibrium), stored with the point; a stored point
        without it gains it on a rerun.
    **attractor_options
        Passed to :func:`fempipe.analyses.limit_cycle.find_attractor` (``t_max``,
        ``rtol``, ``shoot_rtol`` ...).

    Returns
    -------
    list of BifurcationPoint

    Raises
    ------
    ValueError
        If the model has hysteretic damping (no time-domain meaning).
    """
    refuse_hysteretic(model.params, "sweep")
    vals = _ordered(values, direction)
    if not vals:
        raise ValueError("values must not be empty")
    q, p = q0, qdot0
    previous_equilibrium = q0 is None
    prev_cycle = None
    points = []
    for i, v in enumerate(vals):
        m = model.with_params(model.params.with_flow(v))
        old = None if store is None else _stored_point(store, alpha_index, direction, i, v)
        if old is not None and out_of_plane and old.three_d is None:
            old = replace(old, three_d=_three_d_verdict(m, old))
            store.save(alpha_index, old)
        if old is not None:
            points.append(old)
            q, p = old.q, old.qdot
            previous_equilibrium = old.attractor == "equilibrium"
            prev_cycle = (old.period, old.period_n) if old.attractor == "periodic" else None
            if progress is not None:
                progress(old)
            continue
        q, p = _start_state(m, q, p, previous_equilibrium, perturbation)
        t0 = time.perf_counter()
        att = None
        if (
            continue_cycles
            and prev_cycle is not None
            and attractor_options.get("use_shooting", True)
        ):
            att = _continue_cycle(m, q, p, prev_cycle, attractor_options)
        if att is None:
            att = find_attractor(m, q, p, perturbation=perturbation, **attractor_options)
        point = _new_point(att, m, direction, i, v, t0)
        if out_of_plane:
            point = replace(point, three_d=_three_d_verdict(m, point, att.cycle))
        if store is not None:
            store.save(alpha_index, point)
        points.append(point)
        q, p = point.q, point.qdot
        previous_equilibrium = att.kind == "equilibrium"
        prev_cycle = (att.period, att.period_n) if att.cycle is not None else None
        if progress is not None:
            progress(point)
    return points


def _three_d_verdict(m: PipeModel, point: BifurcationPoint, cycle=None) -> dict:
    """``stable_3d`` of a sweep's attractor and its out-of-plane evidence.

    A periodic attractor: its out-of-plane Floquet multipliers
    (:func:`fempipe.analyses.periodic.out_of_plane.cycle_verdict`; the orbit from
    ``cycle``, or a stored point's state and period); an equilibrium: the
    out-of-plane spectrum (an attractor is stable in the plane); a
    non-periodic attractor: ``stable_3d`` None.
    """
    if point.attractor == "equilibrium":
        return equilibrium_verdict(m, point.q, True)
    if point.attractor != "periodic" or point.period is None:
        return {"stable_3d": None}
    if cycle is None:
        empty = np.zeros(0)
        cycle = LimitCycle(
            period=float(point.period),
            q0=point.q,
            qdot0=point.qdot,
            level=math.nan,
            tip={},
            floquet_multipliers=np.zeros(0, complex),
            stable=True,
            iterations=0,
            residual=0.0,
            orbit_t=empty,
            orbit_q=empty,
            orbit_qdot=empty,
        )
    stable = point.max_multiplier is None or point.max_multiplier < 1.0
    try:
        return cycle_verdict(m, cycle, stable)
    except SolverError as exc:
        return {"stable_3d": None, "out_of_plane_error": str(exc)}


def _start_state(m: PipeModel, q, p, previous_equilibrium: bool, perturbation: float):
    """The state a point starts from: ``(q, p)``, perturbed after an equilibrium.

    With no previous state, the static state of ``m`` plus the perturbation.
    """
    if q is None:
        q, p = make_initial_state(m, 1, perturbation)
    elif previous_equilibrium:
        dq, _ = make_initial_state(m, 1, perturbation, q_static=np.zeros(m.n))
        q, p = np.asarray(q) + dq, np.zeros(m.n)
    return q, p


def _stored_point(
    store: PointStore, alpha_index: int, direction: str, index: int, v: float
) -> BifurcationPoint | None:
    """The point ``index`` of a sweep from the store, None if not there yet.

    Raises ValueError if the stored point is of another flow velocity.
    """
    old = store.load(alpha_index, direction, index)
    if old is not None and not math.isclose(old.v, v, rel_tol=0, abs_tol=1e-12):
        raise ValueError(f"stored point {index} ({direction}) has v = {old.v}, expected {v}")
    return old


def _new_point(
    att: Attractor, m: PipeModel, direction: str, index: int, v: float, t0: float
) -> BifurcationPoint:
    """The point of an attractor found at v (``t0``: when its computation began); logged."""
    point = BifurcationPoint(
        v=float(v),
        direction=direction,
        index=index,
        alpha=float(m.params.alpha),
        attractor=att.kind,
        eta_tip=att.tip["eta_tip"] if att.tip else [math.nan, math.nan],
        X_tip=att.tip["X_tip"] if att.tip else [math.nan, math.nan],
        Z_tip=att.tip["Z_tip"] if att.tip else [math.nan, math.nan],
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
        # A tenth of the shooting tolerance: the residual understates the error of
        # the orbit by 1 / (1 - mu) for a multiplier mu near 1 (near the Hopf
        # point: 2.2e-6 in eta_tip at v = 6.6, P3:16, with the residual below 1e-6).
        cyc = shoot(
            model,
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
    store_dir: str,
    manifest: dict,
    options: dict,
    on_point: Callable[[BifurcationPoint], None] | None = None,
    out_of_plane: bool = False,
) -> list[dict]:
    """One independent sweep (in a worker, or in this process with ``on_point``).

    Opens the store itself (a worker cannot share the caller's object) and
    returns the points as dicts without their states.
    """
    store = PointStore(store_dir, manifest)
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


def _manifest(model: PipeModel, values, directions, alphas, options) -> dict:
    p = model.params.to_dict()
    p.pop("v")
    p.pop("alpha")
    return {
        "discretization": model.disc.to_dict(),
        "params": p,
        "alphas": [float(a) for a in alphas],
        "values": sorted(float(v) for v in values),
        "directions": list(directions),
        "options": {k: options[k] for k in sorted(options)},
    }


@dataclass(frozen=True)
class BifurcationDiagram:
    """All points of a set of sweeps, with run diagnostics.

    Attributes
    ----------
    points : list of dict
        :meth:`BifurcationPoint.to_dict` of every point (without the states),
        ordered by alpha, direction, then sweep order.
    wall_time : float
        Seconds for the whole run (loading stored points included).
    manifest : dict
        The run's description, as in the point store's ``run.json``.
    """

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


def bifurcation_diagram(
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
    """Sweeps up and/or down (for one or several alpha), in parallel.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
        Flow velocities.
    directions : sequence of {"up", "down"}
    alphas : sequence of float, optional
        Inclinations; default ``[model.params.alpha]``.
    store_dir : path, optional
        Point store (resume); a temporary directory if omitted.
    executor : concurrent.futures.Executor, optional
        Runs the independent sweeps (any Executor: process pool, Dask's
        ``Client.get_executor()``).  With a remote executor the store directory
        must be visible to the workers.
    workers : int, optional
        Without an executor: > 1 runs the sweeps in that many local worker
        processes (:func:`fempipe.core.parallel.process_pool`: they exit with this
        process, however it ends); 1 or None runs in this process.
    progress : callable, optional
        Called as ``progress(done, total)`` when points finish (or are loaded
        from the store).
    out_of_plane : bool
        Each point's 3-D verdict (:func:`sweep`); not part of the store's
        manifest, so that a planar run's store is resumed, adding it.
    **attractor_options
        Passed to :func:`fempipe.analyses.limit_cycle.find_attractor`.

    Returns
    -------
    BifurcationDiagram
        Points ordered by alpha, direction, then sweep order.

    Raises
    ------
    ValueError
        If the model has hysteretic damping (no time-domain meaning).
    Exception
        The error of the first sweep (in that order) that failed, once all
        sweeps have ended; the points finished before it are in the store.
    KeyboardInterrupt
        Including :class:`fempipe.core.parallel.Interrupted`: the workers are
        stopped first; rerun on the same store to resume.
    """
    refuse_hysteretic(model.params, "bifurcation_diagram")
    t0 = time.perf_counter()
    directions = list(directions)
    _check_diagram_args(values, directions, workers)
    alphas = [model.params.alpha] if alphas is None else [float(a) for a in alphas]
    manifest = _manifest(model, values, directions, alphas, attractor_options)
    tmp = None
    if store_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="fempipe-sweep-")
        store_dir = tmp.name
    try:
        store = PointStore(store_dir, manifest)
        total = len(values) * len(directions) * len(alphas)
        sweeps = [(ia, a, d) for ia, a in enumerate(alphas) for d in directions]
        in_process = executor is None and (workers is None or int(workers) == 1 or len(sweeps) == 1)
        counter = _ProgressCounter(store, total, progress)
        args = [
            (
                model.with_params(replace(model.params, alpha=float(a))),
                list(values),
                d,
                ia,
                str(store_dir),
                manifest,
                dict(attractor_options),
                counter.on_point if in_process else None,
                out_of_plane,
            )
            for ia, a, d in sweeps
        ]
        results = run_tasks(
            _sweep_task,
            args,
            workers=None if in_process else workers,
            executor=executor,
            heartbeat=None if in_process else counter.poll_store,
        )
        if not in_process:
            counter.poll_store()
    finally:
        if tmp is not None:
            tmp.cleanup()
    for r in results:
        if isinstance(r, BaseException):
            # The other sweeps ran to their end and their points are stored.
            raise r
    points = [pt for r in results for pt in r]
    return BifurcationDiagram(points=points, wall_time=time.perf_counter() - t0, manifest=manifest)


def _check_diagram_args(values, directions: list, workers: int | None) -> None:
    """ValueError for an unknown direction, no values, or fewer than one worker."""
    for d in directions:
        if d not in DIRECTIONS:
            raise ValueError(f"direction must be 'up' or 'down', got {d!r}")
    if not len(values):
        raise ValueError("values must not be empty")
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")


class _ProgressCounter:
    """Reports ``progress(done, total)`` of a bifurcation diagram's points.

    In this process every finished point is counted (:meth:`on_point`); with
    workers the files they have written to the store are (:meth:`poll_store`,
    reported only when the count changed).
    """

    def __init__(
        self, store: PointStore, total: int, progress: Callable[[int, int], None] | None
    ) -> None:
        self.store = store
        self.total = total
        self.progress = progress
        self.done = 0
        self.shown = -1

    def on_point(self, _point: BifurcationPoint) -> None:
        """Count a point finished (or loaded) in this process."""
        self.done += 1
        if self.progress is not None:
            self.progress(self.done, self.total)

    def poll_store(self) -> None:
        """Count the points the workers have written to the store."""
        n = self.store.count()
        if self.progress is not None and n != self.shown:
            self.progress(n, self.total)
            self.shown = n

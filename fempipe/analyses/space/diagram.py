"""Bifurcation diagrams of the 3-D motion: the attractors of the 3-D model against v.

A sweep steps v up (or down); at each v the 3-D model is integrated until its
attractor is recognized (:func:`~fempipe.analyses.space.motion.simulate_space`)
and the point records its kind (equilibrium, periodic, whirl, quasi-periodic,
non-periodic),
whether the motion is planar, the tip's [min, max] in the plane (eta_tip,
X_tip, Z_tip) and out of it (Y_tip), the period and the whirl rate.  Each
point starts from the state the previous one ended on (its cycle's start, or
the last state of its run); after an equilibrium, and at the first point,
from the static state of its own v perturbed in the plane and out of it
(``started`` says which).  So the sweep follows the attractor it is
on, and sweeping up and down shows where two attractors coexist.

Every finished point is written at once to a point store (one JSON file each,
with the state it ended on); a rerun on the same store computes only the
missing points, from the same starting states.
"""

from __future__ import annotations

import json
import math
import os
import tempfile
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from ...core.files import claim_run_directory, write_text
from ...model.operators import PipeModel
from .motion import TIP3_KEYS, SpaceMotion, simulate_space

__all__ = ["SpacePoint", "SpacePointStore", "space_sweep", "space_diagram"]

DIRECTIONS = ("up", "down")


@dataclass(frozen=True)
class SpacePoint:
    """One point of a 3-D sweep.

    Attributes
    ----------
    v : float
    direction : {"up", "down"}
    index : int
        Position in the sweep.
    alpha : float
    attractor : str
        ``"equilibrium"``, ``"periodic"``, ``"whirl"`` or ``"non-periodic"``.
    motion : str
        ``"planar"`` or ``"nonplanar"``.
    eta_tip, X_tip, Z_tip, Y_tip : list of float
        [min, max] on the attractor (Y_tip: out of the static plane).
    period : float or None
    period_n : int or None
    whirl_rate : float or None
    planarity : float
    stable : bool or None
        The shot orbit's 3-D Floquet verdict (None without a shot orbit).
    started : str
        ``"previous attractor"`` or ``"static state"`` (perturbed).
    steps, rejected_steps : int
    t_end, cpu_time : float
    U, Udot : ndarray
        The state the point ended on (on the orbit when one was shot).
    """

    v: float
    direction: str
    index: int
    alpha: float
    attractor: str
    motion: str
    eta_tip: list
    X_tip: list
    Z_tip: list
    Y_tip: list
    period: float | None
    period_n: int | None
    whirl_rate: float | None
    planarity: float
    stable: bool | None
    started: str
    steps: int
    rejected_steps: int
    t_end: float
    cpu_time: float
    U: np.ndarray = field(repr=False)
    Udot: np.ndarray = field(repr=False)

    def to_dict(self, state: bool = False) -> dict:
        """Plain JSON; with ``state`` also U and Udot (as the store keeps them)."""
        d = {k: getattr(self, k) for k in self.__dataclass_fields__ if k not in ("U", "Udot")}
        if state:
            d["U"] = [float(x) for x in self.U]
            d["Udot"] = [float(x) for x in self.Udot]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> SpacePoint:
        """Inverse of ``to_dict(state=True)``."""
        kw = {k: d[k] for k in cls.__dataclass_fields__ if k not in ("U", "Udot")}
        return cls(**kw, U=np.asarray(d["U"], dtype=float), Udot=np.asarray(d["Udot"], dtype=float))


class SpacePointStore:
    """A directory of finished 3-D points, one JSON file each, written atomically.

    ``run.json`` holds the run's manifest; a store of another run is refused
    (ValueError) so that a resume never mixes results.
    """

    def __init__(self, directory: str | os.PathLike, manifest: dict) -> None:
        self.manifest = json.loads(json.dumps(manifest))
        self.directory = claim_run_directory(directory, self.manifest)

    def path(self, direction: str, index: int) -> Path:
        return self.directory / f"space-{direction}-{index:03d}.json"

    def load(self, direction: str, index: int, v: float) -> SpacePoint | None:
        """The stored point, None if not finished; ValueError if it is of another v."""
        p = self.path(direction, index)
        if not p.exists():
            return None
        pt = SpacePoint.from_dict(json.loads(p.read_text()))
        if abs(pt.v - v) > 1e-12:
            raise ValueError(f"stored point {index} ({direction}) has v = {pt.v}, expected {v}")
        return pt

    def save(self, point: SpacePoint) -> None:
        write_text(self.path(point.direction, point.index), json.dumps(point.to_dict(state=True)))


def _point(motion: SpaceMotion, m: PipeModel, direction, index, v, started) -> SpacePoint:
    if motion.cycle is not None:
        U, Ud = motion.cycle.q0, motion.cycle.qdot0
    else:
        U, Ud = motion.U[-1], motion.Udot[-1]
    return SpacePoint(
        v=float(v),
        direction=direction,
        index=index,
        alpha=float(m.params.alpha),
        attractor=motion.kind,
        motion=motion.motion,
        **{k: [float(x) for x in motion.tip[k]] for k in TIP3_KEYS},
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
        U=np.asarray(U, dtype=float),
        Udot=np.asarray(Ud, dtype=float),
    )


def space_sweep(
    model: PipeModel,
    values: Sequence[float],
    direction: str = "up",
    *,
    store: SpacePointStore | None = None,
    progress: Callable[[SpacePoint], None] | None = None,
    **motion_options,
) -> list[SpacePoint]:
    """Sweep the flow velocity in 3-D, each point from the previous attractor.

    Parameters
    ----------
    model : PipeModel
        The planar model (discretization, parameters); ``params.v`` is replaced.
    values : sequence of float
    direction : {"up", "down"}
    store : SpacePointStore, optional
        Finished points are read from and written to it (resume).
    progress : callable, optional
        Called with each finished (or loaded) point.
    **motion_options
        Passed to :func:`simulate_space` (``out_of_plane_amplitude``, ``t_max``,
        ``rtol``, ...).

    Returns
    -------
    list of SpacePoint
    """
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be 'up' or 'down', got {direction!r}")
    vals = sorted(float(v) for v in values)
    if direction == "down":
        vals = vals[::-1]
    prev: SpacePoint | None = None
    out = []
    for i, v in enumerate(vals):
        m = model.with_params(replace(model.params, v=v))
        old = None if store is None else store.load(direction, i, v)
        if old is None:
            options = dict(motion_options)
            started = "static state"
            if prev is not None and prev.attractor != "equilibrium":
                options["initial"] = (prev.U, prev.Udot)
                started = "previous attractor"
            motion = simulate_space(m, **options)
            old = _point(motion, m, direction, i, v, started)
            if store is not None:
                store.save(old)
        out.append(old)
        prev = old
        if progress is not None:
            progress(old)
    return out


def _manifest(model: PipeModel, values, directions, options) -> dict:
    p = model.params.to_dict()
    p.pop("v")
    return {
        "model": "3d",
        "discretization": model.disc.to_dict(),
        "params": p,
        "values": sorted(float(v) for v in values),
        "directions": list(directions),
        "options": {k: options[k] for k in sorted(options)},
    }


def space_diagram(
    model: PipeModel,
    values: Sequence[float],
    directions: Sequence[str] = ("up",),
    *,
    store_dir: str | os.PathLike | None = None,
    progress: Callable[[SpacePoint], None] | None = None,
    **motion_options,
) -> dict:
    """The 3-D attractors against v by sweeps (:func:`space_sweep`), resumable.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
        Flow velocities.
    directions : sequence of {"up", "down"}
    store_dir : path, optional
        Point store (``run.json`` and one file per point); a temporary one if omitted.
    progress : callable, optional
        Called with each finished (or loaded) point.
    **motion_options
        Passed to :func:`simulate_space`; part of the store's manifest.

    Returns
    -------
    dict
        ``{"points": [SpacePoint.to_dict() ...], "wall_time", "cpu_time",
        "manifest"}``: points by direction, then sweep order; ``cpu_time`` sums
        the points' own (loaded points included).
    """
    t0 = time.perf_counter()
    if not len(values):
        raise ValueError("values must not be empty")
    for d in directions:
        if d not in DIRECTIONS:
            raise ValueError(f"direction must be 'up' or 'down', got {d!r}")
    manifest = _manifest(model, values, directions, motion_options)
    tmp = None
    if store_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="fempipe-space-sweep-")
        store_dir = tmp.name
    try:
        store = SpacePointStore(store_dir, manifest)
        points = [
            p
            for d in directions
            for p in space_sweep(model, values, d, store=store, progress=progress, **motion_options)
        ]
    finally:
        if tmp is not None:
            tmp.cleanup()
    return {
        "points": [p.to_dict() for p in points],
        "wall_time": time.perf_counter() - t0,
        "cpu_time": math.fsum(p.cpu_time for p in points),
        "manifest": manifest,
    }

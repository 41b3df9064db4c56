"""The points of a bifurcation diagram, their store and the resumable diagram driver.

:class:`PointStore` keeps finished points as one JSON file each (written atomically) in a
directory claimed by the run's manifest; :func:`sweep_points` steps v reusing stored points,
:func:`run_diagram` runs a diagram's independent tasks here or on workers.
Details: docs/theory/numerics.md, "Bifurcation sweeps".
"""

from __future__ import annotations

import json
import os
import tempfile
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fempipe.core.errors import PointStoreMismatchError
from fempipe.core.files import write_text
from fempipe.core.parallel import run_tasks

__all__ = [
    "DIRECTIONS",
    "POINT_KEYS",
    "POINT_KEYS_3D",
    "BifurcationPoint",
    "PointStore",
    "diagram_manifest",
    "ordered",
    "run_diagram",
    "sweep_points",
]

DIRECTIONS = ("up", "down")

#: The JSON keys of a point, in order: planar, and (:data:`POINT_KEYS_3D`) of the 3-D model.
POINT_KEYS = tuple(
    "v direction index alpha attractor eta_tip X_tip Z_tip period period_n max_multiplier "
    "steps rejected_steps wall_time".split()
)
POINT_KEYS_3D = tuple(
    "v direction index alpha attractor motion eta_tip X_tip Z_tip Y_tip period period_n "
    "whirl_rate planarity stable started steps rejected_steps t_end cpu_time".split()
)


@dataclass(frozen=True)
class BifurcationPoint:
    """One point of a sweep, of the planar model or (``motion`` set) of the 3-D model.

    The JSON keys are those of ``fempipe bifurcation --json`` (docs/cli/commands.md).
    ``attractor``: equilibrium, periodic, non-periodic (3-D also whirl, quasi-periodic);
    the tips [min, max] on it; ``q``, ``qdot``: the state it ended on, where the next point
    starts (``U``, ``Udot`` in a 3-D point's JSON).  Planar only: ``max_multiplier`` (largest
    non-trivial Floquet modulus), ``wall_time``, ``three_d`` (the 3-D verdict, whose keys join
    the point's).  3-D only: ``motion`` (planar, nonplanar), ``Y_tip``, ``whirl_rate``,
    ``planarity``, ``stable`` (the shot orbit's Floquet verdict), ``started`` (previous
    attractor, static state), ``t_end``, ``cpu_time``.
    """

    v: float
    direction: str
    index: int
    alpha: float
    attractor: str
    eta_tip: list
    X_tip: list
    Z_tip: list
    period: float | None
    period_n: int | None
    steps: int
    rejected_steps: int
    q: np.ndarray = field(repr=False)
    qdot: np.ndarray = field(repr=False)
    max_multiplier: float | None = None
    wall_time: float | None = None
    three_d: dict | None = None
    motion: str | None = None
    Y_tip: list | None = None
    whirl_rate: float | None = None
    planarity: float | None = None
    stable: bool | None = None
    started: str | None = None
    t_end: float | None = None
    cpu_time: float | None = None

    def to_dict(self, state: bool = False) -> dict:
        """Plain JSON; with ``state`` also the state (as the point store keeps it)."""
        is_3d = self.motion is not None
        d = {k: getattr(self, k) for k in (POINT_KEYS_3D if is_3d else POINT_KEYS)}
        if self.three_d is not None:
            d.update(self.three_d)
        if state:
            if not is_3d:
                d["three_d"] = self.three_d
            # repr-exact floats: a resumed sweep restarts from exactly this state.
            q, qdot = ("U", "Udot") if is_3d else ("q", "qdot")
            d[q] = [float(x) for x in self.q]
            d[qdot] = [float(x) for x in self.qdot]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> BifurcationPoint:
        """Inverse of ``to_dict(state=True)``."""
        is_3d = "U" in d
        q, qdot = ("U", "Udot") if is_3d else ("q", "qdot")
        return cls(
            **{k: d[k] for k in (POINT_KEYS_3D if is_3d else POINT_KEYS)},
            q=np.asarray(d[q], dtype=float),
            qdot=np.asarray(d[qdot], dtype=float),
            three_d=d.get("three_d"),
        )


def _differences(old, new, prefix: str = "") -> list[str]:
    """The dotted keys where two manifests differ."""
    if not (isinstance(old, dict) and isinstance(new, dict)):
        return [] if old == new else [prefix or "run.json"]
    out = []
    for k in sorted(set(old) | set(new), key=str):
        name = f"{prefix}.{k}" if prefix else str(k)
        if k not in old or k not in new:
            out.append(name)
        else:
            out += _differences(old[k], new[k], name)
    return out


class PointStore:
    """A directory (created if missing) of finished points, one JSON file each, written
    atomically; ``run.json`` holds the run's ``manifest``, and a directory of another run
    raises :class:`~fempipe.core.errors.PointStoreMismatchError` naming what differs."""

    def __init__(self, directory: str | os.PathLike, manifest: dict) -> None:
        self.manifest = json.loads(json.dumps(manifest))
        self.directory = Path(directory)
        self.directory.mkdir(parents=True, exist_ok=True)
        path = self.directory / "run.json"
        if not path.exists():
            write_text(path, json.dumps(self.manifest, indent=1))
            return
        old = json.loads(path.read_text())
        disc = old.get("discretization", {})
        if disc.get("kind") == "modal":
            disc.setdefault("basis", "sine")  # a modal run that names no basis is of sine modes
        if old != self.manifest:
            raise PointStoreMismatchError(self.directory, _differences(old, self.manifest))

    def path(self, sweep: str, direction: str, index: int) -> Path:
        """File of point ``index`` of the sweep ``direction`` of ``sweep`` (``a00``, ``space``)."""
        return self.directory / f"{sweep}-{direction}-{index:03d}.json"

    def load(self, sweep: str, direction: str, index: int, v: float) -> BifurcationPoint | None:
        """The stored point, None if not finished; PointStoreMismatchError if it is of another v."""
        p = self.path(sweep, direction, index)
        if not p.exists():
            return None
        point = BifurcationPoint.from_dict(json.loads(p.read_text()))
        if abs(point.v - v) > 1e-12:
            raise PointStoreMismatchError(
                self.directory, [f"v of point {index} ({direction}): {point.v}, expected {v}"]
            )
        return point

    def save(self, sweep: str, point: BifurcationPoint) -> None:
        """Write a finished point with its state (atomically: complete or absent)."""
        write_text(
            self.path(sweep, point.direction, point.index), json.dumps(point.to_dict(state=True))
        )

    def count(self) -> int:
        """Number of finished points of the sweeps in the store."""
        # Temporary files of unfinished writes start with "." and are not counted.
        return sum(
            1
            for d in DIRECTIONS
            for p in self.directory.glob(f"*-{d}-*.json")
            if not p.name.startswith(".")
        )


def ordered(values: Sequence[float], direction: str) -> list[float]:
    """``values`` sorted up or down; ValueError for another direction or no values."""
    if direction not in DIRECTIONS:
        raise ValueError(f"direction must be 'up' or 'down', got {direction!r}")
    vals = sorted(float(v) for v in values)
    if not vals:
        raise ValueError("values must not be empty")
    return vals if direction == "up" else vals[::-1]


def sweep_points(
    values: Sequence[float],
    direction: str,
    step: Callable[[int, float, BifurcationPoint | None], BifurcationPoint],
    *,
    store: PointStore | None = None,
    sweep: str = "a00",
    progress: Callable[[BifurcationPoint], None] | None = None,
    amend: Callable[[float, BifurcationPoint], BifurcationPoint] | None = None,
) -> list[BifurcationPoint]:
    """Step v through ``values`` in ``direction``: ``step(index, v, previous)`` computes a
    point (``previous`` None at the first) unless ``store`` has it under the name ``sweep``;
    ``amend(v, point)`` completes a loaded point (saved again if it returns another);
    ``progress(point)`` follows every point."""
    points: list[BifurcationPoint] = []
    for i, v in enumerate(ordered(values, direction)):
        point = None if store is None else store.load(sweep, direction, i, v)
        if point is not None and amend is not None:
            amended = amend(v, point)
            if amended is not point:
                store.save(sweep, amended)
            point = amended
        if point is None:
            point = step(i, v, points[-1] if points else None)
            if store is not None:
                store.save(sweep, point)
        points.append(point)
        if progress is not None:
            progress(point)
    return points


def diagram_manifest(
    model, values, options: dict, *, head=None, alphas=None, directions=None
) -> dict:
    """A diagram's ``run.json``: ``head``, the model but v (and alpha, given ``alphas``),
    the values, ``directions`` and the options."""
    p = model.params.to_dict()
    p.pop("v")
    if alphas is not None:
        p.pop("alpha")
    m = dict(head or {})
    m.update(discretization=model.disc.to_dict(), params=p)
    if alphas is not None:
        m["alphas"] = [float(a) for a in alphas]
    m["values"] = sorted(float(v) for v in values)
    if directions is not None:
        m["directions"] = list(directions)
    m["options"] = {k: options[k] for k in sorted(options)}
    return m


class _Progress:
    """``progress(done, total)``: points finished in this process (:meth:`tick`), or the
    points the workers have written to the store (:meth:`poll`, told when it changed)."""

    def __init__(self, store: PointStore, total, progress) -> None:
        self.store, self.total, self.progress = store, total, progress
        self.done, self.shown = 0, -1

    def tick(self, *_point) -> None:
        self.done += 1
        if self.progress is not None:
            self.progress(self.done, self.total)

    def poll(self) -> None:
        n = self.store.count()
        if self.progress is not None and n != self.shown:
            self.progress(n, self.total)
            self.shown = n


def run_diagram(
    task: Callable,
    tasks: Sequence[tuple],
    manifest: dict,
    *,
    store_dir: str | os.PathLike | None = None,
    executor=None,
    workers: int | None = None,
    progress: Callable[[int, int | None], None] | None = None,
    total: int | None = None,
) -> list:
    """Run the independent tasks of a resumable diagram; their results in order.

    Parameters
    ----------
    task : callable
        ``task(*args, store, on_point)`` per ``args`` of ``tasks`` (``on_point`` None in a worker).
    tasks : sequence of tuple
    manifest : dict
        The run (:func:`diagram_manifest`).
    store_dir : path, optional
        The point store; a temporary directory if omitted.
    executor, workers : Executor, int, optional
        Any executor that sees the store, or > 1 local processes.
    progress, total : callable, int, optional
        ``progress(done, total)``.

    Raises
    ------
    Exception
        The first failed task's error, once all have ended.
    """
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    tmp = None
    if store_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="fempipe-diagram-")
        store_dir = tmp.name
    try:
        store = PointStore(store_dir, manifest)
        in_process = executor is None and (workers is None or int(workers) == 1 or len(tasks) == 1)
        counter = _Progress(store, total, progress)
        on_point = counter.tick if in_process else None
        poll = None if in_process or total is None else counter.poll
        results = run_tasks(
            task,
            [(*args, store, on_point) for args in tasks],
            workers=None if in_process else workers,
            executor=executor,
            heartbeat=poll,
        )
        if poll is not None:
            poll()
    finally:
        if tmp is not None:
            tmp.cleanup()
    for r in results:
        if isinstance(r, BaseException):
            # The other tasks ran to their end and their points are stored.
            raise r
    return results

"""Bifurcation diagrams by continuation (Figs. 7-10): the static branch and every branch of
periodic orbits, per alpha, resumable (:func:`compute_cycle_diagram`).

Method: docs/theory/numerics.md, "Branches of periodic orbits".
"""

from __future__ import annotations

import json
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, replace

from fempipe.analyses.limit_cycle import TIP_KEYS
from fempipe.core.files import write_text
from fempipe.model.dynamics_problem import refuse_hysteretic
from fempipe.model.plane.operators import PipeModel

from .branch import continue_cycles
from .hopf import analyse_static, equilibrium_tip, point_dict, primary_states, static_points
from .out_of_plane import VerdictStore, branch_verdicts, equilibrium_verdict
from .points import PointStore, diagram_manifest, run_diagram
from .results import CycleContinuationError, CyclePoint, HopfPoint

__all__ = ["N_MULTIPLIERS", "CycleDiagram", "compute_cycle_diagram", "cycle_point_dict"]

#: Floquet multipliers listed per point in the JSON (largest moduli).
N_MULTIPLIERS = 8


def cycle_point_dict(pt: CyclePoint, branch: str, index: int, alpha: float) -> dict:
    """A cycle as a point of ``fempipe bifurcation --json``: the sweep's keys and ``stable``,
    ``branch``, ``requested``, ``source``, ``floquet_multipliers``."""
    d = point_dict(pt.v, "continuation", index, alpha, "periodic")
    d.update({k: list(pt.tip[k]) for k in TIP_KEYS})
    d.update(
        period=pt.period,
        period_n=1,
        max_multiplier=pt.max_multiplier,
        steps=pt.steps,
        rejected_steps=pt.rejected_steps,
        wall_time=pt.wall_time,
        stable=pt.stable,
        branch=branch,
        requested=pt.source == "grid",
        source=pt.source,
        floquet_multipliers=[
            [float(z.real), float(z.imag)] for z in pt.multipliers[:N_MULTIPLIERS]
        ],
        newton_iterations=pt.iterations,
        residual=pt.residual,
    )
    return d


#: The lists of a :class:`CycleDiagram`, joined over the alphas.
_PARTS = ("points", "branches", "special_points", "hopf_points", "errors")


@dataclass(frozen=True)
class CycleDiagram:
    """A bifurcation diagram by continuation: equilibria and periodic orbits.

    ``points``: by alpha the equilibria (``direction="static"``) at the requested v, then every
    branch's orbits (``"continuation"``) in arclength order; ``branches``, ``special_points``,
    ``hopf_points``: dicts with ``alpha``; ``errors``: branches not continued.
    """

    points: list
    branches: list
    special_points: list
    hopf_points: list
    errors: list
    wall_time: float
    manifest: dict

    def to_dict(self) -> dict:
        d = {k: list(getattr(self, k)) for k in _PARTS}
        m = self.manifest
        return d | {
            "wall_time": self.wall_time,
            "discretization": m["discretization"],
            "params": m["params"],
        }


def _alpha_task(
    model: PipeModel,
    values: list,
    alpha_index: int,
    options: dict,
    out_of_plane,
    store: PointStore,
    on_point: Callable[[], None] | None,
) -> dict:
    """The static branch, Hopf points and branches of orbits at one alpha (and their 3-D verdicts)."""
    alpha = float(model.params.alpha)
    v_lo, v_hi = min(values), max(values)
    static_path = store.directory / f"a{alpha_index:02d}-static.json"
    if static_path.exists():
        st = json.loads(static_path.read_text())
        hopf = [HopfPoint.from_dict(h) for h in st["hopf"]]
        eq_points = st["points"]
    else:
        hopf, v_start, events = analyse_static(model, v_lo, v_hi)
        eq_points = static_points(model, values, v_start, events)
        hopf_dicts = [h.to_dict(state=True) for h in hopf]
        write_text(
            static_path, json.dumps({"hopf": hopf_dicts, "v_start": v_start, "points": eq_points})
        )
    if out_of_plane:
        v_start = json.loads(static_path.read_text())["v_start"]
        _static_verdicts(model, values, v_start, eq_points, store.directory, alpha_index)
    if on_point is not None:
        on_point()
    out = {
        "points": list(eq_points),
        "branches": [],
        "special_points": [],
        "errors": [],
        "hopf_points": [
            dict(h.to_dict(), alpha=alpha, branch=f"H{k}", **equilibrium_tip(model, h.q_static))
            for k, h in enumerate(hopf, start=1)
        ],
    }
    covered: list[tuple[float, float]] = []
    for k, h in enumerate(hopf, start=1):
        name = f"H{k}"
        if any(abs(h.v - a) < 1e-6 or abs(h.v - b) < 1e-6 for a, b in covered):
            # The branch of an earlier Hopf point ended here: the same orbits.
            continue
        path = store.directory / f"a{alpha_index:02d}-{name}.json"
        resume = json.loads(path.read_text()) if path.exists() else None

        def save(state: dict, path=path) -> None:
            write_text(path, json.dumps(state))
            if on_point is not None:
                on_point()

        try:
            br = continue_cycles(
                model,
                h,
                (v_lo, v_hi),
                values,
                name=name,
                resume=resume,
                on_point=save,
                **options,
            )
        except CycleContinuationError as exc:
            br = exc.branch
            out["errors"].append(f"alpha = {alpha:.6g}: {exc}")
        if br is None:
            continue
        if br.points and br.end_reason.startswith("returned to an equilibrium"):
            covered.append((h.v, br.points[-1].v))
            # The other end: the next Hopf point nearest to where the branch ended.
            ends = [g.v for g in hopf if g is not h]
            if ends:
                near = min(ends, key=lambda x: abs(x - br.points[-1].v))
                covered.append((near, near))
        pts = [cycle_point_dict(p, name, i, alpha) for i, p in enumerate(br.points)]
        if out_of_plane:
            where = store.directory / f"a{alpha_index:02d}-{name}-3d.json"
            _add_verdicts(model, br.points, pts, out_of_plane, where, on_point)
        out["points"].extend(pts)
        out["branches"].append(dict(br.to_dict(), alpha=alpha))
        out["special_points"].extend(
            dict(s.to_dict(), alpha=alpha, branch=name) for s in br.special_points
        )
    return out


def _static_verdicts(model, values, v_start, eq_points, directory, alpha_index) -> None:
    """The 3-D verdicts of the static points, in place (kept in the store)."""
    store = VerdictStore(directory / f"a{alpha_index:02d}-static-3d.json")
    states = None
    for i, d in enumerate(eq_points):
        got = store.get(i, d["v"])
        if got is None:
            if states is None:
                states = primary_states(model, values, v_start)
            m = model.with_params(replace(model.params, v=d["v"]))
            got = equilibrium_verdict(m, states[d["v"]], d["stable"])
            store.put(i, d["v"], got)
        d.update(got)


def _add_verdicts(model, points, dicts, select, where, on_point) -> None:
    """The 3-D verdicts of the orbits ``select`` picks (True: all), merged into their dicts."""
    indices = range(len(points)) if select is True else select(points)
    verdicts = branch_verdicts(model, points, list(indices), VerdictStore(where), on_point)
    for i, d in enumerate(dicts):
        d.update(verdicts.get(i, {"stable_3d": None}))


def compute_cycle_diagram(
    model: PipeModel,
    values: Sequence[float],
    *,
    alphas: Sequence[float] | None = None,
    store_dir: str | os.PathLike | None = None,
    executor: Executor | None = None,
    workers: int | None = None,
    progress: Callable[[int, None], None] | None = None,
    out_of_plane=None,
    **options,
) -> CycleDiagram:
    """Per alpha, the primary static branch's equilibria at ``values`` and the orbits born at
    every Hopf point (:func:`continue_cycles`; once per branch), as in Figs 7-10.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
        Requested flow velocities (the range is their min to max).
    alphas : sequence of float, optional
        Inclinations; default ``[model.params.alpha]``.
    store_dir, executor, workers
        As :func:`fempipe.analyses.periodic.points.run_diagram` (a rerun resumes).
    progress : callable, optional
        ``progress(done, None)`` whenever a point is finished.
    out_of_plane : bool or callable, optional
        Also the 3-D verdicts of the static points and of the orbits (all, or the indices a
        callable such as :class:`~fempipe.analyses.periodic.out_of_plane.EveryKth` picks).
    **options
        Passed to :func:`continue_cycles`.

    Returns
    -------
    CycleDiagram
    """
    refuse_hysteretic(model.params, "compute_cycle_diagram")
    t0 = time.perf_counter()
    values = sorted(float(v) for v in values)
    if len(values) < 2 or values[0] == values[-1]:
        raise ValueError("values must span a range of v (at least two different values)")
    alphas = [model.params.alpha] if alphas is None else [float(a) for a in alphas]
    manifest = diagram_manifest(
        model, values, options, head={"method": "continuation"}, alphas=alphas
    )
    tasks = [
        (model.with_params(replace(model.params, alpha=a)), values, ia, dict(options), out_of_plane)
        for ia, a in enumerate(alphas)
    ]
    results = run_diagram(
        _alpha_task,
        tasks,
        manifest,
        store_dir=store_dir,
        executor=executor,
        workers=workers,
        progress=progress,
    )
    return CycleDiagram(
        **{k: [x for r in results for x in r[k]] for k in _PARTS},
        wall_time=time.perf_counter() - t0,
        manifest=manifest,
    )

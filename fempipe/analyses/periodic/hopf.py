"""Hopf points of the static branch, where branches of periodic orbits start
(:func:`find_hopf_points`), and the equilibria of the primary branch with their stability.

The critical eigenvector is that of the first-order form of Eqs. (31b)-(33).
Theory: docs/theory/numerics.md, "Branches of periodic orbits".
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from fempipe.analyses.limit_cycle import TIP_KEYS
from fempipe.analyses.stability import analyse_stability, linearized_matrices, linearly_stable
from fempipe.analyses.statics import solve_path
from fempipe.core.companion import first_order_matrix
from fempipe.model.kinematics import compute_tip
from fempipe.model.plane.operators import PipeModel

from .points import POINT_KEYS
from .results import HopfPoint

__all__ = [
    "analyse_static",
    "equilibrium_tip",
    "find_hopf_points",
    "point_dict",
    "primary_states",
    "static_points",
]


def primary_states(model: PipeModel, values: Sequence[float], v_start: float) -> dict:
    """Static states of the primary branch (continued in v from ``v_start``) at ``values``, by v."""
    vals = sorted({float(v_start), *(float(v) for v in values)})
    sols = solve_path(model.with_params(replace(model.params, v=vals[0])), vals, "v")
    return {v: s.q for v, s in zip(vals, sols, strict=True)}


def critical_eigenvector(model: PipeModel, q: np.ndarray, omega: float) -> tuple[float, np.ndarray]:
    """(omega, z): the eigenpair of the first-order form nearest to i omega."""
    K, Cd, M = (
        np.asarray(a.toarray() if hasattr(a, "toarray") else a)
        for a in linearized_matrices(model, q)
    )
    n = model.n
    # factor="lu": the two solves this start has always used (Cholesky differs by round-off)
    A = first_order_matrix(K, Cd, M, factor="lu")
    lam, Z = np.linalg.eig(A)
    k = int(np.argmin(np.abs(lam - 1j * omega)))
    z = Z[:, k]
    z = z / np.sqrt(np.mean(np.abs(z[:n]) ** 2))
    return float(lam[k].imag), z


def find_hopf_points(
    model: PipeModel, v_min: float, v_max: float, *, ds_max: float = 0.1
) -> tuple[list[HopfPoint], float]:
    """The Hopf points of the primary static branch that matter for [v_min, v_max].

    The flutter-type events of :func:`fempipe.analyses.stability.analyse_stability` from
    ``v_min``, or from 0 if the branch is unstable there.

    Returns
    -------
    hopf, v_start : list of HopfPoint (by v), float
    """
    hopf, v_start, _ = analyse_static(model, v_min, v_max, ds_max)
    return hopf, v_start


def analyse_static(model: PipeModel, v_min: float, v_max: float, ds_max: float = 0.1):
    """(Hopf points, start of the analysis, events of the primary branch)."""
    res = analyse_stability(model, v_max, v_min, follow_bifurcations=False, ds_max=ds_max)
    v_start = v_min
    if v_min > 0 and any(e.at_start for e in res.events):
        v_start = 0.0
        res = analyse_stability(model, v_max, 0.0, follow_bifurcations=False, ds_max=ds_max)
    events = [
        e
        for e in res.events
        if e.branch == "primary" and not e.at_start and e.frequency > 0 and e.type != "fold"
    ]
    states = primary_states(model, [e.v for e in events], v_start) if events else {}
    out = []
    for e in events:
        m = model.with_params(replace(model.params, v=e.v))
        omega, z = critical_eigenvector(m, states[float(e.v)], abs(e.frequency))
        out.append(HopfPoint(float(e.v), omega, e.type, states[float(e.v)], z))
    primary = [e for e in res.events if e.branch == "primary"]
    return out, v_start, primary


def _stable_between_events(events: Sequence, v: float) -> bool:
    """Linear stability of the primary branch at v from its events (stable_before/after)."""
    before = [e for e in events if e.v <= v]
    if before:
        return bool(before[-1].stable_after)
    after = [e for e in events if e.v > v]
    return bool(after[0].stable_before) if after else True


def static_points(
    model: PipeModel,
    values: Sequence[float],
    v_start: float | None = None,
    events: Sequence | None = None,
) -> list[dict]:
    """Equilibria of the primary branch at ``values`` with their linear stability.

    Dicts with the keys of a bifurcation point (``direction`` ``"static"``, tips [y, y])
    and ``stable``: from the branch's stability ``events`` if given, else
    :func:`fempipe.analyses.stability.linearly_stable` (the same criterion).
    """
    vals = sorted(float(v) for v in values)
    start = vals[0] if v_start is None else float(v_start)
    states = primary_states(model, vals, start)
    out = []
    for i, v in enumerate(vals):
        t0 = time.perf_counter()
        m = model.with_params(replace(model.params, v=v))
        q = states[v]
        stable = _stable_between_events(events, v) if events is not None else linearly_stable(m, q)
        d = point_dict(v, "static", i, model.params.alpha, "equilibrium")
        d.update(equilibrium_tip(model, q))
        d.update(
            stable=bool(stable) if stable is not None else None,
            branch="static",
            requested=True,
            source="grid",
            floquet_multipliers=None,
            wall_time=time.perf_counter() - t0,
        )
        out.append(d)
    return out


def equilibrium_tip(model: PipeModel, q: np.ndarray) -> dict:
    """``{"eta_tip": [y, y], ...}``: an equilibrium's tip in the [min, max] form of the points."""
    tip = compute_tip(model.disc, q, model.params.alpha)
    return {k: [float(tip[k]), float(tip[k])] for k in TIP_KEYS}


def point_dict(v, direction, index, alpha, attractor) -> dict:
    """The keys of a diagram's point (:data:`POINT_KEYS`), the tips and period empty."""
    d = dict.fromkeys(POINT_KEYS)
    d.update(v=float(v), direction=direction, index=index, alpha=float(alpha))
    d.update(attractor=attractor, steps=0, rejected_steps=0, wall_time=0.0)
    return d

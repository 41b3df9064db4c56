"""The static benchmarks ``static_path`` and ``static_scaling`` (docs/cli/commands.md)."""

from __future__ import annotations

import math

import numpy as np

from fempipe.analyses.statics import continue_static, solve_path
from fempipe.bench.harness import PAPER, TEXIER_DORBOLO, best_time, register
from fempipe.model.discretization import DEFAULT_FE, FiniteElement, parse_discretization
from fempipe.model.kinematics import compute_tip
from fempipe.model.params import Params, PipeSI
from fempipe.model.plane.operators import PipeModel


def _fit_exponent(n: np.ndarray, t: np.ndarray) -> float:
    """Least-squares slope of log t against log n."""
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def _path_case(name: str, params, disc, values: list[float], repeats: int) -> dict:
    model = PipeModel(disc, params)
    t_path, sols = best_time(lambda: solve_path(model, values), repeats)
    t_arc, branch = best_time(lambda: continue_static(model, "v", stop=values[-1]), repeats)
    last = sols[-1]
    tip = compute_tip(disc, last.q, params.alpha)
    tip_arc = compute_tip(disc, branch.points[-1].q, params.alpha)
    return {
        "case": name,
        "discretization": disc.name,
        "n_dofs": disc.n,
        "n_points": len(values),
        "v_max": values[-1],
        "seconds": t_path,
        "ms_per_point": 1e3 * t_path / len(values),
        "newton_iterations_total": int(sum(s.iterations for s in sols)),
        "theta_tip_at_v_max": tip["theta_tip"],
        "X_tip_at_v_max": tip["X_tip"],
        "arclength_seconds": t_arc,
        "arclength_steps": branch.steps,
        "arclength_rejected_steps": branch.rejected_steps,
        # Both routes must land on the same state: a cheap consistency check.
        "arclength_theta_tip_diff": abs(tip_arc["theta_tip"] - tip["theta_tip"]),
    }


@register("static_path")
def bench_static_path(quick: bool = False) -> dict:
    """61-point path in v = 0..10 at the default discretization, two cases."""
    n_points = 11 if quick else 61
    repeats = 1 if quick else 3
    values = list(np.linspace(0.0, 10.0, n_points))
    disc = parse_discretization(DEFAULT_FE)
    td = PipeSI(alpha=math.pi / 2, **TEXIER_DORBOLO).params(0.0)
    rows = [
        _path_case("paper alpha=pi/2", Params(**PAPER), disc, values, repeats),
        _path_case("Texier-Dorbolo alpha=pi/2", td, disc, values, repeats),
    ]
    return {"repeats": repeats, "table": rows}


@register("static_scaling")
def bench_static_scaling(quick: bool = False) -> dict:
    """Cost of the 61-point path as the P3 mesh doubles from 8 to 256 elements."""
    n_points = 11 if quick else 61
    repeats = 1 if quick else 3
    meshes = [8, 16, 32] if quick else [8, 16, 32, 64, 128, 256]
    values = list(np.linspace(0.0, 10.0, n_points))
    params = Params(**PAPER)
    rows = []
    for n_el in meshes:
        disc = FiniteElement(n_el, 3)
        model = PipeModel(disc, params)
        t, sols = best_time(lambda model=model: solve_path(model, values), repeats)
        rows.append(
            {
                "n_elements": n_el,
                "n_dofs": disc.n,
                "seconds": t,
                "ms_per_point": 1e3 * t / n_points,
                "newton_iterations_total": int(sum(s.iterations for s in sols)),
                "us_per_newton_iteration": 1e6 * t / sum(s.iterations for s in sols),
            }
        )
    n = np.array([r["n_elements"] for r in rows], dtype=float)
    tt = np.array([r["seconds"] for r in rows])
    return {
        "element": "P3",
        "n_points": n_points,
        "repeats": repeats,
        "exponent_all": _fit_exponent(n, tt),
        "exponent_finest_3": _fit_exponent(n[-3:], tt[-3:]),
        "table": rows,
    }

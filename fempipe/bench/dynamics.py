"""Benchmarks of the nonlinear dynamics ``limit_cycle`` and ``fig7`` (docs/cli/commands.md)."""

from __future__ import annotations

import statistics

import numpy as np

from fempipe.analyses.bifurcation import compute_bifurcation_diagram
from fempipe.analyses.limit_cycle import find_attractor
from fempipe.bench.harness import best_time, child_json, register
from fempipe.model.discretization import DEFAULT_FE, discretization_from_name
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel


def _disc(spec: str):
    """The discretization named ``spec`` (``disc.name``: ``P3:16``, ``modal:4``, ``modal-beam:4``)."""
    return discretization_from_name(spec)


def bench_limit_cycle(spec: str = DEFAULT_FE) -> dict:
    """One converged limit cycle at alpha = 0, v = 10; returns timing and the cycle."""
    model = PipeModel(_disc(spec), Params(alpha=0.0, v=10.0, **PAPER_CASE))
    wall, att = best_time(lambda: find_attractor(model))
    return {
        "name": "limit_cycle",
        "disc": spec,
        "wall_time": wall,
        "attractor": att.kind,
        "period": att.period,
        "eta_tip": att.tip["eta_tip"],
        "steps": att.stats["steps"],
        "shooting_iterations": att.cycle.iterations if att.cycle else None,
    }


def bench_fig7(spec: str = DEFAULT_FE, workers: int = 2, n_values: int = 36) -> dict:
    """The Fig. 7 sweep up and down in parallel; returns timing and a summary."""
    model = PipeModel(_disc(spec), Params(alpha=0.0, **PAPER_CASE))
    values = np.linspace(5.0, 12.0, n_values)
    wall, d = best_time(
        lambda: compute_bifurcation_diagram(model, values, workers=workers, shoot_rtol=1e-6)
    )
    pts = d.points
    first_periodic = {
        direction: min(
            (p["v"] for p in pts if p["direction"] == direction and p["attractor"] == "periodic"),
            default=None,
        )
        for direction in ("up", "down")
    }
    return {
        "name": "fig7",
        "disc": spec,
        "workers": workers,
        "wall_time": wall,
        "target_s": FIG7_TARGET_S,
        "n_points": len(pts),
        "kinds": {k: sum(p["attractor"] == k for p in pts) for k in {p["attractor"] for p in pts}},
        "first_periodic_v": first_periodic,
        "max_point_wall_time": max(p["wall_time"] for p in pts),
        "eta_tip_at_v12": [p["eta_tip"] for p in pts if p["v"] == 12.0],
    }


#: Wall seconds allowed for the Fig. 7 sweep up and down on 2 processes.
FIG7_TARGET_S = 300.0
#: Whole-process CPU target of ``fempipe simulate --alpha 0 --v 10 --json``.
PROCESS_TARGET_S = 2.0
#: Relative accuracy target of the period and the tip extrema.
ACCURACY_TARGET = 1e-6


def _relative_errors(d: dict, ref: dict) -> dict:
    """|x / x_ref - 1| of the period and of every tip extremum."""
    errs = {"period": abs(d["period"] / ref["period"] - 1.0)}
    for key, (lo, hi) in d["tip"].items():
        rlo, rhi = ref["tip"][key]
        errs[key] = [abs(lo / rlo - 1.0), abs(hi / rhi - 1.0)]
    return errs


def bench_limit_cycle_process(alpha: float = 0.0, v: float = 10.0, runs: int = 5) -> dict:
    """Median CPU-s of whole ``simulate --alpha A --v V --json`` processes, errors against ``--shoot-rtol 1e-10``."""
    argv = ["simulate", "--alpha", repr(alpha), "--v", repr(v), "--json"]
    _, ref = child_json(["-m", "fempipe", *argv, "--shoot-rtol", "1e-10"])
    cpus, d = [], None
    for _ in range(runs):
        cpu, d = child_json(["-m", "fempipe", *argv])
        cpus.append(cpu)
    errs = _relative_errors(d, ref)
    worst = max([errs["period"], *(x for k in errs if k != "period" for x in errs[k])])
    return {
        "name": "limit_cycle_process",
        "command": "fempipe " + " ".join(argv),
        "cpu_s_median": statistics.median(cpus),
        "cpu_s_runs": cpus,
        "target_s": PROCESS_TARGET_S,
        "meets_target": statistics.median(cpus) < PROCESS_TARGET_S and worst < ACCURACY_TARGET,
        "attractor": d["attractor"],
        "period": d["period"],
        "period_reference": ref["period"],
        "relative_errors": errs,
        "max_relative_error": worst,
        "accuracy_target": ACCURACY_TARGET,
        "steps": d["steps"],
        "t_transient": d["t_transient"],
    }


@register("limit_cycle")
def limit_cycle(quick: bool = False) -> dict:
    """One converged limit cycle, as a process and in-process (quick: smaller discretizations)."""
    proc = bench_limit_cycle_process(runs=1 if quick else 5)
    specs = ("P3:8", "modal:3") if quick else (DEFAULT_FE, "modal:4")
    rows = [bench_limit_cycle(s) for s in specs]
    return {
        "target_s": PROCESS_TARGET_S,
        "process_cpu_s_median": proc["cpu_s_median"],
        "process_meets_target": proc["meets_target"],
        "max_relative_error": proc["max_relative_error"],
        "process": proc,
        "table": rows,
    }


@register("fig7")
def fig7(quick: bool = False) -> dict:
    """The Fig. 7 sweep (36 v, up and down, 2 workers) on P3:16 and modal N = 4 (quick: 4 v, P3:8, N = 3)."""
    specs = ("P3:8", "modal:3") if quick else (DEFAULT_FE, "modal:4")
    rows = [bench_fig7(s, workers=2, n_values=4 if quick else 36) for s in specs]
    table = [
        {k: r[k] for k in ("disc", "workers", "n_points", "wall_time", "target_s")} for r in rows
    ]
    return {"target_s": FIG7_TARGET_S, "table": table, "details": rows}

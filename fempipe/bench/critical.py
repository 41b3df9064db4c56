"""Benchmarks of the stability analysis: ``stability_vcr``, ``critical_3d``, ``stability_curve``."""

from __future__ import annotations

import math

import numpy as np

from fempipe.analyses.stability import (
    PLANES,
    analyse_stability,
    find_critical_velocity,
    map_stability,
    resolution,
)
from fempipe.bench.harness import PAPER, best_time, in_turns, register
from fempipe.model.discretization import DEFAULT_FE, FiniteElement, parse_discretization
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

#: Seconds allowed for the v_cr of ``stability_vcr``.
VCR_TARGET_S = 3.0
#: Largest accepted ratio of the CPU seconds of both planes' analysis to the planar one's.
SPATIAL_TARGET_RATIO = 1.5
#: Seconds allowed for the 37 inclinations of ``stability_curve``.
CURVE_TARGET_S = 60.0


@register("stability_vcr")
def bench_stability_vcr(quick: bool = False) -> dict:
    """v_cr at alpha = pi/2 (paper's case), events to 1e-10 in v; accuracy against P3:32."""
    disc = parse_discretization(DEFAULT_FE)
    resolution(disc)  # canonical modes, cached per discretization
    model = PipeModel(disc, Params(**PAPER))
    t, res = best_time(lambda: find_critical_velocity(model, 10.0), 1 if quick else 3)
    out = {
        "discretization": disc.name,
        "alpha": PAPER["alpha"],
        "v_cr": res.v_cr,
        "type": res.critical.type,
        "mode": res.critical.mode,
        "frequency": res.critical.frequency,
        "n_spectra": res.n_spectra,
        "seconds": t,
        "target_seconds": VCR_TARGET_S,
    }
    if not quick:
        fine = find_critical_velocity(PipeModel(FiniteElement(32, 3), Params(**PAPER)), 10.0)
        out["v_cr_P3_32"] = fine.v_cr
        out["rel_diff_vs_P3_32"] = abs(res.v_cr / fine.v_cr - 1.0)
    return out


@register("critical_3d")
def bench_critical_3d(quick: bool = False) -> dict:
    """CPU seconds of the analysis in both planes against the planar one, four inclinations,
    in turns, each the minimum of its repeats; target: the ratio of the sums."""
    disc = parse_discretization(DEFAULT_FE)
    resolution(disc)
    repeats = 1 if quick else 3
    cases = []
    for alpha in (math.pi / 4, math.pi / 2, 3 * math.pi / 4, math.pi):
        model = PipeModel(disc, Params(**{**PAPER, "alpha": alpha}))
        (t_in, t_3d), (planar, res3) = in_turns(
            [
                lambda _, model=model: analyse_stability(model, 10.0),
                lambda _, model=model: analyse_stability(model, 10.0, planes=PLANES),
            ],
            repeats,
        )
        t_in, t_3d = min(t_in), min(t_3d)
        cases.append(
            {
                "alpha": alpha,
                "v_cr_planar": planar.v_cr,
                "v_cr_in_plane": res3.in_plane.v_cr,
                "v_cr_out_of_plane": res3.out_of_plane.v_cr,
                "first_plane": None if res3.critical is None else res3.critical.plane,
                "cpu_planar": t_in,
                "cpu_3d": t_3d,
                "ratio": t_3d / t_in,
            }
        )
    total_in = sum(c["cpu_planar"] for c in cases)
    total_3d = sum(c["cpu_3d"] for c in cases)
    return {
        "discretization": disc.name,
        "cases": cases,
        "cpu_planar": total_in,
        "cpu_3d": total_3d,
        "ratio": total_3d / total_in,
        "target_ratio": SPATIAL_TARGET_RATIO,
    }


@register("stability_curve")
def bench_stability_curve(quick: bool = False) -> dict:
    """v_cr(alpha) at 37 inclinations 0..pi (Fig. 6) on 2 processes; target :data:`CURVE_TARGET_S`."""
    n_alpha = 5 if quick else 37
    alphas = np.linspace(0.0, math.pi, n_alpha)
    disc = parse_discretization(DEFAULT_FE)
    t, smap = best_time(
        lambda: map_stability(
            disc, alphas, [(PAPER["beta"], PAPER["gamma"])], mu=PAPER["mu"], v_max=10.0, workers=2
        )
    )
    rows = smap.rows()
    return {
        "n_alpha": n_alpha,
        "workers": 2,
        "seconds": t,
        "target_seconds": CURVE_TARGET_S,
        "failed_points": sum(1 for r in rows if r["error"]),
        "table": [{k: r[k] for k in ("alpha", "v_cr", "type", "mode", "v_flutter")} for r in rows],
    }

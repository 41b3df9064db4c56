"""Benchmark ``parametric_region``: one region of the hanging pipe's parametric resonance chart."""

from __future__ import annotations

import time

import numpy as np

from fempipe.analyses.parametric import compute_parametric_chart
from fempipe.analyses.stability import find_critical_velocity
from fempipe.bench.harness import best_time, register
from fempipe.model.discretization import DEFAULT_FE, parse_discretization
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

#: CPU seconds allowed for one region (threshold and boundary at 10 amplitudes).
REGION_TARGET_S = 30.0
#: Paidoussis & Issid's hanging pipe at the mean flow of the benchmark.
HANGING = {"alpha": 0.0, "beta": 0.2, "gamma": 10.0, "mu": 0.005, "v": 6.0}


@register("parametric_region")
def bench_parametric_region(quick: bool = False) -> dict:
    """CPU seconds of the second mode's principal region at v0 = 6 (omega 24..36) and its
    boundary at sigma = 0.10, ..., 0.19, against the same pipe's critical velocity."""
    disc = parse_discretization(DEFAULT_FE)
    model = PipeModel(disc, Params(**HANGING))
    sigmas = np.round(np.linspace(0.10, 0.19, 5 if quick else 10), 6).tolist()
    chart_cpu, chart = best_time(
        lambda: compute_parametric_chart(model, HANGING["v"], (24.0, 36.0), sigmas),
        clock=time.process_time,
    )
    vcr_cpu, res = best_time(lambda: find_critical_velocity(model, 10.0), clock=time.process_time)
    (region,) = chart.regions
    return {
        "discretization": disc.name,
        "sigma_threshold": region.sigma_threshold,
        "omega_threshold": region.omega_threshold,
        "boundary_rows": len(region.boundary),
        "candidates_closed": len(chart.closed),
        "monodromy_matrices": chart.evaluations,
        "cpu_seconds": chart_cpu,
        "v_cr": res.v_cr,
        "v_cr_cpu_seconds": vcr_cpu,
        "ratio_to_v_cr": chart_cpu / vcr_cpu,
        "target_seconds": REGION_TARGET_S,
    }

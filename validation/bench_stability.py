"""Benchmarks of the linear stability analysis (timings, not tests).

``run(quick=False)`` returns a dict of measured times and results:

* ``vcr_one_alpha``: v_cr at alpha = pi/2 (the paper's beta, gamma, mu) on the
  default discretisation, events located to 1e-10 in v; target under 3 s.
  Its accuracy is checked against P3:32 (relative difference, target 1e-6).
* ``vcr_curve``: v_cr at 37 inclinations 0..pi (Fig. 6) on 2 processes;
  target under 60 s.

Run: ``python validation/bench_stability.py`` (prints JSON).
"""

from __future__ import annotations

import json
import time

import numpy as np

from fempipe import FiniteElement, Params, PipeModel
from fempipe.discretization import parse_discretization
from fempipe.stability import critical_velocity, resolution, stability_map

PAPER = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3}
TARGETS = {"vcr_one_alpha_s": 3.0, "vcr_curve_s": 60.0}


def bench_vcr_one_alpha(alpha: float = np.pi / 2) -> dict:
    disc = parse_discretization()
    resolution(disc)  # the canonical modes are cached per discretisation
    t0 = time.perf_counter()
    res = critical_velocity(PipeModel(disc, Params(alpha=alpha, **PAPER)), 10.0)
    elapsed = time.perf_counter() - t0
    fine = critical_velocity(PipeModel(FiniteElement(32, 3), Params(alpha=alpha, **PAPER)), 10.0)
    return {
        "alpha": alpha,
        "discretization": disc.name,
        "v_cr": res.v_cr,
        "v_cr_P3_32": fine.v_cr,
        "rel_diff_vs_P3_32": abs(res.v_cr / fine.v_cr - 1),
        "n_spectra": res.n_spectra,
        "seconds": elapsed,
        "target_seconds": TARGETS["vcr_one_alpha_s"],
    }


def bench_vcr_curve(n_alpha: int = 37, workers: int = 2) -> dict:
    disc = parse_discretization()
    alphas = np.linspace(0.0, np.pi, n_alpha)
    t0 = time.perf_counter()
    smap = stability_map(
        disc, alphas, [(PAPER["beta"], PAPER["gamma"])], mu=PAPER["mu"], v_max=10.0, workers=workers
    )
    elapsed = time.perf_counter() - t0
    return {
        "n_alpha": n_alpha,
        "workers": workers,
        "v_cr": smap.array()[0].tolist(),
        "v_flutter": smap.array("v_flutter")[0].tolist(),
        "seconds": elapsed,
        "target_seconds": TARGETS["vcr_curve_s"],
    }


def run(quick: bool = False) -> dict:
    out = {"vcr_one_alpha": bench_vcr_one_alpha()}
    out["vcr_curve"] = bench_vcr_curve(n_alpha=7 if quick else 37)
    return out


if __name__ == "__main__":
    print(json.dumps(run(), indent=2))

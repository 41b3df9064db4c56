"""Acceptance measurements of the nonlinear dynamics (quoted in ``fempipe/analyses/dynamics.py``).

Run ``python validation/dynamics_acceptance.py [--quick] [--out FILE.json]``.

1. ``steps``: one fixed trajectory (alpha = 0, v = 10, static state + 0.01 rad
   in the first sine mode, tau in [0, 2], rtol = 1e-6) on P3 with 8, 16, 32, 64
   elements and on the 4-mode Galerkin model: steps, rejected steps, wall time.
   The stiff rates grow 4096x from 8 to 64 elements; the step counts must not.
2. ``cycles``: the limit cycle at v = 10 (the paper's reference case,
   :data:`fempipe.model.params.PAPER_CASE`) for alpha = 0, pi/4, pi/2 by shooting (rtol 1e-8) on
   P3:8, 16, 32, 64 (mesh convergence: successive differences) and on the
   modal N = 3, 4 of the paper: period, tip extrema of eta(1), X_g(1), Z_g(1),
   largest non-trivial Floquet multiplier.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.dynamics import make_initial_state, simulate
from fempipe.analyses.limit_cycle import find_attractor
from fempipe.io import json_dumps, write_json


def steps(elements=(8, 16, 32, 64), t_end: float = 2.0) -> list[dict]:
    rows = []
    discs = [(f"P3:{ne}", FiniteElement(ne, 3)) for ne in elements] + [("modal:4", Modal(4))]
    for name, disc in discs:
        m = PipeModel(disc, Params(alpha=0.0, v=10.0))
        q0, p0 = make_initial_state(m, 1, 0.01)
        tr = simulate(m, q0, p0, t_end, rtol=1e-6)
        rows.append({"disc": name, "n": m.n, **tr.stats()})
        print(rows[-1], flush=True)
    return rows


def cycles(alphas=(0.0, math.pi / 4, math.pi / 2), elements=(8, 16, 32, 64)) -> list[dict]:
    rows = []
    discs = [(f"P3:{ne}", FiniteElement(ne, 3)) for ne in elements]
    discs += [("modal:3", Modal(3)), ("modal:4", Modal(4))]
    for alpha in alphas:
        for name, disc in discs:
            m = PipeModel(disc, Params(alpha=alpha, v=10.0))
            t0 = time.perf_counter()
            att = find_attractor(m, shoot_rtol=1e-8, shoot_tol=1e-7)
            row = {
                "alpha": alpha,
                "disc": name,
                "attractor": att.kind,
                "period": att.period,
                "period_n": att.period_n,
                **att.tip,
                "max_multiplier": att.cycle.max_nontrivial_multiplier if att.cycle else None,
                "wall_time": time.perf_counter() - t0,
            }
            rows.append(row)
            print(json_dumps(row, indent=None), flush=True)
    return rows


def convergence_table(rows: list[dict]) -> list[dict]:
    """Differences between successive P3 meshes (the mesh-convergence evidence)."""
    out = []
    for alpha in sorted({r["alpha"] for r in rows}):
        fe = [r for r in rows if r["alpha"] == alpha and r["disc"].startswith("P3")]
        for a, b in zip(fe, fe[1:], strict=False):
            diff = {"period": abs(a["period"] - b["period"])}
            for k in ("eta_tip", "X_tip", "Z_tip"):
                diff[k] = float(np.max(np.abs(np.subtract(a[k], b[k]))))
            out.append({"alpha": alpha, "from": a["disc"], "to": b["disc"], **diff})
    return out


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--quick", action="store_true", help="8 and 16 elements only")
    ap.add_argument("--out", default=None)
    args = ap.parse_args()
    elements = (8, 16) if args.quick else (8, 16, 32, 64)
    res = {"steps": steps(elements)}
    res["cycles"] = cycles(elements=elements)
    res["convergence"] = convergence_table(res["cycles"])
    for row in res["convergence"]:
        print(json_dumps(row, indent=None))
    if args.out:
        write_json(args.out, res)


if __name__ == "__main__":
    main()

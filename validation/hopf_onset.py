"""Hopf normal form against the limit cycles shot near onset (fempipe.analyses.stability.hopf).

For every flutter event of the primary branch over 0 <= v <= 16 the predicted
cycle (first Lyapunov coefficient l1, Re lambda'(v_cr)) is compared with the
periodic orbit computed by Newton shooting (fempipe.analyses.limit_cycle.shoot, started
from the normal-form prediction, so unstable cycles are found too) at
v = v_cr (1 +- eps) on the side where the cycles exist:

* the ratio of the shot eta_tip amplitude (max - min)/2 to the predicted
  c sqrt(|v - v_cr|) must tend to 1, its deviation like |v - v_cr|;
* amplitude^2 is proportional to |v - v_cr|: slope 1 on log-log.

Usage: python validation/hopf_onset.py [--fe P3:8] [--alpha A ...] [--beta B
--gamma G --mu M --end-mass E] [--eps 1e-3,4e-3,1.6e-2] [--first-only] [--json out.json]

The subcritical case (unstable cycles below v_cr):
python validation/hopf_onset.py --alpha 0 --beta 0.15 --end-mass 0.5 --first-only
--eps 2.5e-4,1e-3,4e-3
"""

from __future__ import annotations

import argparse
import json
import math
import time
from dataclasses import replace

import numpy as np

from fempipe.analyses.limit_cycle import shoot
from fempipe.analyses.stability import analyse_stability
from fempipe.analyses.stability.hopf import normal_forms
from fempipe.model.discretization import discretization_from_name
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel


def onset_table(
    model: PipeModel,
    v_max: float,
    eps_list,
    rtol: float = 1e-9,
    tol: float = 1e-8,
    first_only: bool = False,
):
    """One row per (flutter event, eps): prediction, shot amplitude, ratio, period."""
    res = analyse_stability(model, v_max=v_max, follow_bifurcations=False)
    t0 = time.process_time()
    forms = normal_forms(model, res)
    cpu_l1 = time.process_time() - t0
    rows = []
    items = sorted(forms.items(), key=lambda kv: kv[0][2])
    for key, nf in items[:1] if first_only else items:
        if isinstance(nf, str):
            rows.append({"event": list(key), "note": nf})
            continue
        sign = 1.0 if nf.side == "above" else -1.0
        c = nf.amplitude_coefficients["eta_tip"]
        amps, prev = [], None
        for eps in sorted(eps_list):
            v = nf.v * (1.0 + sign * eps)
            m = model.with_params(replace(model.params, v=v))
            q0, qd0, T = nf.initial_state(v)
            if prev is not None:
                # The deviation from the prediction grows like |v - v_cr|: start
                # from the prediction corrected by the last one's deviation, so
                # Newton does not fall onto the equilibrium (an unstable cycle
                # is not an attractor of shooting either).
                scale = 1.0 + prev[1] * eps / prev[0]
                q0 = nf.q_static + scale * (q0 - nf.q_static)
                qd0 = scale * qd0
            t1 = time.process_time()
            try:
                cyc = shoot(PipeDynamics(m), q0, qd0, T, rtol=rtol, tol=tol, max_iter=20)
            except Exception as exc:  # noqa: BLE001 - reported in the table
                rows.append({"event": list(key), "eps": eps, "note": f"shooting failed: {exc}"})
                continue
            lo, hi = cyc.tip["eta_tip"]
            amp = 0.5 * (hi - lo)
            pred = c * math.sqrt(abs(v - nf.v))
            amps.append((abs(v - nf.v), amp))
            prev = (eps, amp / pred - 1.0)
            rows.append(
                {
                    "event": list(key),
                    "l1": nf.l1,
                    "criticality": nf.criticality,
                    "transversality": nf.transversality,
                    "omega": nf.omega,
                    "eps": eps,
                    "v": v,
                    "predicted": pred,
                    "shot": amp,
                    "ratio": amp / pred,
                    "period_ratio": cyc.period * nf.omega / (2 * math.pi),
                    "cycle_stable": bool(cyc.stable),
                    "max_multiplier": cyc.max_nontrivial_multiplier,
                    "newton_iterations": cyc.iterations,
                    "cpu_shoot": time.process_time() - t1,
                }
            )
        if len(amps) >= 2:
            x, y = np.log([a[0] for a in amps]), np.log([a[1] ** 2 for a in amps])
            slope = float(np.polyfit(x, y, 1)[0])
            rows.append({"event": list(key), "slope_amp2_vs_dv": slope, "cpu_l1_all": cpu_l1})
    return rows


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--fe", default="P3:8")
    ap.add_argument(
        "--alpha",
        type=float,
        nargs="*",
        default=[0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4, math.pi],
    )
    ap.add_argument("--beta", type=float, default=0.142)
    ap.add_argument("--gamma", type=float, default=18.9)
    ap.add_argument("--mu", type=float, default=5e-3)
    ap.add_argument("--end-mass", type=float, default=0.0)
    ap.add_argument("--v-max", type=float, default=16.0)
    ap.add_argument("--eps", default="1e-3,4e-3,1.6e-2")
    ap.add_argument("--rtol", type=float, default=1e-9)
    ap.add_argument("--first-only", action="store_true")
    ap.add_argument("--json")
    args = ap.parse_args()
    disc = discretization_from_name(args.fe)
    eps_list = [float(e) for e in args.eps.split(",")]
    out = []
    for alpha in args.alpha:
        p = Params(
            alpha=alpha, beta=args.beta, gamma=args.gamma, mu=args.mu, end_mass=args.end_mass
        )
        rows = onset_table(
            PipeModel(disc, p),
            args.v_max,
            eps_list,
            rtol=args.rtol,
            tol=10 * args.rtol,
            first_only=args.first_only,
        )
        for r in rows:
            r["alpha"] = alpha
            print(json.dumps(r))
        out.extend(rows)
    if args.json:
        with open(args.json, "w") as f:
            json.dump(out, f, indent=1)


if __name__ == "__main__":
    main()

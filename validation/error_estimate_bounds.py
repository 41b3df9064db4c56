"""Does ``--error-estimate`` bound the true error?  The measurement behind the claim of the docs (docs/cli/options.md, "How reliable").

Run ``python validation/error_estimate_bounds.py [--quick] [--out FILE.json]``.

For every case the numbers are those of the command line itself
(``fempipe static|critical ... --error-estimate --json``, run in-process), so
the measurement is of what a user gets; the true error is measured against
a converged reference computed independently with the library on a fine
mesh (P3:128 for the static states, P3:64 for the stability events, whose
difference from P3:32 is below 1e-9), with the reference's own uncertainty
taken as its difference from the next coarser P3 mesh.

Cases (the paper's beta = 0.142, gamma = 18.9, mu = 5e-3):

* static tip values theta_tip, X_tip, Z_tip, eta_tip at several alpha and v;
* v_cr and the critical frequency for alpha = 0, pi/4, pi/2, 3pi/4; at
  alpha = pi, where v_cr = 0 (the standing pipe is unstable at v = 0), the
  restabilization, the first flutter and its frequency;

each on FE P1, P2, P3 at several mesh sizes and on the sine modes N = 2..16.

For each case: ``ratio = estimate / true error``; the estimate *bounds* the
error when ratio >= 1, and ``ratio`` is its *pessimism*.  Where the true
error is below the noise of the comparison (the solver tolerance that is the
estimate's floor, or 10 times the reference's uncertainty) the ratio says
nothing: those cases are counted apart.  A case whose estimate is null (the
command found the event on one discretization only and said so) is counted
apart as well.  :func:`summarize` gives, overall and per family, the number
of cases, how many are bounded, and the largest pessimism and the smallest
ratio over the resolvable cases.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import time
from collections.abc import Sequence

import numpy as np

from fempipe import FiniteElement, Params, PipeModel
from fempipe.analyses.stability import analyse_stability
from fempipe.analyses.statics import solve_path
from fempipe.cli import main as cli_main
from fempipe.model.kinematics import compute_tip

#: The paper's reference case.
CASE = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3}
STATIC_QUANTITIES = ("theta_tip", "X_tip", "Z_tip", "eta_tip")
#: The solver tolerances that are the floors of the estimates (relative to
#: max(1, |Q|)): Newton's 1e-10 (static), the 1e-10 of the located events.
TOLERANCE = 1e-10

FULL = {
    "static_alphas": (math.pi / 4, math.pi / 2, 3 * math.pi / 4),
    "static_vs": (0.0, 2.0, 5.0),
    "critical_alphas": (0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4, math.pi),
    "discretizations": (
        *(f"P1:{n}" for n in (4, 8, 16, 32)),
        *(f"P2:{n}" for n in (2, 4, 8, 16)),
        *(f"P3:{n}" for n in (1, 2, 4, 8)),
        *(f"modal:{n}" for n in range(2, 17)),
    ),
    "static_reference": 128,
    "critical_reference": 64,
}
QUICK = {
    "static_alphas": (math.pi / 2,),
    "static_vs": (2.0,),
    "critical_alphas": (math.pi / 2,),
    "discretizations": ("P2:4", "P3:2", "modal:3", "modal:6"),
    "static_reference": 64,
    "critical_reference": 16,
}


def cli_json(argv: Sequence[str]) -> dict:
    """``fempipe ARGV --json --quiet`` in-process; its JSON output."""
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        code = cli_main([*argv, "--json", "--quiet"])
    if code != 0:
        raise RuntimeError(f"fempipe {' '.join(argv)} exited with {code}")
    return json.loads(buf.getvalue())


def _disc_args(name: str) -> list[str]:
    return ["--modal", name.split(":")[1]] if name.startswith("modal") else ["--fe", name]


def _family(name: str) -> str:
    return "sine modes" if name.startswith("modal") else f"FE {name.split(':')[0]}"


def _row(family, disc, case, quantity, value, error, refined, ref, ref_unc) -> dict:
    true = None if value is None else abs(value - ref)
    noise = max(10.0 * ref_unc, TOLERANCE * max(1.0, abs(ref)))
    resolvable = true is not None and true > noise
    ratio = None if error is None or true is None or true == 0 else error / true
    return {
        "family": family,
        "discretization": disc,
        "case": case,
        "quantity": quantity,
        "value": value,
        "estimate": error,
        "refined": refined,
        "reference": ref,
        "reference_uncertainty": ref_unc,
        "true_error": true,
        "ratio": ratio,
        "bounded": None if error is None or true is None else bool(error >= true),
        "resolvable": resolvable,
    }


def static_reference(alpha: float, vs: Sequence[float], n_elements: int = 128) -> dict:
    """``{quantity: (values at vs, uncertainties)}`` on P3:n against P3:n/2."""
    out = {}
    tips = []
    for n in (n_elements // 2, n_elements):
        disc = FiniteElement(n, 3)
        sols = solve_path(PipeModel(disc, Params(alpha=alpha, **CASE)), list(vs))
        tips.append([compute_tip(disc, s.q, alpha) for s in sols])
    for k in STATIC_QUANTITIES:
        coarse = np.array([t[k] for t in tips[0]])
        fine = np.array([t[k] for t in tips[1]])
        out[k] = (fine, np.abs(fine - coarse) / 63.0 + 1e-15)
    return out


def static_rows(alphas, vs, discretizations, n_reference: int = 128) -> list[dict]:
    """One row per (alpha, v, quantity, discretization): ``fempipe static --error-estimate``."""
    rows = []
    v_arg = ",".join(repr(float(v)) for v in vs)
    for alpha in alphas:
        ref = static_reference(alpha, vs, n_reference)
        for name in discretizations:
            d = cli_json(
                ["static", *_disc_args(name), "--alpha", repr(alpha), "--v", v_arg]
                + ["--error-estimate"]
            )
            for i, pt in enumerate(d["points"]):
                case = f"static alpha={alpha:.4f} v={pt['v']:g}"
                for k in STATIC_QUANTITIES:
                    rows.append(
                        _row(
                            _family(name),
                            name,
                            case,
                            k,
                            pt[k],
                            pt[k + "_error"],
                            pt[k + "_refined"],
                            float(ref[k][0][i]),
                            float(ref[k][1][i]),
                        )
                    )
    return rows


def _critical_quantities(d: dict, standing: bool) -> dict:
    """``{name: (value, error, refined)}`` of one ``critical`` JSON (library result if
    ``d`` is a StabilityResult dict without estimates)."""
    out = {}
    prim = [e for e in d["events"] if e["branch"] == "primary"]

    def first(kind):
        return next((e for e in prim if e["type"] == kind), None)

    def triple(e, key):
        if e is None:
            return None, None, None
        return e[key], e.get(key + "_error"), e.get(key + "_refined")

    if standing:
        out["v_restabilization"] = triple(first("restabilization"), "v")
        out["v_flutter"] = (d["v_flutter"], d.get("v_flutter_error"), d.get("v_flutter_refined"))
        out["frequency_flutter"] = triple(first("flutter"), "frequency")
    else:
        out["v_cr"] = (d["v_cr"], d.get("v_cr_error"), d.get("v_cr_refined"))
        c = d["critical"]
        out["frequency_cr"] = triple(c, "frequency")
    return out


def critical_reference(alpha: float, v_max: float, n_elements: int = 64) -> dict:
    """``{quantity: (value, uncertainty)}`` on P3:n against P3:n/2 (library, no CLI)."""
    vals = []
    for n in (n_elements // 2, n_elements):
        model = PipeModel(FiniteElement(n, 3), Params(alpha=alpha, **CASE))
        res = analyse_stability(model, v_max=v_max, follow_bifurcations=False)
        vals.append(_critical_quantities(res.to_dict(), _standing(alpha)))
    return {k: (vals[1][k][0], abs(vals[1][k][0] - vals[0][k][0]) / 63.0 + 1e-15) for k in vals[1]}


def _standing(alpha: float) -> bool:
    return abs(alpha - math.pi) < 1e-12


def critical_rows(alphas, discretizations, v_max: float = 8.0, n_reference: int = 64) -> list:
    """One row per (alpha, quantity, discretization): ``fempipe critical --error-estimate``."""
    rows = []
    for alpha in alphas:
        ref = critical_reference(alpha, v_max, n_reference)
        for name in discretizations:
            d = cli_json(
                ["critical", *_disc_args(name), "--alpha", repr(alpha), "--v", f"0,{v_max:g}"]
                + ["--no-branches", "--error-estimate", "--planar"]
            )
            for k, (value, err, fine) in _critical_quantities(d, _standing(alpha)).items():
                rows.append(
                    _row(
                        _family(name),
                        name,
                        f"critical alpha={alpha:.4f}",
                        k,
                        value,
                        err,
                        fine,
                        ref[k][0],
                        ref[k][1],
                    )
                )
    return rows


def summarize(rows: Sequence[dict]) -> dict:
    """Counts and extremes, overall and per family (module docstring)."""

    def stats(rs):
        with_est = [r for r in rs if r["estimate"] is not None and r["true_error"] is not None]
        res = [r for r in with_est if r["resolvable"]]
        ratios = [r["ratio"] for r in res]
        return {
            "cases": len(rs),
            "no_estimate": len(rs) - len(with_est),
            "with_estimate": len(with_est),
            "bounded": sum(bool(r["bounded"]) for r in with_est),
            "resolvable": len(res),
            "bounded_resolvable": sum(bool(r["bounded"]) for r in res),
            "max_pessimism": max(ratios) if ratios else None,
            "min_ratio": min(ratios) if ratios else None,
            "median_ratio": float(np.median(ratios)) if ratios else None,
        }

    out = {"all": stats(rows)}
    for fam in sorted({r["family"] for r in rows}):
        out[fam] = stats([r for r in rows if r["family"] == fam])
    for kind in ("static", "critical"):
        out[kind] = stats([r for r in rows if r["case"].startswith(kind)])
    return out


def measure(config: dict | None = None) -> dict:
    """The whole measurement: ``{"config", "rows", "summary", "wall_time"}``.

    ``config`` has the keys of :data:`FULL` (default) or :data:`QUICK`.
    """
    config = dict(FULL if config is None else config)
    t0 = time.perf_counter()
    discs = config["discretizations"]
    rows = static_rows(
        config["static_alphas"], config["static_vs"], discs, config["static_reference"]
    )
    rows += critical_rows(
        config["critical_alphas"], discs, n_reference=config["critical_reference"]
    )
    return {
        "config": config,
        "rows": rows,
        "summary": summarize(rows),
        "wall_time": time.perf_counter() - t0,
    }


def main(argv: Sequence[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="a small subset (about a minute)")
    p.add_argument("--out", default=None, help="write the rows and the summary as JSON")
    args = p.parse_args(argv)
    from fempipe.io import json_dumps, write_json

    result = measure(QUICK if args.quick else FULL)
    if args.out:
        write_json(args.out, result)
    print(json_dumps(result["summary"]))
    worst = sorted(
        (r for r in result["rows"] if r["resolvable"] and r["ratio"] is not None),
        key=lambda r: r["ratio"],
    )
    for r in worst[:5] + worst[-5:]:
        print(
            f"{r['case']:>32} {r['quantity']:>18} {r['discretization']:>9}: "
            f"estimate {r['estimate']:.3g}, true {r['true_error']:.3g}, ratio {r['ratio']:.3g}"
        )
    print(f"wall time {result['wall_time']:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

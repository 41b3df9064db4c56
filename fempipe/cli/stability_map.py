"""``fempipe stability-map``: the critical flow velocity against the inclination (Fig. 6).

For every alpha of ``--alphas`` and every curve -- each beta of ``--betas`` at
the gamma of ``--gamma``, and each gamma of ``--gammas`` at the beta of
``--beta`` (Fig. 6(a) and 6(b)) -- computes v_cr, the first loss of
stability of the gravity-loaded branch for v up to the largest ``--v``
(:func:`fempipe.stability.stability_map`).  Points are independent and run
on ``--workers N`` processes; a failed point is reported and does not stop
the others.

The variants of the pipe (``--end-mass``, ``--external-damping``,
``--hysteretic-damping``, ``--spring``) apply to every point.

``--json`` prints ``{"alphas", "curves": [{"beta", "gamma"}], "mu",
"end_mass", "external_damping", "hysteretic_damping", "springs", "v_max",
"discretization", "points": [{"alpha", "beta", "gamma", "v_cr", "type",
"frequency", "mode", "v_flutter", "error"}, ...]}``.  ``--out DIR`` writes
stability_map.json, stability_map.csv and stability_map.png.  At alpha = pi
the straight pipe can be unstable from v = 0 (divergence, v_cr = 0); its
first flutter velocity is in "v_flutter".
"""

from __future__ import annotations

import argparse
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.params import VARIANT_FIELDS


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser, alpha=False)
    common.add_flow_arguments(parser, default="0,10")
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("map")
    g.add_argument(
        "--alphas",
        metavar="LIST",
        default="0:pi:13",
        help="inclinations: alpha spellings as a list (0,pi/4,pi/2) or start:stop:count "
        "(default 0:pi:13)",
    )
    g.add_argument(
        "--betas",
        metavar="LIST",
        type=parsing.option_type("--betas", lambda t: _list(t, "beta", 1.0)),
        default=None,
        help="mass ratios, one curve each at --gamma (Fig. 6(a)), e.g. "
        f"0.1,{parsing.DEFAULT_BETA:g},0.3,0.5",
    )
    g.add_argument(
        "--gammas",
        metavar="LIST",
        type=parsing.option_type("--gammas", lambda t: _list(t, "gamma", parsing.GAMMA_MAX)),
        default=None,
        help="gravity parameters, one curve each at --beta (Fig. 6(b)), e.g. "
        f"5,10,{parsing.DEFAULT_GAMMA:g},30",
    )
    common.add_workers_argument(g, "local processes (default 1)")
    common.add_output_arguments(parser)


def _list(text: str, field: str, high: float) -> parsing.ValueList:
    """``--betas`` / ``--gammas``: a list whose values lie in [0, high]."""
    opt = f"--{field}s"
    spec = parsing.value_list(text, opt)
    for x in (spec.low, spec.high):
        if not 0 <= x <= high:
            raise ValueError(f"values must satisfy 0 <= {field} <= {high:g}, got {x:g}")
    return spec


def _curves(args, setup) -> list[tuple[float, float]]:
    large = parsing.allow_large(args)
    betas = None if args.betas is None else args.betas.values(large)
    gammas = None if args.gammas is None else args.gammas.values(large)
    p = setup.params
    if setup.pipe is not None and (betas or gammas):
        opt = "--betas" if betas else "--gammas"
        raise CLIError(opt, "cannot be combined with the SI pipe (beta, gamma follow from it)")
    curves: list[tuple[float, float]] = []
    for b in betas or []:
        curves.append((b, p.gamma))
    for g in gammas or []:
        curves.append((p.beta, g))
    if not curves:
        curves = [(p.beta, p.gamma)]
    seen, out = set(), []
    for c in curves:
        if c not in seen:
            seen.add(c)
            out.append(c)
    return out


def run(args: argparse.Namespace) -> int:
    from fempipe.io import json_dumps
    from fempipe.stability import stability_map

    if args.alpha is not None:
        raise CLIError("--alpha", "stability-map takes its inclinations from --alphas")
    setup = common.setup_from_args(args)
    flow_opt = "--U" if args.U is not None else "--v"
    if not setup.v or max(setup.v) <= 0:
        raise CLIError(flow_opt, "give the flow range, e.g. --v 0,10")
    v_max = max(setup.v)
    if min(setup.v) != 0:
        raise CLIError(flow_opt, "the map searches from v = 0: give a range starting at 0")
    large = parsing.allow_large(args)
    alphas = parsing.parse_alpha_list(args.alphas, "--alphas", large)
    curves = _curves(args, setup)
    workers = args.workers
    total = len(alphas) * len(curves)
    parsing.check_count("--alphas", total, parsing.MAX_VALUES, large, "points (alphas x curves)")
    with reporting.progress(args, total, "stability map") as bar:
        smap = stability_map(
            setup.disc,
            alphas,
            curves,
            mu=setup.params.mu,
            v_max=v_max,
            variants={k: getattr(setup.params, k) for k in VARIANT_FIELDS},
            workers=workers,
            callback=lambda done, n, r: bar.update(),
        )
    result = smap.to_dict()
    if setup.pipe is not None:
        result["pipe_SI"] = setup.pipe.to_dict()
        for row in result["points"]:
            row["U_cr"] = None if row["v_cr"] is None else setup.pipe.U_of_v(row["v_cr"])
    failed = [r for r in result["points"] if r.get("error")]
    for r in failed:
        print(
            f"fempipe stability-map: warning: alpha={r['alpha']:.6g}, beta={r['beta']:g}, "
            f"gamma={r['gamma']:g} failed: {r['error']}",
            file=sys.stderr,
        )
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        _write(output, result, smap)
    if args.json:
        print(json_dumps(result))
    else:
        _print(result)
    if output is not None:
        output.report(args)
    return 1 if failed and len(failed) == total else 0


def _write(output: reporting.Output, result: dict, smap) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.plotting.stability import plot_stability_map

    ax = plot_stability_map(smap)
    try:
        output.json("stability_map.json", result)
        output.csv("stability_map.csv", result["points"])
        output.figure("stability_map.png", ax.figure, dpi=150)
    finally:
        plt.close(ax.figure)


def _print(result: dict) -> None:
    disc, _ = reporting.describe({"params": {}, "discretization": result["discretization"]})
    print(f"critical flow velocity, mu = {result['mu']:g}, v <= {result['v_max']:g}; {disc}")
    variants = [f"{k} = {result[k]}" for k in VARIANT_FIELDS if result.get(k)]
    if variants:
        print("variants: " + ", ".join(variants))
    print(
        f"{'alpha/pi':>9} {'beta':>7} {'gamma':>7} {'v_cr':>14} {'type':>11} {'mode':>5} {'v_flutter':>14}"
    )
    for r in result["points"]:
        v = "-" if r["v_cr"] is None else f"{r['v_cr']:.10f}"
        vf = "-" if r.get("v_flutter") is None else f"{r['v_flutter']:.10f}"
        t = "error" if r.get("error") else (r.get("type") or "stable")
        mode = "-" if r.get("mode") is None else str(r["mode"])
        print(
            f"{r['alpha'] / math.pi:9.4f} {r['beta']:7.4g} {r['gamma']:7.4g} {v:>14} {t:>11} "
            f"{mode:>5} {vf:>14}"
        )

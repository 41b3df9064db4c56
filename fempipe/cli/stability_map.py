"""``fempipe stability-map``: the critical flow velocity against the inclination (Fig. 6).

For every alpha of ``--alphas`` and every curve -- each beta of ``--betas`` at
the gamma of ``--gamma``, and each gamma of ``--gammas`` at the beta of
``--beta`` (Fig. 6(a) and 6(b)) -- computes v_cr, the first loss of
stability of the gravity-loaded branch for v up to the largest ``--v``
(:func:`fempipe.analyses.stability.stability_map`).  Points are independent and run
on ``--workers N`` processes; a failed point is reported and does not stop
the others.

The variants of the pipe (``--end-mass``, ``--external-damping``,
``--hysteretic-damping``, ``--spring``) apply to every point.

The pipe is round: each point analyses the motion in the plane of the
static state and out of it (:mod:`fempipe.model.out_of_plane`) along the same
static branch (:func:`fempipe.analyses.stability.spatial_critical_velocity`), and
v_cr is the first loss of stability in three dimensions, the first of the
two planes' (at alpha = 0 they are the same: "in").  ``--planar`` maps the
paper's planar model alone, every output as before.

``--json`` prints ``{"alphas", "curves": [{"beta", "gamma"}], "mu",
"end_mass", "external_damping", "hysteretic_damping", "springs", "v_max",
"discretization", "points": [{"alpha", "beta", "gamma", "v_cr", "type",
"frequency", "mode", "v_flutter", "error", "v_cr_in_plane",
"frequency_in_plane", "type_in_plane", "mode_in_plane",
"v_flutter_in_plane", "v_cr_out_of_plane", "frequency_out_of_plane",
"type_out_of_plane", "mode_out_of_plane", "v_flutter_out_of_plane",
"first_plane"}, ...]}``: v_cr, type, frequency and mode are those of the
first loss of stability in three dimensions, v_flutter the first flutter
in either plane, ``first_plane`` "in" or "out" (null if stable up to
v_max); with the SI pipe also ``U_cr``, ``U_cr_in_plane``,
``U_cr_out_of_plane``.  With ``--planar`` the points are ``{"alpha",
"beta", "gamma", "v_cr", "type", "frequency", "mode", "v_flutter",
"error"}`` (and ``U_cr``), as before.  ``--out DIR`` writes
stability_map.json, stability_map.csv (one row per point, its keys) and
stability_map.png (the flutter velocity against alpha: in the plane solid
with open circles, out of it dashed with open triangles, an earlier loss of
stability as open squares and diamonds, and a pale band along v_cr in three
dimensions).  At alpha = pi the straight pipe can be unstable from v = 0
(divergence, v_cr = 0); its first flutter velocity is in "v_flutter".
"""

from __future__ import annotations

import argparse
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.model.params import VARIANT_FIELDS


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
    common.add_planar_argument(g, "v_cr is then the in-plane critical velocity")
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
    from fempipe.analyses.stability import stability_map
    from fempipe.io import json_dumps

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
            planar=args.planar,
        )
    result = smap.to_dict()
    if setup.pipe is not None:
        result["pipe_SI"] = setup.pipe.to_dict()
        keys = ("", "_in_plane", "_out_of_plane") if not args.planar else ("",)
        for row in result["points"]:
            for k in keys:
                v = row["v_cr" + k]
                row["U_cr" + k] = None if v is None else setup.pipe.U_of_v(v)
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
    spatial = any("first_plane" in r for r in result["points"])
    if spatial:
        print(
            "v_cr: the first loss of stability in three dimensions (plane: in the plane of the "
            "static state or out of it); in, out: each plane's v_cr"
        )
    planes = f" {'plane':>5} {'v_cr in':>14} {'v_cr out':>14}" if spatial else ""
    print(
        f"{'alpha/pi':>9} {'beta':>7} {'gamma':>7} {'v_cr':>14} {'type':>11} {'mode':>5} "
        f"{'v_flutter':>14}{planes}"
    )

    def num(x) -> str:
        return "-" if x is None else f"{x:.10f}"

    for r in result["points"]:
        t = "error" if r.get("error") else (r.get("type") or "stable")
        mode = "-" if r.get("mode") is None else str(r["mode"])
        cells = ""
        if spatial:
            plane = r.get("first_plane") or "-"
            cells = (
                f" {plane:>5} {num(r.get('v_cr_in_plane')):>14} "
                f"{num(r.get('v_cr_out_of_plane')):>14}"
            )
        print(
            f"{r['alpha'] / math.pi:9.4f} {r['beta']:7.4g} {r['gamma']:7.4g} {num(r['v_cr']):>14} "
            f"{t:>11} {mode:>5} {num(r.get('v_flutter')):>14}{cells}"
        )

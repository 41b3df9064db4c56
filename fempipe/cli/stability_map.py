"""``fempipe stability-map``: the critical flow velocity against the inclination (Fig. 6).

v_cr at every alpha of ``--alphas`` for each beta of ``--betas`` and gamma of ``--gammas``
(:func:`fempipe.analyses.stability.map_stability`), a failed point reported without stopping the
others.  Keys and files: docs/cli/commands.md, "fempipe stability-map".
"""

from __future__ import annotations

import argparse
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.io import ranges
from fempipe.model.params import VARIANT_FIELDS

EXAMPLES = (
    "fempipe stability-map --alphas 0:pi:37 --betas 0.1,0.3,0.5 --gammas 5,10,30 --workers 2 "
    "--out out-map/",
    "fempipe stability-map --alphas 0,pi/2,pi --planar --json",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, "0,10", alpha=False)
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
        f"0.1,{ranges.DEFAULT_BETA:g},0.3,0.5",
    )
    g.add_argument(
        "--gammas",
        metavar="LIST",
        type=parsing.option_type("--gammas", lambda t: _list(t, "gamma", ranges.GAMMA_MAX)),
        default=None,
        help="gravity parameters, one curve each at --beta (Fig. 6(b)), e.g. "
        f"5,10,{ranges.DEFAULT_GAMMA:g},30",
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
    """The (beta, gamma) of every curve, each once."""
    large = parsing.allow_large(args)
    betas = None if args.betas is None else args.betas.values(large)
    gammas = None if args.gammas is None else args.gammas.values(large)
    p = setup.params
    if setup.pipe is not None and (betas or gammas):
        opt = "--betas" if betas else "--gammas"
        raise CLIError(opt, "cannot be combined with the SI pipe (beta, gamma follow from it)")
    curves = [(b, p.gamma) for b in betas or []] + [(p.beta, g) for g in gammas or []]
    return list(dict.fromkeys(curves or [(p.beta, p.gamma)]))


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.stability import map_stability

    if args.alpha is not None:
        raise CLIError("--alpha", "stability-map takes its inclinations from --alphas")
    setup = common.setup_from_args(args)
    flow_opt = common.flow_option(args)
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
        smap = map_stability(
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
    reporting.deliver(
        args, result, write=lambda output: _write(output, result, smap), text=lambda: _print(result)
    )
    return 1 if failed and len(failed) == total else 0


def _write(output: reporting.Output, result: dict, smap) -> None:
    reporting.agg()
    from fempipe.plotting.stability import plot_stability_map

    ax = plot_stability_map(smap)
    output.json("stability_map.json", result)
    output.csv("stability_map.csv", result["points"])
    output.figure("stability_map.png", ax.figure)


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

    def num(x) -> str:
        return "-" if x is None else f"{x:.10f}"

    cols = [
        ("alpha/pi", lambda r: f"{r['alpha'] / math.pi:.4f}"),
        ("beta", lambda r: f"{r['beta']:.4g}"),
        ("gamma", lambda r: f"{r['gamma']:.4g}"),
        ("v_cr", lambda r: num(r["v_cr"])),
        ("type", lambda r: "error" if r.get("error") else (r.get("type") or "stable")),
        ("mode", lambda r: "-" if r.get("mode") is None else str(r["mode"])),
        ("v_flutter", lambda r: num(r.get("v_flutter"))),
    ]
    if spatial:
        cols += [
            ("plane", lambda r: r.get("first_plane") or "-"),
            ("v_cr in", lambda r: num(r.get("v_cr_in_plane"))),
            ("v_cr out", lambda r: num(r.get("v_cr_out_of_plane"))),
        ]
    reporting.print_table(cols, result["points"])

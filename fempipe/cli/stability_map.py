"""``fempipe stability-map``: the critical flow velocity against the inclination (Fig. 6).

For every alpha of ``--alphas`` and every curve -- each beta of ``--betas`` at
the gamma of ``--gamma``, and each gamma of ``--gammas`` at the beta of
``--beta`` (Fig. 6(a) and 6(b)) -- computes v_cr, the first loss of
stability of the gravity-loaded branch for v up to the largest ``--v``
(:func:`fempipe.stability.stability_map`).  Points are independent and run
on ``--workers N`` processes; a failed point is reported and does not stop
the others.

``--json`` prints ``{"alphas", "curves": [{"beta", "gamma"}], "mu", "v_max",
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

from fempipe.cli import common
from fempipe.cli.common import CLIError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser)
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
        default=None,
        help="mass ratios, one curve each at --gamma (Fig. 6(a)), e.g. 0.1,0.142,0.3,0.5",
    )
    g.add_argument(
        "--gammas",
        metavar="LIST",
        default=None,
        help="gravity parameters, one curve each at --beta (Fig. 6(b)), e.g. 5,10,18.9,30",
    )
    g.add_argument("--workers", metavar="N", default="1", help="local processes (default 1)")
    common.add_output_arguments(parser)


def _alphas(text: str) -> list[float]:
    return common.parse_alpha_list(text, "--alphas")


def _list(args, name: str, low: float, high: float | None) -> list[float] | None:
    text = getattr(args, name)
    if text is None:
        return None
    opt = f"--{name}"
    try:
        values = common.parse_values(text, opt)
    except ValueError as exc:
        raise CLIError(opt, str(exc)) from None
    for x in values:
        if x < low or (high is not None and x > high):
            rng = f"{low:g} <= value <= {high:g}" if high is not None else f"value >= {low:g}"
            raise CLIError(opt, f"values must satisfy {rng}, got {x:g}")
    return values


def _curves(args, setup) -> list[tuple[float, float]]:
    betas = _list(args, "betas", 0.0, 1.0)
    gammas = _list(args, "gammas", 0.0, None)
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

    setup = common.setup_from_args(args)
    flow_opt = "--U" if args.U is not None else "--v"
    if not setup.v or max(setup.v) <= 0:
        raise CLIError(flow_opt, "give the flow range, e.g. --v 0,10")
    v_max = max(setup.v)
    if min(setup.v) != 0:
        raise CLIError(flow_opt, "the map searches from v = 0: give a range starting at 0")
    alphas = _alphas(args.alphas)
    curves = _curves(args, setup)
    workers = common.parse_workers(args.workers)
    total = len(alphas) * len(curves)
    with common.progress(args, total, "stability map") as bar:
        smap = stability_map(
            setup.disc,
            alphas,
            curves,
            mu=setup.params.mu,
            v_max=v_max,
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
    if args.out is not None:
        _write(args, result, smap)
    if args.json:
        print(json_dumps(result))
    else:
        _print(result)
    return 1 if failed and len(failed) == total else 0


def _write(args, result: dict, smap) -> None:
    from pathlib import Path

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.io import write_csv, write_figure, write_json
    from fempipe.plotting.stability import plot_stability_map

    out = Path(args.out)
    ax = plot_stability_map(smap)
    try:
        write_json(out / "stability_map.json", result)
        write_csv(out / "stability_map.csv", result["points"])
        write_figure(out / "stability_map.png", ax.figure, dpi=150)
    finally:
        plt.close(ax.figure)
    if not args.json and args.progress is not False:
        for name in ("stability_map.json", "stability_map.csv", "stability_map.png"):
            print(f"wrote {out / name}", file=sys.stderr)


def _print(result: dict) -> None:
    disc, _ = common.describe({"params": {}, "discretization": result["discretization"]})
    print(f"critical flow velocity, mu = {result['mu']:g}, v <= {result['v_max']:g}; {disc}")
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

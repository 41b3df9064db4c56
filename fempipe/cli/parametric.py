"""``fempipe parametric``: where a pulsating flow v0 (1 + sigma sin(omega tau)) destabilizes a pipe.

Method: docs/theory/parametric.md; keys and files: docs/cli/commands.md, "fempipe parametric".
"""

from __future__ import annotations

import argparse
import math
import time

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

EXAMPLES = (
    "fempipe parametric --v 6 --beta 0.2 --gamma 10 --omega 2:40 --sigma 0.1,0.2,0.3,0.4,0.5 "
    "--out out-par/",
    "fempipe parametric --v 5 --alpha pi --omega 5:60 --json",
    "fempipe parametric --v 4 --alpha pi/2 --beta 0.142 --gamma 18.9 --fe P2:8 --omega 10:30 "
    "--sigma 0.3,0.5 --compare-modal none --out out-par-bent/",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, None)
    g = parser.add_argument_group("pulsation")
    g.add_argument(
        "--omega",
        metavar="A:B",
        type=parsing.option_type("--omega", parsing.parse_band),
        default=(2.0, 40.0),
        help="the band of pulsation frequencies searched, 0 < A < B (default 2:40)",
    )
    g.add_argument(
        "--sigma",
        metavar="LIST",
        type=parsing.option_type("--sigma", _sigmas),
        default=(0.1, 0.2, 0.3, 0.4, 0.5),
        help="pulsation amplitudes, 0 < sigma <= 1, at which the boundaries are given; the "
        "largest bounds the search (default 0.1,0.2,0.3,0.4,0.5)",
    )
    g.add_argument(
        "--max-order",
        metavar="N",
        type=parsing.positive_int,
        default=2,
        help="resonances up to omega = 2 omega_k / N (default 2)",
    )
    g.add_argument(
        "--compare-modal",
        metavar="LIST",
        type=parsing.option_type("--compare-modal", _modal_list),
        default=(3, 4),
        help="numbers of the paper's sine modes whose charts are computed beside "
        "(default 3,4; 'none' for none)",
    )
    g.add_argument(
        "--omega-tol",
        metavar="TOL",
        type=parsing.number_type("--omega-tol", 1e-14, 1e-2),
        default=1e-8,
        help="relative tolerance of the boundary frequencies (default 1e-8)",
    )
    common.add_planar_argument(
        g,
        "on a bent pipe the forced response's multipliers in the plane alone, about half the work",
    )
    common.add_output_arguments(parser)


def _sigmas(text: str) -> tuple[float, ...]:
    """``--sigma``: distinct amplitudes 0 < sigma <= 1, sorted."""
    values = parsing.parse_values(text, "--sigma")
    bad = [s for s in values if not 0 < s <= 1]
    if bad:
        raise ValueError(f"every sigma must satisfy 0 < sigma <= 1, got {bad[0]:g}")
    return tuple(sorted(set(values)))


def _modal_list(text: str) -> tuple[int, ...]:
    """``--compare-modal``: numbers of sine modes, or 'none'."""
    if str(text).strip().lower() == "none":
        return ()
    try:
        values = tuple(int(x) for x in str(text).split(","))
    except ValueError:
        raise ValueError(
            f"expects a list of mode numbers like 3,4, or 'none', got {text!r}"
        ) from None
    if any(not 1 <= n <= 64 for n in values):
        raise ValueError(f"expects numbers of modes 1..64, got {text!r}")
    return values


def run(args: argparse.Namespace) -> int:
    from dataclasses import replace

    from fempipe.analyses.parametric import compute_parametric_chart
    from fempipe.model.discretization import Modal
    from fempipe.model.plane.operators import PipeModel

    setup = common.setup_from_args(args, need_flow=False)
    if len(setup.v) != 1:
        raise CLIError("--v", f"give the one mean flow velocity v0 (got {len(setup.v)} values)")
    v0 = float(setup.v[0])
    model = PipeModel(setup.disc, replace(setup.params, v=v0))
    discs = [setup.disc] + [Modal(n, basis="sine") for n in args.compare_modal]
    charts = []
    t0 = time.process_time()
    with reporting.progress(args, None, "parametric") as bar:
        for disc in discs:
            try:
                charts.append(
                    compute_parametric_chart(
                        model if disc is setup.disc else PipeModel(disc, model.params),
                        v0,
                        args.omega,
                        args.sigma,
                        max_order=args.max_order,
                        omega_tol=args.omega_tol,
                        planes=("in",) if args.planar else ("in", "out"),
                        callback=lambda cand, region: bar.update(),
                    )
                )
            except ValueError as exc:  # the options are checked: only v0 can be refused here
                raise CLIError("--v", str(exc)) from None
    cpu = reporting.cpu_seconds(t0)
    result = charts[0].to_dict()
    result["cpu_seconds"] = cpu
    result["compare"] = {c.discretization["name"]: c.to_dict() for c in charts[1:]}
    if setup.pipe is not None:
        result["U0"] = setup.pipe.U_of_v(v0)
    reporting.deliver(
        args,
        result,
        write=lambda out: _write(out, result, charts),
        text=lambda: _print(charts, cpu),
    )
    return 0


def _rows(charts) -> list[dict]:
    rows = []
    for chart in charts:
        for r in chart.to_dict()["regions"]:
            for s, lo, hi in r["boundary"] or [[None, None, None]]:
                rows.append(
                    {
                        "discretization": chart.discretization["name"],
                        "mode": "+".join(map(str, r["mode"])),
                        "kind": r["kind"],
                        "order": r["order"],
                        "plane": r["plane"],
                        "sigma_threshold": r["sigma_threshold"],
                        "omega_threshold": r["omega_threshold"],
                        "sigma": s,
                        "omega_lo": lo,
                        "omega_hi": hi,
                    }
                )
    return rows


def _write(output: reporting.Output, result: dict, charts) -> None:
    reporting.agg()
    from fempipe.plotting.parametric import plot_parametric_chart

    ax = plot_parametric_chart(charts[0], charts[1:])
    output.json("parametric.json", result)
    output.csv("parametric.csv", _rows(charts))
    output.figure("chart.png", ax.figure)


def _print(charts, cpu: float) -> None:
    chart = charts[0]
    p = chart.params
    lo, hi = chart.band
    about = "the straight pipe" if chart.straight else "the bent pipe's forced response"
    print(
        f"parametric resonance of {about}, v(tau) = v0 (1 + sigma sin(omega tau)), "
        f"v0 = {p.v:g}, alpha = {p.alpha:g}, beta = {p.beta:g}, gamma = {p.gamma:g}, "
        f"mu = {p.mu:g}; omega {lo:g} to {hi:g}, sigma up to {max(chart.sigmas):g}"
    )
    print(
        "modes (numbered from v = 0) and frequencies of the mean flow: "
        + ", ".join(f"{k}: {w:.6g}" for k, w in zip(chart.modes, chart.frequencies, strict=True))
        + ("; in and out of the plane alike (straight pipe)" if chart.straight else " in the plane")
    )
    if chart.modes_out_of_plane:
        print(
            "out of the plane: "
            + ", ".join(
                f"{k}: {w:.6g}"
                for k, w in zip(
                    chart.modes_out_of_plane, chart.frequencies_out_of_plane, strict=True
                )
            )
        )
    for c in charts:
        name = c.discretization["name"]
        if not c.regions:
            print(f"{name}: no region opens for sigma <= {max(c.sigmas):g}")
            continue
        for r in c.regions:
            cand = r.candidate
            what = (
                f"principal, omega ~ 2 omega_{cand.mode[0]}/{cand.order}"
                if cand.kind == "principal"
                else f"{cand.kind} combination of modes {cand.mode[0]} and {cand.mode[1]} /{cand.order}"
            )
            if cand.plane is not None:
                what += ", in the plane" if cand.plane == "in" else ", out of the plane"
            print(
                f"{name}: {what}: opens at sigma = {r.sigma_threshold:.8g}, omega = "
                f"{r.omega_threshold:.6g} (multiplier {r.multiplier.real:+.4f}"
                f"{r.multiplier.imag:+.4f}i)"
            )
            for s, w_lo, w_hi in r.boundary:
                edges = [
                    f"{w:.8g}" if math.isfinite(w) else "(beyond the band, or in another region)"
                    for w in (w_lo, w_hi)
                ]
                print(f"    sigma = {s:g}: unstable for {edges[0]} < omega < {edges[1]}")
    counted = "monodromy matrices" if chart.straight else "forced orbits"
    print(f"{sum(c.evaluations for c in charts)} {counted}, {cpu:.1f} CPU-s")

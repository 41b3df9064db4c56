"""``fempipe critical``: critical flow velocity and every stability event on the static branches.

Follows the gravity-loaded static branch in v over the range of ``--v`` (or
``--U``: their smallest and largest values), locates every change of stability
and every fold to 1e-10 in v, follows the branches born at branch points
(pitchforks at alpha = 0, pi; ``--no-branches`` to skip) and reports the first
loss of stability of the primary branch as v_cr
(:func:`fempipe.stability.stability_analysis`).

``--json`` prints ``{"v_cr": float or null, "events": [{"v", "type", "branch",
"frequency", "mode", "stable_before", "stable_after"}, ...], "critical",
"v_flutter", "v_range", "params", "discretization", "branches", ...}``.  The
type is flutter, divergence (the system or a mode loses stability),
restabilization (the system is stable above it), mode_restabilization (one
mode gains stability while another stays unstable) or fold;
``stable_before`` / ``stable_after`` say whether the whole system is stable
just below and above the event; frequency = Im lambda = Re Omega at the
crossing; mode numbers are those of ``fempipe spectrum`` (carried from
v = 0).  An instability already present at the start of the range is listed
at that v.  With an SI pipe, "U_cr" (m/s) is added.  ``--out DIR`` writes
critical.json, events.csv and branches.png.

The continuation's step budget follows from the range (:func:`step_budget`).
Should the primary branch still stop before the end of the range (its JSON
``end_reason`` is ``"max_steps"``), the command says so on stderr, with the v
reached, and exits 1 (the files and the output cover the part that was
followed); ``--allow-partial`` makes that exit 0, with the warning.
"""

from __future__ import annotations

import argparse
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser)
    common.add_flow_arguments(parser, default="0,10")
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("stability")
    g.add_argument(
        "--no-branches",
        action="store_true",
        help="do not follow the branches born at branch points (faster; v_cr is unaffected)",
    )
    g.add_argument(
        "--ds-max",
        metavar="DS",
        type=parsing.number_type("--ds-max", 0.0, 1.0, strict_low=True),
        default="0.1",
        help="largest continuation step; spectra are computed at every step (default 0.1)",
    )
    g.add_argument(
        "--allow-partial",
        action="store_true",
        help="exit 0 (with a warning) if the continuation ran out of steps before the end "
        "of the range",
    )
    common.add_output_arguments(parser)


def step_budget(v_min: float, v_max: float, ds_max: float) -> int:
    """Continuation steps allowed for the range: 4 steps of ``ds_max`` per unit of v, >= 2000.

    The arclength step measures the change of (theta, v) together, so one
    step advances v by at most ``ds_max``; the factor 4 leaves room for
    stretches where the shape changes faster than v and for steps shortened
    near events and folds.  The library's default of 2000 steps is kept as
    the floor (it cut ``--v 0,300`` at v = 200 before the budget followed the
    range).
    """
    return max(2000, math.ceil(4.0 * (v_max - v_min) / ds_max))


def run(args: argparse.Namespace) -> int:
    from fempipe.io import json_dumps
    from fempipe.operators import PipeModel
    from fempipe.stability import stability_analysis

    setup = common.setup_from_args(args)
    flow_opt = "--U" if args.U is not None else "--v"
    if not setup.v:
        raise CLIError(flow_opt, "give the flow range, e.g. --v 0,10")
    v_min, v_max = min(setup.v), max(setup.v)
    if v_max <= v_min:
        raise CLIError(flow_opt, f"needs a range with two different values, got {v_min:g} only")
    ds_max = args.ds_max
    model = PipeModel(setup.disc, setup.params)
    with reporting.progress(args, None, "critical") as bar:

        def on_sample(branch: str, v: float) -> None:
            bar.update()
            bar.set_postfix_str(f"{branch} v={v:.4f}")

        try:
            res = stability_analysis(
                model,
                v_max=v_max,
                v_min=v_min,
                follow_bifurcations=not args.no_branches,
                ds_max=ds_max,
                max_steps=step_budget(v_min, v_max, ds_max),
                callback=on_sample,
            )
        except ValueError as exc:
            raise CLIError("--fe" if args.modal is None else "--modal", str(exc)) from None
    head = setup.to_dict()
    result = res.to_dict()
    result["params"] = head["params"]
    result["discretization"] = head["discretization"]
    if setup.pipe is not None:
        pipe = setup.pipe
        result["U_cr"] = None if res.v_cr is None else pipe.U_of_v(res.v_cr)
        result["U_range"] = [pipe.U_of_v(v_min), pipe.U_of_v(v_max)]
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        _write(output, result, res)
    if args.json:
        print(json_dumps(result))
    else:
        _print(result, setup.pipe)
    if output is not None:
        output.report(args)
    return _check_coverage(args, result, v_max)


def _check_coverage(args: argparse.Namespace, result: dict, v_max: float) -> int:
    """Warn on stderr and return 1 if the primary branch ran out of steps (module docstring)."""
    primary = next((b for b in result.get("branches", []) if b["name"] == "primary"), None)
    if primary is None or primary["end_reason"] != "max_steps":
        return 0
    tail = "" if args.allow_partial else " (--allow-partial accepts this)"
    print(
        f"fempipe critical: warning: the primary branch ran out of continuation steps at "
        f"v = {primary['v_max']:.6g} < {v_max:g}; events above it are not listed{tail}",
        file=sys.stderr,
    )
    return 0 if args.allow_partial else 1


def _write(output: reporting.Output, result: dict, res) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.plotting.stability import plot_branches

    rows = sorted((ev.details() for ev in res.events), key=lambda r: r["v"])
    for r in rows:
        r["eigenvalue_re"], r["eigenvalue_im"] = r.pop("eigenvalue")
    ax = plot_branches(res)
    try:
        output.json("critical.json", result)
        output.csv("events.csv", rows)
        output.figure("branches.png", ax.figure, dpi=150)
    finally:
        plt.close(ax.figure)


def _print(result: dict, pipe) -> None:
    disc, head = reporting.describe(result)
    lo, hi = result["v_range"]
    print(f"stability for {lo:g} <= v <= {hi:g}, {head}; discretisation {disc}")
    v_cr = result["v_cr"]
    if v_cr is None:
        print("v_cr: none (the primary branch is stable over the range)")
    else:
        c = result["critical"]
        extra = f" (U = {result['U_cr']:.6g} m/s)" if pipe is not None else ""
        print(
            f"v_cr = {v_cr:.10f}{extra}: {c['type']} in mode {c['mode']}, Im lambda = {c['frequency']:.6f}"
        )
    if result["v_flutter"] is not None and result["v_flutter"] != v_cr:
        print(f"first flutter of the primary branch: v = {result['v_flutter']:.10f}")
    print(
        f"{'branch':>8} {'type':>20} {'v':>15} {'mode':>5} {'Im lambda':>11}  system below -> above"
    )
    for ev in result["events"]:
        mode = "-" if ev["mode"] is None else str(ev["mode"])
        before, after = (
            "stable" if ev[k] else "unstable" for k in ("stable_before", "stable_after")
        )
        print(
            f"{ev['branch']:>8} {ev['type']:>20} {ev['v']:15.10f} {mode:>5} "
            f"{ev['frequency']:11.6f}  {before} -> {after}"
        )

"""``fempipe critical``: the critical flow velocity and the stability events on the static branches.

Events to 1e-10 in v, in 3-D or with ``--planar`` in the plane, each flutter with its Hopf normal
form.  Keys and files: docs/cli/commands.md, "fempipe critical".
"""

from __future__ import annotations

import argparse
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

EXAMPLES = (
    "fempipe critical --alpha pi --v 0,6 --json                   # every event on every branch",
    "fempipe critical --alpha pi/2 --v 0,8 --error-estimate",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, "0,10")
    g = parser.add_argument_group("stability")
    g.add_argument(
        "--no-branches",
        action="store_true",
        help="do not follow the branches born at branch points (faster; v_cr is unaffected)",
    )
    common.add_planar_argument(g, "v_cr is then the in-plane critical velocity")
    g.add_argument(
        "--ds-max",
        metavar="DS",
        type=parsing.number_type("--ds-max", 0.0, 1.0, strict_low=True),
        default="0.1",
        help="largest continuation step; spectra are computed at every step (default 0.1; "
        "on a straight branch, alpha = 0 or pi, every 4 DS)",
    )
    g.add_argument(
        "--allow-partial",
        action="store_true",
        help="exit 0 (with a warning) if the continuation ran out of steps before the end "
        "of the range",
    )
    common.add_output_arguments(parser)
    common.add_error_estimate_argument(
        parser, "v_cr, v_flutter and the v and frequency of every event"
    )


def step_budget(v_min: float, v_max: float, ds_max: float) -> int:
    """Continuation steps allowed for the range: 4 steps of ``ds_max`` per unit of v (a step
    advances v by at most ``ds_max``; room for shortened steps near events), at least 2000."""
    return max(2000, math.ceil(4.0 * (v_max - v_min) / ds_max))


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.stability import PLANES, analyse_stability
    from fempipe.analyses.stability.hopf import decorate_events
    from fempipe.model.plane.operators import PipeModel

    setup = common.setup_from_args(args)
    flow_opt = common.flow_option(args)
    if not setup.v:
        raise CLIError(flow_opt, "give the flow range, e.g. --v 0,10")
    v_min, v_max = min(setup.v), max(setup.v)
    if v_max <= v_min:
        raise CLIError(flow_opt, f"needs a range with two different values, got {v_min:g} only")
    if setup.v[0] > setup.v[-1]:
        raise CLIError(
            flow_opt,
            f"the range runs downwards ({setup.v[0]:g} to {setup.v[-1]:g}); the branch is "
            f"followed upwards in v: give {v_min:g} first",
        )
    ds_max = args.ds_max
    model = PipeModel(setup.disc, setup.params)
    kwargs = {
        "v_max": v_max,
        "v_min": v_min,
        "follow_bifurcations": not args.no_branches,
        "ds_max": ds_max,
        "max_steps": step_budget(v_min, v_max, ds_max),
    }
    with reporting.progress(args, None, "critical") as bar:

        def on_sample(branch: str, v: float) -> None:
            bar.update()
            bar.set_postfix_str(f"{branch} v={v:.4f}")

        try:
            planes = ("in",) if args.planar else PLANES
            res = analyse_stability(model, callback=on_sample, planes=planes, **kwargs)
        except ValueError as exc:
            raise CLIError("--fe" if args.modal is None else "--modal", str(exc)) from None
        result = res.to_dict()
        out_of_plane = {} if args.planar else _out_of_plane_forms(result, model)
        result = decorate_events(result, model, res if args.planar else res.in_plane, out_of_plane)
        result |= setup.to_dict()
        if setup.pipe is not None:
            pipe = setup.pipe
            result["U_cr"] = None if res.v_cr is None else pipe.U_of_v(res.v_cr)
            result["U_range"] = [pipe.U_of_v(v_min), pipe.U_of_v(v_max)]
            for key in ("in_plane", "out_of_plane") if not args.planar else ():
                v = result["v_cr_" + key]
                result["U_cr_" + key] = None if v is None else pipe.U_of_v(v)
        if args.error_estimate:
            result = _with_estimates(result, model, res, kwargs, setup.pipe, bar)
    reporting.deliver(
        args,
        result,
        write=lambda output: _write(output, result, res),
        text=lambda: _print(result, setup.pipe),
    )
    return _check_coverage(args, result, v_max)


def _with_estimates(result: dict, model, res, kwargs: dict, pipe, bar) -> dict:
    """:func:`fempipe.studies.estimates.estimate_errors`, counted by the progress bar."""
    from fempipe.studies.error_estimate import refine
    from fempipe.studies.estimates import estimate_errors

    fine = refine(model.disc)

    def on_sample(branch: str, v: float) -> None:
        bar.update()
        bar.set_postfix_str(f"refined {fine.name} {branch} v={v:.4f}")

    return estimate_errors(result, model, res, pipe=pipe, fine=fine, callback=on_sample, **kwargs)


def _check_coverage(args: argparse.Namespace, result: dict, v_max: float) -> int:
    """1 (0 with ``--allow-partial``) and a warning if the primary branch ran out of steps."""
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
    reporting.agg()
    from fempipe.plotting.stability import plot_branches

    rows = []
    for ev, d in zip(res.events, result["events"], strict=True):
        row = ev.details()
        row.update({k: x for k, x in d.items() if k.endswith(reporting.ERROR)})
        rows.append(row)
    rows.sort(key=lambda r: r["v"])
    for r in rows:
        r["eigenvalue_re"], r["eigenvalue_im"] = r.pop("eigenvalue")
    if hasattr(res, "in_plane"):
        from fempipe.plotting.planes import plot_branches_in_planes

        ax = plot_branches_in_planes(res)
    else:
        ax = plot_branches(res)
    output.json("critical.json", result)
    output.csv("events.csv", rows, reporting.error_columns(rows))
    output.figure("branches.png", ax.figure, bbox_inches="tight")


def _out_of_plane_forms(result: dict, model) -> dict:
    """``{(branch, v): keys}``: 3-D Hopf normal forms of the primary flutters out of the plane."""
    from fempipe.analyses.three_d.onset import out_of_plane_event_keys

    return {
        ("primary", float(ev["v"])): out_of_plane_event_keys(model, float(ev["v"]))
        for ev in result.get("events", [])
        if ev["type"] == "flutter" and ev.get("plane") == "out" and ev["branch"] == "primary"
    }


def _print(result: dict, pipe) -> None:
    disc, head = reporting.describe(result)
    lo, hi = result["v_range"]
    with_errors = "error_estimate" in result

    def num(d: dict, key: str, spec: str) -> str:
        return reporting.value(d, key, spec, with_errors)

    print(f"stability for {lo:g} <= v <= {hi:g}, {head}; discretization {disc}")
    v_cr = result["v_cr"]
    if v_cr is None:
        print("v_cr: none (the primary branch is stable over the range)")
    else:
        c = result["critical"]
        extra = f" (U = {num(result, 'U_cr', '{:.6g}')} m/s)" if pipe is not None else ""
        print(
            f"v_cr = {num(result, 'v_cr', '{:.10f}')}{extra}: {c['type']} in mode {c['mode']}, "
            f"Im lambda = {num(c, 'frequency', '{:.6f}')}"
        )
    if "first_instability" in result:
        _print_planes(result, num)
    if result["v_flutter"] is not None and result["v_flutter"] != v_cr:
        print(f"first flutter of the primary branch: v = {num(result, 'v_flutter', '{:.10f}')}")
    if not result["events"]:
        print(f"events: none (no eigenvalue crosses Re lambda = 0 for {lo:g} <= v <= {hi:g})")
        return

    def change(ev: dict) -> str:
        before, after = (
            "stable" if ev[k] else "unstable" for k in ("stable_before", "stable_after")
        )
        note = f"  ({ev['error_note']})" if ev.get("error_note") else ""
        return f"{before} -> {after}{note}" + (
            reporting_hopf(ev) if ev["type"] == "flutter" else ""
        )

    reporting.print_table(
        [
            ("branch", lambda ev: ev["branch"]),
            ("plane", lambda ev: ev.get("plane", "in")),
            ("type", lambda ev: ev["type"]),
            ("v", lambda ev: num(ev, "v", "{:.10f}")),
            ("mode", lambda ev: "-" if ev["mode"] is None else str(ev["mode"])),
            ("Im lambda", lambda ev: num(ev, "frequency", "{:.6f}")),
            ("system below -> above", change, "<"),
        ],
        result["events"],
    )
    print(
        "mode k: the eigenvalue that is the k-th natural mode of the pipe without flow "
        "(v = 0, same alpha, beta, gamma, mu), followed in v by continuity"
    )
    if with_errors:
        reporting.print_footer(result["error_estimate"])


def _print_planes(result: dict, num) -> None:
    """Which plane loses stability first, and by how much."""
    vi, vo = result["v_cr_in_plane"], result["v_cr_out_of_plane"]
    fi, fo = result["frequency_in_plane"], result["frequency_out_of_plane"]
    for name, v, f, key in (
        ("in the plane", vi, fi, "v_cr_in_plane"),
        ("out of the plane", vo, fo, "v_cr_out_of_plane"),
    ):
        if v is None:
            print(f"  {name}: stable over the range")
        else:
            print(f"  {name}: v_cr = {num(result, key, '{:.10f}')}, Im lambda = {f:.6f}")
    first = result["first_instability"]
    if first is None or vi is None or vo is None:
        if first is not None:
            print(f"the pipe first loses stability {_PLANE_WORDS[first['plane']]}")
        return
    if abs(vi - vo) <= 1e-9 * max(1.0, abs(vi)):
        print("both planes lose stability at the same v (the straight pipe: every plane alike)")
        return
    gap = abs(vi - vo)
    print(
        f"the pipe first loses stability {_PLANE_WORDS[first['plane']]}, "
        f"{gap:.6g} ({100.0 * gap / max(vi, vo):.3g} %) below the other plane's v_cr"
    )


_PLANE_WORDS = {"in": "in the plane", "out": "out of the plane"}


def reporting_hopf(ev: dict) -> str:
    """``"  (supercritical, l1 = ...)"`` for a flutter event (or the reason there is none)."""
    if ev.get("criticality") is None:
        return f"  (no Hopf normal form: {ev.get('hopf_note')})" if ev.get("hopf_note") else ""
    text = f"  ({ev['criticality']}, l1 = {ev['first_lyapunov_coefficient']:.6g}"
    c = ev.get("Y_tip_amplitude_coefficient")
    if c is not None:
        side = ev.get("cycle_side")
        text += f"; Y_tip swing {c:.4g} sqrt(|v - v_cr|), {side} v_cr"
    return text + ")"

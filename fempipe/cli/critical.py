"""``fempipe critical``: critical flow velocity and every stability event on the static branches.

Follows the gravity-loaded static branch in v over the range of ``--v`` (or
``--U``: their smallest and largest values), locates every change of stability
and every fold to 1e-10 in v, follows the branches born at branch points
(pitchforks at alpha = 0, pi; ``--no-branches`` to skip) and reports the first
loss of stability of the primary branch as v_cr.  The pipe is round: its
motion in the plane of the static state (Eq. (32)) and out of it
(:mod:`fempipe.model.out_of_plane`) are both analysed along the same branches
(:func:`fempipe.analyses.stability.spatial_stability_analysis`), and v_cr is the first
loss of stability in three dimensions.  ``--planar`` analyses the paper's
planar model alone (:func:`fempipe.analyses.stability.stability_analysis`), every
output as before the out-of-plane analysis existed (events gain ``plane``).

In three dimensions the JSON also carries ``v_cr_in_plane``,
``frequency_in_plane``, ``v_cr_out_of_plane``, ``frequency_out_of_plane``
(null where that plane stays stable), ``first_instability`` ({``v``,
``plane`` ("in" or "out"), ``type``, ``frequency``}, null if stable; where
both planes lose stability at the same v, within 1e-9, as the straight
hanging or standing pipe does in every plane through its axis, "in"),
``v_flutter_in_plane``, ``v_flutter_out_of_plane``, ``critical_in_plane``,
``critical_out_of_plane`` and ``branches_out_of_plane``; ``v_flutter`` is the
first flutter in either plane, ``events`` lists both planes' events (each
with ``plane``; a fold once, as an in-plane event), and with an SI pipe
``U_cr_in_plane`` and ``U_cr_out_of_plane`` are added.  An out-of-plane flutter
of the primary branch carries the 3-D model's Hopf normal form, with
``Y_tip_amplitude_coefficient`` (:func:`fempipe.analyses.space.onset.out_of_plane_event_keys`).

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

``--error-estimate`` runs the whole analysis again on the refined
discretization (:func:`fempipe.studies.error_estimate.refine`: P_k elements halved,
or twice the modes, plus one for an odd N), pairs the events of the two runs by branch, type and
mode (:func:`fempipe.studies.error_estimate.match_events`, not by position) and adds
beside ``v_cr``, ``v_flutter`` (and ``U_cr``), beside ``v`` and
``frequency`` of every event and of ``critical``, the estimate ``Q_error`` =
max(3 |Q - Q_refined| 2^p / (2^p - 1), 1e-10 max(1, |Q|)) (Roache's Grid
Convergence Index, p = 2k for P_k, 3 for the sine modes; the floor is the
1e-10 to which events are located) and ``Q_refined``.  Every event gets
``error_note``: null, or why it has no estimate (no such event in the
refined run); ``v_cr_error`` is null, with a note, when the refined run
loses stability first by another event.  The top-level ``"error_estimate"``
describes the method and lists the notes (also refined events the reported
run lacks).  events.csv gains ``v_error`` and ``frequency_error`` after its
columns; the text shows ``value ± error``.  It costs about one more run on
the refined discretization; the ``branches`` entries are those of the
reported run, without estimates.  The library does it
(:func:`fempipe.studies.estimates.refined_stability`,
:func:`~fempipe.studies.estimates.with_stability_estimates`); this module shows it.

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

from fempipe.cli import common, estimates, parsing, reporting
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
        "--planar",
        action="store_true",
        help="the paper's planar model only: no analysis of the motion out of the plane "
        "(v_cr is then the in-plane critical velocity, every output as before)",
    )
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
    estimates.add_argument(parser, "v_cr, v_flutter and the v and frequency of every event")


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
    from fempipe.analyses.stability import spatial_stability_analysis, stability_analysis
    from fempipe.io import json_dumps
    from fempipe.model.operators import PipeModel

    setup = common.setup_from_args(args)
    flow_opt = "--U" if args.U is not None else "--v"
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
    refined = None
    with reporting.progress(args, None, "critical") as bar:

        def on_sample(branch: str, v: float) -> None:
            bar.update()
            bar.set_postfix_str(f"{branch} v={v:.4f}")

        try:
            analysis = stability_analysis if args.planar else spatial_stability_analysis
            res = analysis(model, callback=on_sample, **kwargs)
        except ValueError as exc:
            raise CLIError("--fe" if args.modal is None else "--modal", str(exc)) from None
        if args.error_estimate:
            refined = _refined_run(model, kwargs, bar, args.planar)
    head = setup.to_dict()
    result = res.to_dict()
    # Hopf criticality of the flutter events (fempipe.analyses.stability.hopf).
    from fempipe.analyses.stability.hopf import decorate_events

    out_of_plane = {} if args.planar else _out_of_plane_forms(result, model)
    result = decorate_events(result, model, res if args.planar else res.in_plane, out_of_plane)
    result["params"] = head["params"]
    result["discretization"] = head["discretization"]
    if setup.pipe is not None:
        pipe = setup.pipe
        result["U_cr"] = None if res.v_cr is None else pipe.U_of_v(res.v_cr)
        result["U_range"] = [pipe.U_of_v(v_min), pipe.U_of_v(v_max)]
        for key in ("in_plane", "out_of_plane") if not args.planar else ():
            v = result["v_cr_" + key]
            result["U_cr_" + key] = None if v is None else pipe.U_of_v(v)
    if refined is not None:
        from fempipe.studies.estimates import with_stability_estimates

        result = with_stability_estimates(result, res, refined, setup.pipe)
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


def _refined_run(model, kwargs: dict, bar, planar: bool):
    """:func:`fempipe.studies.estimates.refined_stability`, the progress bar counting its
    samples too."""
    from fempipe.studies.error_estimate import refine
    from fempipe.studies.estimates import refined_stability

    fine = refine(model.disc)

    def on_sample(branch: str, v: float) -> None:
        bar.update()
        bar.set_postfix_str(f"refined {fine.name} {branch} v={v:.4f}")

    return refined_stability(model, planar=planar, fine=fine, callback=on_sample, **kwargs)


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

    rows = []
    for ev, d in zip(res.events, result["events"], strict=True):
        row = ev.details()
        row.update({k: x for k, x in d.items() if k.endswith(estimates.ERROR)})
        rows.append(row)
    rows.sort(key=lambda r: r["v"])
    for r in rows:
        r["eigenvalue_re"], r["eigenvalue_im"] = r.pop("eigenvalue")
    if hasattr(res, "in_plane"):
        from fempipe.plotting.spatial import plot_spatial_branches

        ax = plot_spatial_branches(res)
    else:
        ax = plot_branches(res)
    try:
        output.json("critical.json", result)
        output.csv("events.csv", rows, estimates.error_columns(rows))
        output.figure("branches.png", ax.figure, dpi=150, bbox_inches="tight")
    finally:
        plt.close(ax.figure)


def _out_of_plane_forms(result: dict, model) -> dict:
    """``{(branch, v): keys}`` of the primary branch's flutters out of the plane: the 3-D
    model's Hopf normal form (:func:`fempipe.analyses.space.onset.out_of_plane_event_keys`)."""
    from fempipe.analyses.space.onset import out_of_plane_event_keys

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
        if with_errors and key + estimates.ERROR in d:
            return estimates.pm(d[key], d[key + estimates.ERROR], spec)
        return spec.format(d[key])

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
    w_v, w_f = (25, 21) if with_errors else (15, 11)
    print(
        f"{'branch':>8} {'plane':>5} {'type':>20} {'v':>{w_v}} {'mode':>5} {'Im lambda':>{w_f}}  "
        "system below -> above"
    )
    for ev in result["events"]:
        mode = "-" if ev["mode"] is None else str(ev["mode"])
        before, after = (
            "stable" if ev[k] else "unstable" for k in ("stable_before", "stable_after")
        )
        note = f"  ({ev['error_note']})" if ev.get("error_note") else ""
        if ev["type"] == "flutter":
            note += reporting_hopf(ev)
        print(
            f"{ev['branch']:>8} {ev.get('plane', 'in'):>5} {ev['type']:>20} "
            f"{num(ev, 'v', '{:15.10f}'):>{w_v}} {mode:>5} "
            f"{num(ev, 'frequency', '{:11.6f}'):>{w_f}}  {before} -> {after}{note}"
        )
    print(
        "mode k: the eigenvalue that is the k-th natural mode of the pipe without flow "
        "(v = 0, same alpha, beta, gamma, mu), followed in v by continuity"
    )
    if with_errors:
        estimates.print_footer(result["error_estimate"])


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

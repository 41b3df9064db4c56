"""``fempipe static``: large static deformation along a list of flow velocities.

Solves Eq. (31a) at each value of ``--v`` (or ``--U`` in m/s) by Newton and
continuation from the gravity-sagged state (:func:`fempipe.analyses.statics.solve_path`),
and reports the tip values (Eq. (28)) as a table, as JSON (``--json``) or as
files (``--out DIR``: static.json, static.csv, shapes.png, shapes.vtu).

``--continuation gamma`` or ``--continuation alpha`` with ``--values LIST``
follows the static state in gravity or inclination at one flow velocity instead.

``stable`` is the linear stability of each state in three dimensions: the
pipe is round, and a state is stable when its motion in the plane of the
static state (Eq. (32)) and out of it (:mod:`fempipe.model.out_of_plane`) are both
stable (:func:`fempipe.analyses.stability.linearly_stable` of ``model`` and of
``out_of_plane_model(model)``); ``stable_in_plane`` and
``stable_out_of_plane`` are each plane's verdict.  ``--planar`` decides in
the plane alone, every output as before (``stable`` only).

``--error-estimate`` also solves every point on the refined discretization
(:func:`fempipe.studies.error_estimate.refine`: P_k elements halved, or twice the
modes), by Newton from the coarse state transferred to it (the L2
projection, exact for these nested spaces, so the refined state is the same
branch), and adds beside each tip value Q of a point (``theta_tip``,
``eta_tip``, ``X_tip``, ``Z_tip``, ``varsigma_tip``, ``tip_drop`` and the SI
values) ``Q_error`` = max(3 |Q - Q_refined| 2^p / (2^p - 1), 1e-10 max(1, |Q|))
(Roache's Grid Convergence Index with p = 2k for P_k, 3 for the sine modes;
the floor is Newton's tolerance) and ``Q_refined``, and the top-level
``"error_estimate"`` (method, refined discretization, order, formula, notes).
static.csv gains the ``Q_error`` columns after the others; the table shows
``value ± error``.  The run costs about one more run on the refined
discretization.  The library does it
(:func:`fempipe.studies.estimates.refined_static_states`,
:func:`~fempipe.studies.estimates.with_static_estimates`); this module shows it.
"""

from __future__ import annotations

import argparse
import math
import sys
from dataclasses import replace

from fempipe.cli import common, estimates, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.studies.estimates import STATIC_TIP_KEYS

__all__ = ["STATIC_TIP_KEYS", "add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser)
    common.add_flow_arguments(parser, default="0:10:11")
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("continuation")
    g.add_argument(
        "--continuation",
        choices=("v", "gamma", "alpha"),
        default="v",
        help="parameter to step through (default v: the flow list); gamma or alpha use --values "
        "at a single flow velocity",
    )
    g.add_argument(
        "--values",
        metavar="LIST",
        default=None,
        help="values of the --continuation parameter (gamma: 0:100:11; alpha: items as in --alpha, "
        "e.g. 0,pi/4,pi/2 or 0deg:180deg:7)",
    )
    g = parser.add_argument_group("stability")
    common.add_planar_argument(g, "stable is then the verdict in the plane")
    common.add_output_arguments(parser)
    estimates.add_argument(parser, "each tip value of a point")


def _continuation_values(args: argparse.Namespace, setup: common.Setup) -> tuple[str, list]:
    """The continued parameter and its values, validated (CLIError naming the option)."""
    parameter = args.continuation
    if parameter == "v":
        if args.values is not None:
            raise CLIError("--values", "only with --continuation gamma|alpha; use --v or --U")
        return parameter, list(setup.v)
    if args.values is None:
        raise CLIError("--values", f"--continuation {parameter} needs --values LIST")
    if parameter == "gamma" and setup.pipe is not None:
        raise CLIError(
            "--continuation",
            "gamma is fixed by the SI pipe (--length --EI --m --M --g); use dimensionless input",
        )
    large = parsing.allow_large(args)
    if parameter == "alpha":
        values = parsing.parse_alpha_list(args.values, "--values", large)
    else:
        try:
            spec = parsing.value_list(args.values, "--values")
        except ValueError as exc:
            raise CLIError("--values", str(exc)) from None
        for x in (spec.low, spec.high):
            try:
                parsing.check_gamma(x, "--values")
            except ValueError as exc:
                raise CLIError("--values", str(exc)) from None
        values = spec.values(large)
    return parameter, values


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.statics import NewtonError, solve_path
    from fempipe.model.kinematics import shape, tip_values
    from fempipe.model.operators import PipeModel

    setup = common.setup_from_args(args)
    pipe, disc = setup.pipe, setup.disc
    parameter, values = _continuation_values(args, setup)
    base = setup.params
    if parameter != "v":
        flow_given = args.v is not None or args.U is not None
        if flow_given and len(setup.v) != 1:
            opt = "--U" if args.U is not None else "--v"
            raise CLIError(opt, f"--continuation {parameter} takes a single flow velocity")
        base = replace(base, v=setup.v[0] if flow_given else 0.0)
    if not values:
        raise CLIError("--v", "no values to solve")

    model = PipeModel(disc, replace(base, **{parameter: values[0]}))
    solved = []
    work = len(values) * (2 if args.error_estimate else 1)
    with reporting.progress(args, work, f"static ({parameter})") as bar:

        def on_point(i, sol):
            solved.append(sol)
            bar.update()

        try:
            sols = solve_path(model, values, parameter=parameter, callback=on_point)
        except NewtonError as exc:
            where = ""
            if pipe is not None and parameter == "v":
                U = pipe.U_of_v(exc.params.v)
                where = f" (U = {U:.6g} m/s)"
            raise NewtonError(
                f"{exc}{where}; {len(solved)} of {len(values)} points solved, nothing written",
                params=exc.params,
                iterations=exc.iterations,
                residual=exc.residual,
            ) from exc
        refined = _refined_states(model, sols, parameter, bar) if args.error_estimate else None

    points = [_point(disc, sol, parameter, pipe, tip_values) for sol in sols]
    # solve_path reaches its first point by the gravity loading (gamma continued
    # from 0, fempipe.analyses.statics.solve_sagged), whose Newton iterations are in that
    # point's newton_iterations; the others are Newton from the previous point.
    for row, sol in zip(points, sols, strict=True):
        row["includes_gravity_loading"] = sol.loading_iterations > 0
    for row, sol in zip(points, sols, strict=True):
        row.update(_stability(model.with_params(sol.params), sol.q, args.planar))
    result = setup.to_dict()
    result["params"].pop(parameter, None)
    if parameter != "v":
        result["params"]["v"] = base.v
    result = {
        "points": points,
        "params": result["params"],
        "discretization": result["discretization"],
    }
    if refined is not None:
        from fempipe.studies.estimates import with_static_estimates

        result = with_static_estimates(result, sols, refined, pipe)
        points = result["points"]

    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        shapes = [shape(disc, sol.q, sol.params.alpha) for sol in sols]
        _write_outputs(output, result, points, shapes, values, parameter, pipe)

    if args.json:
        from fempipe.io import json_dumps

        print(json_dumps(result))
    else:
        _print_table(result, parameter, pipe)
        sys.stdout.flush()
    if output is not None:
        output.report(args)
    return 0


def _refined_states(model, sols, parameter: str, bar):
    """:func:`fempipe.studies.estimates.refined_static_states`, the progress bar counting
    the refined states."""
    from fempipe.studies.error_estimate import refine
    from fempipe.studies.estimates import refined_static_states

    fine = refine(model.disc)
    bar.set_postfix_str(f"refined {fine.name}")
    return refined_static_states(
        model, sols, parameter, fine=fine, callback=lambda i, state: bar.update()
    )


def _stability(model, q, planar: bool = False) -> dict:
    """``{"stable"}`` with ``planar``, else ``{"stable", "stable_in_plane",
    "stable_out_of_plane"}``: the verdict in three dimensions and each plane's.

    Stable in three dimensions when stable in both planes; unstable when
    unstable in either; None when neither says unstable and one resolves nothing.
    """
    from fempipe.model.out_of_plane import out_of_plane_model

    inp = _stable(model, q)
    if planar:
        return {"stable": inp}
    out = _stable(out_of_plane_model(model), q)
    if inp is False or out is False:
        both = False
    elif inp is None or out is None:
        both = None
    else:
        both = True
    return {"stable": both, "stable_in_plane": inp, "stable_out_of_plane": out}


def _stable(model, q) -> bool | None:
    """Linear stability of the static state in ``model``'s plane (Eq. (32) in it); None if
    nothing is resolved.

    :func:`fempipe.analyses.stability.linearly_stable`: the criterion of ``fempipe
    spectrum`` and ``fempipe critical``, computed for large meshes from the few
    lowest modes by sparse shift-invert (O(n) per point).

    A static state can be an equilibrium nobody observes: at alpha = pi with
    gamma > 7.837 the straight column is one.  ``fempipe critical`` follows
    the other branches.
    """
    from fempipe.analyses.stability import linearly_stable

    return linearly_stable(model, q)


def _point(disc, sol, parameter: str, pipe, tip_values) -> dict:
    """One row of the results: tip values, Newton diagnostics, SI values if SI."""
    p = sol.params
    tip = tip_values(disc, sol.q, p.alpha)
    row: dict = {"v": p.v}
    if parameter != "v":
        row[parameter] = getattr(p, parameter)
    row.update({k: tip[k] for k in STATIC_TIP_KEYS})
    # Drop of the tip along gravity relative to the undeformed (straight) pipe,
    # whose tip sits at X_g = cos(alpha): positive = the tip moved down.
    row["tip_drop"] = tip["X_tip"] - math.cos(p.alpha)
    row["newton_iterations"] = sol.iterations
    row["gravity_loading_iterations"] = sol.loading_iterations
    row["residual_norm"] = sol.residual_norm
    if pipe is not None:
        L = pipe.L
        row["U"] = pipe.U_of_v(p.v)
        row["X_tip_m"] = tip["X_tip"] * L
        row["Z_tip_m"] = tip["Z_tip"] * L
        row["eta_tip_m"] = tip["eta_tip"] * L
        row["varsigma_tip_m"] = tip["varsigma_tip"] * L
        row["tip_drop_mm"] = row["tip_drop"] * L * 1e3
    return row


def _labels(values, parameter: str, pipe) -> list[str]:
    if parameter == "alpha":
        return [f"α = {math.degrees(a):.4g}°" for a in values]
    if parameter == "gamma":
        return [f"γ = {g:.4g}" for g in values]
    if pipe is None:
        return [f"v = {v:.4g}" for v in values]
    return [f"v = {v:.4g}  (U = {pipe.U_of_v(v):.3g} m/s)" for v in values]


def _write_outputs(output, result, points, shapes, values, parameter, pipe) -> None:
    """Make everything in memory first, then write each file atomically."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.io import write_shapes
    from fempipe.plotting.static import plot_shapes

    p = result["params"]
    if pipe is not None:
        title = (
            f"L = {pipe.L * 1e3:.4g} mm, EI = {pipe.EI:.3g} N m², α = {math.degrees(pipe.alpha):.4g}°"
            f"  (β = {p['beta']:.4g}, γ = {p['gamma']:.4g})"
        )
    else:
        fixed = [f"{sym} = {p[k]:.4g}" for k, sym in (("beta", "β"), ("gamma", "γ")) if k in p]
        if "alpha" in p:
            fixed.insert(0, f"α = {math.degrees(p['alpha']):.4g}°")
        if parameter != "v":
            fixed.append(f"v = {p['v']:.4g}")
        title = ", ".join(fixed)
    ax = plot_shapes(
        shapes,
        _labels(values, parameter, pipe),
        si_length=None if pipe is None else pipe.L,
        alpha=_alphas(values, parameter, p),
        title=title,
        stable=[row["stable"] for row in points],
        stable_in_plane=(
            [row["stable_in_plane"] for row in points] if "stable_in_plane" in points[0] else None
        ),
    )
    fig = ax.figure
    try:
        output.json("static.json", result)
        output.csv("static.csv", points, estimates.error_columns(points))
        output.figure("shapes.png", fig, dpi=150)
        length = None if pipe is None else pipe.L
        output.record(
            write_shapes(
                output.path("shapes.vtu"),
                shapes,
                values,
                parameter=parameter,
                length=length,
                params={k: x for k, x in p.items() if isinstance(x, (int, float))},
            )
        )
    finally:
        plt.close(fig)


def _alphas(values, parameter: str, p: dict) -> list[float]:
    if parameter == "alpha":
        return list(values)
    return [p["alpha"]] * len(values)


def _print_table(result: dict, parameter: str, pipe) -> None:
    disc, head = reporting.describe(result, ("alpha", "beta", "gamma", "mu", "v"))
    spatial = "stable_in_plane" in result["points"][0]
    # stable: linear stability in three dimensions; in, out: each plane's.
    planes = "; stable in 3-D (in: in the plane, out: out of it)" if spatial else ""
    print(f"static deformation, {head}; discretization {disc}{planes}")
    if pipe is not None:
        print(
            f"SI pipe: L = {pipe.L:g} m, EI = {pipe.EI:g} N m^2, m = {pipe.m:g} kg/m, "
            f"M = {pipe.M:g} kg/m, g = {pipe.g:g} m/s^2; v = {1 / pipe.velocity_scale:.6g} U"
        )
    cols = [("v", "v", "{:8.4f}")]
    if parameter != "v":
        cols.insert(0, (parameter, parameter, "{:9.5f}"))
    if pipe is not None:
        cols.append(("U", "U [m/s]", "{:8.4f}"))
    cols += [
        ("theta_tip", "theta_tip", "{:+10.6f}"),
        ("X_tip", "X_tip", "{:+10.6f}"),
        ("Z_tip", "Z_tip", "{:+10.6f}"),
        ("eta_tip", "eta_tip", "{:+10.6f}"),
    ]
    if pipe is not None:
        cols.append(("tip_drop_mm", "drop [mm]", "{:+10.4f}"))
    cols += [("newton_iterations", "Newton", "{:6d}"), ("residual_norm", "residual", "{:9.2e}")]
    cols.append(("stable", "stable", "{!s:>6}"))
    if spatial:
        cols += [("stable_in_plane", "in", "{!s:>5}"), ("stable_out_of_plane", "out", "{!s:>5}")]
    with_errors = "error_estimate" in result

    def cell(row, key, fmt):
        if with_errors and key + estimates.ERROR in row:
            return estimates.pm(row[key], row[key + estimates.ERROR], fmt)
        return fmt.format(row[key])

    sample = result["points"][0]
    widths = [
        max(
            len(h),
            len(cell(sample, k, f)) if with_errors else len(f.format(0 if "d}" in f else 0.0)),
        )
        for k, h, f in cols
    ]
    print("  ".join(h.rjust(w) for (_, h, _), w in zip(cols, widths, strict=True)))
    for row in result["points"]:
        cells = [cell(row, k, f).rjust(w) for (k, h, f), w in zip(cols, widths, strict=True)]
        print("  ".join(cells))
    if with_errors:
        estimates.print_footer(result["error_estimate"])
    if any(row["stable"] is False for row in result["points"]):
        print(
            "note: states marked stable=False are unstable equilibria (linearized, Eq. (32)"
            + (" and out of the plane" if spatial else "")
            + "); `fempipe critical` lists the stability events and follows the other branches"
        )

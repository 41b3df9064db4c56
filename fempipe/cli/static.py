"""``fempipe static``: the large static deformation, Eq. (31a), along a list of flow velocities.

Newton and continuation (:func:`fempipe.analyses.statics.solve_path`) in v or, with
``--continuation gamma|alpha``, at one flow; each state's linear stability in three dimensions
or, with ``--planar``, in its plane.  Keys and files: docs/cli/commands.md, "fempipe static".
"""

from __future__ import annotations

import argparse
import math
from dataclasses import replace

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.io import ranges
from fempipe.studies.error_estimate import STATIC_TIP_KEYS

__all__ = ["EXAMPLES", "add_arguments", "run"]

EXAMPLES = (
    "fempipe static --alpha pi/2 --v 0:10:11 --json",
    "fempipe static --alpha 45deg --continuation gamma --values 0:100:6 --v 2 --out out-gamma/",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, "0:10:11")
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
    common.add_error_estimate_argument(parser, "each tip value of a point")


def _continuation_values(args: argparse.Namespace, setup: common.Setup) -> tuple[str, list]:
    """The continued parameter and its values, validated."""
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
        return parameter, parsing.parse_alpha_list(args.values, "--values", large)
    try:
        spec = parsing.value_list(args.values, "--values")
        for x in (spec.low, spec.high):
            ranges.check_param("gamma", x)
    except ValueError as exc:
        raise CLIError("--values", str(exc)) from None
    return parameter, spec.values(large)


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.statics import NewtonError, solve_path
    from fempipe.model.kinematics import compute_shape
    from fempipe.model.plane.operators import PipeModel

    setup = common.setup_from_args(args)
    pipe, disc = setup.pipe, setup.disc
    parameter, values = _continuation_values(args, setup)
    base = setup.params
    if parameter != "v":
        flow_given = args.v is not None or args.U is not None
        if flow_given and len(setup.v) != 1:
            option = common.flow_option(args)
            raise CLIError(option, f"--continuation {parameter} takes a single flow velocity")
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
                where = f" (U = {pipe.U_of_v(exc.params.v):.6g} m/s)"
            raise NewtonError(
                f"{exc}{where}; {len(solved)} of {len(values)} points solved, nothing written",
                params=exc.params,
                iterations=exc.iterations,
                residual=exc.residual,
            ) from exc
        points = [_point(disc, sol, parameter, pipe) for sol in sols]
        for row, sol in zip(points, sols, strict=True):
            # the first point is reached by the gravity loading (gamma continued from 0)
            row["includes_gravity_loading"] = sol.loading_iterations > 0
            row.update(_stability(model.with_params(sol.params), sol.q, args.planar))
        head = setup.to_dict()
        head["params"].pop(parameter, None)
        if parameter != "v":
            head["params"]["v"] = base.v
        result = {"points": points, **head}
        if args.error_estimate:
            result = _with_estimates(result, model, sols, parameter, pipe, bar)

    def write(output: reporting.Output) -> None:
        shapes = [compute_shape(disc, sol.q, sol.params.alpha) for sol in sols]
        _write(output, result, shapes, values, parameter, pipe)

    reporting.deliver(args, result, write=write, text=lambda: _print(result, parameter, pipe))
    return 0


def _with_estimates(result: dict, model, sols, parameter: str, pipe, bar) -> dict:
    """:func:`fempipe.studies.estimates.estimate_errors`, counted by the progress bar."""
    from fempipe.studies.error_estimate import refine
    from fempipe.studies.estimates import estimate_errors

    fine = refine(model.disc)
    bar.set_postfix_str(f"refined {fine.name}")
    return estimate_errors(
        result,
        model,
        sols,
        parameter=parameter,
        pipe=pipe,
        fine=fine,
        callback=lambda i, s: bar.update(),
    )


def _stability(model, q, planar: bool = False) -> dict:
    """``stable`` in 3-D (both planes combined) and each plane's; in-plane if ``planar``."""
    from fempipe.analyses.stability import linearly_stable
    from fempipe.model.out_of_plane.model import build_out_of_plane_model

    inp = linearly_stable(model, q)
    if planar:
        return {"stable": inp}
    out = linearly_stable(build_out_of_plane_model(model), q)
    both = False if False in (inp, out) else None if None in (inp, out) else True
    return {"stable": both, "stable_in_plane": inp, "stable_out_of_plane": out}


def _point(disc, sol, parameter: str, pipe) -> dict:
    """One row of the results: tip values, Newton diagnostics, SI values with an SI pipe."""
    from fempipe.model.kinematics import compute_tip

    p = sol.params
    tip = compute_tip(disc, sol.q, p.alpha)
    row: dict = {"v": p.v}
    if parameter != "v":
        row[parameter] = getattr(p, parameter)
    row.update({k: tip[k] for k in STATIC_TIP_KEYS})
    row["tip_drop"] = tip["X_tip"] - math.cos(p.alpha)  # the straight pipe's tip is at cos(alpha)
    row["newton_iterations"] = sol.iterations
    row["gravity_loading_iterations"] = sol.loading_iterations
    row["residual_norm"] = sol.residual_norm
    if pipe is not None:
        row["U"] = pipe.U_of_v(p.v)
        for k in ("X_tip", "Z_tip", "eta_tip", "varsigma_tip"):
            row[f"{k}_m"] = tip[k] * pipe.L
        row["tip_drop_mm"] = row["tip_drop"] * pipe.L * 1e3
    return row


def _labels(values, parameter: str, pipe) -> list[str]:
    if parameter == "alpha":
        return [f"α = {math.degrees(a):.4g}°" for a in values]
    if parameter == "gamma":
        return [f"γ = {g:.4g}" for g in values]
    if pipe is None:
        return [f"v = {v:.4g}" for v in values]
    return [f"v = {v:.4g}  (U = {pipe.U_of_v(v):.3g} m/s)" for v in values]


def _write(output, result, shapes, values, parameter, pipe) -> None:
    reporting.agg()
    from fempipe.io import write_shapes
    from fempipe.plotting.static import plot_shapes

    p, points = result["params"], result["points"]
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
        alpha=list(values) if parameter == "alpha" else [p["alpha"]] * len(values),
        title=title,
        stable=[row["stable"] for row in points],
        stable_in_plane=(
            [row["stable_in_plane"] for row in points] if "stable_in_plane" in points[0] else None
        ),
    )
    output.json("static.json", result)
    output.csv("static.csv", points, reporting.error_columns(points))
    output.figure("shapes.png", ax.figure)
    numbers = {k: x for k, x in p.items() if isinstance(x, (int, float))}
    length = None if pipe is None else pipe.L
    path = output.path("shapes.vtu")
    output.record(
        write_shapes(path, shapes, values, parameter=parameter, length=length, params=numbers)
    )


def _print(result: dict, parameter: str, pipe) -> None:
    disc, head = reporting.describe(result, ("alpha", "beta", "gamma", "mu", "v"))
    planes = "stable_in_plane" in result["points"][0]
    note = "; stable in 3-D (in: in the plane, out: out of it)" if planes else ""
    print(f"static deformation, {head}; discretization {disc}{note}")
    if pipe is not None:
        print(
            f"SI pipe: L = {pipe.L:g} m, EI = {pipe.EI:g} N m^2, m = {pipe.m:g} kg/m, "
            f"M = {pipe.M:g} kg/m, g = {pipe.g:g} m/s^2; v = {1 / pipe.velocity_scale:.6g} U"
        )
    with_errors = "error_estimate" in result
    cols = [] if parameter == "v" else [(parameter, parameter, "{:9.5f}")]
    cols.append(("v", "v", "{:8.4f}"))
    if pipe is not None:
        cols.append(("U", "U [m/s]", "{:8.4f}"))
    cols += [(k, k, "{:+10.6f}") for k in ("theta_tip", "X_tip", "Z_tip", "eta_tip")]
    if pipe is not None:
        cols.append(("tip_drop_mm", "drop [mm]", "{:+10.4f}"))
    cols += [("newton_iterations", "Newton", "{:6d}"), ("residual_norm", "residual", "{:9.2e}")]
    cols.append(("stable", "stable", "{!s:>6}"))
    if planes:
        cols += [("stable_in_plane", "in", "{!s:>5}"), ("stable_out_of_plane", "out", "{!s:>5}")]
    reporting.print_table(
        [(h, lambda row, k=k, f=f: reporting.value(row, k, f, with_errors)) for k, h, f in cols],
        result["points"],
    )
    if with_errors:
        reporting.print_footer(result["error_estimate"])
    if any(row["stable"] is False for row in result["points"]):
        print(
            "note: states marked stable=False are unstable equilibria (linearized, Eq. (32)"
            + (" and out of the plane" if planes else "")
            + "); `fempipe critical` lists the stability events and follows the other branches"
        )

"""``fempipe bifurcation``: tip extrema against v, by continuation (default) or by sweeps.

``--3d`` sweeps the 3-D model's attractors; ``--out DIR`` keeps the point store DIR/points/ (a
rerun resumes).  Keys and files: docs/cli/commands.md, "fempipe bifurcation".
"""

from __future__ import annotations

import argparse
from pathlib import Path

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

EXAMPLES = (
    "fempipe bifurcation --alpha 0 --v 5:12:36 --out fig07",
    "fempipe bifurcation --method sweep --alphas pi/4,pi/2 --v 5:12:15 --workers 2",
    "fempipe bifurcation --3d --method sweep --alpha 1.2 --v 3:5:5 --out b3",
)

#: The diagrams of a planar run and of a 3-D run.
KEYS = ("eta_tip", "X_tip", "Z_tip")
KEYS_3D = ("Y_tip", "eta_tip", "X_tip", "Z_tip")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, "5:12:36")
    g = parser.add_argument_group("sweep")
    g.add_argument(
        "--method",
        choices=("continuation", "sweep"),
        default=None,
        help="continuation of equilibria and periodic orbits (stable and unstable; default) "
        "or sweeps of attractors up and down (the independent check)",
    )
    g.add_argument(
        "--directions",
        metavar="D",
        type=parsing.option_type("--directions", _directions),
        default="up,down",
        help="sweep directions: up, down or up,down (default up,down)",
    )
    g.add_argument(
        "--alphas",
        metavar="LIST",
        default=None,
        help="several inclinations swept independently (alpha spellings, e.g. 0,pi/4,pi/2); "
        "overrides --alpha",
    )
    common.add_integration_arguments(
        parser,
        shoot_rtol="1e-6",
        shoot_help="shooting tolerance; the tip extrema are accurate to ~1e-7 at 1e-6",
        group=g,
        per="per point",
    )
    g.add_argument(
        "--orbit-rtol",
        metavar="TOL",
        type=parsing.number_type("--orbit-rtol", 0.0, 0.1, strict_low=True),
        default="1e-5",
        help="integration tolerance of the continuation (1e-5: periods and tip extrema within "
        "1e-6 of rtol = 1e-10 at P3:16, 4.1e-7 measured; --shoot-rtol, --rtol, --t-max are "
        "the sweep's)",
    )
    par = parser.add_argument_group("parallel")
    ex = par.add_mutually_exclusive_group()
    common.add_workers_argument(ex, "local processes for independent sweeps (1)")
    ex.add_argument(
        "--dask",
        metavar="ADDRESS",
        default=None,
        help="run the sweeps on a Dask cluster, e.g. tcp://127.0.0.1:8786 (needs fempipe[dask]; "
        "the --out directory must be visible to the workers)",
    )
    three = parser.add_argument_group("three dimensions")
    common.add_planar_argument(
        three,
        "no out-of-plane Floquet multipliers and no stable_3d (they cost 1.3-2.3 s CPU a cycle "
        "point on P3:16)",
    )
    three.add_argument(
        "--3d",
        dest="three_d",
        action="store_true",
        help="sweep the attractors of the 3-D model instead (motion, Y_tip, whirl_rate against v)",
    )
    three.add_argument(
        "--out-of-plane-amplitude",
        metavar="A",
        type=parsing.number_type("--out-of-plane-amplitude", 0.0, 1.0),
        default="0.01",
        help="with --3d: out-of-plane rotation in rad (first sine mode) added to the first "
        "point's start and to every point that starts from an equilibrium (0.01)",
    )
    common.add_output_arguments(parser)


def solver_error_hint(args: argparse.Namespace) -> str | None:
    """After a failed sweep: the finished points are in the store, a rerun resumes."""
    if args.out is None:
        return None
    return f"finished points are kept in {args.out}/points; rerun the command to resume"


def _directions(text: str) -> list[str]:
    """``--directions``: up, down or both, each once."""
    directions = [d.strip() for d in str(text).split(",")]
    if any(d not in ("up", "down") for d in directions):
        raise ValueError(f"expects up, down or up,down, got {text!r}")
    if len(set(directions)) != len(directions):
        raise ValueError(f"repeats a direction: {text!r}")
    return directions


def _on_progress(bar):
    """A library ``progress(done, total)`` advancing ``bar`` to ``done``."""
    seen = [0]

    def on_progress(done, _total) -> None:
        if done > seen[0]:
            bar.update(done - seen[0])
            seen[0] = done

    return on_progress


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.bifurcation import compute_bifurcation_diagram
    from fempipe.model.plane.operators import PipeModel

    common.refuse_hysteretic(args, "bifurcation")
    setup = common.setup_from_args(args)
    if args.three_d:
        return _run_3d(args, setup)
    if args.method is None:  # None: not given (--3d refuses an explicit continuation)
        args.method = "continuation"
    alphas = None
    if args.alphas is not None:
        alphas = parsing.parse_alpha_list(args.alphas, "--alphas", parsing.allow_large(args))
    total = _check_work(args, setup, 1 if alphas is None else len(alphas))
    if args.method == "continuation":
        return _run_continuation(args, setup, alphas)
    executor = client = None
    if args.dask is not None:
        try:
            from dask.distributed import Client
        except ImportError:
            raise CLIError(
                "--dask", "needs dask.distributed: pip install 'fempipe[dask]'"
            ) from None
        try:
            client = Client(args.dask, timeout="10s")
        except (OSError, TimeoutError, ValueError) as exc:
            raise CLIError("--dask", f"cannot connect to {args.dask}: {exc}") from None
        executor = client.get_executor()
    store_dir = _store_dir(args)
    try:
        with reporting.progress(args, total, "bifurcation") as bar:
            diagram = compute_bifurcation_diagram(
                PipeModel(setup.disc, setup.params),
                setup.v,
                args.directions,
                alphas=alphas,
                store_dir=store_dir,
                executor=executor,
                workers=args.workers if executor is None else None,
                progress=_on_progress(bar),
                out_of_plane=not args.planar,
                t_max=args.t_max,
                rtol=args.rtol,
                shoot_rtol=args.shoot_rtol,
            )
    finally:
        if client is not None:
            client.close()
    result = _result(setup, alphas)
    result["points"] = diagram.points
    result["wall_time"] = diagram.wall_time
    _deliver(args, store_dir, result, KEYS)
    return 0


def _check_work(args, setup, n_alpha: int | None) -> int:
    """The number of points (``n_alpha`` None: a 3-D sweep), within the work limits."""
    flow_opt = common.flow_option(args)
    if not setup.v:
        raise CLIError(flow_opt if n_alpha is None else "--v", "no flow velocities to sweep")
    large = parsing.allow_large(args)
    parsing.check_count("--t-max", args.t_max, parsing.T_MAX, large, "time units")
    total = len(setup.v) * len(args.directions) * (n_alpha or 1)
    what = "points (v x directions" + (")" if n_alpha is None else " x alphas)")
    parsing.check_count(flow_opt, total, parsing.MAX_VALUES, large, what)
    return total


def _store_dir(args) -> Path | None:
    return Path(args.out) / "points" if args.out is not None else None


def _result(setup, alphas) -> dict:
    result = setup.to_dict()
    result["params"].pop("v", None)
    if alphas is not None:
        result["params"]["alphas"] = alphas
    return result


def _run_continuation(args: argparse.Namespace, setup, alphas) -> int:
    """``--method continuation``."""
    from fempipe.analyses.periodic import compute_cycle_diagram
    from fempipe.core.errors import SolverError
    from fempipe.model.plane.operators import PipeModel

    flow_opt = common.flow_option(args)
    if len(set(setup.v)) < 2:
        raise CLIError(flow_opt, "continuation needs a range of v (at least two values)")
    if args.dask is not None:
        raise CLIError("--dask", "runs sweeps only; use --method sweep or --workers")
    store_dir = _store_dir(args)
    with reporting.progress(args, None, "bifurcation") as bar:
        diagram = compute_cycle_diagram(
            PipeModel(setup.disc, setup.params),
            setup.v,
            alphas=alphas,
            store_dir=store_dir,
            workers=args.workers,
            progress=_on_progress(bar),
            out_of_plane=not args.planar,
            rtol=args.orbit_rtol,
        )
    result = _result(setup, alphas)
    result["method"] = "continuation"
    d = diagram.to_dict()
    for key in ("points", "branches", "special_points", "hopf_points", "errors", "wall_time"):
        result[key] = d[key]
    _deliver(args, store_dir, result, KEYS)
    if result["errors"]:
        raise SolverError("; ".join(result["errors"]))
    return 0


def _refuse_3d(args: argparse.Namespace) -> None:
    """CLIError for an option that has no meaning for the 3-D sweep."""
    if args.method == "continuation":
        raise CLIError(
            "--method", "--3d sweeps the attractors (no continuation in 3-D): use --method sweep"
        )
    if args.planar:
        raise CLIError("--planar", "contradicts --3d")
    if args.alphas is not None:
        raise CLIError("--alphas", "--3d sweeps one inclination; use --alpha")
    if args.dask is not None:
        raise CLIError("--dask", "--3d runs in this process")
    if args.workers is not None and int(args.workers) > 1:
        raise CLIError("--workers", "--3d runs in this process (use --workers 1)")
    if getattr(args, "sigma", 0) > 0:
        raise CLIError("--sigma", "a pulsating flow is not available with --3d (use sigma = 0)")


def _run_3d(args: argparse.Namespace, setup) -> int:
    """``--3d``: the attractors of the 3-D model swept against v."""
    from fempipe.analyses.three_d.diagram import compute_diagram_3d
    from fempipe.model.plane.operators import PipeModel

    _refuse_3d(args)
    total = _check_work(args, setup, None)
    store_dir = _store_dir(args)
    with reporting.progress(args, total, "bifurcation --3d") as bar:
        diagram = compute_diagram_3d(
            PipeModel(setup.disc, setup.params),
            setup.v,
            args.directions,
            store_dir=store_dir,
            progress=_on_progress(bar),
            out_of_plane_amplitude=args.out_of_plane_amplitude,
            t_max=args.t_max,
            rtol=args.rtol,
            shoot_rtol=args.shoot_rtol,
        )
    result = _result(setup, None)
    result["model"] = "3d"
    result["method"] = "sweep"
    result["points"] = diagram.points
    result["wall_time"] = diagram.wall_time
    result["cpu_time"] = diagram.cpu_time
    _deliver(args, store_dir, result, KEYS_3D)
    return 0


def _deliver(args, store_dir, result: dict, keys) -> None:
    """The point store recorded in --out, then :func:`fempipe.cli.reporting.deliver`."""
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        output.record(store_dir)
    is_3d = result.get("model") == "3d"
    reporting.deliver(
        args,
        result,
        output,
        lambda out: _write_outputs(out, result, keys),
        lambda: (_print_table_3d if is_3d else _print_table)(result),
    )


def _write_outputs(output: reporting.Output, result: dict, keys) -> None:
    reporting.agg()
    from fempipe.plotting.dynamics import diagram_figure, diagram_figure_3d

    figure = diagram_figure_3d if result.get("model") == "3d" else diagram_figure
    for key in keys:
        output.figure(f"{key}.png", figure(result, key), dpi=130)
    output.json("bifurcation.json", result)


def _print_table(result: dict) -> None:
    """One line per point; ``branch``: ``eq``, the cycle branch (``H1``, ...) or the sweep's
    direction; ``point``: ``requested`` (a v of ``--v``) or ``step``."""
    cols = [
        ("alpha", lambda pt: f"{pt['alpha']:.4g}"),
        (
            "branch",
            lambda pt: {"continuation": pt.get("branch", "c"), "static": "eq"}.get(
                pt["direction"], pt["direction"]
            ),
        ),
        ("v", lambda pt: f"{pt['v']:.4g}"),
        ("attractor", lambda pt: pt["attractor"], "<"),
        ("stable", lambda pt: _yes_no(pt.get("stable")), "<"),
        ("point", lambda pt: "requested" if pt.get("requested", True) else "step", "<"),
        *_extrema_columns(("eta", "X", "Z")),
    ]
    if any("stable_3d" in pt for pt in result["points"]):
        cols.append(("3d", lambda pt: _yes_no(pt.get("stable_3d")), "<"))
    reporting.print_table(cols, result["points"])
    for sp in result.get("special_points", []):
        print(
            f"special point: alpha {sp['alpha']:.4g} {sp['branch']} {sp['type']} v = {sp['v']:.6g}"
        )


def _extrema_columns(names) -> list:
    """The period, then min and max of each ``NAME_tip``."""
    cols = [("period", lambda pt: f"{pt['period']:.6g}" if pt["period"] else "-")]
    for name in names:
        for i, end in enumerate(("min", "max")):
            cols.append((f"{name}_{end}", lambda pt, k=f"{name}_tip", i=i: f"{pt[k][i]:.5f}"))
    return cols


def _print_table_3d(result: dict) -> None:
    """One line per point of a 3-D run."""
    cols = [
        ("dir", lambda pt: pt["direction"]),
        ("v", lambda pt: f"{pt['v']:.4g}"),
        ("attractor", lambda pt: pt["attractor"], "<"),
        ("motion", lambda pt: pt["motion"], "<"),
        *_extrema_columns(("Y", "eta")),
    ]
    cols.insert(
        5, ("whirl", lambda pt: "-" if pt["whirl_rate"] is None else f"{pt['whirl_rate']:.4g}")
    )
    reporting.print_table(cols, result["points"])


def _yes_no(flag) -> str:
    return {True: "yes", False: "no"}.get(flag, "-")

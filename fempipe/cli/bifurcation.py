"""``fempipe bifurcation``: tip extrema against v, by continuation (default) or by sweeps.

``--method continuation`` (the default) follows the equilibria of the primary
static branch and the branch of periodic orbits born at every Hopf point
(flutter event) by pseudo-arclength continuation
(:func:`fempipe.analyses.periodic.cycle_diagram`): stable and unstable orbits, their
Floquet multipliers, and the folds, period doublings and Neimark-Sacker points
of the branches; every requested v is landed on exactly (``requested``: true,
``source``: "grid"), the continuation's own points have ``requested``: false.
Points gain ``stable``, ``branch`` and ``floquet_multipliers``; the result
gains ``branches``, ``special_points``, ``hopf_points`` and ``errors``.  A
branch that cannot be continued is reported (exit 1) after its finished
points are written.  ``--directions`` has no meaning there; ``--orbit-rtol``
is its integration tolerance (``--shoot-rtol``, ``--rtol`` and ``--t-max`` are
the sweep's).

``--method sweep`` is the independent check.  Each point starts from the attractor of the previous one
(:func:`fempipe.analyses.bifurcation.sweep`); up and down sweeps (and several
inclinations given with ``--alphas``) are independent and run in parallel on
``--workers N`` local processes or on a Dask cluster (``--dask tcp://host:port``,
needs the optional extra ``fempipe[dask]``).

Whether each planar state survives in three dimensions (as ``simulate``
reports it; ``--planar`` leaves it out): every periodic point (the continued
orbits, stable and unstable, and the sweep's periodic attractors) gains
``out_of_plane_floquet_multipliers`` (the six largest, ``[re, im]``, of the
out-of-plane perturbations, :func:`fempipe.analyses.space.out_of_plane_floquet`),
``max_nontrivial_out_of_plane_multiplier`` (at alpha = 0 and pi the neutral
rotation about the vertical left out, and reported as
``neutral_out_of_plane_multiplier`` with its distance from 1,
``out_of_plane_symmetry_defect``), ``stable_out_of_plane``, ``stable_3d``
(stable in the plane and out of it) and, where that verdict is rough (a few
modes, or a neutral multiplier more than 1e-2 from 1), ``stable_3d_note``; an equilibrium
``stable_out_of_plane`` and ``stable_3d`` from its out-of-plane spectrum.  The
verdicts are kept in the point store with their points.  ``--3d`` sweeps the
attractors of the 3-D model instead (:mod:`fempipe.cli.bifurcation_space`).

``--json`` prints ``{"points": [{"v", "direction", "attractor", "eta_tip":
[min, max], "X_tip": [...], "Z_tip": [...], "period"}, ...]}``.  ``--out DIR``
writes bifurcation.json, the diagrams eta_tip.png, X_tip.png and Z_tip.png
(one panel per inclination; for the paper's case, each panel names the
panel of the paper's Figs. 7-10 it redraws), and keeps the point store DIR/points/: every
finished point is written at once, and rerunning the same command resumes,
computing only the missing points.
"""

from __future__ import annotations

import argparse
import math

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser)
    common.add_flow_arguments(parser, default="5:12:36")
    common.add_discretization_arguments(parser)
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
        help="sweep the attractors of the 3-D model instead (fempipe.cli.bifurcation_space: "
        "motion, Y_tip, whirl_rate against v)",
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


def _parse(args):
    directions = args.directions
    alphas = None
    if args.alphas is not None:
        alphas = parsing.parse_alpha_list(args.alphas, "--alphas", parsing.allow_large(args))
    return directions, alphas, args.workers


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.bifurcation import bifurcation_diagram
    from fempipe.model.operators import PipeModel

    common.refuse_hysteretic(args, "bifurcation")
    setup = common.setup_from_args(args)
    if args.three_d:
        from fempipe.cli.bifurcation_space import run_3d

        return run_3d(args, setup)
    if args.method is None:  # None: not given (--3d refuses an explicit continuation)
        args.method = "continuation"
    directions, alphas, workers = _parse(args)
    t_max, rtol, shoot_rtol = args.t_max, args.rtol, args.shoot_rtol
    large = parsing.allow_large(args)
    parsing.check_count("--t-max", t_max, parsing.T_MAX, large, "time units")
    if not setup.v:
        raise CLIError("--v", "no flow velocities to sweep")
    n_alpha = 1 if alphas is None else len(alphas)
    total = len(setup.v) * len(directions) * n_alpha
    flow_opt = "--U" if args.U is not None else "--v"
    parsing.check_count(
        flow_opt, total, parsing.MAX_VALUES, large, "points (v x directions x alphas)"
    )
    if args.method == "continuation":
        return _run_continuation(args, setup, alphas, workers)
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
    store_dir = None
    if args.out is not None:
        from pathlib import Path

        store_dir = Path(args.out) / "points"
    model = PipeModel(setup.disc, setup.params)
    try:
        with reporting.progress(args, total, "bifurcation") as bar:
            seen = [0]

            def on_progress(done, _total):
                if done > seen[0]:
                    bar.update(done - seen[0])
                    seen[0] = done

            try:
                diagram = bifurcation_diagram(
                    model,
                    setup.v,
                    directions,
                    alphas=alphas,
                    store_dir=store_dir,
                    executor=executor,
                    workers=workers if executor is None else None,
                    progress=on_progress,
                    out_of_plane=not args.planar,
                    t_max=t_max,
                    rtol=rtol,
                    shoot_rtol=shoot_rtol,
                )
            except ValueError as exc:
                if "point store" in str(exc):
                    raise CLIError("--out", str(exc)) from None
                raise
    finally:
        if client is not None:
            client.close()

    result = setup.to_dict()
    result["params"].pop("v", None)
    if alphas is not None:
        result["params"]["alphas"] = alphas
    result["points"] = diagram.points
    result["wall_time"] = diagram.wall_time
    _deliver(args, store_dir, result)
    return 0


def _run_continuation(args: argparse.Namespace, setup, alphas, workers) -> int:
    """``--method continuation``: :func:`fempipe.analyses.periodic.cycle_diagram`."""
    from fempipe.analyses.periodic import cycle_diagram
    from fempipe.core.errors import SolverError
    from fempipe.model.operators import PipeModel

    flow_opt = "--U" if args.U is not None else "--v"
    if len(set(setup.v)) < 2:
        raise CLIError(flow_opt, "continuation needs a range of v (at least two values)")
    if args.dask is not None:
        raise CLIError("--dask", "runs sweeps only; use --method sweep or --workers")
    store_dir = None
    if args.out is not None:
        from pathlib import Path

        store_dir = Path(args.out) / "points"
    model = PipeModel(setup.disc, setup.params)
    with reporting.progress(args, None, "bifurcation") as bar:
        try:
            diagram = cycle_diagram(
                model,
                setup.v,
                alphas=alphas,
                store_dir=store_dir,
                workers=workers,
                progress=bar.update,
                out_of_plane=not args.planar,
                rtol=args.orbit_rtol,
            )
        except ValueError as exc:
            if "point store" in str(exc):
                raise CLIError("--out", str(exc)) from None
            raise
    result = setup.to_dict()
    result["params"].pop("v", None)
    if alphas is not None:
        result["params"]["alphas"] = alphas
    result["method"] = "continuation"
    d = diagram.to_dict()
    for key in ("points", "branches", "special_points", "hopf_points", "errors", "wall_time"):
        result[key] = d[key]
    _deliver(args, store_dir, result)
    if result["errors"]:
        raise SolverError("; ".join(result["errors"]))
    return 0


def _deliver(args, store_dir, result: dict) -> None:
    """The point store recorded in --out, then :func:`fempipe.cli.reporting.deliver`."""
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        output.record(store_dir)
    reporting.deliver(
        args, result, output, lambda out: _write_outputs(out, result), lambda: _print_table(result)
    )


def _write_outputs(output: reporting.Output, result) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for key in ("eta_tip", "X_tip", "Z_tip"):
        fig = diagram_figure(result, key)
        try:
            output.figure(f"{key}.png", fig, dpi=130)
        finally:
            plt.close(fig)
    output.json("bifurcation.json", result)


def diagram_figure(result: dict, key: str):
    """The figure of ``key`` (``eta_tip``, ``X_tip``, ``Z_tip``): one panel per
    inclination, the run's parameters above, one legend below the panels."""
    import textwrap

    import matplotlib.pyplot as plt

    from fempipe.plotting.dynamics import plot_bifurcation
    from fempipe.plotting.layout import shared_legend

    p = result["params"]
    groups = sorted({pt["alpha"] for pt in result["points"]})
    fig, axes = plt.subplots(
        1, len(groups), figsize=(5.5 * len(groups), 4.6), squeeze=False, layout="constrained"
    )
    for ax, a in zip(axes[0], groups, strict=True):
        pts = [pt for pt in result["points"] if pt["alpha"] == a]
        plot_bifurcation(
            pts,
            key,
            ax=ax,
            title=f"α = {math.degrees(a):.4g}°, β = {p['beta']:.4g}, "
            f"γ = {p['gamma']:.4g}" + paper_panel(key, a, p),
            special_points=[s for s in result.get("special_points", []) if s["alpha"] == a],
            hopf_points=[h for h in result.get("hopf_points", []) if h["alpha"] == a],
        )
    shared_legend(fig, axes[0])
    # Wrapped to the figure's width (about 70 characters of 9 pt per 5.5 in).
    fig.suptitle(textwrap.fill(_caption(result), 70 * len(groups)), fontsize=9)
    return fig


def paper_panel(key: str, alpha: float, params: dict) -> str:
    """`` (cf. Fig. 8(b))``: the panel of the paper's Figs. 7-10 that a diagram
    redraws, or ``""`` where it redraws none (another case, another alpha).

    Fig. 7 is alpha = 0 with (a) eta(1), (b) X_g(1), (c) Z_g(1); Figs. 8, 9 and
    10 are eta(1), X_g(1) and Z_g(1) with (a)-(d) alpha = pi/4, pi/2, 3pi/4, pi,
    all for the reference case beta = 0.142, gamma = 18.9, mu = 0.005.
    """
    from fempipe.model.params import PAPER_CASE, VARIANT_FIELDS

    if any(not math.isclose(params.get(k, math.nan), v) for k, v in PAPER_CASE.items()):
        return ""
    if any(params.get(k) for k in VARIANT_FIELDS):
        return ""  # a variant of the pipe: the paper has no such figure
    column = ("eta_tip", "X_tip", "Z_tip").index(key)
    if math.isclose(alpha, 0.0, abs_tol=1e-12):
        return f" (cf. Fig. 7({'abc'[column]}))"
    for k in range(1, 5):
        if math.isclose(alpha, k * math.pi / 4):
            return f" (cf. Fig. {8 + column}({'abcd'[k - 1]}))"
    return ""


def _caption(result: dict) -> str:
    """The run's parameters, written under each diagram."""
    p = result["params"]
    disc = result.get("discretization", {})
    if disc.get("kind") == "fe":
        name = f"{disc.get('element')}:{disc.get('n_elements')}"
    else:
        name = f"{disc.get('kind', '')} {disc.get('n_modes', disc.get('n_dofs', ''))}"
    text = f"μ = {p['mu']:.4g}, {name.strip()}; "
    if result.get("method") == "continuation":
        text += (
            "continuation of equilibria and periodic orbits (solid stable, dashed unstable; "
            "dots: requested v)"
        )
    else:
        text += "sweeps of attractors up and down"
    return text


def _print_table(result: dict) -> None:
    """One line per point.  ``branch``: ``eq`` (the static branch), the cycle
    branch's name (``H1``, ...) or the sweep's direction; ``stable``: from the
    eigenvalues or Floquet multipliers (``-`` for a sweep's attractor, which is
    not analysed); ``point``: ``requested`` (a v of ``--v``) or ``step`` (the
    continuation's own); ``3d``: ``stable_3d`` (``-`` where undecided; the
    column only when the verdicts were computed)."""
    three = any("stable_3d" in pt for pt in result["points"])
    print(
        f"{'alpha':>8s} {'branch':>6s} {'v':>8s}  {'attractor':<12s} {'stable':<6s} "
        f"{'point':<9s} {'period':>10s} {'eta_min':>9s} {'eta_max':>9s} {'X_min':>9s} "
        f"{'X_max':>9s} {'Z_min':>9s} {'Z_max':>9s}" + (f" {'3d':<4s}" if three else "")
    )
    for pt in result["points"]:
        per = f"{pt['period']:.6g}" if pt["period"] else "-"
        stable = _yes_no(pt.get("stable"))
        point = "requested" if pt.get("requested", True) else "step"
        branch = {"continuation": pt.get("branch", "c"), "static": "eq"}.get(
            pt["direction"], pt["direction"]
        )
        print(
            f"{pt['alpha']:8.4g} {branch:>6s} {pt['v']:8.4g}  {pt['attractor']:<12s} "
            f"{stable:<6s} {point:<9s} {per:>10s} {pt['eta_tip'][0]:9.5f} "
            f"{pt['eta_tip'][1]:9.5f} {pt['X_tip'][0]:9.5f} {pt['X_tip'][1]:9.5f} "
            f"{pt['Z_tip'][0]:9.5f} {pt['Z_tip'][1]:9.5f}"
            + (f" {_yes_no(pt.get('stable_3d')):<4s}" if three else "")
        )
    for sp in result.get("special_points", []):
        print(
            f"special point: alpha {sp['alpha']:.4g} {sp['branch']} {sp['type']} v = {sp['v']:.6g}"
        )


def _yes_no(flag) -> str:
    return {True: "yes", False: "no"}.get(flag, "-")

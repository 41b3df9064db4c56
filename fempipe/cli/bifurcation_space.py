"""``fempipe bifurcation --3d``: the attractors of the 3-D model against v, by sweeps.

Each point integrates the 3-D model (:mod:`fempipe.model.space`) until its
attractor is recognized (:func:`fempipe.analyses.space.simulate_space`),
starting from the previous point's attractor where it can
(:func:`fempipe.analyses.space.diagram.space_sweep`: ``started`` says whether
it did), else from the static state perturbed in the plane (0.01 rad, first
sine mode) and out of it (``--out-of-plane-amplitude``).  ``--directions``
chooses the sweeps (up, down; a sweep down costs as much as one up).

``--json`` prints ``{"model": "3d", "points": [{"v", "direction", "attractor"
("equilibrium", "periodic", "whirl", "quasi-periodic", "non-periodic"), "motion" ("planar" or
"nonplanar"), "eta_tip", "X_tip", "Z_tip", "Y_tip": [min, max], "period",
"period_n", "whirl_rate", "planarity", "stable", "started", ...}, ...]}``.
``--out DIR`` writes bifurcation.json, the diagrams Y_tip.png, eta_tip.png,
X_tip.png, Z_tip.png, and keeps the point store DIR/points/ (one file per
finished point): rerunning the same command resumes.

Refused with ``--3d`` (no meaning there): ``--method continuation`` (no
continuation of 3-D orbits yet), ``--planar``, ``--alphas``, ``--dask``,
``--workers`` > 1 and a pulsating or hysteretic pipe.
"""

from __future__ import annotations

import argparse
import math

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

KEYS = ("Y_tip", "eta_tip", "X_tip", "Z_tip")


def _refuse(args: argparse.Namespace) -> None:
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


def run_3d(args: argparse.Namespace, setup: common.Setup) -> int:
    """The 3-D sweep: see the module docstring."""
    from pathlib import Path

    from fempipe.analyses.space.diagram import space_diagram
    from fempipe.model.operators import PipeModel

    _refuse(args)
    flow_opt = "--U" if args.U is not None else "--v"
    if not setup.v:
        raise CLIError(flow_opt, "no flow velocities to sweep")
    large = parsing.allow_large(args)
    parsing.check_count("--t-max", args.t_max, parsing.T_MAX, large, "time units")
    total = len(setup.v) * len(args.directions)
    parsing.check_count(flow_opt, total, parsing.MAX_VALUES, large, "points (v x directions)")
    store_dir = Path(args.out) / "points" if args.out is not None else None
    model = PipeModel(setup.disc, setup.params)
    with reporting.progress(args, total, "bifurcation --3d") as bar:
        try:
            diagram = space_diagram(
                model,
                setup.v,
                args.directions,
                store_dir=store_dir,
                progress=lambda _p: bar.update(1),
                out_of_plane_amplitude=args.out_of_plane_amplitude,
                t_max=args.t_max,
                rtol=args.rtol,
                shoot_rtol=args.shoot_rtol,
            )
        except ValueError as exc:
            if "point store" in str(exc):
                raise CLIError("--out", str(exc)) from None
            raise
    result = setup.to_dict()
    result["params"].pop("v", None)
    result["model"] = "3d"
    result["method"] = "sweep"
    result["points"] = diagram["points"]
    result["wall_time"] = diagram["wall_time"]
    result["cpu_time"] = diagram["cpu_time"]
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        output.record(store_dir)
    reporting.deliver(
        args, result, output, lambda out: _write_outputs(out, result), lambda: _print_table(result)
    )
    return 0


def _write_outputs(output: reporting.Output, result: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    for key in KEYS:
        fig = diagram_figure(result, key)
        try:
            output.figure(f"{key}.png", fig, dpi=130)
        finally:
            plt.close(fig)
    output.json("bifurcation.json", result)


#: Marker per attractor kind, color per direction; filled where the motion is non-planar.
_MARKS = {
    "equilibrium": "s",
    "periodic": "o",
    "whirl": "D",
    "quasi-periodic": "^",
    "non-periodic": "x",
}
_COLORS = {"up": "tab:blue", "down": "tab:red"}
_LABELS = {"Y_tip": "Y(1) (out of plane)", "eta_tip": "η(1)", "X_tip": "X_g(1)", "Z_tip": "Z_g(1)"}


def diagram_figure(result: dict, key: str):
    """[min, max] of ``key`` against v: one mark each, the marker by attractor kind, the
    color by sweep direction (a colored line in the legend) (down shifted by a hair to the right so that it does not
    cover up), filled where the motion is non-planar; the run's parameters above."""
    import textwrap

    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
    pts = result["points"]
    vs = [p["v"] for p in pts]
    shift = 0.004 * (max(vs) - min(vs)) if len(set(vs)) > 1 else 0.0
    for p in pts:
        lo, hi = p[key]
        x = p["v"] + (shift if p["direction"] == "down" else 0.0)
        c = _COLORS[p["direction"]]
        face = c if p["motion"] == "nonplanar" else "none"
        mk = _MARKS.get(p["attractor"], "x")
        ax.plot([x, x], [lo, hi], ls="", marker=mk, ms=5, color=c, mfc=face)
    handles = [
        Line2D([], [], ls="-", lw=3, color=c, label=f"sweep {d}")
        for d, c in _COLORS.items()
        if any(p["direction"] == d for p in pts)
    ]
    handles += [
        Line2D([], [], ls="", marker=m, color="0.3", mfc="none", label=k)
        for k, m in _MARKS.items()
        if any(p["attractor"] == k for p in pts)
    ]
    handles.append(Line2D([], [], ls="", marker="o", color="0.3", mfc="0.3", label="non-planar"))
    ax.legend(handles=handles, fontsize=8, loc="best")
    ax.set_xlabel("v")
    ax.set_ylabel(_LABELS[key] + " (/L), min and max")
    ax.grid(alpha=0.3)
    p = result["params"]
    disc = result.get("discretization", {})
    mesh = (
        f"{disc.get('element')}:{disc.get('n_elements')}"
        if disc.get("kind") == "fe"
        else str(disc.get("kind", ""))
    )
    caption = (
        f"3-D attractors, α = {math.degrees(p['alpha']):.4g}°, β = {p['beta']:.4g}, "
        f"γ = {p['gamma']:.4g}, μ = {p['mu']:.4g}, {mesh}; open: planar motion, "
        "filled: non-planar"
    )
    ax.set_title(textwrap.fill(caption, 80), fontsize=9)
    return fig


def _print_table(result: dict) -> None:
    """One line per point."""
    print(
        f"{'dir':>4s} {'v':>8s}  {'attractor':<12s} {'motion':<9s} {'period':>10s} "
        f"{'whirl':>8s} {'Y_min':>9s} {'Y_max':>9s} {'eta_min':>9s} {'eta_max':>9s}"
    )
    for pt in result["points"]:
        per = f"{pt['period']:.6g}" if pt["period"] else "-"
        wr = f"{pt['whirl_rate']:.4g}" if pt["whirl_rate"] is not None else "-"
        print(
            f"{pt['direction']:>4s} {pt['v']:8.4g}  {pt['attractor']:<12s} {pt['motion']:<9s} "
            f"{per:>10s} {wr:>8s} {pt['Y_tip'][0]:9.5f} {pt['Y_tip'][1]:9.5f} "
            f"{pt['eta_tip'][0]:9.5f} {pt['eta_tip'][1]:9.5f}"
        )

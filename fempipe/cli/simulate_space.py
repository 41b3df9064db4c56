"""``fempipe simulate --3d``: the nonlinear motion in three dimensions and its attractor.

The 3-D model from the planar static state perturbed in the plane (``--mode``,
``--amplitude``) and out of it (``--out-of-plane-amplitude``), integrated until the attractor
is recognized (:func:`fempipe.analyses.space.simulate_3d`).  ``--json`` prints the attractor
(:meth:`~fempipe.analyses.space.motion.Motion3D.to_dict`, ``"model": "3d"``); ``--out DIR``
writes simulate.json, tip.csv (tau and the tip coordinates at every step), trajectory.pvd
with its VTU frames (at most 400), tip_orbit.png and snapshots_3d.png.
Keys and files: docs/cli/commands.md.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from fempipe.analyses.space import simulate_3d
from fempipe.analyses.space.verdict import equilibrium_verdict
from fempipe.analyses.stability import linearly_stable
from fempipe.analyses.statics import solve_static
from fempipe.cli import common, reporting
from fempipe.cli.parsing import CLIError
from fempipe.io import json_dumps
from fempipe.model.operators import PipeModel
from fempipe.model.space import SpaceModel, planar_state

TIP3_COLUMNS = ("tau", "eta_tip", "X_tip", "Z_tip", "Y_tip")


def run_3d(args: argparse.Namespace, setup: common.Setup) -> int:
    if args.sigma > 0:
        raise CLIError("--sigma", "a pulsating flow is not available with --3d (use sigma = 0)")
    if args.error_estimate:
        raise CLIError("--error-estimate", "no error estimate is available with --3d yet")
    params, disc = setup.params, setup.disc
    model = PipeModel(disc, params)
    start = time.perf_counter()
    with reporting.progress(args, 100, f"simulate --3d v={params.v:g}") as bar:
        on_time = reporting.time_progress(bar, args.t_max)
        motion = simulate_3d(
            model,
            mode=args.mode,
            amplitude=args.amplitude,
            out_of_plane_amplitude=args.out_of_plane_amplitude,
            t_max=args.t_max,
            rtol=args.rtol,
            callback=on_time,
        )
    result = setup.to_dict()
    result["params"]["v"] = params.v
    result["model"] = "3d"
    result.update(motion.to_dict())
    result["wall_time"] = time.perf_counter() - start
    if setup.pipe is not None:
        ts = setup.pipe.time_scale
        result["period_s"] = result["period"] * ts if result.get("period") else None
        result["tip_m"] = {k: [x * setup.pipe.L for x in v] for k, v in result["tip"].items()}
    space = SpaceModel(disc, params)
    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        _write(output, result, space, motion, _static_state(model))
    if args.json:
        print(json_dumps(result))
    else:
        _summary(result)
    if output is not None:
        output.report(args)
    return 0


def _static_state(model) -> tuple:
    """``(U, stable)``: the static state as 3-D unknowns and its 3-D linear stability (None
    where undecided), for the figures."""
    q = solve_static(model).q
    verdict = equilibrium_verdict(model, q, linearly_stable(model, q))
    return planar_state(q), verdict["stable_3d"]


def _write(output: reporting.Output, result: dict, space, motion, static) -> None:
    import matplotlib  # only with --out

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.io.space_trajectory import write_space_trajectory
    from fempipe.plotting.space import plot_space_snapshots, plot_tip_orbit

    output.json("simulate.json", result)
    rows = []
    for t, U in zip(motion.t, motion.U, strict=True):
        rows.append({"tau": float(t)} | space.tip_coordinates(U))
    output.csv("tip.csv", rows, TIP3_COLUMNS)
    keep = np.unique(np.linspace(0, motion.t.size - 1, min(400, motion.t.size)).round().astype(int))
    output.record(
        write_space_trajectory(output.path("trajectory.pvd"), space, motion.t[keep], motion.U[keep])
    )
    output.record(output.path("trajectory"))
    for name, fig in (
        ("tip_orbit.png", plot_tip_orbit(space, motion, static=static)),
        ("snapshots_3d.png", plot_space_snapshots(space, motion, static=static)),
    ):
        # tight: a 3-D axes' labels reach beyond the box the layout gives it
        output.figure(name, fig, dpi=130, bbox_inches="tight")
        plt.close(fig)


def _summary(r: dict) -> None:
    p = r["params"]
    print(
        f"alpha = {p['alpha']:.6g}, beta = {p['beta']:.6g}, gamma = {p['gamma']:.6g}, "
        f"mu = {p['mu']:.6g}, v = {p['v']:.6g} (3-D)"
    )
    line = f"attractor: {r['attractor']}, motion {r['motion']}"
    if r.get("period"):
        line += f", period {r['period']:.8g}"
    if r.get("whirl_rate") is not None:
        line += f", whirl rate {r['whirl_rate']:.6g}"
    print(line)
    for k, (lo, hi) in r["tip"].items():
        print(f"  {k:8s} min {lo: .8f}  max {hi: .8f}")
    if r.get("floquet_multipliers"):
        mus = ", ".join(f"{abs(complex(a, b)):.4g}" for a, b in r["floquet_multipliers"][:6])
        verdict = "stable" if r.get("stable") else "unstable"
        print(f"  |Floquet multipliers| {mus} ({verdict})")
    if r.get("frequencies"):
        print(f"  frequencies {', '.join(f'{f:.6g}' for f in r['frequencies'])}")
    print(
        f"  planarity {r['planarity']:.3g}, steps {r['steps']}, rejected {r['rejected_steps']}, "
        f"tau {r['t_end']:.4g}, CPU {r['cpu_time']:.1f} s"
    )

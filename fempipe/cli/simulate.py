"""``fempipe simulate``: nonlinear time integration of Eq. (20) and its attractor.

``--sigma`` > 0 a pulsating flow; ``--3d`` the 3-D model (:func:`run_3d`).  Keys and files:
docs/cli/commands.md, "fempipe simulate".
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError

EXAMPLES = (
    "fempipe simulate --v 10 --out out-sim/                     # flutter of the hanging pipe",
    "fempipe simulate --v 6.4 --alpha pi/4 --output-dt 0.01 --out out-sim45/",
)

#: Default --shoot-rtol: the period and tip extrema within 5e-8 and 5e-7 (relative) of 1e-10.
SHOOT_RTOL = 1e-5
#: With --error-estimate, whose floor it is: below a P3:16 cycle's discretization error.
ERROR_ESTIMATE_SHOOT_RTOL = 1e-7


def shoot_rtol_of(args: argparse.Namespace) -> float:
    """--shoot-rtol as given, else the default with or without --error-estimate."""
    if args.shoot_rtol is not None:
        return float(args.shoot_rtol)
    return ERROR_ESTIMATE_SHOOT_RTOL if args.error_estimate else SHOOT_RTOL


def _short(x: float) -> str:
    """1e-05 -> 1e-5 (as the other defaults are written in the help)."""
    return f"{x:g}".replace("e-0", "e-")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_problem_arguments(parser, "10")
    g = common.add_integration_arguments(
        parser,
        shoot_rtol=_short(SHOOT_RTOL),
        shoot_help=(
            "integration tolerance of the shooting; sets the accuracy of the cycle "
            "(1e-5: period to ~5e-8, tip extrema to ~5e-7 relative, measured); "
            f"{_short(ERROR_ESTIMATE_SHOOT_RTOL)} with --error-estimate, whose floor it is, else"
        ),
    )
    # None: resolved in run() (ERROR_ESTIMATE_SHOOT_RTOL with --error-estimate).
    parser.set_defaults(shoot_rtol=None)
    num = parsing.number_type
    common.option(
        g, "--mode", "R", parsing.positive_int, "1", "sine mode r of the initial perturbation (1)"
    )
    g.add_argument(
        "--amplitude",
        metavar="A",
        type=num("--amplitude"),
        default="0.01",
        help="initial perturbation in rad (0.01)",
    )
    common.add_planar_argument(
        g,
        "no out-of-plane Floquet multipliers and no stable_3d (they cost 1.3-2.3 s CPU for a "
        "cycle on P3:16)",
    )
    g.add_argument(
        "--3d",
        dest="three_d",
        action="store_true",
        help="integrate the 3-D model instead (motion, Y_tip, whirl_rate)",
    )
    g.add_argument(
        "--out-of-plane-amplitude",
        metavar="A",
        type=num("--out-of-plane-amplitude"),
        default="0.01",
        help="with --3d: initial out-of-plane rotation in rad, same sine mode (0.01)",
    )
    g.add_argument(
        "--no-shooting",
        action="store_true",
        help="accept a cycle when successive Poincare returns agree to 1e-6 (long integration)",
    )
    g.add_argument(
        "--sigma",
        metavar="S",
        type=num("--sigma", 0.0, 1.0),
        default="0",
        help="pulsating flow amplitude, 0 <= S <= 1 (0)",
    )
    g.add_argument(
        "--omega",
        metavar="W",
        type=num("--omega", 0.0),
        default="0",
        help="pulsating flow frequency (0)",
    )
    common.add_output_arguments(parser)
    parser.add_argument(
        "--output-dt",
        metavar="DT",
        type=num("--output-dt", 0.0, strict_low=True),
        default=None,
        help="tip.csv on a uniform grid of step DT in tau (default: every accepted step)",
    )
    common.add_error_estimate_argument(parser, "the period and each tip extremum")


#: After PROJECT_AFTER CPU-seconds the cost to --t-max is projected; above CPU_LIMIT the run is
#: refused unless --allow-large (CPU time: a busy machine does not change the verdict).
PROJECT_AFTER = 10.0
CPU_LIMIT = 900.0


def _cost_check(v: float, t_max: float, allow: bool):
    """A callback ``(tau, cpu_seconds)`` refusing, once, a run projected past ``CPU_LIMIT``."""
    done = [False]

    def check(t: float, elapsed: float) -> None:
        if done[0] or allow or elapsed < PROJECT_AFTER or t <= 0:
            return
        done[0] = True
        projected = elapsed * t_max / t
        if projected > CPU_LIMIT:
            raise CLIError(
                "--t-max",
                f"at v = {v:g} the integration reached tau = {t:.3g} in {elapsed:.0f} s of CPU; "
                f"reaching --t-max {t_max:g} would take about {projected / 60:.0f} CPU-minutes "
                f"(the step follows the fast large-amplitude motion); give a smaller --t-max, "
                "--modal N, or --allow-large to run it",
            )

    return check


def run(args: argparse.Namespace) -> int:
    from fempipe.analyses.dynamics import PulsatingFlow, make_initial_state, simulate
    from fempipe.analyses.limit_cycle import find_attractor
    from fempipe.analyses.statics import solve_static
    from fempipe.model.plane.operators import PipeModel

    common.refuse_hysteretic(args, "simulate")
    setup = common.setup_from_args(args)
    if len(setup.v) != 1:
        raise CLIError(
            common.flow_option(args), f"simulate takes a single flow velocity, got {len(setup.v)}"
        )
    if args.three_d:
        return run_3d(args, setup)
    args.shoot_rtol = shoot_rtol_of(args)
    t_max, rtol, shoot_rtol = args.t_max, args.rtol, args.shoot_rtol
    amplitude, sigma, omega, mode = args.amplitude, args.sigma, args.omega, args.mode
    parsing.check_count("--t-max", t_max, parsing.T_MAX, parsing.allow_large(args), "time units")
    if args.output_dt is not None:
        parsing.check_count(
            "--output-dt",
            t_max / args.output_dt,
            100 * parsing.MAX_VALUES,
            parsing.allow_large(args),
            "rows of tip.csv",
        )

    params, disc = setup.params, setup.disc
    model = PipeModel(disc, params)
    q_s = solve_static(model).q
    q0, p0 = make_initial_state(model, mode, amplitude, q_static=q_s)
    t_start = time.perf_counter()
    cpu_start = time.process_time()
    work = 200 if args.error_estimate else 100
    with reporting.progress(args, work, f"simulate v={params.v:g}") as bar:
        cost = _cost_check(params.v, t_max, parsing.allow_large(args))
        advance = reporting.time_progress(bar, t_max)

        def on_time(t):
            cost(t, time.process_time() - cpu_start)
            advance(t)

        flow = None
        if sigma > 0:
            flow = PulsatingFlow(params.v, sigma, omega)
            traj = simulate(model, q0, p0, t_max, rtol=rtol, flow=flow, callback=on_time)
            att = None
        else:
            att = find_attractor(
                model,
                q0,
                p0,
                t_max=t_max,
                rtol=rtol,
                shoot_rtol=shoot_rtol,
                use_shooting=not args.no_shooting,
                record=True,
                callback=on_time,
            )
            traj = att.trajectory
        wall_time = time.perf_counter() - t_start
        if advance.done < 100:
            bar.update(100 - advance.done)
        result = _result(setup, traj, att, wall_time, args)
        if att is not None and not args.planar:
            from fempipe.analyses.three_d import classify_3d

            result.update(classify_3d(model, att, rtol=shoot_rtol * 1e-2))
        if args.error_estimate:
            result = _with_estimates(
                result, model, traj if att is None else att, q_s, setup.pipe, args, bar
            )

    reporting.deliver(
        args,
        result,
        write=lambda output: _write_outputs(output, result, model, traj, att, args.output_dt),
        text=lambda: _print_summary(result),
    )
    return 0


def _result(setup: common.Setup, traj, att, wall_time: float, args: argparse.Namespace) -> dict:
    """The JSON of the run: the attractor (or the forced response), the steps, SI values."""
    from fempipe.analyses.limit_cycle import TIP_KEYS
    from fempipe.model.kinematics import compute_tip

    params, disc, sigma, omega = setup.params, setup.disc, args.sigma, args.omega
    result = setup.to_dict()
    result["params"]["v"] = params.v
    if att is None:
        half = traj.t >= 0.5 * traj.t[-1]
        tc = compute_tip(disc, traj.q[half], params.alpha)
        result.update(
            {
                "attractor": "forced",
                "period": None,
                "tip": {k: [float(tc[k].min()), float(tc[k].max())] for k in TIP_KEYS},
                "floquet_multipliers": None,
                "flow": {"v0": params.v, "sigma": sigma, "omega": omega},
            }
        )
        result.update(traj.stats())
    else:
        d = att.to_dict()
        d.pop("params")
        result.update(d)
    result["wall_time"] = wall_time
    return _with_si(result, setup.pipe)


def _with_si(result: dict, pipe) -> dict:
    """``period_s`` and ``tip_m`` with an SI pipe."""
    if pipe is not None:
        result["period_s"] = result["period"] * pipe.time_scale if result.get("period") else None
        result["tip_m"] = {k: [x * pipe.L for x in v] for k, v in result["tip"].items()}
    return result


def _with_estimates(result: dict, model, computed, q_static, pipe, args, bar) -> dict:
    """:func:`fempipe.studies.estimates.estimate_errors`, the progress bar from 100 to 200."""
    from fempipe.studies.error_estimate import refine
    from fempipe.studies.estimates import estimate_errors

    fine = refine(model.disc)
    bar.set_postfix_str(f"refined {fine.name}")
    on_time = reporting.time_progress(bar, args.t_max)
    result = estimate_errors(
        result,
        model,
        computed,
        q_static=q_static,
        pipe=pipe,
        t_max=args.t_max,
        rtol=args.rtol,
        shoot_rtol=args.shoot_rtol,
        use_shooting=not args.no_shooting,
        mode=args.mode,
        amplitude=args.amplitude,
        fine=fine,
        callback=on_time,
    )
    if on_time.done < 100:
        bar.update(100 - on_time.done)
    return result


def _display_states(att, traj, n_periods: int = 3):
    """(t, q, qdot) for the figures: the transient, then a few periods of the cycle from its
    sample nearest the transient's end (from its first sample the traces would jump)."""
    from fempipe.analyses.limit_cycle import state_distance

    t, q, p = traj.t, traj.q, traj.qdot
    if att is None or att.cycle is None:
        return t, q, p
    c = att.cycle
    # One period without its closing sample (orbit_t runs from 0 to T).
    ts, qs, ps = c.orbit_t[:-1], c.orbit_q[:-1], c.orbit_qdot[:-1]
    m = ts.size
    k = int(np.argmin(state_distance(qs - q[-1], ps - p[-1], c.period / (2 * math.pi))))
    j = np.arange(k + 1, k + 1 + n_periods * m)
    tt = t[-1] + (j // m) * c.period + ts[j % m] - ts[k]
    return np.r_[t, tt], np.vstack([q, qs[j % m]]), np.vstack([p, ps[j % m]])


def _write_outputs(output: reporting.Output, result, model, traj, att, output_dt=None) -> None:
    reporting.agg()
    from fempipe.io.trajectory import TIP_COLUMNS, tip_rows, write_trajectory
    from fempipe.plotting.dynamics import (
        animate,
        plot_oscillating_shapes,
        plot_phase_portrait,
        plot_time_traces,
    )

    disc, p = model.disc, model.params
    title = f"α = {math.degrees(p.alpha):.4g}°, β = {p.beta:.4g}, γ = {p.gamma:.4g}, v = {p.v:.4g}"
    t, q, qd = _display_states(att, traj)
    # phase portrait, shapes and animation on the attractor: the cycle, else the second half
    if att is not None and att.cycle is not None:
        ct, cq = att.cycle.orbit_t, att.cycle.orbit_q
    else:
        half = t >= 0.5 * t[-1]
        ct, cq = t[half], q[half]
    output.figure(
        "time_traces.png", plot_time_traces(disc, t, q, p.alpha, title=title).figure, dpi=130
    )
    ax = plot_phase_portrait(disc, q[t >= 0.5 * t[-1]], qd[t >= 0.5 * t[-1]], p.alpha)
    ax.set_title(title, fontsize="small")
    output.figure("phase_portrait.png", ax.figure, dpi=130)
    ax = plot_oscillating_shapes(disc, cq, p.alpha, title=title)
    output.figure("oscillating_shapes.png", ax.figure, dpi=130)
    frames = np.linspace(0, len(ct) - 1, min(48, len(ct))).round().astype(int)
    gif = output.path("pipe.gif")
    animate(gif, disc, ct[frames], cq[frames], p.alpha, fps=16, title=title)
    output.record(gif)
    # at most 400 frames, not one per step of a long run
    keep = np.unique(np.linspace(0, len(t) - 1, min(400, len(t))).round().astype(int))
    pvd = output.path("trajectory.pvd")
    write_trajectory(pvd, disc, t[keep], q[keep], qd[keep], p.alpha, params=p)
    output.record(pvd.with_suffix(""))  # the frames, trajectory/frame_NNNNN.vtu
    output.record(pvd)
    tip = tip_rows(disc, traj.t, traj.q, traj.qdot, p.alpha, output_dt)
    output.csv("tip.csv", tip, TIP_COLUMNS)
    output.json("simulate.json", result)


def _print_summary(r: dict) -> None:
    p = r["params"]
    print(
        f"alpha = {p['alpha']:.6g}, beta = {p['beta']:.6g}, gamma = {p['gamma']:.6g}, "
        f"mu = {p['mu']:.6g}, v = {p['v']:.6g}"
    )
    with_errors = "error_estimate" in r
    line = f"attractor: {r['attractor']}"
    if r.get("period"):
        period = f"{r['period']:.8g}"
        if with_errors:
            period = reporting.pm(r["period"], r["period_error"], "{:.8g}")
        line += f", period {period}"
        if r.get("period_n"):
            line += f" (period-{r['period_n']})"
    print(line)
    errors = (r.get("tip_error") or {}) if with_errors else {}
    for k, ends in r["tip"].items():
        if with_errors:
            ends = [
                reporting.pm(x, e, "{: .8f}")
                for x, e in zip(ends, errors.get(k, (None,) * 2), strict=True)
            ]
        else:
            ends = [f"{x: .8f}" for x in ends]
        print(f"  {k:8s} min {ends[0]}  max {ends[1]}")
    for key, what in (("", ""), ("out_of_plane_", "out-of-plane ")):
        if r.get(key + "floquet_multipliers"):
            mus = ", ".join(f"{abs(complex(a, b)):.4g}" for a, b in r[key + "floquet_multipliers"])
            print(f"  |{what}Floquet multipliers| {mus}")
    if "stable_3d" in r:
        verdict = {True: "stable", False: "unstable", None: "undecided"}[r["stable_3d"]]
        print(f"  in three dimensions: {verdict}")
        if r.get("out_of_plane_symmetry_defect") is not None:
            print(f"  |neutral multiplier - 1| {r['out_of_plane_symmetry_defect']:.2g}")
        if r.get("stable_3d_note"):
            print(f"  note: {r['stable_3d_note']}")
    print(f"  steps {r['steps']}, rejected {r['rejected_steps']}, wall time {r['wall_time']:.2f} s")
    if with_errors:
        reporting.print_footer(
            r["error_estimate"], where=f" (attractor there: {r['attractor_refined']})"
        )


#: Columns of tip.csv of ``--3d``.
TIP3_COLUMNS = ("tau", "eta_tip", "X_tip", "Z_tip", "Y_tip")


def run_3d(args: argparse.Namespace, setup: common.Setup) -> int:
    """``--3d``: the 3-D model from the static state perturbed in and out of the plane."""
    from fempipe.analyses.three_d import simulate_3d
    from fempipe.model.plane.operators import PipeModel

    if args.sigma > 0:
        raise CLIError("--sigma", "a pulsating flow is not available with --3d (use sigma = 0)")
    if args.error_estimate:
        raise CLIError("--error-estimate", "no error estimate is available with --3d yet")
    model = PipeModel(setup.disc, setup.params)
    start = time.perf_counter()
    with reporting.progress(args, 100, f"simulate --3d v={setup.params.v:g}") as bar:
        motion = simulate_3d(
            model,
            mode=args.mode,
            amplitude=args.amplitude,
            out_of_plane_amplitude=args.out_of_plane_amplitude,
            t_max=args.t_max,
            rtol=args.rtol,
            callback=reporting.time_progress(bar, args.t_max),
        )
    result = setup.to_dict()
    result["params"]["v"] = setup.params.v
    result["model"] = "3d"
    result.update(motion.to_dict())
    result["wall_time"] = time.perf_counter() - start
    result = _with_si(result, setup.pipe)
    reporting.deliver(
        args,
        result,
        write=lambda out: _write_3d(out, result, model, motion),
        text=lambda: _summary_3d(result),
    )
    return 0


def _write_3d(output: reporting.Output, result: dict, model, motion) -> None:
    reporting.agg()
    from fempipe.analyses.stability import linearly_stable
    from fempipe.analyses.statics import solve_static
    from fempipe.analyses.three_d.verdict import equilibrium_verdict
    from fempipe.io.trajectory_3d import write_trajectory_3d
    from fempipe.model.three_d.model import PipeModel3D, planar_state
    from fempipe.plotting.three_d import plot_snapshots_3d, plot_tip_orbit

    space = PipeModel3D(model.disc, model.params)
    q = solve_static(model).q  # the static state and its 3-D verdict, for the figures
    static = planar_state(q), equilibrium_verdict(model, q, linearly_stable(model, q))["stable_3d"]
    output.json("simulate.json", result)
    rows = [
        {"tau": float(t)} | space.tip_coordinates(U)
        for t, U in zip(motion.t, motion.U, strict=True)
    ]
    output.csv("tip.csv", rows, TIP3_COLUMNS)
    keep = np.unique(np.linspace(0, motion.t.size - 1, min(400, motion.t.size)).round().astype(int))
    output.record(
        write_trajectory_3d(output.path("trajectory.pvd"), space, motion.t[keep], motion.U[keep])
    )
    output.record(output.path("trajectory"))
    for name, plot in (("tip_orbit.png", plot_tip_orbit), ("snapshots_3d.png", plot_snapshots_3d)):
        # tight: a 3-D axes' labels reach beyond the box the layout gives it
        output.figure(name, plot(space, motion, static=static), dpi=130, bbox_inches="tight")


def _summary_3d(r: dict) -> None:
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

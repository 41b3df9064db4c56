"""``fempipe simulate``: nonlinear time integration of Eq. (20) and its attractor.

Starts from the static state plus a small perturbation in a chosen sine mode,
integrates past the transient, classifies the attractor (equilibrium,
periodic with its period-n, non-periodic) and computes a limit cycle by
shooting with the monodromy matrix (period, tip extrema, Floquet multipliers).
With ``--sigma`` > 0 the flow pulsates, v(tau) = v (1 + sigma sin(omega tau)),
and the command integrates to ``--t-max`` and reports the tip extrema over the
second half (``"attractor": "forced"``, no classification).

``--json`` prints ``{"attractor", "period", "tip": {"eta_tip": [min, max],
"X_tip": [...], "Z_tip": [...]}, "floquet_multipliers", "steps",
"rejected_steps", "wall_time", ...}``.  Whether the planar attractor survives
out of the plane (:func:`fempipe.analyses.space.three_dimensional_verdict`):
``stable_3d`` (null for a motion that is not periodic) and for a cycle
``out_of_plane_floquet_multipliers`` (the six largest, ``[re, im]``; at
alpha = 0 and pi the one closest to 1 is the neutral rotation about the
vertical), ``max_nontrivial_out_of_plane_multiplier``,
``stable_out_of_plane``, ``neutral_out_of_plane_multiplier`` and
``out_of_plane_symmetry_defect`` (its distance from 1; null where alpha is
not 0 or pi), ``stable_3d_note`` where the verdict is rough (a few modes, or
a neutral multiplier more than 1e-2 from 1), for an equilibrium
``stable_out_of_plane``;
``--planar`` leaves them out.  ``--out DIR`` writes simulate.json,
time_traces.png (Fig. 11), phase_portrait.png (Fig. 12),
oscillating_shapes.png, pipe.gif, trajectory.pvd (+ the folder trajectory/
of VTU frames, at most 400: the transient and three periods of the cycle) and
tip.csv, the tip's time series over the integration (:func:`tip_rows`: at
every accepted step, or on a uniform grid with ``--output-dt``).

What the files show is what was computed: the transient integrated at
``--rtol`` from the perturbed static state until the Poincare returns of the
tip agree to 1e-3 (or, where they approach each other slowly, near a
bifurcation, to 2e-2), then the cycle itself, shot at ``--shoot-rtol``.
tip.csv holds the transient only (every row a computed step; it stops
where the shooting took over, the state then 1e-3 to 7e-3 rad (RMS) from the
cycle, measured at alpha = 0 and pi/2, v = 10); the figures and
trajectory.pvd add three periods of the converged cycle after it, from the
cycle's point nearest the transient's end, and the phase portrait, shapes and
animation are of the cycle.  The period, tip extrema and Floquet multipliers of the
JSON are those of the cycle, never of the transient.

``--error-estimate`` computes the attractor again on the refined
discretization (:func:`fempipe.studies.error_estimate.refine`: P_k elements halved,
or twice the modes, plus one for an odd N) without a new transient where it can: a limit cycle is
shot from the coarse cycle transferred to the refined space (the L2
projection :func:`fempipe.model.projection.project`), an equilibrium solved by
Newton from the coarse one (and its linear stability checked); only if that
shooting fails is the refined attractor found by integration from the
transferred state, and a pulsating flow is integrated again from the refined
static state.  Beside ``period`` and ``tip`` (and ``period_s``, ``tip_m``)
it adds ``period_error``, ``period_refined``, ``tip_error`` and
``tip_refined`` (``{"eta_tip": [error of min, error of max], ...}``, the
shape of ``tip``) and ``attractor_refined``; the error of Q is
max(3 |Q - Q_refined| 2^p / (2^p - 1), tol max(1, |Q|)) (Roache's Grid
Convergence Index, p = 2k for P_k, 3 for the sine modes; tol is
``--shoot-rtol`` for a cycle, ``--rtol`` for a pulsating flow, Newton's
1e-10 for an equilibrium).  If the attractors differ in kind (periodic,
period-n, equilibrium; a refined cycle that is unstable) there is no error
number (null) and ``"error_estimate"["notes"]`` says so; a non-periodic
attractor gets none either.  It costs about the refined shooting (a
transient only where needed).  The library does it
(:func:`fempipe.studies.estimates.refined_attractor`,
:func:`~fempipe.studies.estimates.with_attractor_estimates`); this module shows it.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from fempipe.cli import common, estimates, parsing, reporting
from fempipe.cli.parsing import CLIError

#: Default --shoot-rtol.  The period and tip extrema are then within 5e-8 and
#: 5e-7 (relative) of a cycle shot at 1e-10 (measured at alpha = 0, v = 7, 10,
#: 12 and alpha = pi/2, v = 10 on P3:16).
SHOOT_RTOL = 1e-5
#: Default --shoot-rtol with --error-estimate: the estimates' floor is the
#: shooting tolerance (docs, Error estimates), and the discretization error of
#: a P3:16 cycle is about 1e-7, so 1e-5 would hide it under the floor.
ERROR_ESTIMATE_SHOOT_RTOL = 1e-7


def shoot_rtol_of(args: argparse.Namespace) -> float:
    """--shoot-rtol as given, else :data:`ERROR_ESTIMATE_SHOOT_RTOL` with
    --error-estimate and :data:`SHOOT_RTOL` without."""
    if args.shoot_rtol is not None:
        return float(args.shoot_rtol)
    return ERROR_ESTIMATE_SHOOT_RTOL if args.error_estimate else SHOOT_RTOL


def _short(x: float) -> str:
    """1e-05 -> 1e-5 (as the other defaults are written in the help)."""
    return f"{x:g}".replace("e-0", "e-")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    common.add_physical_arguments(parser)
    common.add_flow_arguments(parser, default="10")
    common.add_discretization_arguments(parser)
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
    g.add_argument(
        "--mode",
        metavar="R",
        type=parsing.option_type("--mode", parsing.positive_int),
        default="1",
        help="sine mode r of the initial perturbation (1)",
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
        help="integrate the 3-D model instead (fempipe.cli.simulate_space: motion, Y_tip, "
        "whirl_rate)",
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
    estimates.add_argument(parser, "the period and each tip extremum")


#: Columns of tip.csv; lengths are dimensionless (lengths / L), time tau = t / T
#: with T = L^2 sqrt((m + M)/EI) (Eq. (19)), rates per unit tau.  The header
#: cells carry these units (``tau [T]``, ``X_tip [L]``, ...: fempipe.io.CSV_UNITS).
TIP_COLUMNS = (
    "tau",
    "theta_tip",
    "eta_tip",
    "X_tip",
    "Z_tip",
    "theta_tip_rate",
    "eta_tip_rate",
    "X_tip_rate",
    "Z_tip_rate",
)


def tip_rows(disc, t, q, qdot, alpha: float, output_dt: float | None = None) -> list[dict]:
    """The tip's time series: tau, theta(1), eta(1), X_g(1), Z_g(1) and their rates.

    Parameters
    ----------
    disc : Discretization
    t : ndarray, shape (m,)
        Accepted step times of the integration.
    q, qdot : ndarray, shape (m, n)
    alpha : float
    output_dt : float, optional
        Uniform output step: the states between accepted steps are the cubic
        Hermite interpolants through (q, qdot) at the steps (q exact to the
        step's local error order 4, qdot its derivative).

    Returns
    -------
    list of dict
        Rows with the keys :data:`TIP_COLUMNS`, from
        :func:`fempipe.model.kinematics.tip_values` and
        :func:`~fempipe.model.kinematics.tip_velocity` (theta_tip_rate = theta_dot(1)).
    """
    from fempipe.model.kinematics import tip_values, tip_velocity

    t, q, qdot = np.asarray(t, float), np.asarray(q, float), np.asarray(qdot, float)
    if output_dt is not None:
        from scipy.interpolate import CubicHermiteSpline

        keep = np.concatenate([[True], np.diff(t) > 0])  # no zero-length steps
        spline = CubicHermiteSpline(t[keep], q[keep], qdot[keep], axis=0)
        n = int(math.floor((t[-1] - t[0]) / output_dt * (1 + 1e-12))) + 1
        t = t[0] + output_dt * np.arange(n)
        q, qdot = spline(t), spline.derivative()(t)
    pos = tip_values(disc, q, alpha)
    vel = tip_velocity(disc, q, qdot, alpha)
    theta_rate = np.asarray(disc.tip @ qdot.T)
    cols = {
        "tau": t,
        "theta_tip": pos["theta_tip"],
        "eta_tip": pos["eta_tip"],
        "X_tip": pos["X_tip"],
        "Z_tip": pos["Z_tip"],
        "theta_tip_rate": theta_rate,
        "eta_tip_rate": vel["eta_tip"],
        "X_tip_rate": vel["X_tip"],
        "Z_tip_rate": vel["Z_tip"],
    }
    return [{k: float(cols[k][i]) for k in TIP_COLUMNS} for i in range(t.size)]


#: The cost check of a long integration (see :func:`_cost_check`): after
#: ``PROJECT_AFTER`` s of CPU time in the integration, the CPU time to reach
#: ``--t-max`` is projected from the progress so far; above ``CPU_LIMIT`` s
#: the run is refused (exit 2) unless ``--allow-large``.  CPU time, not wall
#: time, so that a busy machine does not change the verdict.
PROJECT_AFTER = 10.0
CPU_LIMIT = 900.0


def _cost_check(v: float, t_max: float, allow: bool):
    """A callback ``(tau, cpu_seconds)`` that refuses a run projected to take over ``CPU_LIMIT``.

    Why: at high flow the motion is fast and of large amplitude, and the
    error-controlled step follows it: at v = 20 (alpha = 0, paper's case,
    P3:16) the integrator takes about 900 steps per unit tau (about 160 per
    oscillation of period ~0.17, with a Jacobian at most steps and 5 % of the
    steps halved after a Newton failure) for about 4 CPU-s per unit tau, so the
    default ``--t-max 300`` means 20 CPU-minutes.  A coarser mesh does not
    help (P3:8 needs the same steps: the step follows the motion, not the
    mesh).  The check is made once, from a measurement, so that a run which
    finds its attractor early is never refused.
    """
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
    from fempipe.io import json_dumps
    from fempipe.model.operators import PipeModel

    common.refuse_hysteretic(args, "simulate")
    setup = common.setup_from_args(args)
    if len(setup.v) != 1:
        opt = "--U" if args.U is not None else "--v"
        raise CLIError(opt, f"simulate takes a single flow velocity, got {len(setup.v)}")
    if args.three_d:
        from fempipe.cli.simulate_space import run_3d

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
    refined = None
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
        if args.error_estimate:
            refined = _refined_attractor(model, att, q_s, flow, args, bar)

    result = _result(setup, traj, att, wall_time, args)
    if att is not None and not args.planar:
        from fempipe.analyses.space import three_dimensional_verdict

        result.update(three_dimensional_verdict(model, att, rtol=shoot_rtol * 1e-2))
    if refined is not None:
        from fempipe.studies.estimates import with_attractor_estimates

        result = with_attractor_estimates(result, refined, setup.pipe)

    output = reporting.Output(args.out) if args.out is not None else None
    if output is not None:
        _write_outputs(output, result, model, traj, att, args.output_dt)
    if args.json:
        print(json_dumps(result))
    else:
        _print_summary(result)
    if output is not None:
        output.report(args)
    return 0


def _result(setup: common.Setup, traj, att, wall_time: float, args: argparse.Namespace) -> dict:
    """The JSON of the run: the attractor (or the forced response), the steps, SI values."""
    from fempipe.analyses.limit_cycle import TIP_KEYS
    from fempipe.model.kinematics import tip_values

    params, disc, sigma, omega = setup.params, setup.disc, args.sigma, args.omega
    result = setup.to_dict()
    result["params"]["v"] = params.v
    if att is None:
        half = traj.t >= 0.5 * traj.t[-1]
        tc = tip_values(disc, traj.q[half], params.alpha)
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
    if setup.pipe is not None:
        ts = setup.pipe.time_scale
        result["period_s"] = result["period"] * ts if result.get("period") else None
        result["tip_m"] = {k: [x * setup.pipe.L for x in v] for k, v in result["tip"].items()}
    return result


def _refined_attractor(model, att, q_static, flow, args, bar):
    """:func:`fempipe.studies.estimates.refined_attractor` (module docstring), the
    progress bar running from 100 to 200 over this work."""
    from fempipe.studies.error_estimate import refine
    from fempipe.studies.estimates import refined_attractor

    fine = refine(model.disc)
    bar.set_postfix_str(f"refined {fine.name}")
    on_time = reporting.time_progress(bar, args.t_max)
    refined = refined_attractor(
        model,
        att,
        q_static,
        t_max=args.t_max,
        rtol=args.rtol,
        shoot_rtol=args.shoot_rtol,
        use_shooting=not args.no_shooting,
        mode=args.mode,
        amplitude=args.amplitude,
        flow=flow,
        fine=fine,
        callback=on_time,
    )
    if on_time.done < 100:
        bar.update(100 - on_time.done)
    return refined


def _display_states(att, traj, n_periods: int = 3):
    """(t, q, qdot) for the figures: the transient, then a few periods of the cycle.

    The cycle continues from its sample nearest the transient's last state
    (positions and velocities, velocities scaled by T / 2 pi): the shooting's
    phase condition moves the orbit's first sample along the orbit (by 0.006
    tau, 0.16 rad at the tip, at alpha = pi/2, v = 10), and appending the orbit
    from that sample put a jump into the time traces and the animation.
    """
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
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.io.trajectory import write_trajectory
    from fempipe.plotting.dynamics import (
        animate,
        plot_oscillating_shapes,
        plot_phase_portrait,
        plot_time_traces,
    )

    disc, p = model.disc, model.params
    title = f"α = {math.degrees(p.alpha):.4g}°, β = {p.beta:.4g}, γ = {p.gamma:.4g}, v = {p.v:.4g}"
    t, q, qd = _display_states(att, traj)
    # Phase portrait, shapes and animation on the attractor: the cycle if any,
    # else the second half of the computed motion.
    if att is not None and att.cycle is not None:
        ct, cq = att.cycle.orbit_t, att.cycle.orbit_q
    else:
        half = t >= 0.5 * t[-1]
        ct, cq = t[half], q[half]
    figs = []
    try:
        ax = plot_time_traces(disc, t, q, p.alpha, title=title)
        figs.append(("time_traces.png", ax.figure))
        ax = plot_phase_portrait(disc, q[t >= 0.5 * t[-1]], qd[t >= 0.5 * t[-1]], p.alpha)
        ax.set_title(title, fontsize="small")
        figs.append(("phase_portrait.png", ax.figure))
        ax = plot_oscillating_shapes(disc, cq, p.alpha, title=title)
        figs.append(("oscillating_shapes.png", ax.figure))
        for name, fig in figs:
            output.figure(name, fig, dpi=130)
    finally:
        for _, fig in figs:
            plt.close(fig)
    frames = np.linspace(0, len(ct) - 1, min(48, len(ct))).round().astype(int)
    gif = output.path("pipe.gif")
    animate(gif, disc, ct[frames], cq[frames], p.alpha, fps=16, title=title)
    output.record(gif)
    # At most 400 frames (every step of a long run would be thousands of files).
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
            period = estimates.pm(r["period"], r["period_error"], "{:.8g}")
        line += f", period {period}"
        if r.get("period_n"):
            line += f" (period-{r['period_n']})"
    print(line)
    errors = r.get("tip_error") if with_errors else None
    for k, (lo, hi) in r["tip"].items():
        if with_errors:
            e_lo, e_hi = errors[k] if errors else (None, None)
            lo_s, hi_s = estimates.pm(lo, e_lo, "{: .8f}"), estimates.pm(hi, e_hi, "{: .8f}")
            print(f"  {k:8s} min {lo_s}  max {hi_s}")
        else:
            print(f"  {k:8s} min {lo: .8f}  max {hi: .8f}")
    if r.get("floquet_multipliers"):
        mus = ", ".join(f"{abs(complex(a, b)):.4g}" for a, b in r["floquet_multipliers"])
        print(f"  |Floquet multipliers| {mus}")
    if r.get("out_of_plane_floquet_multipliers"):
        mus = ", ".join(
            f"{abs(complex(a, b)):.4g}" for a, b in r["out_of_plane_floquet_multipliers"]
        )
        print(f"  |out-of-plane Floquet multipliers| {mus}")
    if "stable_3d" in r:
        verdict = {True: "stable", False: "unstable", None: "undecided"}[r["stable_3d"]]
        print(f"  in three dimensions: {verdict}")
        if r.get("out_of_plane_symmetry_defect") is not None:
            print(f"  |neutral multiplier - 1| {r['out_of_plane_symmetry_defect']:.2g}")
        if r.get("stable_3d_note"):
            print(f"  note: {r['stable_3d_note']}")
    print(f"  steps {r['steps']}, rejected {r['rejected_steps']}, wall time {r['wall_time']:.2f} s")
    if with_errors:
        estimates.print_footer(
            r["error_estimate"], where=f" (attractor there: {r['attractor_refined']})"
        )

"""Error estimates of an attractor: found again on the refined discretization.

A limit cycle is shot from the coarse cycle transferred to the refined space, an equilibrium
solved by Newton from the coarse one, a pulsating flow integrated again; the period and tip
extrema get estimates if both attractors are of the same kind.  docs/cli/options.md,
"Error estimates".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fempipe.analyses.dynamics import PulsatingFlow, Trajectory, make_initial_state, simulate
from fempipe.analyses.limit_cycle import TIP_KEYS, ShootingError, find_attractor, shoot
from fempipe.analyses.stability import linearly_stable
from fempipe.analyses.statics import solve_static
from fempipe.core.errors import SolverError
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.kinematics import compute_tip
from fempipe.model.plane.operators import PipeModel
from fempipe.model.projection import project
from fempipe.solvers.radau import IntegrationError
from fempipe.studies.error_estimate import ERROR, REFINED, describe, estimate, refine

from .shape import beside, header, pair

__all__ = ["AttractorSummary", "estimate_attractor_errors", "refine_cycle"]


@dataclass(frozen=True)
class AttractorSummary:
    """What is compared of an attractor: its kind, period and tip extrema.

    ``kind`` is "equilibrium", "periodic", "non-periodic", "forced", "unstable equilibrium"
    or "unstable periodic"; ``label`` adds the period-n of a periodic attractor (attractors
    compare only if their labels are equal); ``tip`` is ``{"eta_tip": [min, max], ...}``.
    """

    kind: str
    label: str
    period: float | None = None
    tip: dict | None = None

    @classmethod
    def of(cls, kind: str, period=None, period_n=None, tip=None) -> AttractorSummary:
        label = f"periodic (period-{period_n})" if kind == "periodic" and period_n else kind
        return cls(kind, label, period, tip)


def estimate_attractor_errors(
    result: dict,
    model: PipeModel,
    computed,
    *,
    q_static,
    t_max: float,
    rtol: float,
    shoot_rtol: float,
    use_shooting: bool = True,
    mode: int = 1,
    amplitude: float = 0.01,
    pipe=None,
    fine=None,
    callback: Callable[[float], None] | None = None,
) -> dict:
    """``result`` with the estimates beside ``period`` and ``tip`` (and ``period_s``, ``tip_m``).

    Adds ``period_error``, ``period_refined``, ``tip_error``, ``tip_refined`` (the shape of
    ``tip``) and ``attractor_refined``; attractors of different kinds give None and a note.
    A non-periodic attractor is not refined.

    Parameters
    ----------
    result : dict
        The attractor's dict (``period``, ``tip``; with an SI pipe ``period_s``, ``tip_m``).
    model : PipeModel
    computed : Attractor or Trajectory
        :func:`~fempipe.analyses.limit_cycle.find_attractor`'s result, or a pulsating flow's
        trajectory (integrated again from the refined static state).
    q_static : ndarray
        The coarse static state (the start of a pulsating flow's run).
    t_max, rtol, shoot_rtol, use_shooting, mode, amplitude
        As :func:`~fempipe.analyses.limit_cycle.find_attractor`, :func:`make_initial_state`.
    pipe, fine, callback : PipeSI, FiniteElement or Modal, callable, optional
        The SI pipe; ``refine(model.disc)`` if built; ``callback(tau)`` as the runs advance.
    """
    forced = isinstance(computed, Trajectory)
    att = None if forced else computed
    disc, params = model.disc, model.params
    fine = refine(disc) if fine is None else fine
    fine_model = PipeModel(fine, params)
    notes: list[str] = []
    if forced:
        floor, what = rtol, f"--rtol {rtol:g}"
        coarse = AttractorSummary("forced", "forced", None, result["tip"])
    elif att.kind == "equilibrium":
        floor, what = 1e-10, "Newton's tolerance 1e-10"
        coarse = AttractorSummary.of("equilibrium", tip=att.tip)
    else:
        floor, what = shoot_rtol, f"--shoot-rtol {shoot_rtol:g}"
        coarse = AttractorSummary.of(att.kind, att.period, att.period_n, att.tip)
    info = describe(disc, fine, floor=f"{what} max(1, |Q|)", params=params)
    refined = None
    try:
        if forced:
            flow = PulsatingFlow(**computed.flow)
            q_s = solve_static(fine_model, project(disc, q_static, fine)).q
            q0, p0 = make_initial_state(fine_model, mode, amplitude, q_static=q_s)
            tr = simulate(fine_model, q0, p0, t_max, rtol=rtol, flow=flow, callback=callback)
            tc = compute_tip(fine, tr.q[tr.t >= 0.5 * tr.t[-1]], params.alpha)
            tip = {k: [float(tc[k].min()), float(tc[k].max())] for k in TIP_KEYS}
            refined = AttractorSummary.of("forced", tip=tip)
        elif att.kind == "equilibrium":
            q = solve_static(fine_model, project(disc, att.q, fine)).q
            if linearly_stable(fine_model, q) is True:
                tv = compute_tip(fine, q, params.alpha)
                tip = {k: [float(tv[k])] * 2 for k in TIP_KEYS}
                refined = AttractorSummary.of("equilibrium", tip=tip)
            else:
                refined = AttractorSummary.of("unstable equilibrium")
        elif att.kind == "non-periodic":
            notes.append("a non-periodic attractor has no error estimate; not refined")
        else:
            options = {"rtol": rtol, "shoot_rtol": shoot_rtol, "use_shooting": use_shooting}
            refined, more = refine_cycle(
                model, att, fine_model, t_max=t_max, callback=callback, **options
            )
            notes.extend(more)
    except SolverError as exc:
        notes.append(f"the refined computation on {fine.name} failed ({exc}); no estimates")
        refined = None
    return _attach(result, info, notes, coarse, refined, floor, pipe)


def refine_cycle(
    model: PipeModel,
    attractor,
    fine_model: PipeModel,
    *,
    t_max: float,
    rtol: float,
    shoot_rtol: float,
    use_shooting: bool = True,
    callback: Callable[[float], None] | None = None,
) -> tuple[AttractorSummary, list[str]]:
    """The refined limit cycle: shot from the coarse cycle, else found by integration.

    Returns its summary ("unstable periodic" if the shot cycle is unstable) and a note if
    the shooting failed.
    """
    disc, att, summary = model.disc, attractor, AttractorSummary.of
    fine = fine_model.disc
    c = att.cycle
    q0 = project(disc, att.q if c is None else c.q0, fine)
    p0 = project(disc, att.qdot if c is None else c.qdot0, fine)
    notes = []
    if c is not None:
        try:
            cyc = shoot(PipeDynamics(fine_model), q0, p0, c.period, rtol=shoot_rtol)
        except (ShootingError, IntegrationError) as exc:
            notes.append(
                f"shooting on {fine.name} from the coarse cycle failed ({exc}); integrated"
            )
        else:
            if not cyc.stable:
                return summary("unstable periodic"), notes
            return summary("periodic", cyc.period, att.period_n, cyc.tip), notes
    options = {"rtol": rtol, "shoot_rtol": shoot_rtol, "use_shooting": use_shooting}
    fa = find_attractor(fine_model, q0, p0, t_max=t_max, callback=callback, **options)
    return summary(fa.kind, fa.period, fa.period_n, fa.tip), notes


def _attach(result, info, notes, coarse, fine, floor, pipe) -> dict:
    """``result`` with the estimates of the attractor ``coarse`` against ``fine``."""
    same = fine is not None and fine.label == coarse.label
    if fine is not None and not same:
        notes.append(
            f"the attractors differ: {coarse.label} on {info.discretization}, "
            f"{fine.label} on {info.refined}; no error estimate"
        )

    def err(a, b):
        if a is None or b is None:
            return None
        return estimate(a, b, info.order, info.ratio, floor=floor * max(1.0, abs(a)))

    fine_tip, fine_period = (fine.tip, fine.period) if same else (None, None)
    tip_error = None
    if fine_tip is not None:
        tip_error = {
            k: [err(a, b) for a, b in zip(lo_hi, fine_tip[k], strict=True)]
            for k, lo_hi in result["tip"].items()
        }
    period_error = err(result.get("period"), fine_period)
    result = beside(result, "period", pair("period", period_error, fine_period))
    result = beside(result, "tip", {"tip" + ERROR: tip_error, "tip" + REFINED: fine_tip})
    result = beside(result, "attractor", {"attractor_refined": None if fine is None else fine.kind})
    if pipe is not None:
        L = pipe.L

        def scaled(d):
            return None if d is None else {k: [x * L for x in v] for k, v in d.items()}

        result = beside(
            result, "period_s", pair("period_s", period_error, fine_period, pipe.time_scale)
        )
        tip_m = {"tip_m" + ERROR: scaled(tip_error), "tip_m" + REFINED: scaled(fine_tip)}
        result = beside(result, "tip_m", tip_m)
    result["error_estimate"] = header(info, notes)
    return result

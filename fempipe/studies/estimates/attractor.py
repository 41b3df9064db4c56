"""Error estimates of an attractor: found again on the refined discretization.

A limit cycle is shot from the coarse cycle transferred to the refined space,
an equilibrium solved by Newton from the coarse one, a pulsating flow
integrated again; beside the period and the tip extrema ``Q_error`` and
``Q_refined`` are inserted, if both attractors are of the same kind
(``fempipe simulate --error-estimate``).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from fempipe.core.errors import SolverError
from fempipe.model.kinematics import tip_values
from fempipe.model.projection import project
from fempipe.studies.error_estimate import describe, estimate, refine

from .shape import ERROR, REFINED, Refined, beside, header

__all__ = [
    "AttractorSummary",
    "RefinedAttractor",
    "refined_attractor",
    "refined_cycle",
    "with_attractor_estimates",
]


@dataclass(frozen=True)
class AttractorSummary:
    """What is compared of an attractor: its kind, period and tip extrema.

    Attributes
    ----------
    kind : str
        ``"equilibrium"``, ``"periodic"``, ``"non-periodic"``, ``"forced"``,
        ``"unstable equilibrium"``, ``"unstable periodic"``.
    label : str
        The kind with the period-n of a periodic attractor
        (``"periodic (period-2)"``): attractors compare only if equal.
    period : float or None
    tip : dict or None
        ``{"eta_tip": [min, max], ...}`` (the keys of
        :data:`fempipe.analyses.limit_cycle.TIP_KEYS`).
    """

    kind: str
    label: str
    period: float | None = None
    tip: dict | None = None

    @classmethod
    def of(cls, kind: str, period=None, period_n=None, tip=None) -> AttractorSummary:
        """The summary of an attractor of ``kind`` (the label with ``period_n``)."""
        label = f"periodic (period-{period_n})" if kind == "periodic" and period_n else kind
        return cls(kind, label, period, tip)


@dataclass(frozen=True)
class RefinedAttractor(Refined):
    """:func:`refined_attractor`.

    Attributes
    ----------
    coarse : AttractorSummary or None
        The reported attractor (None for a pulsating flow: its tip extrema are
        the result's).
    refined : AttractorSummary or None
        The attractor on the refined discretization (None if there is nothing
        to compare).
    floor : float
        The relative solver tolerance of the values.
    """

    coarse: AttractorSummary | None = None
    refined: AttractorSummary | None = None
    floor: float = 0.0


def refined_attractor(
    model,
    attractor,
    q_static,
    *,
    t_max: float,
    rtol: float,
    shoot_rtol: float,
    use_shooting: bool = True,
    mode: int = 1,
    amplitude: float = 0.01,
    flow=None,
    fine=None,
    callback: Callable[[float], None] | None = None,
) -> RefinedAttractor:
    """The attractor found again on the refined discretization, without a new transient
    where it can.

    A limit cycle is shot from the coarse cycle transferred to the refined
    space (:func:`refined_cycle`), an equilibrium solved by Newton from the
    coarse one (and its linear stability checked); a pulsating flow is
    integrated again from the refined static state.  A non-periodic
    attractor is not refined (a note says so).

    Parameters
    ----------
    model : PipeModel
        The reported model.
    attractor : Attractor or None
        :func:`fempipe.analyses.limit_cycle.find_attractor`'s result; None for
        a pulsating flow.
    q_static : ndarray
        The coarse static state (the start of a pulsating flow's run).
    t_max, rtol, shoot_rtol, use_shooting : float, float, float, bool
        As for :func:`~fempipe.analyses.limit_cycle.find_attractor`.
    mode, amplitude : int, float
        The initial perturbation of a pulsating flow's run
        (:func:`fempipe.analyses.dynamics.make_initial_state`).
    flow : PulsatingFlow, optional
        The pulsating flow (with ``attractor`` None).
    fine : FiniteElement or Modal, optional
        ``refine(model.disc)`` if already built.
    callback : callable, optional
        ``callback(tau)`` as the refined integrations advance.

    Returns
    -------
    RefinedAttractor
        ``floor``: ``rtol`` for a pulsating flow, Newton's 1e-10 for an
        equilibrium, ``shoot_rtol`` for a cycle.
    """
    # Imported here: the CLI loads this module at start-up (--help); these load scipy.
    from fempipe.model.operators import PipeModel

    att = attractor
    disc, params = model.disc, model.params
    fine = refine(disc) if fine is None else fine
    fine_model = PipeModel(fine, params)
    notes: list[str] = []
    floor, what, coarse = _coarse_summary(att, rtol, shoot_rtol)
    info = describe(disc, fine, floor=f"{what} max(1, |Q|)", params=params)
    refined = None
    try:
        if att is None:
            refined = _refined_forced(
                model, fine_model, q_static, t_max, rtol, mode, amplitude, flow, callback
            )
        elif att.kind == "equilibrium":
            refined = _refined_equilibrium(model, fine_model, att.q)
        elif att.kind == "non-periodic":
            notes.append("a non-periodic attractor has no error estimate; not refined")
        else:
            refined, cycle_notes = refined_cycle(
                model,
                att,
                fine_model,
                t_max=t_max,
                rtol=rtol,
                shoot_rtol=shoot_rtol,
                use_shooting=use_shooting,
                callback=callback,
            )
            notes.extend(cycle_notes)
    except SolverError as exc:
        notes.append(f"the refined computation on {fine.name} failed ({exc}); no estimates")
        refined = None
    return RefinedAttractor(fine, info, tuple(notes), coarse, refined, floor)


def _coarse_summary(att, rtol: float, shoot_rtol: float) -> tuple:
    """``(floor, floor's text, coarse summary)`` of a reported attractor (None: a pulsating flow)."""
    summary = AttractorSummary.of
    if att is None:  # a pulsating flow: the whole integration again
        floor, what = rtol, f"--rtol {rtol:g}"
        coarse = None  # filled in by with_attractor_estimates from the result
    elif att.kind == "equilibrium":
        floor, what = 1e-10, "Newton's tolerance 1e-10"
        coarse = summary("equilibrium", tip=att.tip)
    else:
        floor, what = shoot_rtol, f"--shoot-rtol {shoot_rtol:g}"
        coarse = summary(att.kind, att.period, att.period_n, att.tip)
    return floor, what, coarse


def _refined_forced(
    model, fine_model, q_static, t_max, rtol, mode, amplitude, flow, callback
) -> AttractorSummary:
    """A pulsating flow integrated again from the refined static state: its tip extrema
    over the second half of the run."""
    # Imported here: the CLI loads this module at start-up (--help); these load scipy.
    from fempipe.analyses.dynamics import make_initial_state, simulate
    from fempipe.analyses.limit_cycle import TIP_KEYS
    from fempipe.analyses.statics import solve_static

    disc, fine, params = model.disc, fine_model.disc, model.params
    q_s = solve_static(fine_model, project(disc, q_static, fine)).q
    q0, p0 = make_initial_state(fine_model, mode, amplitude, q_static=q_s)
    tr = simulate(fine_model, q0, p0, t_max, rtol=rtol, flow=flow, callback=callback)
    tc = tip_values(fine, tr.q[tr.t >= 0.5 * tr.t[-1]], params.alpha)
    tip = {k: [float(tc[k].min()), float(tc[k].max())] for k in TIP_KEYS}
    return AttractorSummary.of("forced", tip=tip)


def _refined_equilibrium(model, fine_model, q_coarse) -> AttractorSummary:
    """The equilibrium solved by Newton on the refined discretization from the coarse
    one, with its tip values if it is linearly stable."""
    # Imported here: the CLI loads this module at start-up (--help); these load scipy.
    from fempipe.analyses.limit_cycle import TIP_KEYS
    from fempipe.analyses.stability import linearly_stable
    from fempipe.analyses.statics import solve_static

    disc, fine, params = model.disc, fine_model.disc, model.params
    q = solve_static(fine_model, project(disc, q_coarse, fine)).q
    if linearly_stable(fine_model, q) is True:
        tv = tip_values(fine, q, params.alpha)
        return AttractorSummary.of("equilibrium", tip={k: [float(tv[k])] * 2 for k in TIP_KEYS})
    return AttractorSummary.of("unstable equilibrium")


def refined_cycle(
    model,
    attractor,
    fine_model,
    *,
    t_max: float,
    rtol: float,
    shoot_rtol: float,
    use_shooting: bool = True,
    callback: Callable[[float], None] | None = None,
) -> tuple[AttractorSummary, list[str]]:
    """The refined limit cycle: shot from the coarse cycle, else found by integration.

    Parameters
    ----------
    model, fine_model : PipeModel
        The reported model and the refined one.
    attractor : Attractor
        The reported periodic attractor.
    t_max, rtol, shoot_rtol, use_shooting, callback
        As for :func:`refined_attractor` (the integration if the shooting fails).

    Returns
    -------
    summary : AttractorSummary
        ``"unstable periodic"`` if the shot cycle is unstable.
    notes : list of str
        A note if the shooting failed and the cycle was found by integration.
    """
    # Imported here: the CLI loads this module at start-up (--help); these load scipy.
    from fempipe.analyses.limit_cycle import ShootingError, find_attractor, shoot
    from fempipe.solvers.radau import IntegrationError

    disc, att, summary = model.disc, attractor, AttractorSummary.of
    fine = fine_model.disc
    c = att.cycle
    q0 = project(disc, att.q if c is None else c.q0, fine)
    p0 = project(disc, att.qdot if c is None else c.qdot0, fine)
    notes = []
    if c is not None:
        try:
            cyc = shoot(fine_model, q0, p0, c.period, rtol=shoot_rtol)
        except (ShootingError, IntegrationError) as exc:
            notes.append(
                f"shooting on {fine.name} from the coarse cycle failed ({exc}); integrated"
            )
        else:
            if not cyc.stable:
                return summary("unstable periodic"), notes
            return summary("periodic", cyc.period, att.period_n, cyc.tip), notes
    fa = find_attractor(
        fine_model,
        q0,
        p0,
        t_max=t_max,
        rtol=rtol,
        shoot_rtol=shoot_rtol,
        use_shooting=use_shooting,
        callback=callback,
    )
    return summary(fa.kind, fa.period, fa.period_n, fa.tip), notes


def with_attractor_estimates(result: dict, refined: RefinedAttractor, pipe=None) -> dict:
    """``result`` with the estimates beside ``period`` and ``tip`` (and ``period_s``, ``tip_m``).

    Adds ``period_error``, ``period_refined``, ``tip_error`` and
    ``tip_refined`` (``{"eta_tip": [error of min, error of max], ...}``, the
    shape of ``tip``) and ``attractor_refined``.  If the attractors differ in
    kind (periodic, period-n, equilibrium; a refined cycle that is unstable)
    there is no error number (None) and a note says so.

    Parameters
    ----------
    result : dict
        The attractor's dict (``"period"``, ``"tip"``, with an SI pipe
        ``"period_s"``, ``"tip_m"``).
    refined : RefinedAttractor
        :func:`refined_attractor` of the same attractor.
    pipe : PipeSI, optional

    Returns
    -------
    dict
        With the top-level ``"error_estimate"`` (:func:`header`).
    """
    info, floor, fine = refined.info, refined.floor, refined.refined
    notes = list(refined.notes)
    order = info.order
    coarse = refined.coarse
    if coarse is None:  # a pulsating flow
        coarse = AttractorSummary("forced", "forced", None, result["tip"])
    same = fine is not None and fine.label == coarse.label
    if fine is not None and not same:
        notes.append(
            f"the attractors differ: {coarse.label} on {info.discretization}, "
            f"{fine.label} on {info.refined}; no error estimate"
        )

    def err(a, b):
        if a is None or b is None:
            return None
        return estimate(a, b, order, info.ratio, floor=floor * max(1.0, abs(a)))

    fine_tip = fine.tip if same else None
    fine_period = fine.period if same else None
    tip_error = None
    if fine_tip is not None:
        tip_error = {
            k: [err(a, b) for a, b in zip(lo_hi, fine_tip[k], strict=True)]
            for k, lo_hi in result["tip"].items()
        }
    period_error = err(result.get("period"), fine_period)
    result = beside(
        result, "period", {"period" + ERROR: period_error, "period" + REFINED: fine_period}
    )
    result = beside(result, "tip", {"tip" + ERROR: tip_error, "tip" + REFINED: fine_tip})
    result = beside(result, "attractor", {"attractor_refined": None if fine is None else fine.kind})
    if pipe is not None:
        result = _with_si_attractor_estimates(
            result, pipe, period_error, fine_period, tip_error, fine_tip
        )
    result["error_estimate"] = header(info, notes)
    return result


def _with_si_attractor_estimates(result, pipe, period_error, fine_period, tip_error, fine_tip):
    """``period_s`` and ``tip_m`` with their estimates (the dimensionless ones scaled)."""
    ts, L = pipe.time_scale, pipe.L

    def scaled(d):
        return None if d is None else {k: [x * L for x in v] for k, v in d.items()}

    result = beside(
        result,
        "period_s",
        {
            "period_s" + ERROR: None if period_error is None else period_error * ts,
            "period_s" + REFINED: None if fine_period is None else fine_period * ts,
        },
    )
    return beside(
        result,
        "tip_m",
        {"tip_m" + ERROR: scaled(tip_error), "tip_m" + REFINED: scaled(fine_tip)},
    )

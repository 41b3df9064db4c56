"""The attractor reached from an initial state (:func:`find_attractor`).

Integration past the transient with a Poincare section of eta_tip, recognition of an
equilibrium or of a recurrence of the section, and the shooting from there.  The stages:
docs/theory/numerics.md, "Attractors and limit cycles".
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable

import numpy as np

from fempipe.analyses.statics import NewtonError, solve_static
from fempipe.core.parallel import single_blas_thread
from fempipe.core.rootfinding import brentq
from fempipe.model.dynamics_problem import PipeDynamics, refuse_hysteretic
from fempipe.model.kinematics import compute_tip
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import IntegrationError, Radau

from ..dynamics import Trajectory, make_initial_state
from ..stability import linearly_stable
from .results import Attractor, ShootingError, state_distance
from .shooting import shoot
from .tips import TIP_KEYS, TipTrace, eta_tip, tip_extrema

__all__ = ["MAX_WAITS", "find_attractor", "recurrence"]

log = logging.getLogger(__name__)

#: Returns within ``recurrence_tol`` that :func:`find_attractor` integrates past (fast
#: contraction, not yet within ``start_tol``) before it shoots anyway: from 2e-2, eight
#: returns contracting 2x reach 8e-5.
MAX_WAITS = 8

#: Steps whose tip samples the transient keeps (memory bound on long runs).
MAX_TRACE_STEPS = 20000


def _linearly_stable(model: PipeModel, q_static: np.ndarray) -> bool:
    """:func:`~fempipe.analyses.stability.linearly_stable`; no decision (None) never stops
    the search at an equilibrium."""
    return linearly_stable(model, q_static) is True


def find_attractor(
    model: PipeModel,
    q0: np.ndarray | None = None,
    qdot0: np.ndarray | None = None,
    *,
    t_max: float = 300.0,
    rtol: float = 1e-5,
    shoot_rtol: float = 1e-5,
    shoot_tol: float = 1e-6,
    use_shooting: bool = True,
    recurrence_tol: float = 2e-2,
    start_tol: float = 1e-3,
    converged_tol: float = 1e-6,
    equilibrium_radius: float = 1e-2,
    n_max: int = 8,
    record: bool = False,
    perturbation: float = 0.01,
    callback: Callable[[float], None] | None = None,
) -> Attractor:
    """Integrate past the transient and classify the attractor (docs/theory/numerics.md).

    Parameters
    ----------
    model : PipeModel
    q0, qdot0 : ndarray, optional
        Initial state; default the static state + ``perturbation`` rad (first sine mode).
    t_max, rtol : float
        Longest integration (tau; then non-periodic) and its tolerance.
    shoot_rtol, shoot_tol : float
        Integration and Newton tolerances of the shooting.
    use_shooting, converged_tol : bool, float
        Without shooting, a cycle is accepted when returns agree to ``converged_tol``.
    recurrence_tol, start_tol : float
        Returns this close (RMS) start the shooting; fast ones (2x) wait for ``start_tol``.
    equilibrium_radius : float
        RMS distance to a linearly stable static state, approached, that is the attractor.
    n_max : int
        Largest period-n looked for.
    record : bool
        Keep the transient in ``Attractor.trajectory``.
    callback : callable, optional
        Called with tau after every step.

    Returns
    -------
    Attractor

    Raises
    ------
    ValueError
        If the model has hysteretic damping.
    """
    refuse_hysteretic(model.params, "find_attractor")
    if not t_max > 0:
        raise ValueError(f"t_max must be > 0, got {t_max}")
    search = _AttractorSearch(
        model,
        t_max=t_max,
        rtol=rtol,
        shoot_rtol=shoot_rtol,
        shoot_tol=shoot_tol,
        use_shooting=use_shooting,
        recurrence_tol=recurrence_tol,
        start_tol=start_tol,
        converged_tol=converged_tol,
        equilibrium_radius=equilibrium_radius,
        n_max=n_max,
        record=record,
        callback=callback,
    )
    return search.run(q0, qdot0, perturbation)


def recurrence(sec_t: list, sec_x: list, n_max: int):
    """(n, d_n) for the smallest n whose return distance |x_k - x_{k-n}| (section times
    ``sec_t``, states ``sec_x``) is within 2x the smallest over n <= n_max; None at first."""
    k = len(sec_x) - 1
    d = []
    for nn in range(1, min(n_max, k) + 1):
        T = sec_t[k] - sec_t[k - nn]
        (qa, pa), (qb, pb) = sec_x[k], sec_x[k - nn]
        d.append(state_distance(qa - qb, pa - pb, T / (2 * math.pi * nn)))
    if not d:
        return None
    best = min(d)
    for nn, dn in enumerate(d, start=1):
        if dn <= 2.0 * best:
            return nn, dn
    return None  # pragma: no cover


class _AttractorSearch:
    """The state of one :func:`find_attractor` (its options): transient, section, shooting."""

    def __init__(self, model: PipeModel, **options) -> None:
        self.model = model
        self.disc, self.alpha, self.n = model.disc, model.params.alpha, model.n
        self.__dict__.update(options)
        counts = dict.fromkeys(("steps", "rejected_steps", "n_residual", "n_jacobian"), 0)
        self.stats = counts | {"wall_time": 0.0}

    # -- the start ---------------------------------------------------------
    def _static_start(self, q0, qdot0, perturbation: float):
        """The static state (q_s, or None) and its stability; the initial state and level."""
        model = self.model
        guess = None if q0 is None else np.asarray(q0, dtype=float)
        try:
            q_s = solve_static(model, guess).q
        except NewtonError:
            try:
                q_s = solve_static(model).q
            except NewtonError:
                q_s = None
        self.q_s = q_s
        self.stable = q_s is not None and _linearly_stable(model, q_s)
        if q0 is None:
            if q_s is None:
                raise ValueError("no initial state given and the static problem has no solution")
            q0, qdot0 = make_initial_state(model, 1, perturbation, q_static=q_s)
        qdot0 = np.zeros(self.n) if qdot0 is None else np.asarray(qdot0, dtype=float)
        self.level = eta_tip(self.disc, q_s if q_s is not None else np.asarray(q0))
        return q0, qdot0

    def run(self, q0, qdot0, perturbation: float) -> Attractor:
        """Integrate until the attractor is recognized or t_max is reached."""
        q0, qdot0 = self._static_start(q0, qdot0, perturbation)
        disc, q_s = self.disc, self.q_s
        self.stepper = stepper = Radau(PipeDynamics(self.model), q0, qdot0, 0.0, rtol=self.rtol)
        self.rec_t, self.rec_q, self.rec_p = [stepper.t], [stepper.q.copy()], [stepper.qdot.copy()]
        self.sec_t: list[float] = []
        self.sec_x: list[tuple[np.ndarray, np.ndarray]] = []
        self.sec_i: list[int] = []  # index into ``trace`` at each section point
        self.trace = TipTrace(self.model, per_step=4)  # tip coordinates on every step
        self.s_old = eta_tip(disc, stepper.q) - self.level
        self.next_eq_check = 0.5
        self.d_prev = (
            state_distance(np.asarray(q0) - q_s, qdot0, 0.05) if q_s is not None else math.inf
        )
        self.tried_tol = self.recurrence_tol
        self.last_dist: dict[int, float] = {}  # return distance of period-n when last seen
        self.waits = 0  # returns within recurrence_tol not shot from because they contract fast
        self.level_time = 0.0
        result = None
        with single_blas_thread():
            while stepper.t < self.t_max:
                self._step()
                result = self._equilibrium()
                if result is not None:
                    break
                result = self._section()
                if result is not None:
                    break
        if result is None:
            trace = self.trace
            tip = self._tip(trace[len(trace) // 2 :]) if len(trace) else None
            msg = f"no recurrence of the Poincare section within t_max = {self.t_max:g}"
            result = self._finish("non-periodic", tip=tip, msg=msg)
        return result

    def _step(self) -> None:
        """One step of the transient: recorded, reported, its tip sampled."""
        stepper = self.stepper
        try:
            stepper.step(self.t_max)
        except IntegrationError as exc:
            raise IntegrationError(
                f"{exc} (alpha = {self.alpha:.6g}, v = {self.model.params.v:.6g})", exc.t, exc.h
            ) from None
        if self.record:
            self.rec_t.append(stepper.t)
            self.rec_q.append(stepper.q.copy())
            self.rec_p.append(stepper.qdot.copy())
        if self.callback is not None:
            self.callback(stepper.t)
        self.trace.record(stepper)
        if len(self.trace) > MAX_TRACE_STEPS:  # keep memory bounded on long runs
            drop = len(self.trace) - MAX_TRACE_STEPS
            self.trace = self.trace[drop:]
            self.sec_i = [i - drop for i in self.sec_i]

    def _tip(self, trace: TipTrace) -> dict:
        return tip_extrema(self.model, trace, per_step=trace.per_step, fine=0)

    def _finish(
        self, kind, period=None, period_n=None, tip=None, cycle=None, q=None, p=None, msg=""
    ):
        """The Attractor, with the statistics of the transient added to ``stats``."""
        stepper, stats = self.stepper, self.stats
        st = stepper.stats
        stats.update({k: v + getattr(st, k) for k, v in stats.items()})
        traj = None
        if self.record:
            traj = Trajectory.recorded(self.rec_t, self.rec_q, self.rec_p, st, self.rtol)
        return Attractor(
            kind=kind,
            period=period,
            period_n=period_n,
            tip=tip,
            cycle=cycle,
            q=stepper.q.copy() if q is None else q,
            qdot=stepper.qdot.copy() if p is None else p,
            params=self.model.params,
            t_end=stepper.t,
            stats=stats,
            trajectory=traj,
            message=msg,
        )

    # -- equilibrium -------------------------------------------------------
    def _equilibrium(self) -> Attractor | None:
        """The equilibrium if near a linearly stable static state, not leaving it (each 0.5 tau)."""
        stepper, model = self.stepper, self.model
        if stepper.t < self.next_eq_check:
            return None
        self.next_eq_check = stepper.t + 0.5
        q_s = self.q_s
        if q_s is None or state_distance(stepper.q - q_s, stepper.qdot, 0.05) > 0.3:
            # Far from the known static state and almost at rest: maybe
            # another equilibrium (e.g. a buckled branch at alpha = pi).
            if np.sqrt(np.mean(stepper.qdot**2)) < 1e-3:
                try:
                    q_new = solve_static(model, stepper.q).q
                    if _linearly_stable(model, q_new):
                        self.q_s, self.stable, self.d_prev = q_new, True, math.inf
                        self.level = eta_tip(self.disc, q_new)
                except NewtonError:
                    pass
        q_s = self.q_s
        if q_s is not None and self.stable:
            d = state_distance(stepper.q - q_s, stepper.qdot, 0.05)
            if d < self.equilibrium_radius and d <= self.d_prev:
                tv = compute_tip(self.disc, q_s, self.alpha)
                tip = {k: [float(tv[k]), float(tv[k])] for k in TIP_KEYS}
                return self._finish("equilibrium", tip=tip, q=q_s.copy(), p=np.zeros(self.n))
            self.d_prev = d if d < self.equilibrium_radius else math.inf
        return None

    # -- Poincare section --------------------------------------------------
    def _section(self) -> Attractor | None:
        """Upward crossing of eta_tip through the level: a section point, and the
        periodic attractor if the section recurs."""
        stepper, disc = self.stepper, self.disc
        # The static value is crossed by a Hopf cycle near onset; a cycle
        # that has drifted away from it is sectioned at its own mean
        # instead, once no crossing has happened for 3 tau (~10 periods).
        last_cross = max(self.sec_t[-1] if self.sec_t else 0.0, self.level_time)
        if stepper.t - last_cross > 3.0 and len(self.trace):
            recent = self.trace[-400:]
            keep = recent.times() >= stepper.t - 1.0
            self.level = float(np.mean(recent.values("eta_tip")[keep]))
            self.level_time = stepper.t
            self.sec_t, self.sec_x, self.sec_i = [], [], []
            self.s_old = eta_tip(disc, stepper.q) - self.level
            log.debug("section level moved to the mean eta_tip %.6g", self.level)
        s_new = eta_tip(disc, stepper.q) - self.level
        result = None
        if self.s_old < 0.0 <= s_new:
            f = lambda tt, c=self.level: eta_tip(disc, stepper.dense(tt)[0]) - c  # noqa: E731
            t_c = stepper.t if s_new == 0 else brentq(f, stepper.t_old, stepper.t, xtol=1e-13)
            self.sec_t.append(t_c)
            self.sec_x.append(stepper.dense(t_c))
            self.sec_i.append(len(self.trace))
            found = recurrence(self.sec_t, self.sec_x, self.n_max)
            if found is not None:
                result = self._recurred(*found)
        self.s_old = s_new
        return result

    def _recurred(self, nn: int, dist: float) -> Attractor | None:
        """The section recurs after nn points at distance dist: shoot, or wait, or accept."""
        T_guess = self.sec_t[-1] - self.sec_t[-1 - nn]
        qk, pk = self.sec_x[-1]
        prev = self.last_dist.get(nn)
        self.last_dist[nn] = dist
        # Integrate on while the returns contract fast and are not
        # yet within start_tol (the first return has no rate yet).
        fast = prev is None or dist < 0.5 * prev
        # At most MAX_WAITS such returns (a period-n that keeps
        # changing its n never shows a rate: shoot as before then).
        wait = fast and dist > self.start_tol and self.waits < MAX_WAITS
        if self.use_shooting and dist < self.tried_tol and wait:
            self.waits += 1
        if self.use_shooting and dist < self.tried_tol and not wait:
            return self._shoot(nn, dist, T_guess, qk, pk)
        if not self.use_shooting and dist < self.converged_tol:
            tip = self._tip(self.trace[max(self.sec_i[-1 - nn] - 1, 0) :])
            return self._finish("periodic", period=T_guess, period_n=nn, tip=tip)
        return None

    def _shoot(self, nn: int, dist: float, T_guess: float, qk, pk) -> Attractor | None:
        """The periodic attractor if the shooting from (qk, pk) finds a stable cycle."""
        stats = self.stats
        try:
            cyc = shoot(
                PipeDynamics(self.model),
                qk,
                pk,
                T_guess,
                level=self.level,
                rtol=self.shoot_rtol,
                tol=self.shoot_tol,
            )
        except (ShootingError, IntegrationError) as exc:
            log.info("shooting failed, integrating on: %s", exc)
            self.tried_tol = dist / 10.0
            return None
        stats["steps"] += cyc.total_steps
        stats["rejected_steps"] += cyc.rejected_steps
        stats["wall_time"] += cyc.wall_time
        if cyc.stable:
            return self._finish(
                "periodic",
                period=cyc.period,
                period_n=nn,
                tip=cyc.tip,
                cycle=cyc,
                q=cyc.q0.copy(),
                p=cyc.qdot0.copy(),
            )
        self.tried_tol = dist / 10.0
        return None

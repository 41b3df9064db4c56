"""The periodic-orbit problem by single shooting, as a continuation problem.

In u = (x0, T, v): phi_T(x0; v) - x0 = 0 and <f_ref, x0 - x_ref> = 0 (bordered chord matrix
``[[M - I, F(phi_T), d phi_T / dv], [f_ref, 0, 0], [row]]``); :class:`CycleCorrector` is the
branches' chord Newton with a trust region.

Derivation: docs/theory/numerics.md, "Branches of periodic orbits".
"""

from __future__ import annotations

import logging
import math
import time
from dataclasses import dataclass

import numpy as np

from fempipe.analyses.limit_cycle import state_distance
from fempipe.analyses.limit_cycle.tips import CollocationOrbit, tip_extrema
from fempipe.model.dynamics_problem import PipeDynamics, acceleration
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.continuation import BorderedSolution, CorrectorError
from fempipe.solvers.radau import IntegrationError, Radau

from .results import CyclePoint, HopfPoint, nontrivial_multipliers

__all__ = [
    "MONODROMY_AT_ORBIT",
    "MONODROMY_NEAR",
    "CycleCorrector",
    "Flow",
    "OrbitProblem",
    "period_flow",
]

log = logging.getLogger(__name__)

#: On the continuation's own steps the monodromy is taken within this fraction of the
#: orbit's amplitude; their multipliers (stability, special points) carry an error of
#: about this size (docs/theory/numerics.md).
MONODROMY_NEAR = 1e-3
#: ... and within this fraction at the requested v, whose multipliers are reported.
MONODROMY_AT_ORBIT = 1e-6


@dataclass
class Flow:
    """phi_T(x): end state, its derivative, monodromy and d phi_T / dv, steps, step record."""

    xT: np.ndarray
    fT: np.ndarray
    monodromy: np.ndarray | None
    dv: np.ndarray | None  # d phi_T(x) / dv at fixed x and T
    steps: int
    rejected: int
    record: list


def period_flow(model: PipeModel, x: np.ndarray, T: float, rtol: float, sensitivity: bool) -> Flow:
    """phi_T(x) with the step data (for the tip extrema) and, if asked, the monodromy."""
    n = model.n
    st = Radau(
        PipeDynamics(model),
        x[:n],
        x[n:],
        0.0,
        rtol=rtol,
        sensitivity=sensitivity,
        velocity_sensitivity=True,
    )
    record = []
    for _ in st.steps(T):
        t_old, h, q_old, p_old, Q, P, _acc = st.last
        record.append((t_old, h, q_old, Q))
    return Flow(
        xT=np.r_[st.q, st.qdot],
        fT=np.r_[st.qdot, st.qddot],
        monodromy=st.sensitivity_matrix if sensitivity else None,
        dv=st.velocity_sensitivity if sensitivity else None,
        steps=st.stats.steps,
        rejected=st.stats.rejected_steps,
        record=record,
    )


class OrbitProblem:
    """The periodic-orbit problem at the phase section through ``u_ref`` (orthogonal to the
    flow there in the metric ``S``), a ``ContinuationProblem`` in y = u = (x0, T, v)."""

    def __init__(self, corrector: CycleCorrector, u_ref: np.ndarray, rtol: float) -> None:
        n2 = 2 * corrector.n
        self.n2, self.S, self.at, self.rtol = n2, corrector.S, corrector.at, rtol
        self.x_ref = x_ref = u_ref[:n2]
        m_ref = corrector.at(u_ref[-1])
        f_ref = np.r_[x_ref[n2 // 2 :], acceleration(m_ref, x_ref[: n2 // 2], x_ref[n2 // 2 :])]
        # Orthogonal in the metric: on a near-Hopf orbit, an ellipse in the
        # plane of Re z, Im z, a section through a principal axis stays there.
        f_ref = self.S[:n2] ** 2 * f_ref
        self.f_ref = f_ref / np.linalg.norm(f_ref)

    def flow(self, u: np.ndarray, sensitivity: bool) -> Flow:
        """phi_T(x0; v) at u (raises IntegrationError)."""
        n2 = self.n2
        return period_flow(self.at(u[-1]), u[:n2], u[n2], self.rtol, sensitivity=sensitivity)

    def phase(self, x: np.ndarray) -> float:
        """The phase condition <f_ref, x - x_ref>."""
        return float(self.f_ref @ (x - self.x_ref))

    # -- ContinuationProblem ----------------------------------------------------
    def residual(self, u: np.ndarray) -> np.ndarray:
        """(phi_T(x0) - x0, phase) at u."""
        fl = self.flow(u, sensitivity=False)
        return np.r_[fl.xT - u[: self.n2], self.phase(u[: self.n2])]

    def derivatives(self, u: np.ndarray) -> Flow:
        """The flow with its monodromy and d phi_T / dv."""
        return self.flow(u, sensitivity=True)

    def solve_bordered(
        self, lin: Flow, row: np.ndarray | None, rhs: np.ndarray, *, determinant: bool = False
    ) -> BorderedSolution:
        """The chord matrix of the flow ``lin`` (at fixed v where ``row`` is None), solved."""
        n2 = self.n2
        fixed_v = row is None
        k = n2 + (1 if fixed_v else 2)
        J = np.zeros((k, k))
        J[:n2, :n2] = lin.monodromy - np.eye(n2)
        J[:n2, n2] = lin.fT
        J[n2, :n2] = self.f_ref
        if not fixed_v:
            J[:n2, -1] = lin.dv
            J[-1] = row
        try:
            z = np.linalg.solve(J, rhs)
        except np.linalg.LinAlgError:
            raise CorrectorError("singular Jacobian") from None
        if determinant:
            sign, logdet = np.linalg.slogdet(J)
            return BorderedSolution(z, int(sign), float(logdet))
        return BorderedSolution(z)

    def inner(self, a: np.ndarray, b: np.ndarray) -> float:
        """(S a) . (S b), the metric of docs/theory/numerics.md, "Branches of periodic orbits"."""
        return float((self.S * a) @ (self.S * b))

    def dual(self, t: np.ndarray) -> np.ndarray:
        """The row S^2 t of <t, .>."""
        return self.S * (self.S * t)


class CycleCorrector:
    """Newton correctors of one branch from the Hopf point ``hopf`` (its period scales the
    metric); ``rtol`` of the integration, ``tol``/``xtol`` of Newton on the residual and the
    correction, ``max_iter`` iterations."""

    def __init__(
        self, model: PipeModel, hopf: HopfPoint, rtol: float, tol: float, xtol: float, max_iter: int
    ):
        self.model, self.hopf, self.n = model, hopf, model.n
        self.rtol, self.tol, self.xtol, self.max_iter = rtol, tol, xtol, max_iter
        self.T_H = 2 * math.pi / hopf.omega
        n = self.n
        s = self.T_H / (2 * math.pi)
        # u -> z = S u: the metric of the arclength (docs/theory/numerics.md).
        self.S = np.r_[
            np.full(n, 1 / math.sqrt(n)), np.full(n, s / math.sqrt(n)), 1 / self.T_H, 1.0
        ]
        self.integrations = self.rejected_integration_steps = 0

    def at(self, v: float) -> PipeModel:
        """The model at flow velocity v."""
        return self.model.with_params(self.model.params.with_flow(float(v)))

    def residual_norm(self, r: np.ndarray, T: float) -> float:
        """RMS of r = (q part, q' part), q' scaled by T / 2 pi (:func:`state_distance`)."""
        return state_distance(r[: self.n], r[self.n :], T / (2 * math.pi))

    def tip_extrema(self, v: float, record: list) -> dict:
        """[min, max] of the tip over the period in ``record`` (its Radau steps), refined."""
        return tip_extrema(self.at(v), CollocationOrbit(record), refine="bounded")

    def rtol_after(self, previous: CyclePoint | None) -> float:
        """``rtol`` times the distance of the previous orbit's nearest non-trivial multiplier
        from 1 (at least a tenth): an error e of the flow moves the orbit by e / |1 - mu|."""
        if previous is None:
            return 0.1 * self.rtol
        mu = nontrivial_multipliers(previous.multipliers)
        d = float(np.min(np.abs(1.0 - mu))) if mu.size else 1.0
        return self.rtol * min(1.0, max(0.1, d))

    def correct(
        self,
        u_pred: np.ndarray,
        tangent: np.ndarray | None,
        u_ref: np.ndarray | None = None,
        rtol: float | None = None,
        monodromy_at: float = MONODROMY_NEAR,
        seed: Flow | None = None,
    ) -> tuple:
        """Newton from ``u_pred``: pseudo-arclength along ``tangent``, or at fixed v if None.

        The monodromy is taken within ``monodromy_at`` times the orbit's amplitude; ``seed`` (a flow
        with the sensitivity at a nearby orbit) gives the first chord matrix; the phase section
        passes through ``u_ref`` (None: the predictor).  Returns (u, flow, monodromy, iterations,
        rejected steps).
        """
        n2 = 2 * self.n
        rtol = self.rtol if rtol is None else rtol
        u = u_pred.copy()
        u_ref = u_pred if u_ref is None else u_ref
        section = OrbitProblem(self, u_ref, rtol)
        fixed_v = tangent is None
        row = None if fixed_v else tangent * self.S
        lin = None  # the flow whose monodromy is in the chord matrix
        res_prev = res_exact = math.inf
        stale, rejected = False, 0
        monodromy = u_mono = None

        if seed is not None and seed.monodromy is not None and seed.dv is not None:
            lin, monodromy = seed, seed.monodromy
        # Where the multipliers are wanted at the orbit, the iterate predicted
        # to be the last (the residual and the correction times the chord's
        # contraction rate within tol and xtol) gets the sensitivity, once: it
        # is then within about xtol of the converged orbit and no extra flow
        # is needed after convergence.
        at_orbit = monodromy_at < MONODROMY_NEAR
        last_next = asked = False
        for it in range(1, self.max_iter + 1):
            T = u[n2]
            need = lin is None or stale or last_next
            last_next = False
            fl, r, g, c = self._evaluate(section, u, u_pred, tangent, need)
            rejected += fl.rejected
            res = self.residual_norm(r, T)
            log.debug("corrector it %d need %s res %.3e g %.2e c %.2e", it, need, res, g, c)
            if need:
                if res > 0.5 * res_exact:
                    # An exact Newton step that did not halve the residual: the
                    # integration noise, not the linearization, limits it.
                    raise CorrectorError(f"Newton stalled at the residual {res:.1e}")
                res_exact = res
                monodromy = fl.monodromy
                u_mono = u.copy()
                lin = fl
            stale = not need and res > res_prev / 4
            rate = min(1.0, res / res_prev) if math.isfinite(res_prev) else 0.1
            res_prev = res
            rhs = -np.r_[r, g] if fixed_v else -np.r_[r, g, c]
            du = section.solve_bordered(lin, row, rhs).z
            if not np.all(np.isfinite(du)):
                raise CorrectorError("non-finite Newton step")
            # Converged when the residual is small and so is the correction it
            # asks for: the error of this iterate (the residual alone hides it
            # where a multiplier is near 1, e.g. close to the Hopf point).
            dv = 0.0 if fixed_v else abs(du[-1])  # state part (as the residual), T relative, v
            correction = max(self.residual_norm(du[:n2], T), abs(du[n2]) / T, dv)
            if (
                res < self.tol
                and abs(g) < self.tol
                and abs(c) < self.tol
                and correction < self.xtol
            ):
                fl, monodromy, it, rejected = self._at_orbit(
                    section, u, fl, u_mono, monodromy, monodromy_at, it, rejected
                )
                return u, fl, monodromy, it, rejected
            if at_orbit and not need and not asked:
                last_next = rate * res < self.tol and rate * correction < self.xtol
                asked = last_next
            self._damped_update(u, du, fixed_v)
        raise CorrectorError(f"no convergence in {self.max_iter} Newton iterations")

    def _evaluate(self, section, u, u_pred, tangent, need: bool) -> tuple:
        """(flow, r, g, c) at u: r = phi_T(x0) - x0, phase g, arclength c; one integration."""
        n2 = 2 * self.n
        x = u[:n2]
        try:
            fl = section.flow(u, sensitivity=need)
        except IntegrationError as exc:
            raise CorrectorError(str(exc)) from None
        self.integrations += 1
        c = 0.0 if tangent is None else float(tangent @ (self.S * (u - u_pred)))
        return fl, fl.xT - x, section.phase(x), c

    def _damped_update(self, u: np.ndarray, du: np.ndarray, fixed_v: bool) -> None:
        """u += lam du in place, the step limited to 0.3 in the metric (the trust region)."""
        n2 = 2 * self.n
        size = float(np.linalg.norm(self.S[:n2] * du[:n2]) * math.sqrt(2))
        lam = min(1.0, 0.3 / size) if size > 0 else 1.0
        u[: n2 + 1 if fixed_v else u.size] += lam * du
        if not u[n2] > 0:
            raise CorrectorError("the period became negative")

    def _at_orbit(self, section, u, fl, u_mono, monodromy, monodromy_at, it, rejected):
        """(flow, monodromy, iterations, rejected) of a converged orbit, the monodromy taken
        again at it if the chord's was farther than ``monodromy_at`` times its amplitude."""
        n2 = 2 * self.n
        T = u[n2]
        amplitude = self.residual_norm(fl.fT * T / (2 * math.pi), T)
        if u_mono is None or self.residual_norm(u[:n2] - u_mono[:n2], T) > monodromy_at * amplitude:
            # The multipliers of a matrix taken this far from the orbit (small orbits
            # near the Hopf point) would be off by as much: once more at the orbit.
            fl = section.flow(u, sensitivity=True)
            self.integrations += 1
            rejected += fl.rejected
            monodromy = fl.monodromy
            it += 1
        return fl, monodromy, it, rejected

    def point(self, u, fl, monodromy, it, rejected, source, t0) -> CyclePoint:
        """The converged orbit u as a :class:`CyclePoint` (multipliers, tip extrema)."""
        n = self.n
        mu = np.linalg.eigvals(monodromy)
        mu = mu[np.argsort(-np.abs(mu))]
        return CyclePoint(
            v=float(u[-1]),
            period=float(u[2 * n]),
            q0=u[:n].copy(),
            qdot0=u[n : 2 * n].copy(),
            tip=self.tip_extrema(u[-1], fl.record),
            multipliers=mu,
            stable=bool(np.all(np.abs(nontrivial_multipliers(mu)) < 1.0)),
            source=source,
            iterations=it,
            residual=self.residual_norm(fl.xT - u[: 2 * n], u[2 * n]),
            steps=fl.steps,
            rejected_steps=rejected,
            wall_time=time.perf_counter() - t0,
        )

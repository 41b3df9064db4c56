"""Out-of-plane perturbations of a *moving* planar state: the linear problem, one operator per term.

Along a planar limit cycle the out-of-plane perturbations obey
M psi_ddot + C(tau) psi_dot + K(tau) psi = 0, whose monodromy holds the cycle's out-of-plane
Floquet multipliers: the 3-D model in another parametrization (one unknown psi, no gauge),
so the two computations are independent.  :class:`OutOfPlaneMotion` holds the terms (at rest
the static model's matrices); :class:`OutOfPlaneVariation` is the integrator's problem of the
planar motion with its variation.

Derivation: docs/theory/out_of_plane.md, "About a moving planar state".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.out_of_plane.model import OutOfPlaneOperators
from fempipe.model.plane.operators import PipeModel

__all__ = ["OutOfPlaneMotion", "OutOfPlaneVariation"]


@dataclass(frozen=True)
class _Base:
    """The planar motion at the quadrature points: the static model's state at tau and the rates."""

    state: object
    rate: np.ndarray  # theta_dot
    drate: np.ndarray  # theta_dot'
    accel: np.ndarray  # theta_ddot


class OutOfPlaneMotion:
    """K(tau), C(tau), M of out-of-plane perturbations about a moving planar state (no springs)."""

    def __init__(self, model: PipeModel) -> None:
        if model.params.springs:
            raise ValueError(
                "out-of-plane perturbations of a moving state: springs = () is required "
                f"(got springs = {model.params.springs!r})"
            )
        self.static = OutOfPlaneOperators(model)
        self.model, self.params = model, model.params
        self.quad, self.w, self.x = self.static.quad, self.static.w, self.static.x

    def base(self, q, qdot, qddot) -> _Base:
        """The planar motion (q, q', q'') at the quadrature points."""
        f = self.static.fixed()
        return _Base(
            state=self.static.state(q),
            rate=f["Phi"] @ qdot,
            drate=f["dPhi"] @ qdot,
            accel=f["Phi"] @ qddot,
        )

    def base_force(self, b: _Base, v_dot: float = 0.0) -> np.ndarray:
        """G_0, the force field of the planar motion, shape (n_q, 2): the 3-D model's
        :meth:`~fempipe.model.three_d.model.PipeModel3D.force_field` at the planar state.
        """
        p, quad, st = self.params, self.quad, b.state
        t = np.stack([np.cos(st.theta), np.sin(st.theta)], axis=1)
        n = np.stack([-t[:, 1], t[:, 0]], axis=1)
        t_dot = b.rate[:, None] * n
        t_ddot = b.accel[:, None] * n - (b.rate**2)[:, None] * t
        # the integral terms share their operators: C^R (C (t_ddot + sigma t_dot) + c t_dot)
        inner = t_ddot + p.external_damping * t_dot if p.external_damping else t_ddot
        flow = (2.0 * p.v * math.sqrt(p.beta)) * t_dot
        if v_dot:
            flow = flow + (v_dot * math.sqrt(p.beta)) * t
        G = quad.from_tip(quad.cumulative(inner) + flow)
        G += (p.v * p.v) * np.array([math.cos(st.theta_tip), math.sin(st.theta_tip)])
        g = np.array([math.cos(p.alpha), -math.sin(p.alpha)])
        G -= p.gamma * (1.0 - self.x + p.end_mass)[:, None] * g
        if p.end_mass:
            G += p.end_mass * quad.integrate(t_ddot)
        return G

    def axial_stiffness(self, b: _Base, v_dot: float = 0.0) -> np.ndarray:
        """``-\\int (t_p . G_0) phi_i phi_j``: the planar motion's tangential force."""
        G = self.base_force(b, v_dot)
        theta = b.state.theta
        return -self.static.weighted_gram(np.cos(theta) * G[:, 0] + np.sin(theta) * G[:, 1])

    def jet(self) -> np.ndarray:
        """``v^2 \\int phi_i phi_j(1)``: the jet turns with the tip out of the plane."""
        f = self.static.fixed()
        return (self.params.v**2) * np.outer(f["integral"], self.model.disc.tip)

    def flow_acceleration(self, v_dot: float) -> np.ndarray:
        """``v_dot sqrt(beta) \\int phi_i \\int_xi^1 phi_j``: the force v_dot sqrt(beta) t of an
        unsteady flow turns with the pipe out of the plane (Eq. (20)'s dv/dtau term)."""
        return (v_dot * math.sqrt(self.params.beta)) * self.static.fixed()["coriolis"]

    def kelvin_voigt(self, b: _Base) -> tuple[np.ndarray, np.ndarray]:
        """(damping, stiffness) of the objective Kelvin-Voigt law about the moving state; stiffness zero at rest."""
        f = self.static.fixed()
        Phi, dPhi, w, C = f["Phi"], f["dPhi"], self.w, self.quad.cumulative
        dtheta = b.state.dtheta
        d = dtheta[:, None]
        B = self.static.curvature_rate(b.state)  # chi[phi_j] at theta(tau)
        WB = B * w[:, None]
        damping = WB.T @ B
        spin = (b.rate * dtheta)[:, None] * Phi - d * C(b.rate[:, None] * dPhi)
        tilt = C(d * Phi) * w[:, None]  # C(theta' phi_i), weighted
        stiffness = (
            WB.T @ spin
            - self.static.weighted_gram(b.drate * dtheta)
            - tilt.T @ (b.drate[:, None] * dPhi)
        )
        mu = self.params.mu
        return mu * damping, mu * stiffness

    def matrices(
        self, q, qdot, qddot, v_dot: float = 0.0
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(K, C, M) about the planar state (q, q', q''), the flow accelerating at ``v_dot``."""
        b = self.base(np.asarray(q, float), np.asarray(qdot, float), np.asarray(qddot, float))
        s, p = self.static, self.params
        K = s.bending(b.state) + self.axial_stiffness(b, v_dot) + self.jet()
        if v_dot:
            K = K + self.flow_acceleration(v_dot)
        C = s.coriolis()
        if p.external_damping:
            C = C + s.external_damping()
        if p.mu:
            c_kv, k_kv = self.kelvin_voigt(b)
            C, K = C + c_kv, K + k_kv
        return K, C, s.inertia()


class OutOfPlaneVariation:
    """The planar motion and its out-of-plane variation as the integrator's problem.

    Unknowns (q, psi), ``n = 2 model.n``: Eq. (20) and ``M psi_ddot + C psi_dot + K psi = 0``.
    Meant for psi = 0, where the psi rows' derivative in q vanishes, the Jacobians are exact and
    the sensitivity is block diagonal (rule 7 of :mod:`fempipe.solvers.radau.contract`), its psi
    block the out-of-plane monodromy.  ``model`` is the planar pipe; ``flow`` (tau -> (v,
    v_dot), rule 9) an unsteady flow, by default the steady ``model.params.v``.
    """

    def __init__(self, model: PipeModel, flow=None) -> None:
        self.planar = PipeDynamics(model, flow)
        self.motion = OutOfPlaneMotion(model)
        self.model, self.flow = model, flow
        self.m = model.n
        self.n = 2 * model.n
        self.autonomous = flow is None
        self.parameter_derivative = None
        self.stage_residuals = self._stage_residuals if self.planar.stage_residuals else None
        self.stage_jacobians = self._stage_jacobians if self.planar.stage_jacobians else None
        self.prefers_batched_stage_jacobians = self.planar.prefers_batched_stage_jacobians
        self.decoupled_blocks = (np.arange(self.m), np.arange(self.m, self.n))

    def _matrices(self, t: float, q, qd, qdd):
        """(K, C, M) of the psi rows at tau = t."""
        if self.flow is None:
            return self.motion.matrices(q, qd, qdd)
        model, v_dot = self.planar.model_at(t)
        return OutOfPlaneMotion(model).matrices(q, qd, qdd, v_dot)

    def _psi_rows(self, t, q, qd, qdd, s, sd, sdd) -> np.ndarray:
        if not (np.any(s) or np.any(sd) or np.any(sdd)):
            return np.zeros(self.m)  # the linear equation at psi = 0: no matrices needed
        K, C, M = self._matrices(t, q, qd, qdd)
        return K @ s + C @ sd + M @ sdd

    def residual(self, t: float, q, qdot, qddot) -> np.ndarray:
        """R(q, psi), shape (n,) (rule 2)."""
        m = self.m
        return np.concatenate(
            [
                self.planar.residual(t, q[:m], qdot[:m], qddot[:m]),
                self._psi_rows(t, q[:m], qdot[:m], qddot[:m], q[m:], qdot[m:], qddot[m:]),
            ]
        )

    def _blocks(self, planar, psi) -> tuple[np.ndarray, ...]:
        m, out = self.m, []
        for P, X in zip(planar, psi, strict=True):
            J = np.zeros((self.n, self.n))
            J[:m, :m], J[m:, m:] = P, X
            out.append(J)
        return tuple(out)

    def jacobians(self, t: float, q, qdot, qddot):
        """Block-diagonal (dR/dq, dR/dq', dR/dq'') at psi = 0 (rule 3)."""
        m = self.m
        planar = self.planar.jacobians(t, q[:m], qdot[:m], qddot[:m])
        return self._blocks(planar, self._matrices(t, q[:m], qdot[:m], qddot[:m]))

    def _stage_residuals(self, Q, P, A) -> np.ndarray:
        m = self.m
        R = np.empty(np.shape(Q))
        R[:, :m] = self.planar.stage_residuals(Q[:, :m], P[:, :m], A[:, :m])
        for i in range(R.shape[0]):
            R[i, m:] = self._psi_rows(
                0.0, Q[i, :m], P[i, :m], A[i, :m], Q[i, m:], P[i, m:], A[i, m:]
            )
        return R

    def _stage_jacobians(self, Q, P, A):
        m = self.m
        planar = self.planar.stage_jacobians(Q[:, :m], P[:, :m], A[:, :m])
        per = [
            self._blocks([J[i] for J in planar], self.motion.matrices(Q[i, :m], P[i, :m], A[i, :m]))
            for i in range(np.shape(Q)[0])
        ]
        return tuple(np.stack([blocks[k] for blocks in per]) for k in range(3))

    def acceleration(self, t: float, q, qdot) -> np.ndarray:
        """(q'', psi'') (rule 4)."""
        m = self.m
        qdd = self.planar.acceleration(t, q[:m], qdot[:m])
        K, C, M = self._matrices(t, q[:m], qdot[:m], qdd)
        return np.concatenate([qdd, -np.linalg.solve(M, K @ q[m:] + C @ qdot[m:])])

    def describe(self) -> str:
        """For error messages (rule 14)."""
        return f"v = {self.model.params.v:.6g} (out-of-plane variation)"

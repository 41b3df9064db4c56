"""The pipe in three dimensions: the geometrically exact weak form, one method per term.

:class:`PipeModel3D` is the planar model's pipe (Eq. (20)) in space, under the same
assumptions, on the same discretizations.  The unknown is the tangent t through the chart of
:mod:`fempipe.model.three_d.chart`, three fields U = (theta_dofs, a_dofs, b_dofs); the
``gauge`` term gives the chart's free direction an equation of its own, zero at planar
states (:func:`planar_state`).  Jacobians are exact, by :class:`~fempipe.core.dual.Dual`
fields pulled back through the transposed integration operators.

Derivation, the table of terms and the gauge: docs/theory/space.md, "The weak form".
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from fempipe.core.dual import Dual, cross, dot, linear_functional, pullback, stack
from fempipe.model.discretization import Discretization
from fempipe.model.params import Params
from fempipe.model.three_d.assembly import KINDS, Seeds
from fempipe.model.three_d.chart import Fields3D, compute_fields_3d, tangent

__all__ = [
    "GAUGE_DAMPING",
    "GAUGE_STIFFNESS",
    "GAUGE_WEIGHT",
    "PipeModel3D",
    "planar_state",
]

#: c_g and k_g of the gauge equation: the gauge relaxes with the rates 50 and 100 (roots of
#: s^2 + c_g s + k_g), so that its Floquet multipliers (e^(-50 T) and below) lie far
#: inside those of the physics (:mod:`fempipe.analyses.three_d.floquet`).
GAUGE_DAMPING = 150.0
GAUGE_STIFFNESS = 5000.0
#: w_g: the weight of the gauge equation in the weak form (docs/theory/space.md: a heavier
#: gauge makes the integrator's frozen mass matrix a poor one as the fiber turns).
GAUGE_WEIGHT = 0.03


def planar_state(q: np.ndarray) -> np.ndarray:
    """The 3-D state U = (q, 0, 0) of a planar state q (the exact planar reduction)."""
    q = np.asarray(q, dtype=float)
    return np.concatenate([q, np.zeros(2 * q.size)])


class PipeModel3D:
    """The residual of the 3-D weak form and its exact Jacobians.

    Parameters
    ----------
    disc : Discretization
        The discretization of each of the three fields.
    params : Params
        Dimensionless parameters; springs (no 3-D term) and hysteretic damping (no time-domain
        meaning) are refused.

    Attributes
    ----------
    n : int
        ``3 disc.n`` unknowns.
    """

    gauge_damping = GAUGE_DAMPING
    gauge_stiffness = GAUGE_STIFFNESS
    gauge_weight = GAUGE_WEIGHT

    def __init__(self, disc: Discretization, params: Params) -> None:
        if params.springs:
            raise ValueError(
                "the 3-D model has no spring term: springs = () is required "
                f"(got springs = {params.springs!r})"
            )
        if params.hysteretic_damping:
            raise ValueError(
                "the 3-D model integrates in time: hysteretic damping (mu_h = "
                f"{params.hysteretic_damping:g}) has no time-domain meaning; set it to 0"
            )
        self.disc = disc
        self.params = params
        self.quad = disc.quad
        self.x = disc.quad.x
        self.w = disc.quad.w
        self.n_theta = disc.n
        self.n = 3 * disc.n
        self._seeds = Seeds.of(disc)
        # Phi^T W and dPhi^T W: the test integrals of the two parts of the weak form.
        self._tests = tuple(
            np.ascontiguousarray((B * self.w[:, None]).T)
            for B in (self._seeds.Phi, self._seeds.dPhi)
        )

    def with_params(self, params: Params) -> PipeModel3D:
        """The model on the same discretization with other parameters."""
        return PipeModel3D(self.disc, params)

    @property
    def gravity_direction(self) -> np.ndarray:
        """g = (cos alpha, -sin alpha, 0) in the pipe's frame: t . g = cos(theta + alpha)."""
        a = self.params.alpha
        return np.array([np.cos(a), -np.sin(a), 0.0])

    def fields(self, U, Ud=None, Udd=None, blocks: tuple[str, ...] = ()) -> Fields3D:
        """The kinematics at the quadrature points (last axis: the S states of U, Ud, Udd of
        shape (S, 3 n) or (3 n,)); Duals in the ``blocks`` (of ``"q"``, ``"qdot"``, ``"qddot"``)."""
        s = self._seeds
        nt = self.n_theta
        U = np.atleast_2d(np.asarray(U, dtype=float))
        S = U.shape[0]
        zero = np.zeros_like(U)
        Ud = zero if Ud is None else np.atleast_2d(np.asarray(Ud, dtype=float))
        Udd = zero if Udd is None else np.atleast_2d(np.asarray(Udd, dtype=float))
        values = {"u": U, "u_prime": U, "u_dot": Ud, "u_dot_prime": Ud, "u_ddot": Udd}
        out = {}
        for k, (name, basis, _block) in enumerate(KINDS):
            val = getattr(s, basis) @ values[name].reshape(S * 3, nt).T  # (n_q, S 3)
            val = np.ascontiguousarray(val.reshape(-1, S, 3).transpose(0, 2, 1))
            if blocks:
                loc = np.zeros((1, 3, 1, 3 * len(KINDS)))
                for c in range(3):
                    loc[0, c, 0, 3 * k + c] = 1.0
                val = Dual(val, np.broadcast_to(loc, val.shape + loc.shape[-1:]))
            out[name] = val
        tip_val = (U.reshape(S, 3, nt) @ s.tip).T[None]  # (1, 3, S)
        return compute_fields_3d(
            out["u"],
            out["u_dot"],
            out["u_ddot"],
            out["u_prime"],
            out["u_dot_prime"],
            linear_functional(tip_val, s.tip_der) if blocks else tip_val,
        )

    def _integral(self, x, which: str):
        """Integration operator ``which`` ("C", "CR" or "int") applied to x."""
        op, adjoint = self._seeds.ops[which]
        if not isinstance(x, Dual):
            return op(x)
        return x.nonlocal_map(op, adjoint)

    def inertia(self, fl: Fields3D) -> Dual:
        """``C^R C t_ddot``: the pipe's inertia force beyond xi, centripetal part included."""
        return self._integral(self._integral(fl.t_ddot, "C"), "CR")

    def coriolis(self, fl: Fields3D) -> Dual:
        """``2 v sqrt(beta) C^R t_dot``."""
        p = self.params
        return (2.0 * p.v * np.sqrt(p.beta)) * self._integral(fl.t_dot, "CR")

    def flow_acceleration(self, fl: Fields3D, v_dot: float) -> Dual | None:
        """``v_dot sqrt(beta) C^R t`` (unsteady flow)."""
        if not v_dot:
            return None
        return (v_dot * np.sqrt(self.params.beta)) * self._integral(fl.t, "CR")

    def follower(self, fl: Fields3D) -> Dual:
        """``v^2 t(1)``: the jet's reaction and the fluid's centrifugal force, Eq. (14)."""
        v = self.params.v
        return (v * v) * fl.t_tip

    def gravity(self) -> np.ndarray:
        """``-gamma (1 - xi + Gamma) g``: the weight of the pipe and of the end mass beyond xi."""
        p = self.params
        lever = 1.0 - self.x + p.end_mass
        return -p.gamma * lever[:, None, None] * self.gravity_direction[None, :, None]

    def end_mass_inertia(self, fl: Fields3D) -> Dual | None:
        """``Gamma r_ddot(1)``: the end mass's inertia, felt by every section."""
        G = self.params.end_mass
        if not G:
            return None
        return G * self._integral(fl.t_ddot, "int")  # (1, 3, S)

    def external_damping(self, fl: Fields3D) -> Dual | None:
        """``sigma C^R C t_dot``: a viscous force -sigma r_dot along the pipe."""
        sigma = self.params.external_damping
        if not sigma:
            return None
        rdot = self._integral(fl.t_dot, "C")
        return sigma * self._integral(rdot, "CR")

    def bending(self, fl: Fields3D) -> tuple[Dual, Dual]:
        """(A, B): the variation of ``(1/2) \\int |t'|^2`` is ``\\int A_c phi_i + B_c phi_i'``."""
        tp = fl.t_prime
        A = stack([dot(tp, fl.dt_prime[c]) for c in range(3)], axis=1)
        B = stack([dot(tp, fl.J[c]) for c in range(3)], axis=1)
        return A, B

    def curvature_rate(self, fl: Fields3D) -> Dual:
        """k = t x t_dot' + Omega t': the co-rotational rate of the curvature vector."""
        Omega = self._integral(dot(fl.t_prime, cross(fl.t, fl.t_dot)), "C")
        return cross(fl.t, fl.t_dot_prime) + fl.t_prime * Omega[:, None]

    def kelvin_voigt(self, fl: Fields3D) -> tuple[Dual, Dual] | None:
        """(A, B) of the objective Kelvin-Voigt damping (docs/theory/space.md)."""
        mu = self.params.mu
        if not mu:
            return None
        k = self.curvature_rate(fl)
        kxt = cross(k, fl.t)
        tail = self._integral(dot(k, fl.t_prime), "CR")
        tpxt = cross(fl.t_prime, fl.t) * tail[:, None]
        A = stack([dot(fl.dt_prime[c], kxt) + dot(fl.J[c], tpxt) for c in range(3)], axis=1)
        B = stack([dot(fl.J[c], kxt) for c in range(3)], axis=1)
        return mu * A, mu * B

    def gauge(self, fl: Fields3D) -> Dual:
        """A of the gauge term: ``w_g r_g f_c`` (docs/theory/space.md)."""
        f, u = fl.fiber, fl.u
        rate = dot(f, fl.u_dot)
        r = (
            dot(f, fl.u_ddot)
            + dot(fl.fiber_dot, fl.u_dot)
            + self.gauge_damping * rate
            + self.gauge_stiffness * (f[:, 1] * u[:, 1] + f[:, 2] * u[:, 2])
        )
        return f * (self.gauge_weight * r)[:, None]

    def force_field(self, fl: Fields3D, v_dot: float = 0.0) -> Dual:
        """The sum G of the force fields of all terms tested as ``\\int delta t . G``."""
        G = self.inertia(fl) + self.coriolis(fl) + self.follower(fl) + self.gravity()
        for extra in (
            self.flow_acceleration(fl, v_dot),
            self.end_mass_inertia(fl),
            self.external_damping(fl),
        ):
            if extra is not None:
                G = G + extra
        return G

    def _weak_form(self, fl: Fields3D, v_dot: float) -> tuple:
        """(A, B): the residual is ``\\int phi_i A_c + phi_i' B_c`` (Duals or arrays (n_q, 3, S))."""
        G = self.force_field(fl, v_dot)
        A, B = self.bending(fl)
        A = A + stack([dot(fl.J[c], G) for c in range(3)], axis=1) + self.gauge(fl)
        kv = self.kelvin_voigt(fl)
        if kv is not None:
            A, B = A + kv[0], B + kv[1]
        return A, B

    def _assemble(self, A, B) -> np.ndarray:
        """The residuals (S, 3 n) of the values (n_q, 3, S) of A and B."""
        r = 0.0
        for x, T in zip((A, B), self._tests, strict=True):
            x = np.asarray(x)
            r = r + (T @ x.reshape(x.shape[0], -1)).reshape((T.shape[0],) + x.shape[1:])
        # (nt, 3, S) -> (S, 3, nt)
        return np.ascontiguousarray(np.transpose(r, (2, 1, 0))).reshape(r.shape[2], self.n)

    def _derivatives(self, A: Dual, B: Dual, blocks: tuple[str, ...]) -> np.ndarray:
        """dR/d(blocks) of each state from the Duals A, B: shape (S, 3 n, len(blocks) 3 n)."""
        s = self._seeds
        S = A.shape[-1]
        pairs = list(zip((A, B), s.tests_for(S), strict=True))
        W, G = pullback(pairs, 3 * len(KINDS))
        return s.assemble(W, G, blocks)

    def residual(self, U, Ud=None, Udd=None, v_dot: float = 0.0) -> np.ndarray:
        """R(U, U', U''), shape (3 n,); for S states (rows of (S, 3 n) arrays), (S, 3 n)."""
        r = self._assemble(*self._weak_form(self.fields(U, Ud, Udd), v_dot))
        return r if np.ndim(U) == 2 else r[0]

    def jacobians(self, U, Ud=None, Udd=None, v_dot: float = 0.0):
        """Exact ``(dR/dU, dR/dU', dR/dU'')``, dense (3 n, 3 n) each, dR/dU'' symmetrized; for S
        states (rows of (S, 3 n) arrays), (S, 3 n, 3 n) from one evaluation of the weak form."""
        blocks = ("q", "qdot", "qddot")
        A, B = self._weak_form(self.fields(U, Ud, Udd, blocks=blocks), v_dot)
        D = self._derivatives(A, B, blocks)
        n = self.n
        M = D[:, :, 2 * n :]
        out = D[:, :, :n], D[:, :, n : 2 * n], 0.5 * (M + M.transpose(0, 2, 1))
        return out if np.ndim(U) == 2 else tuple(x[0] for x in out)

    def velocity_derivative(self, U, Ud) -> np.ndarray:
        """dR/dv at fixed (U, U', U''), steady flow: the weak form of ``2 sqrt(beta) C^R t_dot +
        2 v t(1)``, shape (3 n,), or (S, 3 n) for S states."""
        fl = self.fields(U, Ud)
        p = self.params
        G = 2.0 * np.sqrt(p.beta) * self._integral(fl.t_dot, "CR") + (2.0 * p.v) * fl.t_tip
        A = stack([dot(fl.J[c], G) for c in range(3)], axis=1)
        r = self._assemble(A, np.zeros_like(A))
        return r if np.ndim(U) == 2 else r[0]

    def mass_matrix(self, U) -> np.ndarray:
        """dR/dU'' (R is affine in U''), symmetric positive definite, shape (3 n, 3 n)."""
        A, B = self._weak_form(self.fields(U, blocks=("qddot",)), 0.0)
        M = self._derivatives(A, B, ("qddot",))[0]
        return 0.5 * (M + M.T)

    def acceleration(self, U, Ud, v_dot: float = 0.0) -> np.ndarray:
        """U'' from R = 0: ``M U'' = -R(U, U', 0)``."""
        M = self.mass_matrix(U)
        return -sla.cho_solve(sla.cho_factor(M), self.residual(U, Ud, None, v_dot))

    def centerline_velocity(self, fl: Fields3D) -> np.ndarray:
        """r_dot = C t_dot at the quadrature points, shape (n_q, 3)."""
        return self.quad.cumulative(fl.t_dot[:, :, 0])

    def tangents(self, U) -> np.ndarray:
        """t at the quadrature points, shape (n_q, 3, S), from the chart alone."""
        U = np.atleast_2d(np.asarray(U, dtype=float))
        S = U.shape[0]
        u = self._seeds.Phi @ U.reshape(S * 3, self.n_theta).T  # (n_q, S 3)
        return tangent(np.ascontiguousarray(u.reshape(-1, S, 3).transpose(0, 2, 1)))

    def centerline(self, U) -> np.ndarray:
        """r(xi) = \\int_0^xi t at the cell edges, shape (n_cells + 1, 3), in the pipe's frame."""
        return self.quad.at_edges(self.tangents(U)[:, :, 0])

    def tip_position_gradient(self, U) -> np.ndarray:
        """d r(1) / dU in the pipe's frame, shape (3, 3 n): r(1) = \\int_0^1 t."""
        fl = self.fields(U, blocks=("q",))
        seed = np.zeros((self.w.size, 1, 3, 3))
        for c in range(3):
            seed[:, 0, c, c] = self.w  # (q, S, m, R)
        W, G = pullback([(fl.t, seed)], 3 * len(KINDS))
        return self._seeds.assemble(W, G, ("q",))[0]

    def tip_coordinates(self, U) -> dict:
        """eta_tip (e_2 of the pipe's frame), X_tip (along gravity), Z_tip (horizontal, in the
        plane of the static state), Y_tip (out of it); floats, or arrays (S,) for S states."""
        r1 = np.tensordot(self.w, self.tangents(U), axes=(0, 0))  # (3, S)
        a = self.params.alpha
        out = {
            "eta_tip": r1[1],
            "X_tip": np.cos(a) * r1[0] - np.sin(a) * r1[1],
            "Z_tip": np.sin(a) * r1[0] + np.cos(a) * r1[1],
            "Y_tip": r1[2],
        }
        if np.ndim(U) == 1:
            return {k: float(v[0]) for k, v in out.items()}
        return out

    def kinetic_energy(self, U, Ud) -> float:
        """``T = (1/2) \\int |r_dot|^2 + (Gamma/2) |r_dot(1)|^2``."""
        fl = self.fields(U, Ud)
        rd = self.centerline_velocity(fl)
        T = 0.5 * float(self.w @ np.einsum("qc,qc->q", rd, rd))
        G = self.params.end_mass
        if G:
            tip = self.quad.integrate(fl.t_dot[:, :, 0])
            T += 0.5 * G * float(tip @ tip)
        return T

    def potential_energy(self, U) -> float:
        r"""Bending and gravity: ``(1/2) \int |t'|^2 + gamma [cos(alpha)/2 - \int (1 - xi) t . g]
        + gamma Gamma [cos(alpha) - \int t . g]``, zero for the straight pipe.
        """
        fl = self.fields(U)
        p = self.params
        tp = fl.t_prime[:, :, 0]
        tg = fl.t[:, :, 0] @ self.gravity_direction
        V = 0.5 * float(self.w @ np.einsum("qc,qc->q", tp, tp))
        grav = 0.5 * np.cos(p.alpha) - self.w @ ((1.0 - self.x) * tg)
        if p.end_mass:
            grav = grav + p.end_mass * (np.cos(p.alpha) - self.w @ tg)
        return V + p.gamma * float(grav)

    def power_terms(self, U, Ud, Udd, v_dot: float = 0.0) -> dict:
        r"""The power ``U' . R_term`` of each non-conservative term: dE/dtau = -sum of the values.

        Keys: ``coriolis`` (``v sqrt(beta) |r_dot(1)|^2 >= 0``), ``follower``
        (``v^2 r_dot(1) . t(1)``), ``kelvin_voigt`` (``mu \int |k|^2``), ``external_damping``
        (``sigma \int |r_dot|^2``), ``flow_acceleration`` and ``gauge`` (zero in the continuum and
        at planar states, a discretization error elsewhere).
        """
        fl = self.fields(U, Ud, Udd)
        w = self.w
        td = fl.t_dot

        def field_power(G) -> float:
            return (
                0.0
                if G is None
                else float(w @ np.einsum("qcs,qcs->q", td, np.asarray(G) * np.ones_like(td)))
            )

        out = {
            "coriolis": field_power(self.coriolis(fl)),
            "follower": field_power(self.follower(fl)),
            "external_damping": field_power(self.external_damping(fl)),
            "flow_acceleration": field_power(self.flow_acceleration(fl, v_dot)),
        }
        kv = self.kelvin_voigt(fl)
        out["kelvin_voigt"] = 0.0
        if kv is not None:
            out["kelvin_voigt"] = float(
                w
                @ (
                    np.einsum("qcs,qcs->q", kv[0], fl.u_dot)
                    + np.einsum("qcs,qcs->q", kv[1], fl.u_dot_prime)
                )
            )
        out["gauge"] = float(w @ np.einsum("qcs,qcs->q", self.gauge(fl), fl.u_dot))
        return out

    def energy(self, U, Ud) -> float:
        """E = T + V: conserved for v = 0, mu = 0, sigma = 0 (up to the gauge's work)."""
        return self.kinetic_energy(U, Ud) + self.potential_energy(U)

"""The weak form of Eq. (20), one operator per physical term.

Multiplying Eq. (20) by a test function phi_i (phi_i(0) = 0) and integrating
over [0, 1] gives the discrete residual

    R(q, q', q'') = bending + kelvin_voigt + gravity + follower
                    + inertia + centripetal + coriolis + flow_acceleration = 0,

with (theta = Phi q at the quadrature points, t = (cos theta, sin theta) the
tangent and n = (-sin theta, cos theta) the normal):

=====================  ===================================================
bending                ``\\int phi_i' theta'``  (= K q; -theta'' by parts)
kelvin_voigt           ``mu \\int phi_i' theta_dot'``  (= mu K q')
gravity                ``gamma \\int phi_i (1 - xi) sin(theta + alpha)``
follower               ``v^2 \\int phi_i sin(theta(1) - theta)``
inertia                ``\\int phi_i n . C^R C(theta_ddot n)``   (= M(q) q'')
centripetal            ``-\\int phi_i n . C^R C(theta_dot^2 t)``
coriolis               ``2 v sqrt(beta) \\int phi_i n . C^R (theta_dot n)``
flow_acceleration      ``sqrt(beta) v_dot \\int phi_i n . C^R t``
=====================  ===================================================

Here C and C^R are the integration operators from 0 and to 1
(:mod:`fempipe.quadrature`).  Written with n and t the nested brackets of
Eq. (20) read ``n(xi) . \\int_xi^1 r_ddot`` with
``r_ddot = \\int_0^s (theta_ddot n - theta_dot^2 t)`` the acceleration of the
centreline: the generalised inertia force.  The mass matrix is therefore
``M_ij = \\int_0^1 (C phi_i n) . (C phi_j n)``, symmetric positive definite.

Each term also supplies its derivatives with respect to q, q' and q'' so that
Newton's method, the linearised stability matrices (Eqs. (31b)-(33)) and the
implicit time integrators all use the same analytic Jacobians.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .discretization import Discretization
from .params import Params

__all__ = ["Fields", "PipeModel"]


@dataclass(frozen=True)
class Fields:
    """theta, its time derivatives and the local frame at the quadrature points.

    Attributes
    ----------
    theta, theta_dot, theta_ddot : ndarray, shape (n_q,)
    theta_tip : float
        theta(1).
    tangent : ndarray, shape (n_q, 2)
        t = (cos theta, sin theta).
    normal : ndarray, shape (n_q, 2)
        n = (-sin theta, cos theta).
    """

    theta: np.ndarray
    theta_dot: np.ndarray
    theta_ddot: np.ndarray
    theta_tip: float
    tangent: np.ndarray
    normal: np.ndarray


def _rows(d: np.ndarray, A):
    """diag(d) @ A for dense or sparse A."""
    if sp.issparse(A):
        return sp.diags(d) @ A
    return d[:, None] * A


def _dense(A) -> np.ndarray:
    return A.toarray() if sp.issparse(A) else np.asarray(A)


#: Variant terms the model has (the others are refused, never ignored).
IMPLEMENTED_VARIANTS: frozenset[str] = frozenset()


def _check_implemented(params: Params) -> None:
    missing = [
        name
        for name in ("end_mass", "external_damping", "hysteretic_damping", "springs")
        if getattr(params, name) and name not in IMPLEMENTED_VARIANTS
    ]
    if missing:
        raise NotImplementedError(f"the model has no {', '.join(missing)} term yet")


class PipeModel:
    """Residual of the weak form of Eq. (20) and its analytic Jacobians.

    Parameters
    ----------
    disc : Discretization
        :class:`~fempipe.discretization.FiniteElement` or
        :class:`~fempipe.discretization.Modal`.
    params : Params
        Dimensionless parameters.

    Notes
    -----
    ``residual`` costs O(n_q) (plus O(nnz) sparse products).  The Jacobians
    with respect to q' and q'' are dense because the nonlocal terms couple
    every dof with every other; they cost O(n_q n) to form.
    """

    def __init__(self, disc: Discretization, params: Params) -> None:
        _check_implemented(params)
        self.disc = disc
        self.params = params
        self.quad = disc.quad
        self.x = disc.quad.x
        self.w = disc.quad.w
        self._PhiT_W = (disc.Phi.T @ sp.diags(self.w)) if disc.sparse else disc.Phi.T * self.w

    def with_params(self, params: Params) -> PipeModel:
        """Return a model on the same discretisation with other parameters."""
        _check_implemented(params)
        new = object.__new__(PipeModel)
        new.__dict__.update(self.__dict__)
        new.params = params
        return new

    @property
    def n(self) -> int:
        return self.disc.n

    # ------------------------------------------------------------------
    def fields(self, q, qdot=None, qddot=None) -> Fields:
        """theta, its rates and the local frame at the quadrature points."""
        Phi = self.disc.Phi
        theta = Phi @ np.asarray(q)
        zero = np.zeros_like(theta)
        th_d = Phi @ np.asarray(qdot) if qdot is not None else zero
        th_dd = Phi @ np.asarray(qddot) if qddot is not None else zero
        s, c = np.sin(theta), np.cos(theta)
        return Fields(
            theta=theta,
            theta_dot=th_d,
            theta_ddot=th_dd,
            theta_tip=float(self.disc.tip @ np.asarray(q)),
            tangent=np.stack([c, s], axis=1),
            normal=np.stack([-s, c], axis=1),
        )

    def _test(self, f: np.ndarray) -> np.ndarray:
        """``\\int phi_i f`` for f at the quadrature points."""
        return np.asarray(self._PhiT_W @ f)

    def _project(self, F: np.ndarray, fl: Fields) -> np.ndarray:
        """``\\int phi_i n . C^R F`` for a vector field F, shape (n_q, 2)."""
        G = self.quad.from_tip(F)
        return self._test(np.einsum("qc,qc->q", fl.normal, G))

    def _project_jac(self, dF: np.ndarray, fl: Fields) -> np.ndarray:
        """Derivative of ``\\int phi_i n . C^R F`` through F: dF shape (n_q, 2, n)."""
        G = self.quad.from_tip(dF)
        return self._test(np.einsum("qc,qcj->qj", fl.normal, G))

    def _normal_weight(self, F: np.ndarray, fl: Fields) -> np.ndarray:
        """Derivative of ``\\int phi_i n . C^R F`` through n(theta) (dn = -t dtheta):
        ``Phi^T diag(d) Phi`` with the d returned here."""
        return -np.einsum("qc,qc->q", fl.tangent, self.quad.from_tip(F)) * self.w

    @property
    def _Phi_dense(self) -> np.ndarray:
        """Phi as a dense array, cached: the dense Jacobians use it every call."""
        P = self.__dict__.get("_Phi_dense_cache")
        if P is None:
            P = self.__dict__["_Phi_dense_cache"] = _dense(self.disc.Phi)
        return P

    def _phi_field(self, coef: np.ndarray) -> np.ndarray:
        """(coef[:, c] * Phi) stacked as shape (n_q, 2, n)."""
        Phi = self._Phi_dense
        return coef[:, :, None] * Phi[:, None, :]

    # ---------------------------------------------------- local terms --
    def bending(self, q: np.ndarray) -> np.ndarray:
        """Eq. (20) -theta'': ``K q`` with K_ij = \\int phi_i' phi_j'."""
        return np.asarray(self.disc.K @ q)

    def kelvin_voigt(self, qdot: np.ndarray) -> np.ndarray:
        """Eq. (20) -mu theta_dot'': ``mu K q'``."""
        return self.params.mu * np.asarray(self.disc.K @ qdot)

    def gravity(self, fl: Fields) -> np.ndarray:
        """Eq. (20) gamma (1 - xi) sin(theta + alpha)."""
        p = self.params
        return p.gamma * self._test((1.0 - self.x) * np.sin(fl.theta + p.alpha))

    def _gravity_weight(self, fl: Fields) -> np.ndarray:
        """d(gravity)/dq = ``Phi^T diag(d) Phi`` with this d."""
        p = self.params
        return p.gamma * self.w * (1.0 - self.x) * np.cos(fl.theta + p.alpha)

    def gravity_jacobian(self, fl: Fields):
        Phi = self.disc.Phi
        return Phi.T @ _rows(self._gravity_weight(fl), Phi)

    def follower(self, fl: Fields) -> np.ndarray:
        """Eq. (20) v^2 sin(theta(1) - theta): the jet's reaction at the free end, Eq. (14)."""
        # v * v, not v**2: a product overflows to inf (caught by the solvers as
        # a non-finite residual) where a power raises OverflowError.
        return self.params.v * self.params.v * self._test(np.sin(fl.theta_tip - fl.theta))

    def _follower_weights(self, fl: Fields) -> tuple[np.ndarray, np.ndarray]:
        """d(follower)/dq = ``Phi^T diag(d) Phi + tip_col tip^T``: (d, tip_col).

        The theta(1) dependence couples every row to the tip dofs: a rank-one
        update, which is one extra column for finite elements.
        """
        v2 = self.params.v * self.params.v
        c = np.cos(fl.theta_tip - fl.theta)
        return -v2 * self.w * c, v2 * self._test(c)

    def follower_jacobian(self, fl: Fields):
        d, tip_col = self._follower_weights(fl)
        Phi = self.disc.Phi
        local = Phi.T @ _rows(d, Phi)
        if sp.issparse(local):
            tip = sp.csr_matrix(self.disc.tip)
            return local + sp.csr_matrix(tip_col[:, None]) @ tip
        return local + np.outer(tip_col, self.disc.tip)

    # ------------------------------------------------- nonlocal terms --
    def inertia(self, fl: Fields) -> np.ndarray:
        """Eq. (20) theta_ddot terms of the double integrals: ``M(q) q''``."""
        return self._project(self.quad.cumulative(fl.theta_ddot[:, None] * fl.normal), fl)

    def centripetal(self, fl: Fields) -> np.ndarray:
        """Eq. (20) theta_dot^2 terms of the double integrals (N_2 of Eq. (24e))."""
        return self._project(-self.quad.cumulative(fl.theta_dot[:, None] ** 2 * fl.tangent), fl)

    def coriolis(self, fl: Fields) -> np.ndarray:
        """Eq. (20) 2 v sqrt(beta) [sin theta \\int theta_dot sin + cos theta \\int theta_dot cos]."""
        p = self.params
        return 2.0 * p.v * np.sqrt(p.beta) * self._project(fl.theta_dot[:, None] * fl.normal, fl)

    def flow_acceleration(self, fl: Fields, v_dot: float) -> np.ndarray:
        """Eq. (20) v_dot sqrt(beta) [-sin theta \\int cos + cos theta \\int sin]."""
        if v_dot == 0.0:
            return np.zeros(self.n)
        return v_dot * np.sqrt(self.params.beta) * self._project(fl.tangent, fl)

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """``M_ij = \\int_0^1 (C phi_i n).(C phi_j n)``, dense SPD, shape (n, n).

        Identical (to round-off) to ``d inertia / d q''``; the Gram form makes
        the symmetry exact.
        """
        fl = self.fields(q)
        B = self.quad.cumulative(self._phi_field(fl.normal))  # (n_q, 2, n)
        M = np.einsum("qcj,qck->jk", B * self.w[:, None, None], B)
        return 0.5 * (M + M.T)

    # ------------------------------------------------------- totals --
    def residual(self, q, qdot=None, qddot=None, v_dot: float = 0.0) -> np.ndarray:
        """R(q, q', q''), shape (n,): the weak form of Eq. (20)."""
        fl = self.fields(q, qdot, qddot)
        r = self.bending(q) + self.gravity(fl) + self.follower(fl)
        if qdot is not None:
            r = r + self.kelvin_voigt(qdot) + self.centripetal(fl) + self.coriolis(fl)
        if qddot is not None:
            r = r + self.inertia(fl)
        r = r + self.flow_acceleration(fl, v_dot)
        return r

    def static_residual(self, q: np.ndarray) -> np.ndarray:
        """Eq. (31a) in weak form: R(q, 0, 0)."""
        return self.residual(q)

    def static_terms(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The three forces of R(q, 0, 0): (bending, gravity, follower).

        Their sum, in this order, is :meth:`static_residual` to the last bit;
        their sizes say how small the residual must be to call q an
        equilibrium (:func:`fempipe.static.solve_static`).
        """
        fl = self.fields(q)
        return self.bending(q), self.gravity(fl), self.follower(fl)

    def gravity_load(self) -> float:
        """``gamma ||\\int phi_i (1 - xi)||``: the size of the gravity term whatever its
        lever arm sin(theta + alpha) (a norm of the weak-form vector, like R)."""
        return self.params.gamma * float(np.linalg.norm(self._test(1.0 - self.x)))

    def static_jacobian(self, q: np.ndarray):
        """dR(q, 0, 0)/dq: sparse for finite elements, dense for modes."""
        fl = self.fields(q)
        J = self.disc.K + self.gravity_jacobian(fl) + self.follower_jacobian(fl)
        return J.tocsc() if sp.issparse(J) else np.asarray(J)

    def static_parameter_derivative(self, q: np.ndarray, name: str) -> np.ndarray:
        """dR(q, 0, 0)/d(name) for name in {'v', 'gamma', 'alpha'}: continuation."""
        fl = self.fields(q)
        p = self.params
        if name == "v":
            return 2.0 * p.v * self._test(np.sin(fl.theta_tip - fl.theta))
        if name == "gamma":
            return self._test((1.0 - self.x) * np.sin(fl.theta + p.alpha))
        if name == "alpha":
            return p.gamma * self._test((1.0 - self.x) * np.cos(fl.theta + p.alpha))
        raise ValueError(f"continuation parameter must be 'v', 'gamma' or 'alpha', got {name!r}")

    def jacobians(self, q, qdot=None, qddot=None, v_dot: float = 0.0):
        """Analytic ``(dR/dq, dR/dq', dR/dq'')``, each dense, shape (n, n).

        dR/dq'' is the mass matrix M(q).  At a static state (q' = q'' = 0)
        these are the K^d, C^d, M^d of Eqs. (31b)-(33).
        """
        n = self.n
        qdot = np.zeros(n) if qdot is None else np.asarray(qdot)
        qddot = np.zeros(n) if qddot is None else np.asarray(qddot)
        fl = self.fields(q, qdot, qddot)
        p = self.params
        cv = 2.0 * p.v * np.sqrt(p.beta)
        th_d, th_dd = fl.theta_dot, fl.theta_ddot

        # Total inner field F of the projection n . C^R F, to differentiate n.
        F = self.quad.cumulative(th_dd[:, None] * fl.normal - th_d[:, None] ** 2 * fl.tangent)
        F = F + cv * th_d[:, None] * fl.normal + v_dot * np.sqrt(p.beta) * fl.tangent

        # d/dq: through n(theta) in front, and through n, t inside F.
        dF = self.quad.cumulative(
            self._phi_field(-th_dd[:, None] * fl.tangent - th_d[:, None] ** 2 * fl.normal)
        )
        dF = dF + self._phi_field(
            -cv * th_d[:, None] * fl.tangent + v_dot * np.sqrt(p.beta) * fl.normal
        )
        # The gravity, follower (local part) and normal-derivative terms are all
        # Phi^T diag(d) Phi: one dense product instead of three small sparse
        # ones (scipy.sparse overhead dominated the time-integration cost).
        d_follower, tip_col = self._follower_weights(fl)
        d = self._gravity_weight(fl) + d_follower + self._normal_weight(F, fl)
        Phi = self._Phi_dense
        Jq = (
            _dense(self.disc.K)
            + (Phi.T * d) @ Phi
            + np.outer(tip_col, self.disc.tip)
            + self._project_jac(dF, fl)
        )
        # d/dq': centripetal and Coriolis, plus Kelvin-Voigt.
        dFd = self.quad.cumulative(self._phi_field(-2.0 * th_d[:, None] * fl.tangent))
        dFd = dFd + self._phi_field(cv * fl.normal)
        Jqd = p.mu * _dense(self.disc.K) + self._project_jac(dFd, fl)
        M = self.mass_matrix(q)
        return Jq, Jqd, M

    # ------------------------------------------------------- energy --
    def kinetic_energy(self, q, qdot) -> float:
        """T = (1/2) \\int_0^1 |r_dot|^2 = (1/2) q'^T M(q) q'."""
        fl = self.fields(q, qdot)
        rdot = self.quad.cumulative(fl.theta_dot[:, None] * fl.normal)
        return 0.5 * float(self.w @ np.einsum("qc,qc->q", rdot, rdot))

    def potential_energy(self, q) -> float:
        """Bending plus gravity: (1/2) q^T K q + gamma [cos(alpha)/2 - \\int (1 - xi) cos(theta + alpha)].

        The constant makes the straight pipe's gravity energy zero.
        """
        q = np.asarray(q)
        p = self.params
        fl = self.fields(q)
        grav = 0.5 * np.cos(p.alpha) - self.w @ ((1.0 - self.x) * np.cos(fl.theta + p.alpha))
        return 0.5 * float(q @ (self.disc.K @ q)) + p.gamma * float(grav)

    def energy(self, q, qdot) -> float:
        """Total mechanical energy E = T + V, conserved for v = 0 and mu = 0.

        See :func:`fempipe.dynamics.power_terms` for dE/dtau in general.
        """
        return self.kinetic_energy(q, qdot) + self.potential_energy(q)

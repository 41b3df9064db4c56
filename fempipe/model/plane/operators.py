"""The pipe model: the weak form of Eq. (20) summed, with its analytic Jacobians.

:class:`PipeModel` sums the physical terms (:mod:`~fempipe.model.plane.local_terms`,
:mod:`~fempipe.model.plane.nonlocal_terms`, :mod:`~fempipe.model.plane.variants`,
:mod:`~fempipe.model.plane.springs`): the residual R(q, q', q''), its Jacobians (the same ones
serve Newton's method, the stability matrices of Eqs. (31b)-(33) and the implicit
integrators), the mass matrix, the static problem and the energy.

Derivation: docs/theory/weak_form.md.
"""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from fempipe.model.discretization import Discretization
from fempipe.model.params import Params
from fempipe.model.plane.local_terms import LocalTerms
from fempipe.model.plane.nonlocal_terms import NonlocalTerms
from fempipe.model.plane.springs import PartRule, SpringTerms
from fempipe.model.plane.variants import EndMassTerms, ExternalDampingTerm
from fempipe.model.weak_form import Fields

__all__ = ["Fields", "PipeModel"]


class PipeModel(LocalTerms, NonlocalTerms, EndMassTerms, ExternalDampingTerm, SpringTerms):
    r"""The pipe's residual in weak form and its analytic Jacobians.

    ``disc`` is a :class:`~fempipe.model.discretization.FiniteElement` or
    :class:`~fempipe.model.discretization.Modal`, ``params`` the dimensionless parameters;
    ``test_matrix`` is ``Phi^T W`` (``test_matrix @ f`` = ``\int phi_i f``).  The Jacobians in
    q' and q'' are dense (the nonlocal terms couple all dofs).  Hysteretic damping has no term
    here: it acts in the linear stability problem only.
    """

    def __init__(self, disc: Discretization, params: Params) -> None:
        self.disc = disc
        self.params = params
        self.quad = disc.quad
        self.x = disc.quad.x
        self.w = disc.quad.w
        self.test_matrix = (disc.Phi.T @ sp.diags(self.w)) if disc.sparse else disc.Phi.T * self.w
        # Gauss rules on [0, xi_s], built on first use and shared by the
        # models of with_params (same discretization).
        self._part_rules: dict[float, PartRule] = {}

    #: The plane of the linear problem of :meth:`linearization` (``"out"`` for
    #: :func:`fempipe.model.out_of_plane.model.build_out_of_plane_model`).
    plane = "in"

    def with_params(self, params: Params) -> PipeModel:
        """Return a model of the same kind on the same discretization with other parameters."""
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.params = params
        return new

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        r"""``M_ij = \int_0^1 (C phi_i n).(C phi_j n) + Gamma b_i . b_j``, dense SPD, shape (n, n):
        ``d (inertia + end_mass_inertia) / d q''`` in Gram form, which makes the symmetry exact."""
        fl = self.fields(q)
        M = self._pipe_mass(fl)
        G = self.params.end_mass
        if G:
            b = self._end_vector(fl)
            M = M + G * (b @ b.T)
        return M

    def residual(self, q, qdot=None, qddot=None, v_dot: float = 0.0) -> np.ndarray:
        """R(q, q', q''), shape (n,): the weak form of Eq. (20) with the variants."""
        fl = self.fields(q, qdot, qddot)
        p = self.params
        g = self.gravity(fl)
        if p.end_mass:
            g = g + self.end_mass_gravity(fl)
        # The order of static_terms: their sum is R(q, 0, 0) to the last bit.
        r = self.bending(q) + g + self.follower(fl)
        if p.springs:
            r = r + self.spring(q)
        if qdot is not None:
            r = r + self.kelvin_voigt(qdot) + self.centripetal(fl) + self.coriolis(fl)
            if p.external_damping:
                r = r + self.external_damping(fl)
        if qddot is not None:
            r = r + self.inertia(fl)
        if p.end_mass and (qdot is not None or qddot is not None):
            r = r + self.end_mass_inertia(fl)
        r = r + self.flow_acceleration(fl, v_dot)
        return r

    def rate_terms(self, q, qdot, qddot) -> np.ndarray:
        """``C^d q' + M^d q''`` at the static state q (Eqs. (33b), (33c)), without forming them."""
        fl = self.fields(q, qdot, qddot)
        r = self.kelvin_voigt(qdot) + self.coriolis(fl) + self.inertia(fl)
        p = self.params
        if p.external_damping:
            r = r + self.external_damping(fl)
        if p.end_mass:
            acc = self.quad.integrate(fl.theta_ddot[:, None] * fl.normal)
            r = r + p.end_mass * (self._end_vector(fl) @ acc)
        return r

    def static_residual(self, q: np.ndarray) -> np.ndarray:
        """Eq. (31a) in weak form: R(q, 0, 0)."""
        return self.residual(q)

    def static_terms(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The forces of R(q, 0, 0): (bending, gravity, follower, springs).

        Gravity includes the end mass's.  Their sum in this order is :meth:`static_residual` to
        the last bit; their sizes set the residual that makes q an equilibrium.
        """
        fl = self.fields(q)
        p = self.params
        g = self.gravity(fl)
        if p.end_mass:
            g = g + self.end_mass_gravity(fl)
        s = self.spring(q) if p.springs else np.zeros(self.n)
        return self.bending(q), g, self.follower(fl), s

    def gravity_load(self) -> float:
        r"""``gamma ||\int phi_i (1 - xi + Gamma)||``: the size of the gravity term (a norm like R's)."""
        p = self.params
        return p.gamma * float(np.linalg.norm(self._test(1.0 - self.x + p.end_mass)))

    def static_jacobian(self, q: np.ndarray, dense: bool = False):
        """dR(q, 0, 0)/dq: sparse for finite elements, dense for modes or if ``dense``."""
        fl = self.fields(q)
        if dense:
            return self._dense_static_jacobian(q, fl)
        J = self.disc.K + self.gravity_jacobian(fl) + self.follower_jacobian(fl)
        if self.params.springs:
            J = J + self.spring_jacobian(q)
        return J.tocsc() if sp.issparse(J) else np.asarray(J)

    def static_parameter_derivative(self, q: np.ndarray, name: str) -> np.ndarray:
        """dR(q, 0, 0)/d(name) for name in {'v', 'gamma', 'alpha'}: continuation."""
        fl = self.fields(q)
        p = self.params
        lever = 1.0 - self.x + p.end_mass
        if name == "v":
            return 2.0 * p.v * self._test(np.sin(fl.theta_tip - fl.theta))
        if name == "gamma":
            return self._test(lever * np.sin(fl.theta + p.alpha))
        if name == "alpha":
            return p.gamma * self._test(lever * np.cos(fl.theta + p.alpha))
        raise ValueError(f"continuation parameter must be 'v', 'gamma' or 'alpha', got {name!r}")

    def jacobians(self, q, qdot=None, qddot=None, v_dot: float = 0.0):
        """Analytic ``(dR/dq, dR/dq', dR/dq'')``, dense (n, n): at a static state K^d, C^d, M^d
        of Eqs. (31b)-(33)."""
        n = self.n
        qdot = np.zeros(n) if qdot is None else np.asarray(qdot)
        qddot = np.zeros(n) if qddot is None else np.asarray(qddot)
        fl = self.fields(q, qdot, qddot)
        p = self.params
        cv = 2.0 * p.v * np.sqrt(p.beta)
        sigma = p.external_damping
        th_d, th_dd = fl.theta_dot, fl.theta_ddot
        t, nrm = fl.tangent, fl.normal

        # Total inner field F of the projection n . C^R F, to differentiate n:
        # inertia, centripetal and external damping inside C, Coriolis and
        # flow acceleration outside.
        F = self.quad.cumulative(
            th_dd[:, None] * nrm - th_d[:, None] ** 2 * t + sigma * th_d[:, None] * nrm
        )
        F = F + cv * th_d[:, None] * nrm + v_dot * np.sqrt(p.beta) * t

        # d/dq: through n(theta) in front, and through n, t inside F.
        dF = self.quad.cumulative(
            self._phi_field(
                -th_dd[:, None] * t - th_d[:, None] ** 2 * nrm - sigma * th_d[:, None] * t
            )
        )
        dF = dF + self._phi_field(-cv * th_d[:, None] * t + v_dot * np.sqrt(p.beta) * nrm)
        # Gravity, local follower and normal-derivative terms are all Phi^T diag(d) Phi:
        # one dense product avoids the overhead of three small sparse ones.
        d_follower, tip_col = self._follower_weights(fl)
        d = self._gravity_weight(fl) + d_follower + self._normal_weight(F, fl)
        Phi = self._Phi_dense
        # d/dq': centripetal and Coriolis, plus Kelvin-Voigt and external damping.
        dFd = self.quad.cumulative(self._phi_field(-2.0 * th_d[:, None] * t))
        dFd = dFd + self._phi_field(cv * nrm)
        Jqd = p.mu * self._K_dense + self._project_jac(dFd, fl)
        M_pipe = self._pipe_mass(fl)
        if sigma:
            Jqd = Jqd + sigma * M_pipe
        M = M_pipe
        Jq_extra = np.outer(tip_col, self.disc.tip) + self._project_jac(dF, fl)
        if p.end_mass:
            # R_e = Gamma b(q) . a(q, q', q''), a = \int (theta_ddot n - theta_dot^2 t).
            G = p.end_mass
            b = self._end_vector(fl)
            a = self.quad.integrate(th_dd[:, None] * nrm - th_d[:, None] ** 2 * t)
            d = d - G * self.w * (t @ a)  # db_i/dq_j = -\int phi_i phi_j t
            da_dq = self._test(-th_dd[:, None] * t - th_d[:, None] ** 2 * nrm)  # (n, 2)
            Jq_extra = Jq_extra + G * (b @ da_dq.T)
            Jqd = Jqd + G * (b @ self._test(-2.0 * th_d[:, None] * t).T)
            M = M + G * (b @ b.T)
        Jq = self._K_dense + (Phi.T * d) @ Phi + Jq_extra
        if p.springs:
            Jq = Jq + self.spring_jacobian(q, dense=True)
        return Jq, Jqd, M

    def linearization(self, q: np.ndarray):
        """K^d, C^d, M^d of the linear problem about the static state q, in the plane."""
        return self.static_jacobians(q)

    def hysteretic_stiffness(self, q: np.ndarray) -> np.ndarray:
        """The stiffness the hysteretic loss factor multiplies: bending, ``disc.K`` (dense)."""
        return self._K_dense

    def static_jacobians(self, q):
        """:meth:`jacobians` at (q, 0, 0), K^d, C^d, M^d of Eqs. (31b)-(33), without the terms
        that vanish exactly there (two cumulative integrals fewer)."""
        fl = self.fields(q)
        p = self.params
        cv = 2.0 * p.v * np.sqrt(p.beta)
        Jqd = p.mu * self._K_dense + self._project_jac(self._phi_field(cv * fl.normal), fl)
        M_pipe = self._pipe_mass(fl)
        if p.external_damping:
            Jqd = Jqd + p.external_damping * M_pipe
        M = M_pipe
        if p.end_mass:
            b = self._end_vector(fl)
            M = M + p.end_mass * (b @ b.T)
        return self._dense_static_jacobian(q, fl), Jqd, M

    def _dense_static_jacobian(self, q, fl) -> np.ndarray:
        """dR(q, 0, 0)/dq as one product ``Phi^T diag(d) Phi`` plus the tip column and springs."""
        d_follower, tip_col = self._follower_weights(fl)
        d = self._gravity_weight(fl) + d_follower
        Phi = self._Phi_dense
        J = self._K_dense + (Phi.T * d) @ Phi + np.outer(tip_col, self.disc.tip)
        if self.params.springs:
            J = J + self.spring_jacobian(q, dense=True)
        return J

    def kinetic_energy(self, q, qdot) -> float:
        """``T = (1/2) \\int_0^1 |r_dot|^2 + (Gamma/2) |r_dot(1)|^2 = (1/2) q'^T M(q) q'``."""
        fl = self.fields(q, qdot)
        rdot = self.quad.cumulative(fl.theta_dot[:, None] * fl.normal)
        T = 0.5 * float(self.w @ np.einsum("qc,qc->q", rdot, rdot))
        G = self.params.end_mass
        if G:
            tip = self.quad.integrate(fl.theta_dot[:, None] * fl.normal)
            T += 0.5 * G * float(tip @ tip)
        return T

    def potential_energy(self, q) -> float:
        r"""Bending, gravity and springs.

        ``(1/2) q^T K q + gamma [cos(alpha)/2 - \int (1 - xi) cos(theta + alpha)]
        + gamma Gamma [cos(alpha) - \int cos(theta + alpha)] + sum (kappa/2) |r(xi_s) - (xi_s, 0)|^2``,
        zero for the straight pipe.
        """
        q = np.asarray(q)
        p = self.params
        fl = self.fields(q)
        c = np.cos(fl.theta + p.alpha)
        grav = 0.5 * np.cos(p.alpha) - self.w @ ((1.0 - self.x) * c)
        if p.end_mass:
            grav = grav + p.end_mass * (np.cos(p.alpha) - self.w @ c)
        V = 0.5 * float(q @ (self.disc.K @ q)) + p.gamma * float(grav)
        for kappa, _rule, _t, _n, _b, d in self._spring_states(q) if p.springs else ():
            V += 0.5 * kappa * float(d @ d)
        return V

    def energy(self, q, qdot) -> float:
        """Total mechanical energy E = T + V, conserved for v = mu = sigma = 0."""
        return self.kinetic_energy(q, qdot) + self.potential_energy(q)

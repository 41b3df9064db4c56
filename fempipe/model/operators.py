"""The weak form of Eq. (20), one operator per physical term.

Multiplying Eq. (20) by a test function phi_i (phi_i(0) = 0) and integrating
over [0, 1] gives the discrete residual

    R(q, q', q'') = bending + kelvin_voigt + gravity + follower
                    + inertia + centripetal + coriolis + flow_acceleration
                    + end_mass_gravity + end_mass_inertia + external_damping
                    + spring = 0,

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
end_mass_gravity       ``gamma Gamma \\int phi_i sin(theta + alpha)``
end_mass_inertia       ``Gamma (\\int phi_i n) . r_ddot(1)``  (M += Gamma b b^T)
external_damping       ``sigma \\int phi_i n . C^R C(theta_dot n)``  (= sigma M_pipe q')
spring                 ``kappa \\int_0^xi_s phi_i n . (r(xi_s) - (xi_s, 0))``
=====================  ===================================================

Here C and C^R are the integration operators from 0 and to 1
(:mod:`fempipe.model.quadrature`).  Written with n and t the nested brackets of
Eq. (20) read ``n(xi) . \\int_xi^1 r_ddot`` with
``r_ddot = \\int_0^s (theta_ddot n - theta_dot^2 t)`` the acceleration of the
centreline: the generalised inertia force.  The mass matrix is therefore
``M_ij = \\int_0^1 (C phi_i n) . (C phi_j n)``, symmetric positive definite.

The last four rows are the variants of the pipe (:class:`~fempipe.model.params.Params`,
scaled as Eq. (19); README, "Variants of the pipe"), each zero by default:

* an end mass Gamma = M_e/((m+M) L) at xi = 1 (a point mass without fluid):
  its weight adds gamma Gamma sin(theta + alpha) to the gravity lever
  gamma (1 - xi) sin(theta + alpha), and its inertia Gamma r_ddot(1) to the
  inertia force field ``\\int_xi^1 r_ddot`` of every section, with
  ``b_i = \\int_0^1 phi_i n = (C phi_i n)(1)`` and
  ``r_ddot(1) = \\int_0^1 (theta_ddot n - theta_dot^2 t)``;
* external viscous damping sigma = c L^2/sqrt(EI (m+M)), a force -sigma r_dot
  per unit length along the whole velocity r_dot = C(theta_dot n): its
  virtual work is the inertia projection with r_ddot replaced by r_dot;
* linear springs kappa = k L^3/EI tying r(xi_s) = \\int_0^xi_s t to its
  undeformed position (xi_s, 0): the gradient of the potential
  (kappa/2) |r(xi_s) - (xi_s, 0)|^2, integrated over [0, xi_s] with a
  Gauss rule of its own (:meth:`PipeModel.spring`).

Each term also supplies its derivatives with respect to q, q' and q'' so that
Newton's method, the linearised stability matrices (Eqs. (31b)-(33)) and the
implicit time integrators all use the same analytic Jacobians.
"""

from __future__ import annotations

import weakref
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


_DENSE_FORMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _dense_forms(disc: Discretization) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, K) of ``disc`` as dense arrays, computed once per discretisation."""
    forms = _DENSE_FORMS.get(disc)
    if forms is None:
        forms = _DENSE_FORMS[disc] = (_dense(disc.Phi), _dense(disc.K))
    return forms


@dataclass(frozen=True)
class _PartRule:
    """A Gauss rule on [0, xi_s] with the basis at its points (one per spring position).

    Attributes
    ----------
    x, w : ndarray, shape (m,)
        Points and weights; ``w @ f`` integrates f over [0, xi_s].
    Phi : ndarray or scipy.sparse.csr_matrix, shape (m, n)
        phi_j at the points.
    at_node : bool
        Whether xi_s is a cell edge of the model's quadrature (the rule is
        then its restriction to the cells before xi_s).
    """

    x: np.ndarray
    w: np.ndarray
    Phi: np.ndarray | sp.csr_matrix
    at_node: bool


class PipeModel:
    """Residual of the weak form of Eq. (20) and its analytic Jacobians.

    Parameters
    ----------
    disc : Discretization
        :class:`~fempipe.model.discretization.FiniteElement` or
        :class:`~fempipe.model.discretization.Modal`.
    params : Params
        Dimensionless parameters, with the variants of the pipe (module
        docstring).

    Notes
    -----
    ``residual`` costs O(n_q) (plus O(nnz) sparse products).  The Jacobians
    with respect to q' and q'' are dense because the nonlocal terms couple
    every dof with every other; they cost O(n_q n) to form.  A spring at
    xi_s couples every dof of [0, xi_s] with every other (a rank-2 block of
    the static Jacobian), so for finite elements that block is dense.
    ``params.hysteretic_damping`` has no term here: it acts in the linear
    stability problem only (:func:`fempipe.analyses.stability.linear.hysteretic_roots`),
    and the time-domain solvers refuse it (:func:`fempipe.model.dynamics_problem.refuse_hysteretic`).
    """

    def __init__(self, disc: Discretization, params: Params) -> None:
        self.disc = disc
        self.params = params
        self.quad = disc.quad
        self.x = disc.quad.x
        self.w = disc.quad.w
        self.test_matrix = (disc.Phi.T @ sp.diags(self.w)) if disc.sparse else disc.Phi.T * self.w
        # Gauss rules on [0, xi_s], built on first use and shared by the
        # models of with_params (same discretisation).
        self._part_rules: dict[float, _PartRule] = {}

    #: The plane of the linear problem :meth:`linearization` gives: ``"in"``, the
    #: plane of the static state (:class:`fempipe.model.out_of_plane.OutOfPlaneModel`
    #: gives ``"out"``).
    plane = "in"

    def with_params(self, params: Params) -> PipeModel:
        """Return a model of the same kind on the same discretisation with other parameters."""
        new = object.__new__(type(self))
        new.__dict__.update(self.__dict__)
        new.params = params
        return new

    def with_plane(self, plane: str) -> PipeModel:
        """The model of the same pipe whose linearisation is in (``"in"``) or out of
        (``"out"``) the plane of its static states (:mod:`fempipe.model.out_of_plane`)."""
        if plane == self.plane:
            return self
        if plane == "out":
            from .out_of_plane import OutOfPlaneModel

            cls = OutOfPlaneModel
        elif plane == "in":
            cls = PipeModel
        else:
            raise ValueError(f"plane must be 'in' or 'out', got {plane!r}")
        new = object.__new__(cls)
        new.__dict__.update(self.__dict__)
        return new

    @property
    def n(self) -> int:
        return self.disc.n

    def dynamics_problem(self, flow=None):
        """The equations of motion of this model as the integrator's problem.

        Returns :class:`fempipe.model.dynamics_problem.PipeDynamics` ``(self, flow)``;
        :class:`fempipe.solvers.radau.Radau` calls it when given a model instead
        of a problem.  Imported here, not at the top: that module builds on this
        one (its batched kernels know the plain PipeModel).
        """
        from .dynamics_problem import PipeDynamics

        return PipeDynamics(self, flow)

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
        return np.asarray(self.test_matrix @ f)

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
        """Phi as a dense array, cached per discretisation: the dense Jacobians use it
        every call, on models made by :meth:`with_params` (which share the discretisation)."""
        return _dense_forms(self.disc)[0]

    @property
    def _K_dense(self) -> np.ndarray:
        """The bending matrix K as a dense array, cached like :attr:`_Phi_dense`."""
        return _dense_forms(self.disc)[1]

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
        """d(gravity + end_mass_gravity)/dq = ``Phi^T diag(d) Phi`` with this d."""
        p = self.params
        return p.gamma * self.w * (1.0 - self.x + p.end_mass) * np.cos(fl.theta + p.alpha)

    def gravity_jacobian(self, fl: Fields):
        """d(gravity + end_mass_gravity)/dq, sparse for finite elements."""
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
        """Eq. (20) theta_ddot terms of the double integrals: ``M_pipe(q) q''``.

        The pipe's own inertia; with an end mass the whole inertia is
        ``inertia + end_mass_inertia`` (= M(q) q'' + its centripetal part).
        """
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

    # ------------------------------------------------ variant terms --
    def _end_vector(self, fl: Fields) -> np.ndarray:
        """``b_i = \\int_0^1 phi_i n = (C phi_i n)(1)``, shape (n, 2): d r(1) / d q_i."""
        return self._test(fl.normal)

    def end_mass_gravity(self, fl: Fields) -> np.ndarray:
        """Weight of the end mass: ``gamma Gamma \\int phi_i sin(theta + alpha)``.

        The gravity term of Eq. (20) with its lever arm 1 - xi (the pipe's
        weight beyond xi, Eq. (19) scaling) raised by Gamma, the end mass
        beyond every section: the gradient of gamma Gamma (cos alpha - X_g(1)).
        """
        p = self.params
        if not p.end_mass:
            return np.zeros(self.n)
        return p.gamma * p.end_mass * self._test(np.sin(fl.theta + p.alpha))

    def end_mass_inertia(self, fl: Fields) -> np.ndarray:
        """Inertia of the end mass: ``Gamma b_i . r_ddot(1)``.

        With r_ddot(1) = \\int_0^1 (theta_ddot n - theta_dot^2 t) the tip's
        acceleration, the inertia force field n . \\int_xi^1 r_ddot of Eq. (20)
        becomes n . (\\int_xi^1 r_ddot + Gamma r_ddot(1)); its weak form is this
        term: the theta_ddot part Gamma b b^T q'' (in :meth:`mass_matrix`) and
        the centripetal part -Gamma b . \\int theta_dot^2 t.  It is the Lagrange
        derivative of the end mass's kinetic energy (Gamma/2) |r_dot(1)|^2.
        """
        G = self.params.end_mass
        if not G:
            return np.zeros(self.n)
        acc = self.quad.integrate(
            fl.theta_ddot[:, None] * fl.normal - fl.theta_dot[:, None] ** 2 * fl.tangent
        )
        return G * (self._end_vector(fl) @ acc)

    def external_damping(self, fl: Fields) -> np.ndarray:
        """External viscous damping: ``sigma \\int phi_i n . C^R C(theta_dot n)``.

        The force -sigma r_dot per unit length on the centreline, r_dot =
        C(theta_dot n) its whole velocity (not only the lateral part), does
        the virtual work -sigma \\int_0^1 r_dot . delta r with delta r =
        C(delta theta n); exchanging the integrals gives the inertia projection
        with r_ddot replaced by r_dot, so this term is sigma M_pipe(q) q'
        (``M_pipe`` the mass matrix without end mass).  Its power is
        sigma \\int_0^1 |r_dot|^2 (:func:`fempipe.analyses.dynamics.power_terms`).
        """
        sigma = self.params.external_damping
        if not sigma:
            return np.zeros(self.n)
        return sigma * self._project(self.quad.cumulative(fl.theta_dot[:, None] * fl.normal), fl)

    def _part_rule(self, xi_s: float) -> _PartRule:
        """The Gauss rule on [0, xi_s] (cached per position).

        The cells of the model's quadrature before xi_s keep their points; if
        xi_s lies inside a cell, the part [x_c, xi_s] of that cell gets a Gauss
        rule of as many points, with the basis evaluated there
        (``disc.basis_values``).  For finite elements every part is inside
        one element, where theta is a polynomial: the rule is then as exact as
        the model's own on whole cells, whatever xi_s.
        """
        rule = self._part_rules.get(xi_s)
        if rule is not None:
            return rule
        quad, Phi = self.quad, self.disc.Phi
        edges = quad.edges
        k = int(np.argmin(np.abs(edges - xi_s)))
        at_node = abs(edges[k] - xi_s) <= 1e-13
        if at_node:
            m = k * quad.n_gauss
            x, w = quad.x[:m], quad.w[:m]
            P = Phi[:m]
        else:
            c = int(np.searchsorted(edges, xi_s, side="right")) - 1  # cell with xi_s inside
            m = c * quad.n_gauss
            h = xi_s - edges[c]
            xp = edges[c] + h * quad.ref_points
            x = np.concatenate([quad.x[:m], xp])
            w = np.concatenate([quad.w[:m], h * quad.ref_weights])
            Pp = self.disc.basis_values(xp)
            P = (
                sp.vstack([Phi[:m], sp.csr_matrix(Pp)]).tocsr()
                if sp.issparse(Phi)
                else (np.vstack([np.asarray(Phi)[:m], np.asarray(Pp)]))
            )
        rule = _PartRule(x=x, w=w, Phi=P.tocsr() if sp.issparse(P) else P, at_node=at_node)
        self._part_rules[xi_s] = rule
        return rule

    def part_rule(self, xi_s: float) -> _PartRule:
        """The Gauss rule on [0, xi_s] with the basis at its points (see :meth:`_part_rule`)."""
        return self._part_rule(xi_s)

    def spring_forces(self, q: np.ndarray) -> list[np.ndarray]:
        """Per spring, its force on the pipe ``-kappa (r(xi_s) - (xi_s, 0))``, shape (2,)."""
        return [-kappa * d for kappa, _r, _t, _n, _b, d in self._spring_states(q)]

    def _spring_states(self, q: np.ndarray):
        """Per spring: (kappa, rule, t, n, b_s, d) with d = r(xi_s) - (xi_s, 0) and
        ``b_s[i] = \\int_0^xi_s phi_i n = d r(xi_s) / d q_i``."""
        q = np.asarray(q)
        out = []
        for kappa, xi_s in self.params.springs:
            rule = self._part_rule(xi_s)
            th = rule.Phi @ q
            s, c = np.sin(th), np.cos(th)
            t = np.stack([c, s], axis=1)
            nrm = np.stack([-s, c], axis=1)
            # r(xi_s) - (xi_s, 0) = \int_0^xi_s (cos theta - 1, sin theta): the rule
            # integrates 1 to xi_s, and 1 - cos = 2 sin^2(theta/2) has no
            # cancellation, so the force vanishes at the straight pipe exactly
            # (as bending and the follower term do: Newton's test measures it
            # as it is).
            d = rule.w @ np.stack([-2.0 * np.sin(0.5 * th) ** 2, s], axis=1)
            b = np.asarray(rule.Phi.T @ (rule.w[:, None] * nrm))
            out.append((kappa, rule, t, nrm, b, d))
        return out

    def spring(self, q: np.ndarray) -> np.ndarray:
        """Springs: ``sum kappa \\int_0^xi_s phi_i n . (r(xi_s) - (xi_s, 0))``.

        Each spring (kappa, xi_s) ties the centreline point r(xi_s) =
        \\int_0^xi_s t (local frame of Eq. (5): r = (xi + varsigma, eta)) to its
        undeformed position (xi_s, 0) with the isotropic potential
        (kappa/2) |r(xi_s) - (xi_s, 0)|^2, kappa = k L^3/EI; this term is its
        gradient.  In strong form it is a point force at xi_s: theta'' jumps
        there by kappa n(xi_s) . (r(xi_s) - (xi_s, 0)) (a kink of theta').  The
        integrals over [0, xi_s] use :meth:`_part_rule`.
        """
        r = np.zeros(self.n)
        for kappa, _rule, _t, _n, b, d in self._spring_states(q):
            r = r + kappa * (b @ d)
        return r

    def spring_jacobian(self, q: np.ndarray, dense: bool = False):
        """d(spring)/dq, symmetric: ``kappa (b_s b_s^T - Phi_s^T diag(w_s t . d) Phi_s)``.

        Sparse for finite elements unless ``dense``; b_s b_s^T is a dense
        block on the dofs of [0, xi_s].
        """
        n = self.n
        sparse = self.disc.sparse and not dense
        J = sp.csr_matrix((n, n)) if sparse else np.zeros((n, n))
        for kappa, rule, t, _nrm, b, d in self._spring_states(q):
            wt = -kappa * rule.w * (t @ d)
            local = rule.Phi.T @ _rows(wt, rule.Phi)  # banded for finite elements
            if sparse:
                B = sp.csr_matrix(b)
                J = J + local + kappa * (B @ B.T)
            else:
                J = J + _dense(local) + kappa * (b @ b.T)
        return J.tocsr() if sparse else J

    def mass_matrix(self, q: np.ndarray) -> np.ndarray:
        """``M_ij = \\int_0^1 (C phi_i n).(C phi_j n) + Gamma b_i . b_j``, dense SPD, shape (n, n).

        Identical (to round-off) to ``d (inertia + end_mass_inertia) / d q''``;
        the Gram form makes the symmetry exact.  b_i = (C phi_i n)(1)
        (:meth:`end_mass_inertia`).
        """
        fl = self.fields(q)
        M = self._pipe_mass(fl)
        G = self.params.end_mass
        if G:
            b = self._end_vector(fl)
            M = M + G * (b @ b.T)
        return M

    def _pipe_mass(self, fl: Fields) -> np.ndarray:
        """``\\int_0^1 (C phi_i n).(C phi_j n)``: the pipe's own mass matrix."""
        B = self.quad.cumulative(self._phi_field(fl.normal))  # (n_q, 2, n)
        M = np.einsum("qcj,qck->jk", B * self.w[:, None, None], B)
        return 0.5 * (M + M.T)

    # ------------------------------------------------------- totals --
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
        """``C^d q' + M^d q''`` at the static state q, in O(n_q) without forming them.

        The part of R linear in the rates at (q, 0, 0) (Eqs. (33b), (33c)):
        Kelvin-Voigt, Coriolis, external damping, the pipe's and the end
        mass's inertia (the centripetal terms are quadratic in q' and drop
        out).  Equal to ``jacobians(q)[1] @ qdot + jacobians(q)[2] @ qddot``.
        """
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

        ``gravity`` is the weight of the pipe and of the end mass
        (:meth:`gravity` + :meth:`end_mass_gravity`), ``springs`` the sum of
        :meth:`spring` (zero without springs).  Their sum, in this order, is
        :meth:`static_residual` to the last bit; their sizes say how small the
        residual must be to call q an equilibrium
        (:func:`fempipe.analyses.statics.solve_static`).
        """
        fl = self.fields(q)
        p = self.params
        g = self.gravity(fl)
        if p.end_mass:
            g = g + self.end_mass_gravity(fl)
        s = self.spring(q) if p.springs else np.zeros(self.n)
        return self.bending(q), g, self.follower(fl), s

    def gravity_load(self) -> float:
        """``gamma ||\\int phi_i (1 - xi + Gamma)||``: the size of the gravity term (end
        mass included) whatever its lever arm sin(theta + alpha) (a norm of the
        weak-form vector, like R)."""
        p = self.params
        return p.gamma * float(np.linalg.norm(self._test(1.0 - self.x + p.end_mass)))

    def static_jacobian(self, q: np.ndarray, dense: bool = False):
        """dR(q, 0, 0)/dq: sparse for finite elements, dense for modes or if ``dense``.

        The dense form is one product ``Phi^T diag(d) Phi`` (gravity and the
        local follower part) plus the follower's tip column and the springs:
        for the small systems of the continuation (n of a few hundred) it is
        ~10 times cheaper than building the sparse matrix from its parts.
        """
        if dense:
            fl = self.fields(q)
            d_follower, tip_col = self._follower_weights(fl)
            d = self._gravity_weight(fl) + d_follower
            Phi = self._Phi_dense
            J = self._K_dense + (Phi.T * d) @ Phi + np.outer(tip_col, self.disc.tip)
            if self.params.springs:
                J = J + self.spring_jacobian(q, dense=True)
            return J
        fl = self.fields(q)
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
        # The gravity, follower (local part) and normal-derivative terms are all
        # Phi^T diag(d) Phi: one dense product instead of three small sparse
        # ones (scipy.sparse overhead dominated the time-integration cost).
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
        """K^d, C^d, M^d of the linear problem about the static state q, in the plane
        (:meth:`static_jacobians`); the stability solvers call this."""
        return self.static_jacobians(q)

    def hysteretic_stiffness(self, q: np.ndarray) -> np.ndarray:
        """The stiffness the hysteretic loss factor multiplies: bending, ``disc.K`` (dense)."""
        return self._K_dense

    def static_jacobians(self, q):
        """:meth:`jacobians` at the static state (q, 0, 0): K^d, C^d, M^d of Eqs. (31b)-(33).

        The same terms with theta_dot = theta_ddot = 0 dropped before they are
        formed: the inner field F of the projection and its q-derivative
        vanish, so the normal-derivative weight, the q-derivative through F and
        the end mass's acceleration terms are zero, and the two cumulative
        integrals of (n_q, 2, n) fields they need are not computed.  Equal to
        ``jacobians(q)`` (only exact zeros are left out); about half its cost.
        """
        fl = self.fields(q)
        p = self.params
        cv = 2.0 * p.v * np.sqrt(p.beta)
        d_follower, tip_col = self._follower_weights(fl)
        d = self._gravity_weight(fl) + d_follower
        Phi = self._Phi_dense
        Jqd = p.mu * self._K_dense + self._project_jac(self._phi_field(cv * fl.normal), fl)
        M_pipe = self._pipe_mass(fl)
        if p.external_damping:
            Jqd = Jqd + p.external_damping * M_pipe
        M = M_pipe
        if p.end_mass:
            b = self._end_vector(fl)
            M = M + p.end_mass * (b @ b.T)
        Jq = self._K_dense + (Phi.T * d) @ Phi + np.outer(tip_col, self.disc.tip)
        if p.springs:
            Jq = Jq + self.spring_jacobian(q, dense=True)
        return Jq, Jqd, M

    # ------------------------------------------------------- energy --
    def kinetic_energy(self, q, qdot) -> float:
        """T = (1/2) \\int_0^1 |r_dot|^2 + (Gamma/2) |r_dot(1)|^2 = (1/2) q'^T M(q) q'."""
        fl = self.fields(q, qdot)
        rdot = self.quad.cumulative(fl.theta_dot[:, None] * fl.normal)
        T = 0.5 * float(self.w @ np.einsum("qc,qc->q", rdot, rdot))
        G = self.params.end_mass
        if G:
            tip = self.quad.integrate(fl.theta_dot[:, None] * fl.normal)
            T += 0.5 * G * float(tip @ tip)
        return T

    def potential_energy(self, q) -> float:
        """Bending, gravity and springs.

        ``(1/2) q^T K q + gamma [cos(alpha)/2 - \\int (1 - xi) cos(theta + alpha)]
        + gamma Gamma [cos(alpha) - \\int cos(theta + alpha)]
        + sum (kappa/2) |r(xi_s) - (xi_s, 0)|^2``.
        The constants make the straight pipe's gravity energy zero; the end
        mass's is gamma Gamma (cos alpha - X_g(1)).
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
        """Total mechanical energy E = T + V, conserved for v = 0, mu = 0 and sigma = 0.

        See :func:`fempipe.analyses.dynamics.power_terms` for dE/dtau in general.
        """
        return self.kinetic_energy(q, qdot) + self.potential_energy(q)

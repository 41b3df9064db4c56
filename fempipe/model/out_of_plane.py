"""The linearized motion out of the plane of a planar static state, one operator per term.

A round pipe is free to leave the plane of its static deformation.  This
module gives the linear problem of that motion about any planar static state
theta^s of Eq. (31a), on the same discretizations as the planar model; the
stability solvers run on it unchanged (:class:`OutOfPlaneModel`).  The
derivation is in the docs ("Out of the plane"); in short:

* **The unknown.**  The tangent of the deformed pipe is
  t = cos(psi) (cos theta, sin theta, 0) + sin(psi) e_3 in the pipe's frame
  (e_1 along the clamp, e_2 the in-plane normal, e_3 out of the plane); psi is
  the rotation of the tangent out of the plane, the out-of-plane analogue of
  theta, with psi(0) = 0 (clamp) and psi'(1) = 0 (no moment at the free end).
  The out-of-plane deflection is w = \\int_0^xi psi.  About a planar state the
  in-plane and out-of-plane perturbations decouple (mirror symmetry
  e_3 -> -e_3): this is the psi part.
* **No twist.**  For an isotropic section the elastic bending moment
  m = t x t' (EI = 1) is parallel to the curvature vector, so m . t' = 0;
  the moment balance m' + t x n = 0 then gives (m . t)' = m . t' = 0: the
  twisting moment is the same at every section, zero at the torque-free free
  end, so the twist stays zero and GJ drops out.  The centerline alone is the
  state.  (The damping moment below is not parallel to the curvature; the
  twist it would cause is O(mu) and is taken as zero: the pipe is
  torsionally stiff against it, and the reaction torque does no work.)
* **Stiffness** (the second variation of the energy, and the follower
  force from the moment balance): with |t'|^2 = psi'^2 + theta'^2 cos^2 psi
  the bending energy gives ``\\int psi'^2 - theta'^2 psi^2``; the static
  force n^s of the planar state (gravity, the jet's reaction, the end mass,
  the springs) acts on the out-of-plane rotation through its axial component
  N = n^s . t^s:

      N(xi) = gamma (1 - xi + Gamma) cos(theta^s + alpha)
              + v^2 (1 - cos(theta^s(1) - theta^s))
              + sum_s H(xi_s - xi) F_s . t^s,     F_s = -kappa (r^s(xi_s) - xi_s e_1),

  and the follower force of the discharging fluid adds v^2 (psi(1) - psi).
* **Inertia, Coriolis, external damping**: the out-of-plane acceleration
  w_ddot = \\int_0^xi psi_ddot along the fixed direction e_3, so these are the
  planar terms of the straight pipe (cos(theta^s(xi) - theta^s(r)) -> 1);
  the end mass adds Gamma w_ddot(1), a spring kappa w(xi_s).
* **Kelvin-Voigt damping, objective**: the damping moment acts on the
  co-rotational rate of the curvature vector kappa = t x t', the rate seen in
  the section's own (twist-free) frame.  Linearized it is chi_dot n^s with

      chi = psi' + theta^s'(xi) \\int_0^xi theta^s' psi

  (the second term: the frame's spin about the tangent, which a rigid
  rotation of the curved pipe carries); the damping is the Rayleigh
  dissipation (mu/2) \\int chi_dot^2, so C_KV = mu \\int B phi_i B phi_j with
  B psi = chi: symmetric, semi-definite, mu K on a straight pipe (the
  paper's mu theta_dot'').  The hysteretic loss acts on the same material
  curvature: i mu_h sgn(omega) \\int B phi_i B phi_j.

Every term equals the planar one on the straight pipe (theta^s = 0): there the
out-of-plane spectrum is the in-plane spectrum (alpha = 0, and the straight
branch at alpha = pi).  On the buckled branches of the standing pipe
(sin alpha = 0, theta^s != 0) the rotation of the buckled shape about the
vertical is a neutral mode: psi = sin(theta^s) (w = eta^s, the rotated
static shape) solves K psi = 0 exactly in the continuum (docs).  A
discretization does not contain sin(theta^s) exactly: for its L2 projection
x, ||K x|| / (||K|| ||x||) is O(h^4) on P1 to P3 elements (measured: 3.4e-3,
2.7e-4, 1.7e-5, 1.1e-6 on P3 with 4 to 32 elements), and the smallest
eigenvalue of K is O(h^2k) instead of 0 (P3: 1.2e-2, 1.5e-4, 2.5e-6,
4.0e-8).  :meth:`OutOfPlaneOperators.matrices` restores the symmetry with
the rank-one correction K - (K x)(M x)^T / (x^T M x), which makes lambda = 0
exact to round-off with eigenvector x (``neutral_residual`` reports ||K x||
before it).  The other eigenvalues move by far less than ||K x|| (4e-10
relative on P3:16, where ||K x|| is 1.7e-5) and still converge as h^2k.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .operators import PipeModel

__all__ = ["OutOfPlaneMatrices", "OutOfPlaneModel", "OutOfPlaneOperators"]


def _dense(A) -> np.ndarray:
    return A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)


@dataclass(frozen=True)
class _State:
    """The planar static state at the quadrature points (what the operators need of it)."""

    theta: np.ndarray  # (n_q,)
    dtheta: np.ndarray  # theta' (n_q,)
    theta_tip: float
    q: np.ndarray


@dataclass(frozen=True)
class OutOfPlaneMatrices:
    """K, C, M of the out-of-plane problem about one planar static state.

    Attributes
    ----------
    K, C, M : ndarray, shape (n, n)
        Stiffness, damping and mass: M psi_ddot + C psi_dot + K psi = 0.
    material : ndarray, shape (n, n)
        ``\\int B phi_i B phi_j``, the material bending stiffness (the
        hysteretic loss acts on it; C_KV = mu times it).
    neutral : ndarray or None, shape (n,)
        On an axisymmetric buckled state, the rotation mode (L2 projection of
        sin theta^s) made an exact null vector of K; None otherwise.
    neutral_residual : float or None
        ||K x|| / (||K_b||_2 ||x||) before the correction (K_b the bending
        matrix, the leading part of K): how far the
        discretization is from the continuum's exact neutral mode.
    """

    K: np.ndarray
    C: np.ndarray
    M: np.ndarray
    material: np.ndarray
    neutral: np.ndarray | None = None
    neutral_residual: float | None = None


#: max |theta^s| below which a state of the standing or hanging pipe is the
#: straight pipe (no neutral rotation mode: every plane is alike).
STRAIGHT_TOL = 1e-8

_FIXED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


class OutOfPlaneOperators:
    """The weak form of the out-of-plane problem (module docstring), one method per term.

    Parameters
    ----------
    model : PipeModel
        The planar pipe: its discretization, parameters and static states.

    Notes
    -----
    The state-independent matrices (inertia, Coriolis, the follower's, the
    plain integrals) depend on the discretization only and are computed once
    per discretization; a spectrum then costs one O(n_q n^2) product for the
    curvature-dependent terms.
    """

    def __init__(self, model: PipeModel) -> None:
        self.model = model
        self.disc = model.disc
        self.quad = model.disc.quad
        self.w = self.quad.w
        self.x = self.quad.x

    @property
    def params(self):
        return self.model.params

    # -------------------------------------------------- fixed pieces --
    def fixed(self) -> dict:
        """Phi, dPhi dense; the pipe's mass, the integrals C^R phi_j and \\int phi_i."""
        d = _FIXED.get(self.disc)
        if d is None:
            Phi = _dense(self.disc.Phi)
            dPhi = _dense(self.disc.dPhi)
            CPhi = self.quad.cumulative(Phi)  # w = C psi: out-of-plane deflection
            RPhi = self.quad.from_tip(Phi)  # \int_xi^1 psi
            WPhi = Phi * self.w[:, None]
            d = _FIXED[self.disc] = {
                "Phi": Phi,
                "dPhi": dPhi,
                "CPhi": CPhi,
                "mass": (CPhi * self.w[:, None]).T @ CPhi,
                "coriolis": WPhi.T @ RPhi,
                "integral": WPhi.sum(axis=0),  # \int phi_i = (C phi_i)(1)
                "gram": WPhi.T @ Phi,
                "K": _dense(self.disc.K),
            }
            # ||K||_2 of the bending matrix, the leading part of K at every state:
            # the scale of neutral_residual, one SVD per discretization.
            d["K_norm"] = float(np.linalg.norm(d["K"], 2))
        return d

    def state(self, q: np.ndarray) -> _State:
        """theta^s and theta^s' at the quadrature points."""
        f = self.fixed()
        q = np.asarray(q, dtype=float)
        return _State(
            theta=f["Phi"] @ q,
            dtheta=f["dPhi"] @ q,
            theta_tip=float(self.disc.tip @ q),
            q=q,
        )

    def weighted_gram(self, d: np.ndarray) -> np.ndarray:
        """``\\int d phi_i phi_j`` for d at the quadrature points."""
        Phi = self.fixed()["Phi"]
        return (Phi * (self.w * d)[:, None]).T @ Phi

    # ---------------------------------------------------- stiffness --
    def bending(self, st: _State) -> np.ndarray:
        """``\\int phi_i' phi_j' - \\int theta^s'^2 phi_i phi_j``: bending of the curved pipe.

        The second variation of (1/2) \\int |t'|^2 = (1/2) \\int psi'^2 + theta'^2 cos^2 psi:
        out of the plane the static curvature softens the pipe.
        """
        return self.fixed()["K"] - self.weighted_gram(st.dtheta**2)

    def axial_force(self, st: _State) -> np.ndarray:
        """N = n^s . t^s at the quadrature points (without the springs, :meth:`spring_axial`).

        Gravity of the pipe beyond xi and of the end mass, and the jet's
        reaction v^2 (t^s(1) - t^s) projected on the tangent (module docstring).
        """
        p = self.params
        v2 = p.v * p.v
        grav = p.gamma * (1.0 - self.x + p.end_mass) * np.cos(st.theta + p.alpha)
        # 1 - cos(a) as 2 sin^2(a/2): no cancellation near the straight pipe.
        jet = v2 * 2.0 * np.sin(0.5 * (st.theta_tip - st.theta)) ** 2
        return grav + jet

    def geometric_stiffness(self, st: _State) -> np.ndarray:
        """``\\int N phi_i phi_j`` (the springs' part in :meth:`spring`)."""
        return self.weighted_gram(self.axial_force(st))

    def follower(self) -> np.ndarray:
        """``v^2 \\int phi_i (phi_j(1) - phi_j)``: the discharging jet turns with the tip."""
        f = self.fixed()
        v2 = self.params.v * self.params.v
        return v2 * (np.outer(f["integral"], self.disc.tip) - f["gram"])

    def spring(self, st: _State) -> np.ndarray:
        """Springs: ``kappa b_i b_j`` (w(xi_s) tied) plus their static force's axial part.

        b_i = \\int_0^xi_s phi_i; the static spring force F_s acts on the
        sections before xi_s: ``\\int_0^xi_s (F_s . t^s) phi_i phi_j``, on the Gauss
        rule of [0, xi_s] (:meth:`~fempipe.model.operators.PipeModel.part_rule`).
        """
        n = self.disc.n
        S = np.zeros((n, n))
        for (kappa, xi_s), force in zip(
            self.params.springs, self.model.spring_forces(st.q), strict=True
        ):
            rule = self.model.part_rule(xi_s)
            P = _dense(rule.Phi)
            b = P.T @ rule.w
            th = P @ st.q
            axial = force[0] * np.cos(th) + force[1] * np.sin(th)
            S += kappa * np.outer(b, b) + (P * (rule.w * axial)[:, None]).T @ P
        return S

    # ------------------------------------------------- rate matrices --
    def inertia(self) -> np.ndarray:
        """``\\int (C phi_i)(C phi_j) + Gamma (\\int phi_i)(\\int phi_j)``: the mass, SPD."""
        f = self.fixed()
        G = self.params.end_mass
        M = f["mass"]
        if G:
            M = M + G * np.outer(f["integral"], f["integral"])
        return 0.5 * (M + M.T)

    def coriolis(self) -> np.ndarray:
        """``2 v sqrt(beta) \\int phi_i \\int_xi^1 phi_j``."""
        p = self.params
        return 2.0 * p.v * math.sqrt(p.beta) * self.fixed()["coriolis"]

    def external_damping(self) -> np.ndarray:
        """``sigma \\int (C phi_i)(C phi_j)``: the force -sigma w_dot per unit length."""
        return self.params.external_damping * self.fixed()["mass"]

    def curvature_rate(self, st: _State) -> np.ndarray:
        """B phi_j at the quadrature points, shape (n_q, n): chi = psi' + theta' C(theta' psi)."""
        f = self.fixed()
        d = st.dtheta[:, None]
        return f["dPhi"] + d * self.quad.cumulative(d * f["Phi"])

    def material_bending(self, st: _State) -> np.ndarray:
        """``\\int B phi_i B phi_j``: the stiffness of the material curvature."""
        B = self.curvature_rate(st)
        return (B * self.w[:, None]).T @ B

    def kelvin_voigt(self, st: _State) -> np.ndarray:
        """``mu \\int B phi_i B phi_j``: the objective Kelvin-Voigt damping (module docstring)."""
        return self.params.mu * self.material_bending(st)

    # -------------------------------------------------------- totals --
    def matrices(self, q: np.ndarray) -> OutOfPlaneMatrices:
        """K, C, M about the planar static state q (with the neutral mode where it exists)."""
        st = self.state(q)
        p = self.params
        K = self.bending(st) + self.geometric_stiffness(st) + self.follower()
        if p.springs:
            K = K + self.spring(st)
        material = self.material_bending(st) if (p.mu or p.hysteretic_damping) else None
        C = self.coriolis()
        if p.mu:
            C = C + p.mu * material
        if p.external_damping:
            C = C + self.external_damping()
        M = self.inertia()
        if material is None:
            material = self.fixed()["K"]  # not used (no loss): the straight pipe's
        neutral, resid = None, None
        if axisymmetric(p) and np.max(np.abs(st.theta)) > STRAIGHT_TOL:
            K, neutral, resid = self._with_neutral_mode(K, M, st)
        return OutOfPlaneMatrices(K, C, M, material, neutral, resid)

    def neutral_mode(self, q: np.ndarray) -> np.ndarray:
        """The L2 projection of sin theta^s on the basis: the buckled shape turned out of the plane."""
        st = self.state(q)
        f = self.fixed()
        rhs = f["Phi"].T @ (self.w * np.sin(st.theta))
        return np.linalg.solve(f["gram"], rhs)

    def _with_neutral_mode(self, K, M, st: _State):
        x = self.neutral_mode(st.q)
        Kx = K @ x
        scale = self.fixed()["K_norm"] * np.linalg.norm(x)
        resid = float(np.linalg.norm(Kx) / scale) if scale > 0 else 0.0
        Mx = M @ x
        K = K - np.outer(Kx, Mx) / float(x @ Mx)
        return K, x, resid


def axisymmetric(params) -> bool:
    """Whether gravity acts along the clamp's axis (sin alpha = 0): rotations about it are
    symmetries of the pipe (the springs and the end mass are isotropic)."""
    return abs(math.sin(params.alpha)) < 1e-12


class OutOfPlaneModel(PipeModel):
    """The planar pipe whose linearization is the out-of-plane problem.

    Its static states, residual and static Jacobian are those of
    :class:`~fempipe.model.operators.PipeModel` (the static state of a round pipe
    under in-plane loads is planar); :meth:`linearization` and
    :meth:`hysteretic_stiffness` are the out-of-plane ones
    (:class:`OutOfPlaneOperators`), so every stability solver
    (:func:`fempipe.analyses.stability.spectrum`, :func:`fempipe.analyses.stability.stability_analysis`)
    analyses the motion out of the plane when given this model.
    """

    plane = "out"

    @property
    def operators(self) -> OutOfPlaneOperators:
        return OutOfPlaneOperators(self)

    def linearization(self, q: np.ndarray):
        m = self.operators.matrices(q)
        return m.K, m.C, m.M

    def hysteretic_stiffness(self, q: np.ndarray) -> np.ndarray:
        ops = self.operators
        return ops.material_bending(ops.state(q))

    def rate_terms(self, q, qdot, qddot) -> np.ndarray:
        _, C, M = self.linearization(q)
        return C @ np.asarray(qdot) + M @ np.asarray(qddot)

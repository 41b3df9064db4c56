"""The linearized motion out of the plane of a planar static state, one operator per term.

The linear problem, in the rotation psi of the tangent out of the plane (psi(0) = 0,
psi'(1) = 0), about any planar static state of Eq. (31a), on the planar model's
discretizations.  :class:`OutOfPlaneOperators` is its weak form, one method per term;
:class:`OutOfPlaneModel` carries it as a pipe model so the stability solvers run on it
unchanged (:func:`build_out_of_plane_model`, :func:`build_in_plane_model`).  On the buckled branches of
the standing pipe, the rotation about the vertical is made an exact neutral mode.

Derivation: docs/theory/out_of_plane.md.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass

import numpy as np

from fempipe.model.plane.operators import PipeModel
from fempipe.model.weak_form import as_dense

__all__ = [
    "OutOfPlaneMatrices",
    "OutOfPlaneModel",
    "OutOfPlaneOperators",
    "build_in_plane_model",
    "build_out_of_plane_model",
]


@dataclass(frozen=True)
class _State:
    """The planar static state at the quadrature points (what the operators need of it)."""

    theta: np.ndarray  # (n_q,)
    dtheta: np.ndarray  # theta' (n_q,)
    theta_tip: float
    q: np.ndarray


@dataclass(frozen=True)
class OutOfPlaneMatrices:
    r"""K, C, M of the out-of-plane problem about one planar static state.

    Attributes
    ----------
    K, C, M : ndarray, shape (n, n)
        M psi_ddot + C psi_dot + K psi = 0.
    material : ndarray, shape (n, n)
        ``\int B phi_i B phi_j``, the material bending stiffness (C_KV = mu times it).
    neutral : ndarray or None, shape (n,)
        On an axisymmetric buckled state, the rotation mode made an exact null vector of K.
    neutral_residual : float or None
        ||K x|| / (||K_b||_2 ||x||) before that correction.
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
    """The weak form of the out-of-plane problem, one method per term, about the planar
    :class:`~fempipe.model.plane.operators.PipeModel` ``model``."""

    def __init__(self, model: PipeModel) -> None:
        self.model = model
        self.disc = model.disc
        self.quad = model.disc.quad
        self.w = self.quad.w
        self.x = self.quad.x

    @property
    def params(self):
        return self.model.params

    def fixed(self) -> dict:
        """Phi, dPhi dense; the pipe's mass, the integrals C^R phi_j and \\int phi_i."""
        d = _FIXED.get(self.disc)
        if d is None:
            Phi = as_dense(self.disc.Phi)
            dPhi = as_dense(self.disc.dPhi)
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
                "K": as_dense(self.disc.K),
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
            theta=f["Phi"] @ q, dtheta=f["dPhi"] @ q, theta_tip=float(self.disc.tip @ q), q=q
        )

    def weighted_gram(self, d: np.ndarray) -> np.ndarray:
        """``\\int d phi_i phi_j`` for d at the quadrature points."""
        Phi = self.fixed()["Phi"]
        return (Phi * (self.w * d)[:, None]).T @ Phi

    def bending(self, st: _State) -> np.ndarray:
        r"""``\int phi_i' phi_j' - \int theta^s'^2 phi_i phi_j``: out of the plane the static curvature softens the pipe."""
        return self.fixed()["K"] - self.weighted_gram(st.dtheta**2)

    def axial_force(self, st: _State) -> np.ndarray:
        """N = n^s . t^s at the quadrature points: gravity, end mass and the jet's reaction (springs apart)."""
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
        r"""Springs: ``kappa b_i b_j`` (w(xi_s) tied), b_i = \int_0^xi_s phi_i, plus the axial part
        ``\int_0^xi_s (F_s . t^s) phi_i phi_j`` of their static force.
        """
        n = self.disc.n
        S = np.zeros((n, n))
        for (kappa, xi_s), force in zip(
            self.params.springs, self.model.spring_forces(st.q), strict=True
        ):
            rule = self.model.part_rule(xi_s)
            P = as_dense(rule.Phi)
            b = P.T @ rule.w
            th = P @ st.q
            axial = force[0] * np.cos(th) + force[1] * np.sin(th)
            S += kappa * np.outer(b, b) + (P * (rule.w * axial)[:, None]).T @ P
        return S

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
        """``mu \\int B phi_i B phi_j``: the objective Kelvin-Voigt damping (docs/theory/out_of_plane.md)."""
        return self.params.mu * self.material_bending(st)

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
    """The planar pipe (static states, residual, static Jacobian: ``PipeModel``'s) whose
    :meth:`linearization` and :meth:`hysteretic_stiffness` are out of the plane."""

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


def build_out_of_plane_model(model: PipeModel) -> OutOfPlaneModel:
    """An :class:`OutOfPlaneModel` of ``model``'s pipe (``model`` itself if it is one)."""
    if isinstance(model, OutOfPlaneModel):
        return model
    return OutOfPlaneModel(model.disc, model.params)


def build_in_plane_model(model: PipeModel) -> PipeModel:
    """``model``'s pipe with its linearization in the plane (a PipeModel unless it already is one)."""
    if model.plane == "in":
        return model
    return PipeModel(model.disc, model.params)

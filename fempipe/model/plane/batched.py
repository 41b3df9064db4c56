"""The pipe's residual, Jacobians and dR/dv at several states in one call (the Radau stages).

On small meshes :meth:`PipeModel.residual <fempipe.model.plane.operators.PipeModel.residual>` is
mostly call overhead, so :class:`StageKernels` evaluates the terms of Eq. (20) for S states
stacked in (S, n) arrays at once, for the pipe without variants and steady flow
(:meth:`StageKernels.for_model` returns None otherwise).  The integration operators are
dense matrices up to :data:`DENSE_INTEGRALS_MAX` points, cell by cell beyond.

Derivation: docs/theory/weak_form.md, "Projections on the test side".
"""

from __future__ import annotations

import math

import numpy as np

from fempipe.model.plane.operators import PipeModel
from fempipe.model.quadrature import LineQuadrature
from fempipe.model.weak_form import as_dense

__all__ = [
    "DENSE_INTEGRALS_MAX",
    "DENSE_OPERATORS_MAX",
    "StageKernels",
    "frames",
    "integral_operators",
    "projection_fields",
    "stage_operators",
]

#: Up to this many entries (n_q n) Phi, K and Phi^T W are applied as dense
#: arrays in the batched stage functions: for the small systems of limit
#: cycles and continuation (P3:16: 96 x 48) a dense product costs less than
#: scipy.sparse's dispatch alone.
DENSE_OPERATORS_MAX = 32768

#: Up to this many quadrature points the integration operators are applied as
#: dense (n_q, n_q) matrices (one BLAS product; O(n_q^2) work, which beyond
#: this is more than the O(n_q) of :meth:`LineQuadrature.cumulative_cells`): with one
#: BLAS thread a Jacobian evaluation is cheaper dense up to P3:16 (n_q = 96) and cheaper
#: cell by cell from the sine modes' 256 points on.
DENSE_INTEGRALS_MAX = 128


def stage_operators(model: PipeModel):
    """(Phi, K, Phi^T W): dense up to :data:`DENSE_OPERATORS_MAX` entries n_q n, else the model's."""
    Phi, K, PhiT_W = model.disc.Phi, model.disc.K, model.test_matrix
    if model.quad.n_q * model.n <= DENSE_OPERATORS_MAX:
        Phi, K, PhiT_W = (as_dense(a) for a in (Phi, K, PhiT_W))
    return Phi, K, PhiT_W


def frames(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normal and tangent, each (n_q, 2, S), of the angles th, shape (n_q, S)."""
    s, c = np.sin(th), np.cos(th)
    nrm = np.empty((th.shape[0], 2, th.shape[1]))
    tng = np.empty_like(nrm)
    nrm[:, 0], nrm[:, 1] = -s, c
    tng[:, 0], tng[:, 1] = c, s
    return nrm, tng


def integral_operators(quad: LineQuadrature):
    r"""(C, C^R): functions applying ``\int_0^{x_q}`` and ``\int_{x_q}^1`` along axis 0."""
    n_q = quad.n_q
    if n_q > DENSE_INTEGRALS_MAX:
        return quad.cumulative_cells, quad.from_tip_cells
    eye = np.eye(n_q)
    Cm, Rm = quad.cumulative(eye), quad.from_tip(eye)

    def cumulative(f):
        return (Cm @ f.reshape(n_q, -1)).reshape(f.shape)

    def from_tip(f):
        return (Rm @ f.reshape(n_q, -1)).reshape(f.shape)

    return cumulative, from_tip


def projection_fields(quad: LineQuadrature):
    """``g -> (V, U)`` with ``V = (C^R)^T (w g)`` and ``U = C^T V`` along axis 0: the projections
    ``sum w g C^R X = sum V X`` and ``sum w g C^R C X = sum U X`` moved onto the test side.
    """
    n_q, w = quad.n_q, quad.w
    if n_q <= DENSE_INTEGRALS_MAX:
        eye = np.eye(n_q)
        RwT = quad.from_tip(eye).T * w[None, :]
        stacked = np.vstack([RwT, quad.cumulative(eye).T @ RwT])

        def dense(g):
            out = stacked @ g.reshape(n_q, -1)
            return out[:n_q].reshape(g.shape), out[n_q:].reshape(g.shape)

        return dense

    def cells(g):
        wg = w[:, None] * g.reshape(n_q, -1)
        V = quad.cumulative_adjoint(wg)
        np.subtract(w[:, None] * wg.sum(axis=0)[None, :], V, out=V)
        return V.reshape(g.shape), quad.cumulative_adjoint(V).reshape(g.shape)

    return cells


class StageKernels:
    """Residual, Jacobians and dR/dv of the pipe without variants at S stacked states (rows
    ``Q, P, A`` of shape (S, n)), equal to the ``PipeModel``'s row by row, to round-off."""

    def __init__(self, model: PipeModel) -> None:
        p = model.params
        disc, quad = model.disc, model.quad
        self.n = model.n
        # The residual's operators (sparse on large discretizations) ...
        self._res_ops = stage_operators(model)
        # ... and the Jacobians' (always dense).
        self._Phi = as_dense(disc.Phi)
        self._K = as_dense(disc.K)
        self._tip = np.asarray(disc.tip, dtype=float)
        self._lever = p.gamma * (1.0 - model.x)[:, None]
        self._w = model.w
        self._grav = p.gamma * model.w * (1.0 - model.x)
        self._v, self._v2, self._cv = p.v, p.v * p.v, 2.0 * p.v * math.sqrt(p.beta)
        self._c1 = 2.0 * math.sqrt(p.beta)
        self._mu, self._alpha = p.mu, p.alpha
        self._cumulative, self._from_tip = integral_operators(quad)
        self._projection_fields = projection_fields(quad)
        self._PhiT_w = self._Phi.T * model.w  # (n, n_q): \int phi_i f
        self._w2 = np.repeat(model.w, 2)

    @staticmethod
    def applies_to(model: PipeModel) -> bool:
        """Whether the kernels know every term of ``model``: the pipe without
        variants (no end mass, external damping or springs), no subclass."""
        p = model.params
        return type(model) is PipeModel and not (p.end_mass or p.external_damping or p.springs)

    @classmethod
    def for_model(cls, model: PipeModel) -> StageKernels | None:
        """The kernels of ``model``, or None where :meth:`applies_to` is False."""
        return cls(model) if cls.applies_to(model) else None

    def residual(self, Q: np.ndarray, P: np.ndarray, Acc: np.ndarray) -> np.ndarray:
        """``R(Q_s, P_s, A_s)``, shape (S, n), with the inertia, centripetal and Coriolis terms as one
        projection of F = C(theta_ddot n - theta_dot^2 t) + 2 v sqrt(beta) theta_dot n.
        """
        Phi, K, PhiT_W = self._res_ops
        # Stages in columns: theta etc. have shape (n_q, S), frames (n_q, 2, S).
        th = np.asarray(Phi @ Q.T)
        th_d = np.asarray(Phi @ P.T)
        th_dd = np.asarray(Phi @ Acc.T)
        nrm, tng = frames(th)
        F = self._cumulative(th_dd[:, None] * nrm - (th_d**2)[:, None] * tng)
        F = F + self._cv * th_d[:, None] * nrm
        G = self._from_tip(F)
        local = self._lever * np.sin(th + self._alpha) + self._v2 * np.sin(
            (Q @ self._tip)[None, :] - th
        )
        local = local + np.einsum("qcs,qcs->qs", nrm, G)
        return (np.asarray(K @ (Q + self._mu * P).T) + np.asarray(PhiT_W @ local)).T

    def jacobians(self, Q: np.ndarray, P: np.ndarray, Acc: np.ndarray):
        """``(dR/dq, dR/dq', M)``, each (S, n, n), with the projections on the test side."""
        Phi, K, tip, w = self._Phi, self._K, self._tip, self._w
        n_q, n = Phi.shape
        cv, v2 = self._cv, self._v2
        S = Q.shape[0]
        th, th_d, th_dd = Phi @ Q.T, Phi @ P.T, Phi @ Acc.T  # (n_q, S)
        nrm, t = frames(th)  # (n_q, 2, S)
        F = self._cumulative(th_dd[:, None] * nrm - (th_d**2)[:, None] * t)
        F = F + cv * th_d[:, None] * nrm
        n_phi = nrm[..., None] * Phi[:, None, None, :]  # (n_q, 2, S, n): n phi_i
        V, U = self._projection_fields(n_phi)
        a = -th_dd[:, None] * t - (th_d**2)[:, None] * nrm
        ad = -2.0 * th_d[:, None] * t
        b, bd = -cv * th_d[:, None] * t, cv * nrm
        Z = np.empty((2 * S, n_q, n))  # the test fields of dR/dq, then of dR/dq'
        Z[:S] = np.einsum("qcs,qcsi->sqi", a, U) + np.einsum("qcs,qcsi->sqi", b, V)
        Z[S:] = np.einsum("qcs,qcsi->sqi", ad, U) + np.einsum("qcs,qcsi->sqi", bd, V)
        proj = Z.transpose(0, 2, 1) @ Phi
        cos_tip = np.cos((Q @ tip)[None, :] - th)  # (n_q, S)
        d = self._grav[:, None] * np.cos(th + self._alpha) - v2 * w[:, None] * cos_tip
        d = d - np.einsum("qcs,qcs->qs", t, self._from_tip(F)) * w[:, None]
        tip_col = v2 * (self._PhiT_w @ cos_tip)  # (n, S)
        Jq = K[None] + (Phi.T[None] * d.T[:, None, :]) @ Phi[None] + proj[:S]
        Jq = Jq + tip_col.T[:, :, None] * tip[None, None, :]
        Jqd = self._mu * K[None] + proj[S:]
        Bs = self._cumulative(n_phi).transpose(2, 0, 1, 3).reshape(S, 2 * n_q, n)
        M = (Bs * self._w2[None, :, None]).transpose(0, 2, 1) @ Bs
        M = 0.5 * (M + M.transpose(0, 2, 1))
        return Jq, Jqd, M

    def velocity_derivative(self, Q: np.ndarray, P: np.ndarray, Acc: np.ndarray) -> np.ndarray:
        """``dR/dv`` = 2 v follower(v=1) + coriolis(v=1), shape (S, n), steady flow."""
        Phi, _, PhiT_W = self._res_ops
        th = np.asarray(Phi @ Q.T)
        th_d = np.asarray(Phi @ P.T)
        nrm, _ = frames(th)
        G = self._from_tip(self._c1 * th_d[:, None] * nrm)
        local = (2.0 * self._v) * np.sin((Q @ np.asarray(self._tip))[None, :] - th)
        local = local + np.einsum("qcs,qcs->qs", nrm, G)
        return np.asarray(PhiT_W @ local).T

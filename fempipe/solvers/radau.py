"""The variable-step Radau IIA integrator of the equations of motion, in residual form.

The discrete equations of motion are the weak form of Eq. (20),

    R(q, q', q''; v(tau), v'(tau)) = M(q) q'' + (stiffness, gravity, follower,
                                     Kelvin-Voigt, centripetal, Coriolis,
                                     flow-acceleration terms) = 0,

with the analytic Jacobians ``(dR/dq, dR/dq', M)`` of
:meth:`fempipe.model.operators.PipeModel.jacobians`.  :mod:`fempipe.analyses.dynamics` drives
this integrator (trajectories, unsteady flow, energy).

Why this integrator
-------------------
The finite-element system is stiff: the bending frequencies grow like h^-2
and the Kelvin--Voigt damping rates like mu h^-4 (about 2e6 for P3:16 at
mu = 5e-3).  An explicit method would need steps of that inverse size; an
A-stable method that is not L-stable (trapezoid, Gauss) lets the stiff
components ring.  The 3-stage Radau IIA collocation method is L-stable and of
order 5, and its stage equations can be written directly in residual form on
the second-order system, with the stage accelerations as unknowns:

    P_i = p0 + h sum_j a_ij A_j,   Q_i = q0 + c_i h p0 + h^2 sum_j (a^2)_ij A_j,
    R(t0 + c_i h, Q_i, P_i, A_i) = 0,   i = 1, 2, 3.

Newton's method with the Jacobian frozen at the start of the step decouples,
after diagonalising the Butcher matrix a = T diag(g_k) T^-1, into one real and
one complex n x n system ``M + h g_k D + h^2 g_k^2 K`` (K = dR/dq, D = dR/dq'):
no inverse mass matrix is ever formed, and the factorisations are reused over
Newton iterations and over steps while the step size is unchanged (Hairer &
Wanner's RADAU5 strategy, also that of ``scipy.integrate.Radau``).  The error
estimate and the step-size controller (predictive, Gustafsson) are RADAU5's,
transcribed to the second-order form (see :meth:`Radau._error`).

Measured (``validation/dynamics_acceptance.py``; alpha = 0, v = 10, static
state + 0.01 rad in mode 1, tau in [0, 2], rtol = 1e-6): 778, 709, 692, 693
steps on P3 with 8, 16, 32, 64 elements (the stiffest rates grow 4096x) and
871 on the 4-mode Galerkin model.  The step is set by the accuracy of the
physical oscillation; the stiff components are damped by L-stability, not
resolved.  Without Kelvin-Voigt damping (mu = 0) the h^-2 bending modes are
undamped, the error control must follow them and the step count does grow
with the mesh: use mu > 0 (as the paper) or the modal model there.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla

from fempipe.core.errors import SolverError
from fempipe.core.parallel import single_blas_thread
from fempipe.model.operators import PipeModel

__all__ = ["Radau", "IntegrationError", "acceleration", "refuse_hysteretic"]

# --- Radau IIA (s = 3) tableau -------------------------------------------
# The constants of this block, the Newton tolerance and iteration limit, the
# step-size limits and safety factor and the predictive controller
# (:func:`_predict_factor`) are those of Hairer & Wanner's RADAU5 as
# transcribed in scipy.integrate.Radau (scipy/integrate/_ivp/radau.py: C, E,
# MU_REAL, NEWTON_MAXITER, MIN_FACTOR, MAX_FACTOR, predict_factor); see
# E. Hairer, G. Wanner, Solving Ordinary Differential Equations II,
# Sec. IV.8.  A and its eigendecomposition are computed here instead of
# scipy's tabulated T, TI, because the stages are solved for the
# accelerations of the second-order system, not for first-order increments.
_S6 = math.sqrt(6.0)
C = np.array([(4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0])
A = np.array(
    [
        [(88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0],
        [(296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0],
        [(16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0],
    ]
)
A2 = A @ A
#: Error-estimate weights and the real eigenvalue 1/g_0 of A^-1 (RADAU5).
E = np.array([-13.0 - 7.0 * _S6, -13.0 + 7.0 * _S6, -1.0]) / 3.0
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)


def _diagonalise_a():
    lam, T = np.linalg.eig(A)
    order = np.argsort(np.abs(lam.imag))  # real eigenvalue first
    lam, T = lam[order], T[:, order]
    if lam[1].imag < 0:  # keep g_1 with positive imaginary part, g_2 = conj
        lam[[1, 2]] = lam[[2, 1]]
        T[:, [1, 2]] = T[:, [2, 1]]
    T[:, 0] = T[:, 0].real
    return lam, T, np.linalg.inv(T)


_G, _T, _TI = _diagonalise_a()
# The stage accelerations from the transformed increments (:meth:`Radau._newton`):
# dacc = -(T_0 dV_0 + 2 Re(T_1 dV_1)), with T_0 real.
_T0 = _T[:, 0].real[:, None]
_T1R, _T1I = 2.0 * _T[:, 1].real[:, None], 2.0 * _T[:, 1].imag[:, None]
#: Cubic through (0, 0) and (c_i, Z_i): coefficients of theta, theta^2, theta^3.
_DENSE = np.linalg.inv(np.vander(C, 4, increasing=True)[:, 1:])

#: Nodes of the dense-output cubic and its barycentric-like weights 1 / prod(x_j - x_m).
_NODES = np.r_[0.0, C]
_LAGRANGE_W = np.array(
    [1.0 / np.prod([_NODES[j] - _NODES[m] for m in range(4) if m != j]) for j in range(4)]
)


def _lu_factor(a: np.ndarray):
    """LU factors of a real or complex square matrix: LAPACK getrf directly.

    ``scipy.linalg.lu_factor`` / ``lu_solve`` do the same with argument checks
    that cost as much as the factorisation itself at n = 48 (they run twice
    per step and at every Newton iteration of the stage equations).
    """
    getrf = sla.lapack.zgetrf if np.iscomplexobj(a) else sla.lapack.dgetrf
    lu, piv, info = getrf(a, overwrite_a=True)
    if info < 0:  # pragma: no cover - a wrong argument, not a singular matrix
        raise ValueError(f"getrf: illegal argument {-info}")
    return lu, piv


def _lu_solve(lu_piv, b: np.ndarray) -> np.ndarray:
    """Solve with the factors of :func:`_lu_factor` (LAPACK getrs)."""
    lu, piv = lu_piv
    getrs = sla.lapack.zgetrs if np.iscomplexobj(lu) else sla.lapack.dgetrs
    x, info = getrs(lu, piv, b)
    if info != 0:  # pragma: no cover
        raise ValueError(f"getrs: illegal argument {-info}")
    return x


NEWTON_MAXITER = 6
#: A step whose Newton iteration needed more than two iterations at a
#: contraction rate above this gets a fresh Jacobian (RADAU5's THET, 1e-3).
JACOBIAN_RATE = 1e-3
MIN_FACTOR, MAX_FACTOR = 0.2, 10.0


class IntegrationError(SolverError):
    """Time integration failed: says where (tau, step size) and why."""

    def __init__(self, message: str, t: float, h: float) -> None:
        super().__init__(message)
        self.t = t
        self.h = h

    def __reduce__(self):
        # Rebuilt from all the constructor's arguments (pickling across processes).
        return type(self), (str(self), self.t, self.h)


def refuse_hysteretic(params, where: str) -> None:
    """Raise ValueError if ``params`` has hysteretic damping: it has no time-domain meaning.

    The loss factor mu_h multiplies EI by 1 + i mu_h sgn(omega), which is
    defined for harmonic motion only (the linear stability problem,
    :func:`fempipe.analyses.stability.linear.hysteretic_roots`); a time integration
    would silently drop it.  Every time-domain entry point (:class:`Radau`
    and so :func:`fempipe.analyses.dynamics.simulate`, the shooting and attractor
    search of :mod:`fempipe.analyses.limit_cycle`, the sweeps of
    :mod:`fempipe.analyses.bifurcation`) calls this first.

    Parameters
    ----------
    params : Params
    where : str
        The refusing function, named in the message.

    Raises
    ------
    ValueError
        If ``params.hysteretic_damping > 0``.
    """
    mu_h = getattr(params, "hysteretic_damping", 0.0)
    if mu_h:
        raise ValueError(
            f"{where}: hysteretic damping (mu_h = {mu_h:g}) has no time-domain meaning: "
            "EI (1 + i mu_h sgn(omega)) acts on harmonic motion only; use it in the linear "
            "stability problem (spectrum, critical_velocity, stability_map) or set "
            "hysteretic_damping = 0"
        )


def acceleration(model: PipeModel, q: np.ndarray, qdot: np.ndarray, v_dot: float = 0.0):
    """q'' from Eq. (20): solve ``M(q) q'' = -R(q, q', 0)`` (R is linear in q'').

    Returns
    -------
    ndarray, shape (n,)
    """
    M = model.mass_matrix(q)
    r = model.residual(q, qdot, None, v_dot)
    return -sla.cho_solve(sla.cho_factor(M), r)


#: Up to this many entries (n_q n) Phi, K and Phi^T W are applied as dense
#: arrays in the batched stage functions: for the small systems of limit
#: cycles and continuation (P3:16: 96 x 48) a dense product costs a few
#: microseconds where scipy.sparse's dispatch alone costs about ten.
DENSE_OPERATORS_MAX = 32768


def _stage_operators(model: PipeModel):
    """(Phi, K, Phi^T W): dense for small discretisations, else as the model has them."""
    disc = model.disc
    Phi, K, PhiT_W = disc.Phi, disc.K, model._PhiT_W
    if model.quad.n_q * model.n <= DENSE_OPERATORS_MAX:
        Phi, K, PhiT_W = (
            np.asarray(a.toarray() if hasattr(a, "toarray") else a, dtype=float)
            for a in (Phi, K, PhiT_W)
        )
    return Phi, K, PhiT_W


def _rms(x: np.ndarray) -> float:
    return math.sqrt(float(x @ x) / x.size)


def _frames(th: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Normal and tangent (n_q, 2, S) of angles th (n_q, S)."""
    s, c = np.sin(th), np.cos(th)
    nrm = np.empty((th.shape[0], 2, th.shape[1]))
    tng = np.empty_like(nrm)
    nrm[:, 0], nrm[:, 1] = -s, c
    tng[:, 0], tng[:, 1] = c, s
    return nrm, tng


def _batchable(model: PipeModel) -> bool:
    """Whether the batched stage functions know every term of ``model``: the pipe
    without variants (no end mass, external damping or springs), no subclass."""
    p = model.params
    return type(model) is PipeModel and not (p.end_mass or p.external_damping or p.springs)


def _batched_residual(model: PipeModel):
    """``R(Q_i, P_i, A_i)`` of the three stages in one evaluation, or None where unavailable.

    The residual of :meth:`PipeModel.residual` costs about 0.25 ms on P3:16,
    almost all of it call overhead of some forty small array operations on
    n_q = 96 points; the three Radau stages evaluated together cost about one
    evaluation (the stage residuals are 3/4 of an integration step).  The
    terms are those of :meth:`PipeModel.residual` for the pipe without
    variants and steady flow (v_dot = 0), summed in another order: bending
    and Kelvin-Voigt ``K (q + mu q')``; gravity and follower, local; and the
    three projections ``n . C^R F`` (inertia, centripetal, Coriolis) with the
    one field F = C(theta_ddot n - theta_dot^2 t) + 2 v sqrt(beta) theta_dot n,
    since the projection is linear in F.  The variants (end mass, external
    damping, springs) and any subclass of PipeModel use the per-stage
    residual (None here); ``tests/test_dynamics.py`` checks the two agree to
    round-off.
    """
    p = model.params
    if not _batchable(model):
        return None
    disc, quad = model.disc, model.quad
    Phi, K, PhiT_W = _stage_operators(model)
    tip = np.asarray(disc.tip)
    lever = p.gamma * (1.0 - model.x)[:, None]
    cumulative, from_tip = _integrals(quad)
    v2, cv, mu, alpha = p.v * p.v, 2.0 * p.v * math.sqrt(p.beta), p.mu, p.alpha

    def residual(Q: np.ndarray, P: np.ndarray, Acc: np.ndarray) -> np.ndarray:
        # Stages in columns: theta etc. have shape (n_q, 3), frames (n_q, 2, 3).
        th = np.asarray(Phi @ Q.T)
        th_d = np.asarray(Phi @ P.T)
        th_dd = np.asarray(Phi @ Acc.T)
        nrm, tng = _frames(th)
        F = cumulative(th_dd[:, None] * nrm - (th_d**2)[:, None] * tng)
        F = F + cv * th_d[:, None] * nrm
        G = from_tip(F)
        local = lever * np.sin(th + alpha) + v2 * np.sin((Q @ tip)[None, :] - th)
        local = local + np.einsum("qcs,qcs->qs", nrm, G)
        return (np.asarray(K @ (Q + mu * P).T) + np.asarray(PhiT_W @ local)).T

    return residual


def _cumulative(quad, f: np.ndarray) -> np.ndarray:
    """``LineQuadrature.cumulative`` (\\int_0^{x_q} f, quadrature index on axis 0)
    with the trailing axes flattened into one matrix product: its einsum over
    ``...`` slows down 13x from (96, 2, 3, 48) to (96, 2, 9, 48) values."""
    nc, ng = quad.n_cells, quad.n_gauss
    fc = f.reshape(nc, ng, -1)
    local = np.matmul(quad._a, fc) * quad.h[:, None, None]
    totals = (quad.ref_weights @ fc) * quad.h[:, None]
    start = np.cumsum(totals, axis=0) - totals
    return (local + start[:, None, :]).reshape(f.shape)


def _from_tip(quad, f: np.ndarray) -> np.ndarray:
    """``LineQuadrature.from_tip`` (\\int_{x_q}^1 f) through :func:`_cumulative`."""
    fc = f.reshape(f.shape[0], -1)
    return (quad.w @ fc - _cumulative(quad, fc)).reshape(f.shape)


#: Up to this many quadrature points the integration operators are applied as
#: dense (n_q, n_q) matrices (one BLAS product; O(n_q^2) work, which beyond
#: this is more than the O(n_q) of :func:`_cumulative`).  Measured, one
#: Jacobian evaluation (best of 5x50, one BLAS thread), dense against cell-wise:
#: P3:4 (n_q = 24) 0.15 against 0.22 ms, P3:16 (96) 1.11 against 1.16 ms, the
#: sine modes N = 3, 4 (256) 0.32-0.37 against 0.25-0.29 ms, P3:64 (384) 33
#: against 27 ms.
DENSE_INTEGRALS_MAX = 128


def _integrals(quad):
    """(C, C^R): functions applying \\int_0^{x_q} and \\int_{x_q}^1 along axis 0."""
    n_q = quad.n_q
    if n_q > DENSE_INTEGRALS_MAX:
        return (lambda f: _cumulative(quad, f)), (lambda f: _from_tip(quad, f))
    eye = np.eye(n_q)
    Cm, Rm = quad.cumulative(eye), quad.from_tip(eye)

    def cumulative(f):
        return (Cm @ f.reshape(n_q, -1)).reshape(f.shape)

    def from_tip(f):
        return (Rm @ f.reshape(n_q, -1)).reshape(f.shape)

    return cumulative, from_tip


def _cumulative_adjoint(quad, g: np.ndarray) -> np.ndarray:
    """``C^T g`` for the cumulative integral C of :func:`_cumulative` (quadrature
    index on axis 0 of g, trailing axes flattened), O(n_q) per column.

    In cell k at local point a, ``(C f)_{k,a} = h_k sum_b a_ab f_{k,b} +
    sum_{k' < k} h_k' sum_b w_b f_{k',b}`` (w_b the reference weights), so
    ``(C^T g)_{k,b} = h_k (sum_a a_ab g_{k,a} + w_b sum_{k' > k} sum_a g_{k',a})``.
    """
    nc, ng = quad.n_cells, quad.n_gauss
    gc = g.reshape(nc, ng, -1)
    out = np.matmul(quad._a.T, gc)
    s = gc.sum(axis=1)
    after = np.cumsum(s[::-1], axis=0)[::-1]
    after -= s
    for b in range(ng):
        out[:, b] += quad.ref_weights[b] * after
    out *= quad.h[:, None, None]
    return out.reshape(g.shape)


def _projection_fields(quad):
    """``g -> (V, U)`` with ``V = (C^R)^T (w g)`` and ``U = C^T V``, along axis 0.

    For a field X, ``sum_q w_q g_q (C^R X)_q = sum_q V_q X_q`` and
    ``sum_q w_q g_q (C^R C X)_q = sum_q U_q X_q``: the projections of
    :func:`_batched_jacobians` moved onto the test side.  Dense (one product
    with the stacked operators) up to :data:`DENSE_INTEGRALS_MAX` points,
    cell by cell beyond (``C^R = 1 w^T - C``, so ``(C^R)^T y = w (1^T y) - C^T y``).
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
        V = _cumulative_adjoint(quad, wg)
        np.subtract(w[:, None] * wg.sum(axis=0)[None, :], V, out=V)
        return V.reshape(g.shape), _cumulative_adjoint(quad, V).reshape(g.shape)

    return cells


def _batched_jacobians(model: PipeModel):
    """``(dR/dq, dR/dq', M)`` at several states in one evaluation, or None where unavailable.

    The Jacobians of :meth:`PipeModel.jacobians` for the pipe without
    variants and steady flow, at S states (arrays (S, n)).  Radau's Newton
    matrix takes one state; the three stage Jacobians of the sensitivity
    take S = 3 on small discretisations (:data:`BATCHED_STAGES_MAX`), where
    one call is cheaper than three, and S = 1 three times on larger ones.
    Same terms as ``operators.py`` (``jacobians``): with
    F = C(theta_ddot n - theta_dot^2 t) + 2 v sqrt(beta) theta_dot n,

    * dR/dq = K + Phi^T diag(d) Phi + (tip column) tip^T + the projection
      \\int phi_i n . C^R X_j of X_j = dF/dq_j = C(a phi_j) + b phi_j,
      a = -theta_ddot t - theta_dot^2 n, b = -2 v sqrt(beta) theta_dot t,
      with d = gamma w (1 - xi) cos(theta + alpha) - v^2 w cos(theta(1) - theta)
      - w t . C^R F;
    * dR/dq' = mu K + the same projection with a = -2 theta_dot t,
      b = 2 v sqrt(beta) n;
    * M = \\int (C phi n) . (C phi n).

    The projections are taken on the test side: with V = (C^R)^T (w n phi_i)
    and U = C^T V (:func:`_projection_fields`), the (i, j) entry is
    ``sum_q (a . U_i + b . V_i)_q phi_j(x_q)``, one (n_q, n) field per
    Jacobian times Phi.  Integrating the n test fields once, instead of the
    2 x 2 n trial fields of dF/dq and dF/dq' twice each, makes a Jacobian
    cheaper: 0.11 -> 0.08 ms on P3:8, 0.37 -> 0.23 ms on P3:16, 2.5 -> 1.1 ms
    on P3:32 (best of 7, one BLAS thread).  ``tests/test_dynamics.py`` checks
    them against ``PipeModel.jacobians``.
    """
    p = model.params
    if not _batchable(model):
        return None
    disc, quad = model.disc, model.quad
    Phi = np.asarray(disc.Phi.toarray() if hasattr(disc.Phi, "toarray") else disc.Phi)
    K = np.asarray(disc.K.toarray() if hasattr(disc.K, "toarray") else disc.K)
    tip = np.asarray(disc.tip, dtype=float)
    w = model.w
    n_q, n = Phi.shape
    grav = p.gamma * w * (1.0 - model.x)
    v2, cv, mu, alpha = p.v * p.v, 2.0 * p.v * math.sqrt(p.beta), p.mu, p.alpha
    cumulative, from_tip = _integrals(quad)
    projection_fields = _projection_fields(quad)
    PhiT_w = Phi.T * w  # (n, n_q): \\int phi_i f
    w2 = np.repeat(w, 2)

    def jacobians(Q: np.ndarray, P: np.ndarray, Acc: np.ndarray):
        S = Q.shape[0]
        th, th_d, th_dd = Phi @ Q.T, Phi @ P.T, Phi @ Acc.T  # (n_q, S)
        nrm, t = _frames(th)  # (n_q, 2, S)
        F = cumulative(th_dd[:, None] * nrm - (th_d**2)[:, None] * t)
        F = F + cv * th_d[:, None] * nrm
        n_phi = nrm[..., None] * Phi[:, None, None, :]  # (n_q, 2, S, n): n phi_i
        V, U = projection_fields(n_phi)
        a = -th_dd[:, None] * t - (th_d**2)[:, None] * nrm
        ad = -2.0 * th_d[:, None] * t
        b, bd = -cv * th_d[:, None] * t, cv * nrm
        Z = np.empty((2 * S, n_q, n))  # the test fields of dR/dq, then of dR/dq'
        Z[:S] = np.einsum("qcs,qcsi->sqi", a, U) + np.einsum("qcs,qcsi->sqi", b, V)
        Z[S:] = np.einsum("qcs,qcsi->sqi", ad, U) + np.einsum("qcs,qcsi->sqi", bd, V)
        proj = Z.transpose(0, 2, 1) @ Phi
        cos_tip = np.cos((Q @ tip)[None, :] - th)  # (n_q, S)
        d = grav[:, None] * np.cos(th + alpha) - v2 * w[:, None] * cos_tip
        d = d - np.einsum("qcs,qcs->qs", t, from_tip(F)) * w[:, None]
        tip_col = v2 * (PhiT_w @ cos_tip)  # (n, S)
        Jq = K[None] + (Phi.T[None] * d.T[:, None, :]) @ Phi[None] + proj[:S]
        Jq = Jq + tip_col.T[:, :, None] * tip[None, None, :]
        Jqd = mu * K[None] + proj[S:]
        Bs = cumulative(n_phi).transpose(2, 0, 1, 3).reshape(S, 2 * n_q, n)
        M = (Bs * w2[None, :, None]).transpose(0, 2, 1) @ Bs
        M = 0.5 * (M + M.transpose(0, 2, 1))
        return Jq, Jqd, M

    return jacobians


#: Up to this n_q * n the three stage Jacobians of the sensitivity are one
#: batched evaluation (S = 3 in :func:`_batched_jacobians`), beyond it three
#: (its (n_q, 2, S, n) temporaries outgrow the call overhead saved).
#: Measured (best of 7, one BLAS thread), three calls against one: P2:4 (128)
#: 0.15 against 0.07 ms, P3:4 (288) 0.16 against 0.08, sine modes N = 3 on
#: 96 points (288) 0.21 against 0.13, N = 4 on 128 (512) 0.25 against 0.18,
#: P3:8 (1152) 0.23 against 0.15, P3:12 (2592) 0.34 against 0.30, P3:16
#: (4608) 0.60 against 0.55-0.58; P3:20 (7200) 1.02 against 1.43, P3:24
#: (10368) 1.67 against 2.22.
BATCHED_STAGES_MAX = 4608


def _velocity_derivative(model: PipeModel):
    """``(Q, P, Acc) -> dR_i/dv`` of the three stages, shape (3, n), for steady flow.

    Only two terms of Eq. (20) depend on v: the follower force, v^2 times
    :meth:`~fempipe.model.operators.PipeModel.follower` at v = 1, and the Coriolis
    force, v times :meth:`~fempipe.model.operators.PipeModel.coriolis` at v = 1; so
    dR/dv = 2 v follower_1 + coriolis_1, exactly.  For the pipe without
    variants the three stages are evaluated in one call, as
    :func:`_batched_residual` does (``tests/test_dynamics.py`` checks both
    against a difference of :meth:`PipeModel.residual` in v).
    """
    p = model.params
    v = p.v
    if not _batchable(model):
        unit = model.with_params(replace(p, v=1.0))

        def per_stage(Q, P, Acc):
            out = np.empty(Q.shape)
            for i in range(3):
                fl = unit.fields(Q[i], P[i])
                out[i] = 2.0 * v * unit.follower(fl) + unit.coriolis(fl)
            return out

        return per_stage
    Phi, _, PhiT_W = _stage_operators(model)
    tip = np.asarray(model.disc.tip)
    _, from_tip = _integrals(model.quad)
    two_v, c1 = 2.0 * v, 2.0 * math.sqrt(p.beta)

    def batched(Q, P, Acc):
        th = np.asarray(Phi @ Q.T)
        th_d = np.asarray(Phi @ P.T)
        nrm, _ = _frames(th)
        G = from_tip(c1 * th_d[:, None] * nrm)
        local = two_v * np.sin((Q @ tip)[None, :] - th)
        local = local + np.einsum("qcs,qcs->qs", nrm, G)
        return np.asarray(PhiT_W @ local).T

    return batched


@dataclass
class _Stats:
    steps: int = 0
    rejected_steps: int = 0
    newton_failures: int = 0
    n_residual: int = 0
    n_jacobian: int = 0
    n_lu: int = 0
    wall_time: float = 0.0


class Radau:
    """Variable-step, L-stable Radau IIA (order 5) on R(q, q', q'') = 0.

    Parameters
    ----------
    model : PipeModel
        Supplies ``residual`` and ``jacobians``; its ``params.v`` is replaced
        by ``flow(tau)`` when a flow history is given.
    q0, qdot0 : ndarray, shape (n,)
        Initial state (not modified).
    t0 : float
        Initial time tau_0.
    rtol, atol : float
        Local error tolerances on (q, q'); the error of each component is
        measured against ``atol + rtol |y|``.  ``atol`` defaults to ``rtol``
        (theta is O(1) rad, so absolute and relative errors are comparable).
    flow : PulsatingFlow or callable tau -> (v, v_dot), optional
        Unsteady flow; default the steady ``model.params.v``.
    max_step : float
        Largest step.
    first_step : float, optional
        First step (default: from the size of q'' and the tolerance).
    h_fixed : float, optional
        Fixed step size, no error control (for convergence-order studies).
    sensitivity : bool
        Accumulate the derivative of the discrete flow map with respect to
        the initial state (the monodromy matrix over a period; see
        :attr:`sensitivity_matrix`).
    velocity_sensitivity : bool
        With ``sensitivity`` and steady flow, also the derivative with respect
        to the flow velocity v at fixed initial state
        (:attr:`velocity_sensitivity`; the continuation of periodic orbits
        needs it, shooting at fixed v does not).

    Notes
    -----
    Counters in :attr:`stats`: accepted ``steps``, ``rejected_steps`` (error
    test failed), ``newton_failures`` (step halved because Newton did not
    converge), ``n_residual``, ``n_jacobian`` (evaluations of the three
    Jacobians), ``n_lu`` (factorisation pairs), ``wall_time``.
    """

    def __init__(
        self,
        model: PipeModel,
        q0: np.ndarray,
        qdot0: np.ndarray | None = None,
        t0: float = 0.0,
        *,
        rtol: float = 1e-6,
        atol: float | None = None,
        flow: Callable[[float], tuple[float, float]] | None = None,
        max_step: float = math.inf,
        first_step: float | None = None,
        h_fixed: float | None = None,
        sensitivity: bool = False,
        velocity_sensitivity: bool = False,
    ) -> None:
        refuse_hysteretic(model.params, "time integration (Radau)")
        n = model.n
        q0 = np.array(q0, dtype=float)
        qdot0 = np.zeros(n) if qdot0 is None else np.array(qdot0, dtype=float)
        if q0.shape != (n,) or qdot0.shape != (n,):
            raise ValueError(f"q0 and qdot0 must have shape ({n},)")
        if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(qdot0))):
            raise ValueError("q0 and qdot0 must be finite")
        if not (0 < rtol < 1):
            raise ValueError(f"rtol must satisfy 0 < rtol < 1, got {rtol}")
        atol = rtol if atol is None else float(atol)
        if atol <= 0:
            raise ValueError(f"atol must be > 0, got {atol}")
        if not max_step > 0:
            raise ValueError(f"max_step must be > 0, got {max_step}")
        if h_fixed is not None and not h_fixed > 0:
            raise ValueError(f"h_fixed must be > 0, got {h_fixed}")
        self.model = model
        self.n = n
        self.flow = flow
        self.rtol, self.atol = float(rtol), atol
        # Newton tolerance on the stage increments, as RADAU5 / scipy.
        self.newton_tol = max(10 * np.finfo(float).eps / rtol, min(0.03, rtol**0.5))
        self.max_step = float(max_step)
        self.h_fixed = h_fixed
        self.stats = _Stats()
        self.t = float(t0)
        self.q, self.qdot = q0, qdot0
        self.qddot = self._acceleration(self.t, q0, qdot0)
        self._jac = None  # (K, D, M) at the last Jacobian point
        self._current_jac = False
        self._lu = None  # (h, LU_real, LU_complex)
        self._h_old = None
        self._err_old = None
        # RADAU5's FACCON: the contraction factor theta / (1 - theta) of the
        # last converged Newton iteration, used to accept the first iterate
        # of the next step (see :meth:`_newton`).
        self._faccon = 1.0
        self._prev = None  # previous step (t_old, h, a_old, stage accelerations)
        self.last = None  # last accepted step: t_old, h, q_old, p_old, Q, P, Acc
        if h_fixed is not None:
            self.h = float(h_fixed)
        elif first_step is not None:
            self.h = float(first_step)
        else:
            # Local error of a 5th-order step ~ (h |q''|)... use the usual
            # d0/d1 heuristic on the acceleration, then let the controller work.
            d0 = np.sqrt(np.mean(np.r_[q0, qdot0] ** 2)) + 1e-3
            d1 = np.sqrt(np.mean(np.r_[qdot0, self.qddot] ** 2)) + 1e-12
            self.h = min(1e-2 * d0 / d1, 1e-2)
        self.h = min(self.h, self.max_step)
        self._residual3 = None if flow is not None else _batched_residual(model)
        self._jacobians1 = None if flow is not None else _batched_jacobians(model)
        self._stages_batched = (
            self._jacobians1 is not None and model.quad.n_q * n <= BATCHED_STAGES_MAX
        )
        self.sensitivity = bool(sensitivity)
        self.sensitivity_matrix = np.eye(2 * n) if sensitivity else None
        # d(q, q')/dv of the discrete flow map, steady flow only (a flow
        # history has no single v to differentiate by).
        self.velocity_sensitivity = (
            np.zeros(2 * n) if sensitivity and velocity_sensitivity and flow is None else None
        )
        self._stage_residuals_v = (
            _velocity_derivative(model) if self.velocity_sensitivity is not None else None
        )

    # ------------------------------------------------------------------
    def _model_at(self, t: float) -> tuple[PipeModel, float]:
        if self.flow is None:
            return self.model, 0.0
        v, v_dot = self.flow(t)
        return self.model.with_params(self.model.params.with_flow(v)), float(v_dot)

    def _acceleration(self, t, q, p):
        m, vd = self._model_at(t)
        self.stats.n_residual += 1
        return acceleration(m, q, p, vd)

    def _jacobians(self, t, q, p, a):
        self.stats.n_jacobian += 1
        if self._jacobians1 is not None:
            Jq, Jqd, M = self._jacobians1(q[None], p[None], a[None])
            return Jq[0], Jqd[0], M[0]
        m, vd = self._model_at(t)
        return m.jacobians(q, p, a, vd)

    def _factor(self, h: float):
        K, D, M = self._jac
        g0, g1 = _G[0].real, _G[1]
        lu_r = _lu_factor(M + h * g0 * D + (h * g0) ** 2 * K)
        lu_c = _lu_factor(M + h * g1 * D + (h * g1) ** 2 * K)
        self.stats.n_lu += 1
        self._lu = (h, lu_r, lu_c)

    def _scale(self, q, p):
        return self.atol + self.rtol * np.abs(np.concatenate([q, p]))

    # ------------------------------------------------------------------
    def _guess(self, t: float, h: float) -> np.ndarray:
        """Stage accelerations extrapolated from the previous step's polynomial."""
        if self._prev is None:
            return np.tile(self.qddot, (3, 1))
        t_old, h_old, a_old, acc = self._prev
        s = (t + h * C - t_old) / h_old
        # Lagrange extrapolation of the cubic through the 4 nodes (0, c_1, c_2, c_3).
        d0, d1, d2, d3 = (s[:, None] - _NODES[None, :]).T
        d01, d23 = d0 * d1, d2 * d3
        L = np.empty((3, 4))
        L[:, 0], L[:, 1], L[:, 2], L[:, 3] = d1 * d23, d0 * d23, d01 * d3, d01 * d2
        L *= _LAGRANGE_W
        return L[:, :1] * a_old + L[:, 1:] @ acc

    def _stages(self, h, acc):
        P = self.qdot[None, :] + h * (A @ acc)
        Q = self.q[None, :] + h * C[:, None] * self.qdot[None, :] + h * h * (A2 @ acc)
        return Q, P

    def _newton(self, t: float, h: float, acc: np.ndarray, scale: np.ndarray, max_iter=None):
        """Solve the stage equations; return (converged, iterations, acc, rate).

        The iterate is accepted once the predicted remaining error
        ``faccon * dnorm`` (faccon = rate / (1 - rate), the contraction of the
        simplified Newton iteration) is below ``newton_tol``.  As in RADAU5,
        the first iteration uses the factor of the previous step, raised to
        the power 0.8 (Hairer & Wanner, Sec. IV.8, and the FACCON of radau5.f),
        so that a step whose extrapolated guess is already good costs one
        iteration (3 residuals) instead of two; scipy's Radau always does two.
        With ``h_fixed`` (convergence-order studies) a rate is always measured.
        """
        max_iter = NEWTON_MAXITER if max_iter is None else max_iter
        _, lu_r, lu_c = self._lu
        n = self.n
        dnorm_old, rate = None, None
        faccon = max(self._faccon, np.finfo(float).eps) ** 0.8
        G = np.empty((3, n))
        for k in range(max_iter):
            Q, P = self._stages(h, acc)
            if self._residual3 is not None:
                G = self._residual3(Q, P, acc)
            else:
                for i in range(3):
                    m, vd = self._model_at(t + C[i] * h)
                    G[i] = m.residual(Q[i], P[i], acc[i], vd)
            self.stats.n_residual += 3
            # (a sum is finite only if every term is)
            if not math.isfinite(G.sum()):
                return False, k + 1, acc, rate
            W = _TI @ G  # (3, n) complex
            dV0 = _lu_solve(lu_r, W[0].real)
            dV1 = _lu_solve(lu_c, W[1])
            dacc = -(_T0 * dV0 + _T1R * dV1.real - _T1I * dV1.imag)
            # RMS of the increments of (Q, P), scaled: h^2 A^2 dacc and h A dacc.
            eq = (h * h) * (A2 @ dacc) / scale[:n]
            ep = h * (A @ dacc) / scale[n:]
            dnorm = math.sqrt((float(np.vdot(eq, eq)) + float(np.vdot(ep, ep))) / (6 * n))
            if dnorm_old is not None:
                rate = dnorm / dnorm_old
            if rate is not None and (
                rate >= 1 or rate ** (max_iter - k) / (1 - rate) * dnorm > self.newton_tol
            ):
                return False, k + 1, acc, rate
            acc = acc + dacc
            if rate is not None:
                faccon = rate / (1 - rate)
            if dnorm == 0 or (
                (rate is not None or self.h_fixed is None) and faccon * dnorm < self.newton_tol
            ):
                self._faccon = faccon
                return True, k + 1, acc, rate
            if self.h_fixed is not None and dnorm < 1e-3 * self.newton_tol:
                return True, k + 1, acc, rate
            dnorm_old = dnorm
        return False, max_iter, acc, rate

    def _error(self, t, h, Q, P, scale, refine: bool) -> float:
        """RADAU5's embedded error estimate in second-order form.

        RADAU5 computes err = (mu/h I - J)^-1 (f0 + sum_i e_i Z_i / h) with
        J = [[0, I], [-M^-1 K, -M^-1 D]] and mu = MU_REAL.  Eliminating the
        velocity part: e_q = (h g0)^2 (M + h g0 D + (h g0)^2 K)^-1
        [M r_p + (mu/h M + D) r_q], e_p = mu/h e_q - r_q with g0 = 1/mu, so the
        real Newton factorisation is reused.
        """
        K, D, M = self._jac
        _, lu_r, _ = self._lu
        Zq = Q - self.q[None, :]
        Zp = P - self.qdot[None, :]
        mu = MU_REAL
        g0 = 1.0 / mu

        def solve(f_q, f_p):
            r_q = f_q + E @ Zq / h
            r_p = f_p + E @ Zp / h
            rhs = M @ r_p + (mu / h) * (M @ r_q) + D @ r_q
            e_q = (h * g0) ** 2 * _lu_solve(lu_r, rhs)
            return e_q, (mu / h) * e_q - r_q

        e_q, e_p = solve(self.qdot, self.qddot)
        err = _rms(np.concatenate([e_q, e_p]) / scale)
        if refine and err > 1:
            a = self._acceleration(t, self.q + e_q, self.qdot + e_p)
            e_q, e_p = solve(self.qdot + e_p, a)
            err = _rms(np.concatenate([e_q, e_p]) / scale)
        return err

    # ------------------------------------------------------------------
    def step(self, t_bound: float = math.inf) -> None:
        """Advance by one accepted step, not beyond ``t_bound``.

        Raises
        ------
        IntegrationError
            If the step size falls below round-off level.
        """
        t0_wall = time.perf_counter()
        t = self.t
        h = min(self.h, self.max_step)
        h_old, err_old = self._h_old, self._err_old
        rejected = False
        if self._jac is None:
            self._jac = self._jacobians(t, self.q, self.qdot, self.qddot)
            self._current_jac = True
        while True:
            min_step = 10 * abs(np.nextafter(t, math.inf) - t)
            if h < min_step:
                raise IntegrationError(
                    f"time step {h:.3e} below round-off at tau = {t:.6g} "
                    f"(v = {self.model.params.v:.6g}); the motion may be diverging",
                    t=t,
                    h=h,
                )
            if t + h >= t_bound - min_step:
                h = t_bound - t
            if self._lu is None or self._lu[0] != h:
                self._factor(h)
            scale = self._scale(self.q, self.qdot)
            acc0 = self._guess(t, h)
            converged, n_iter, acc, rate = self._newton(t, h, acc0, scale)
            if not converged and not self._current_jac:
                self._jac = self._jacobians(t, self.q, self.qdot, self.qddot)
                self._current_jac = True
                self._factor(h)
                converged, n_iter, acc, rate = self._newton(t, h, acc0, scale)
            if not converged and self.h_fixed is not None:
                # A fixed step cannot be halved: retry from the constant
                # guess (extrapolated stiff accelerations can be far off) with
                # more iterations before giving up.
                acc0 = np.tile(self.qddot, (3, 1))
                converged, n_iter, acc, rate = self._newton(t, h, acc0, scale, max_iter=25)
            if not converged:
                if self.h_fixed is not None:
                    raise IntegrationError(
                        f"Newton did not converge with the fixed step {h:.3e} at tau = {t:.6g}",
                        t=t,
                        h=h,
                    )
                self.stats.newton_failures += 1
                h *= 0.5
                continue
            Q, P = self._stages(h, acc)
            if self.h_fixed is not None:
                err = 0.0
                break
            scale = self.atol + self.rtol * np.maximum(
                np.abs(np.concatenate([self.q, self.qdot])), np.abs(np.concatenate([Q[-1], P[-1]]))
            )
            err = self._error(t, h, Q, P, scale, refine=rejected or self._prev is None)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if err > 1:
                factor = _predict_factor(h, h_old, err, err_old)
                h *= max(MIN_FACTOR, safety * factor)
                rejected = True
                self.stats.rejected_steps += 1
                continue
            break

        if self.sensitivity:
            self._accumulate_sensitivity(t, h, Q, P, acc)
        self.last = (t, h, self.q, self.qdot, Q, P, acc)
        self._prev = (t, h, self.qddot, acc)
        self.t = t + h
        self.q, self.qdot, self.qddot = Q[-1].copy(), P[-1].copy(), acc[-1].copy()
        self.stats.steps += 1
        if self.h_fixed is None:
            recompute_jac = n_iter > 2 and rate is not None and rate > JACOBIAN_RATE
            factor = min(MAX_FACTOR, safety * _predict_factor(h, h_old, err, err_old))
            # RADAU5 keeps h (and the factorisations) for factor < 1.2; a
            # factor below 1 is applied here, so that the error stays controlled.
            if not recompute_jac and 1.0 <= factor < 1.2:
                factor = 1.0
            self._h_old, self._err_old = h, err
            self.h = min(h * factor, self.max_step)
            if recompute_jac:
                if self.sensitivity:
                    self._jac = self._stage3_jac  # evaluated at this very state
                else:
                    self._jac = self._jacobians(self.t, self.q, self.qdot, self.qddot)
                self._current_jac = True
                self._lu = None
            else:
                self._current_jac = False
        else:
            self.h = self.h_fixed
        self.stats.wall_time += time.perf_counter() - t0_wall

    def _accumulate_sensitivity(self, t, h, Q, P, acc) -> None:
        """Exact derivative of the step map y0 -> y1 (stage Jacobians, no freezing).

        Differentiating R(Q_i, P_i, A_i) = 0 with Q, P the stage formulas:
        [M_i d_ij + h a_ij D_i + h^2 (a^2)_ij K_i] dA_j = -K_i dq0 - (c_i h K_i + D_i) dp0,
        and y1 = (Q_3, P_3) since c_3 = 1 (stiffly accurate).  With steady
        flow, the same matrix with the right side -dR_i/dv gives the
        derivative by v at fixed y0 (:func:`_velocity_derivative`), chained
        over the steps as dy_{k+1}/dv = S_k dy_k/dv + (dy_{k+1}/dv at fixed y_k).
        """
        n = self.n
        if self._stages_batched:
            self.stats.n_jacobian += 3
            Ks, Ds, Ms = self._jacobians1(Q, P, acc)  # (3, n, n) each
        else:
            jac = [self._jacobians(t + C[i] * h, Q[i], P[i], acc[i]) for i in range(3)]
            Ks, Ds, Ms = (np.array([j[k] for j in jac]) for k in range(3))  # (3, n, n) each
        # big[i, :, j, :] = M_i d_ij + h a_ij D_i + h^2 (a^2)_ij K_i
        big = np.einsum("ij,iab->iajb", h * A, Ds) + np.einsum("ij,iab->iajb", h * h * A2, Ks)
        big[np.arange(3), :, np.arange(3), :] += Ms
        with_v = self._stage_residuals_v is not None
        rhs = np.empty((3, n, 2 * n + with_v))
        np.negative(Ks, out=rhs[:, :, :n])
        rhs[:, :, n : 2 * n] = -(C[:, None, None] * h * Ks + Ds)
        if with_v:
            # dA/dv at fixed y0: the same matrix, the right side -dR_i/dv.
            rhs[:, :, -1] = -self._stage_residuals_v(Q, P, acc)
        dA = _lu_solve(_lu_factor(big.reshape(3 * n, 3 * n)), rhs.reshape(3 * n, -1))
        dA = dA.reshape(3, n, -1)
        # d y1 / d (y0, v) = [[I, h I], [0, I]] (the stage formulas at c_3 = 1)
        # plus (dq, dp): the derivatives through the stage accelerations.
        D = np.empty((2 * n, dA.shape[2]))
        np.einsum("j,jab->ab", (h * h) * A2[2], dA, out=D[:n])
        np.einsum("j,jab->ab", h * A[2], dA, out=D[n:])
        # The last stage is the end of the step (c_3 = 1): its Jacobians are
        # those at the next step's start, where step() may want them.
        self._stage3_jac = (Ks[2], Ds[2], Ms[2])
        # Chained with the derivatives so far, Y = [d y/d y0, d y/dv]:
        # Y1 = [[I, h I], [0, I]] Y + D[:, :2n] Y (+ D[:, 2n] in the v column).
        Y = self.sensitivity_matrix
        if with_v:
            Y = np.column_stack([Y, self.velocity_sensitivity])
        new = D[:, : 2 * n] @ Y
        new[:n] += Y[:n] + h * Y[n:]
        new[n:] += Y[n:]
        if with_v:
            new[:, -1] += D[:, -1]
            self.velocity_sensitivity = new[:, -1]
            new = new[:, :-1]
        self.sensitivity_matrix = new

    # ------------------------------------------------------------------
    def dense(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(q, q') at tau = t inside the last step: the collocation polynomial."""
        if self.last is None:
            return self.q.copy(), self.qdot.copy()
        t_old, h, q_old, p_old, Q, P, _ = self.last
        s = (t - t_old) / h
        coef = np.array([s, s * s, s**3]) @ _DENSE  # weights of Z_1..Z_3
        return q_old + coef @ (Q - q_old), p_old + coef @ (P - p_old)

    @property
    def t_old(self) -> float:
        return self.t if self.last is None else self.last[0]

    def steps(self, t_end: float) -> Iterator[tuple[float, np.ndarray, np.ndarray]]:
        """Generator of (tau, q, q') after every accepted step up to ``t_end``.

        The initial state is not yielded.  Arrays are fresh copies.
        """
        with single_blas_thread():
            while self.t < t_end - 10 * abs(np.nextafter(t_end, math.inf) - t_end):
                self.step(t_end)
                yield self.t, self.q.copy(), self.qdot.copy()


def _predict_factor(h, h_old, err, err_old) -> float:
    """Step-size factor of the predictive (Gustafsson) controller: scipy's RADAU5 ``predict_factor``."""
    if err_old is None or h_old is None or err == 0:
        multiplier = 1.0
    else:
        multiplier = h / h_old * (err_old / err) ** 0.25
    with np.errstate(divide="ignore"):
        return min(1.0, multiplier) * err**-0.25 if err > 0 else MAX_FACTOR

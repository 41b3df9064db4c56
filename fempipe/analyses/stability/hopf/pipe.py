"""The pipe's first-order Jacobian and its derivatives for the normal form.

D_x F of the first-order form of Eq. (20) (:func:`pipe_jacobian`; docs/theory/stability.md,
"First-order form") and its first and second directional derivatives without differencing
the bending matrix (:func:`pipe_derivatives`; "Derivatives").
"""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from fempipe.core.companion import first_order_matrix
from fempipe.model.operators import PipeModel

from ..linear import straight_is_static


def pipe_jacobian(model: PipeModel, x: np.ndarray) -> np.ndarray:
    """D_x F of the first-order form of Eq. (20) at x = (q, q'), shape (2n, 2n).

    ``[[0, I], [-M^{-1} R_q, -M^{-1} R_q']]`` with the analytic Jacobians of
    :meth:`PipeModel.jacobians` at (q, q', a), a = -M^{-1} R(q, q', 0) the
    acceleration (docs/theory/stability.md, "First-order form"): the companion
    matrix of :func:`fempipe.core.companion.first_order_matrix`, M factorised
    once by Cholesky for both the acceleration and the blocks.
    """
    n = model.n
    q, qd = x[:n], x[n:]
    M = model.mass_matrix(q)
    cf = sla.cho_factor(M)
    a = -sla.cho_solve(cf, model.residual(q, qd, None))
    Jq, Jqd, _ = model.jacobians(q, qd, a)
    return first_order_matrix(Jq, Jqd, M, factor="cholesky", mass_factor=cf)


def dense(A) -> np.ndarray:
    """A matrix of the model (a scipy.sparse matrix or an array) as a dense ndarray."""
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def _without_bending(model: PipeModel) -> PipeModel:
    """The model with the bending matrix K set to zero (a shallow copy).

    Its residual is R - K q - mu K q' and its Jacobians lack the constant K
    and mu K, the largest entries of the finite-element Jacobian (~h^-2):
    differenced, they would only add their rounding.
    """
    disc = copy.copy(model.disc)
    K = model.disc.K
    disc.K = sp.csr_matrix(K.shape) if sp.issparse(K) else np.zeros(K.shape)
    # A new model, not with_params: that would share the caches of the model's
    # matrices (a dense copy of K among them).
    return PipeModel(disc, model.params)


def _mirror_even(model: PipeModel, x0: np.ndarray) -> bool:
    """Whether J is even about x0: the straight pipe x0 = 0 at alpha = 0 or pi.

    The mirror symmetry (theta, alpha) -> (-theta, -alpha) of Eq. (20) maps
    alpha = 0 and pi onto themselves, so there F is odd, F(-x) = -F(x) (every
    term: gravity along the pipe, follower, Coriolis, inertia, the end mass,
    external damping, springs tied to points of the axis), and its Jacobian
    is even, J(-x) = J(x).  At alpha = pi the odd part of gravity is off by
    sin(pi) ~ 1e-16.  A subclass of PipeModel may add terms that are not odd:
    it takes the general path.
    """
    return type(model) is PipeModel and straight_is_static(model.params) and not np.any(x0)


def pipe_derivatives(
    model: PipeModel, x0: np.ndarray, mirror: bool | None = None
) -> Callable[[np.ndarray, float, float], tuple[np.ndarray, np.ndarray]]:
    """``(u, h, dv=0) -> (DJ[u], D2J[u, u])`` of :func:`pipe_jacobian` about x0, without
    differencing the bending matrix.

    The lower block of J is ``-N (Kc + X(x))`` with N = M(q)^{-1},
    Kc = [K, mu K] constant and X(x) the rest of ``[R_q, R_q']`` (a model
    without bending, :func:`_without_bending`, at the full model's
    acceleration).  With Y = N0 (Kc + X(x0)) formed once and differences of
    M and X only (the identities dN = -N dM N and
    d^2N = 2 N dM N dM N - N d^2M N):

        DJ = N0 (DM Y - DX),
        D2J = N0 (D2M Y - D2X - 2 DM N0 (DM Y - DX)).

    The rounding is then eps |M|, eps |X| over h^2 instead of eps |K| / h^2.
    ``dv`` moves v by ``h dv`` along with x (the derivative along the
    static branch, for lambda'(v)).

    On the straight pipe at alpha = 0 or pi (``mirror``; default: detected,
    :func:`_mirror_even`) J is even about x0 = 0, so J(x0 - h u) = J(x0 + h u):
    DJ = 0 (B = 0) and D2J = 2 (J(x0 + h u) - J(x0)) / h^2 take one
    evaluation instead of two (not for ``dv``, which moves v as well).
    """
    n = model.n
    bare = _without_bending(model)
    Kd = dense(model.disc.K)
    Kc = np.hstack([Kd, model.params.mu * Kd])
    v0 = model.params.v

    def parts(x: np.ndarray, dv: float) -> tuple[np.ndarray, np.ndarray]:
        full, m = model, bare
        if dv:
            full = model.with_params(replace(model.params, v=v0 + dv))
            m = _without_bending(full)
        q, qd = x[:n], x[n:]
        M = full.mass_matrix(q)
        a = -sla.cho_solve(sla.cho_factor(M), full.residual(q, qd, None))
        Jq, Jqd, _ = m.jacobians(q, qd, a)
        return M, np.hstack([Jq, Jqd])

    M0, X0 = parts(x0, 0.0)
    # The split must be exact: the full model's Jacobians are Kc + X.
    Jq, Jqd, _ = model.jacobians(x0[:n], x0[n:], np.zeros(n))
    scale = np.abs(Kc).max() + np.abs(X0).max()
    if np.abs(np.hstack([Jq, Jqd]) - Kc - X0).max() > 1e-12 * scale:
        raise RuntimeError("the model without bending does not split the Jacobian as K + X")
    cf = sla.cho_factor(M0)
    Y = sla.cho_solve(cf, Kc + X0)
    even = _mirror_even(model, x0) if mirror is None else bool(mirror)

    def deriv(u: np.ndarray, h: float, dv: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        Mp, Xp = parts(x0 + h * u, h * dv)
        Mm, Xm = (Mp, Xp) if even and not dv else parts(x0 - h * u, -h * dv)
        DM, DX = (Mp - Mm) / (2.0 * h), (Xp - Xm) / (2.0 * h)
        D2M, D2X = (Mp - 2.0 * M0 + Mm) / (h * h), (Xp - 2.0 * X0 + Xm) / (h * h)
        W = DM @ Y - DX
        lower1 = sla.cho_solve(cf, W)
        lower2 = sla.cho_solve(cf, D2M @ Y - D2X - 2.0 * DM @ lower1)
        DJ, D2J = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n))
        DJ[n:], D2J[n:] = lower1, lower2
        return DJ, D2J

    return deriv

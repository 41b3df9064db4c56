"""The pipe's first-order Jacobian and its derivatives for the normal form
(docs/theory/stability.md, "First-order form" and "Derivatives")."""

from __future__ import annotations

import copy
from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from fempipe.core.companion import first_order_matrix
from fempipe.model.plane.operators import PipeModel

from ..linear import straight_is_static


def pipe_jacobian(model, x: np.ndarray) -> np.ndarray:
    """D_x F of the first-order form of Eq. (20) at x = (q, q'), shape (2n, 2n).

    ``[[0, I], [-M^{-1} R_q, -M^{-1} R_q']]`` with the analytic Jacobians at the acceleration
    a = -M^{-1} R(q, q', 0) (docs/theory/stability.md, "First-order form"); ``model`` is a
    :class:`PipeModel` or the 3-D :class:`~fempipe.model.three_d.model.PipeModel3D` (x = (U, U')).
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
    """The model with the bending matrix K set to zero: its Jacobians lack the constant K and
    mu K, which differenced would only add their rounding."""
    disc = copy.copy(model.disc)
    K = model.disc.K
    disc.K = sp.csr_matrix(K.shape) if sp.issparse(K) else np.zeros(K.shape)
    # A new model, not with_params: that would share the caches of the matrices (K among them).
    return PipeModel(disc, model.params)


def _mirror_even(model: PipeModel, x0: np.ndarray) -> bool:
    """Whether J is even about x0 (x0 = 0 at alpha = 0, pi; not for a PipeModel subclass)."""
    return type(model) is PipeModel and straight_is_static(model.params) and not np.any(x0)


def pipe_derivatives(
    model: PipeModel, x0: np.ndarray, mirror: bool | None = None
) -> Callable[[np.ndarray, float, float], tuple[np.ndarray, np.ndarray]]:
    """``(u, h, dv=0) -> (DJ[u], D2J[u, u])`` of :func:`pipe_jacobian` about x0 without differencing
    the bending matrix (docs/theory/stability.md, "Derivatives").

    With N0 = M(q0)^{-1}, Y = N0 (Kc + X(x0)): DJ = N0 (DM Y - DX), D2J = N0 (D2M Y - D2X - 2 DM
    N0 (DM Y - DX)).  ``dv`` moves v by ``h dv`` with x; where J is even (``mirror``) one
    evaluation replaces two.
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

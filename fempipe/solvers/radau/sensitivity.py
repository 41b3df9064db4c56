"""The derivative of one Radau IIA step with respect to its initial state and a parameter.

Exact (from the stage Jacobians, no freezing); :class:`~fempipe.solvers.radau.Radau` chains
it into the monodromy matrix (``sensitivity=True``) and the derivative by v (contract rule 8).

Derivation: docs/theory/numerics.md, "The derivative of a step".
"""

from __future__ import annotations

import numpy as np

from .lapack import lu_factor, lu_solve
from .tableau import A2, A, C

__all__ = ["chain_step", "chain_step_blocks", "step_derivative"]


def step_derivative(h: float, Ks, Ds, Ms, dR_dp: np.ndarray | None = None) -> np.ndarray:
    """The part of d y1 / d (y0, p) through the stage accelerations (``Ks, Ds, Ms``: the stages'
    Jacobians; ``dR_dp`` (3, n)), shape (2n, 2n) or (2n, 2n + 1)."""
    n = Ks.shape[1]
    # big[i, :, j, :] = M_i d_ij + h a_ij D_i + h^2 (a^2)_ij K_i
    big = np.einsum("ij,iab->iajb", h * A, Ds) + np.einsum("ij,iab->iajb", h * h * A2, Ks)
    big[np.arange(3), :, np.arange(3), :] += Ms
    with_p = dR_dp is not None
    rhs = np.empty((3, n, 2 * n + with_p))
    np.negative(Ks, out=rhs[:, :, :n])
    rhs[:, :, n : 2 * n] = -(C[:, None, None] * h * Ks + Ds)
    if with_p:
        # dA/dp at fixed y0: the same matrix, the right side -dR_i/dp.
        rhs[:, :, -1] = -dR_dp
    dA = lu_solve(lu_factor(big.reshape(3 * n, 3 * n)), rhs.reshape(3 * n, -1))
    dA = dA.reshape(3, n, -1)
    # d y1 / d (y0, p) = [[I, h I], [0, I]] (the stage formulas at c_3 = 1)
    # plus (dq, dp): the derivatives through the stage accelerations.
    D = np.empty((2 * n, dA.shape[2]))
    np.einsum("j,jab->ab", (h * h) * A2[2], dA, out=D[:n])
    np.einsum("j,jab->ab", h * A[2], dA, out=D[n:])
    return D


def chain_step(D: np.ndarray, h: float, S: np.ndarray, dy_dp: np.ndarray | None = None):
    """Y1 = [[I, h I], [0, I]] Y + D Y for one step's derivative D: (d y1/d y0, d y1/dp), the
    latter None without ``dy_dp``."""
    n = S.shape[0] // 2
    with_p = dy_dp is not None
    Y = np.column_stack([S, dy_dp]) if with_p else S
    new = D[:, : 2 * n] @ Y
    new[:n] += Y[:n] + h * Y[n:]
    new[n:] += Y[n:]
    if with_p:
        new[:, -1] += D[:, -1]
        return new[:, :-1], new[:, -1]
    return new, None


def chain_step_blocks(h: float, Ks, Ds, Ms, dR_dp, S: np.ndarray, dy_dp: np.ndarray | None, blocks):
    """:func:`step_derivative` and :func:`chain_step` block by block, for Jacobians and ``S`` with
    no coupling between the groups ``blocks``: the same numbers to round-off, entries between
    groups exactly zero.  Returns new arrays as :func:`chain_step`.
    """
    n = Ks.shape[1]
    S = S.copy()
    dy_dp = None if dy_dp is None else dy_dp.copy()
    for idx in blocks:
        ii = np.ix_(np.arange(3), idx, idx)
        I = np.concatenate([idx, n + idx])
        D = step_derivative(h, Ks[ii], Ds[ii], Ms[ii], None if dR_dp is None else dR_dp[:, idx])
        Sb, db = chain_step(D, h, S[np.ix_(I, I)], None if dy_dp is None else dy_dp[I])
        S[np.ix_(I, I)] = Sb
        if dy_dp is not None:
            dy_dp[I] = db
    return S, dy_dp

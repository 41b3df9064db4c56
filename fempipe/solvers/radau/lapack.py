"""LU factors and solves through LAPACK getrf / getrs directly.

``scipy.linalg.lu_factor`` / ``lu_solve`` add argument checks that cost as much as the
factorisation of the integrator's small matrices.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["BlockFactors", "lu_factor", "lu_factor_blocks", "lu_solve"]


def lu_factor(a: np.ndarray):
    """LU factors ``(lu, piv)`` of a real or complex square matrix (overwrites ``a``): LAPACK getrf."""
    getrf = sla.lapack.zgetrf if np.iscomplexobj(a) else sla.lapack.dgetrf
    lu, piv, info = getrf(a, overwrite_a=True)
    if info < 0:  # pragma: no cover - a wrong argument, not a singular matrix
        raise ValueError(f"getrf: illegal argument {-info}")
    return lu, piv


class BlockFactors:
    """The LU factors of a block-diagonal matrix: ``parts``, a list of (index array, factors)."""

    __slots__ = ("parts",)

    def __init__(self, parts: list) -> None:
        self.parts = parts


def lu_factor_blocks(a: np.ndarray, blocks):
    """:func:`lu_factor` of ``a``, or, with ``blocks`` (index arrays partitioning its rows and
    columns, between which ``a`` is zero), of each diagonal block (:class:`BlockFactors`)."""
    if blocks is None:
        return lu_factor(a)
    return BlockFactors([(idx, lu_factor(a[np.ix_(idx, idx)])) for idx in blocks])


def lu_solve(lu_piv, b: np.ndarray) -> np.ndarray:
    """Solve with the factors of :func:`lu_factor` (LAPACK getrs) or :func:`lu_factor_blocks`."""
    if isinstance(lu_piv, BlockFactors):
        dtype = np.result_type(b, *(f[0] for _, f in lu_piv.parts))
        x = np.empty(b.shape, dtype=dtype)
        for idx, f in lu_piv.parts:
            x[idx] = lu_solve(f, b[idx])
        return x
    lu, piv = lu_piv
    getrs = sla.lapack.zgetrs if np.iscomplexobj(lu) else sla.lapack.dgetrs
    x, info = getrs(lu, piv, b)
    if info != 0:  # pragma: no cover
        raise ValueError(f"getrs: illegal argument {-info}")
    return x

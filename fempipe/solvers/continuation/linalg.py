"""A linear solve that also gives the sign and size of the determinant: the test function of
branch points (it flips at a simple branch point, not at a fold), from the same LU.
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla

__all__ = ["permutation_sign", "solve_with_determinant"]


def permutation_sign(perm: np.ndarray) -> int:
    """Sign of a permutation given as an index array, O(n)."""
    perm = np.asarray(perm)
    seen = np.zeros(perm.size, dtype=bool)
    sign = 1
    for i in range(perm.size):
        if not seen[i]:
            j, length = i, 0
            while not seen[j]:
                seen[j] = True
                j = perm[j]
                length += 1
            if length % 2 == 0:
                sign = -sign
    return sign


def solve_with_determinant(A, b: np.ndarray) -> tuple[np.ndarray, int, float]:
    """Solve A x = b with sign(det A) and log|det A| from the same LU (LAPACK dense, SuperLU sparse)."""
    if sp.issparse(A):
        lu = spla.splu(A.tocsc())
        d = lu.U.diagonal()  # SuperLU's L has a unit diagonal
        sign = int(np.prod(np.sign(d))) * permutation_sign(lu.perm_r) * permutation_sign(lu.perm_c)
        x = lu.solve(b)
    else:
        lu, piv = sla.lu_factor(A)
        d = np.diag(lu)
        swaps = int(np.count_nonzero(piv != np.arange(piv.size)))
        sign = int(np.prod(np.sign(d))) * (-1 if swaps % 2 else 1)
        x = sla.lu_solve((lu, piv), b)
    with np.errstate(divide="ignore"):
        logdet = float(np.sum(np.log(np.abs(d))))
    return x, sign, logdet

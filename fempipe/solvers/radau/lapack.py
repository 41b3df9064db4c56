"""LU factors and solves through LAPACK getrf / getrs directly.

``scipy.linalg.lu_factor`` / ``lu_solve`` do the same with argument checks
that cost as much as the factorisation itself at n = 48 (they run twice per
step and at every Newton iteration of the stage equations).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

__all__ = ["lu_factor", "lu_solve"]


def lu_factor(a: np.ndarray):
    """LU factors of a real or complex square matrix (overwrites ``a``): LAPACK getrf.

    Returns
    -------
    (lu, piv)
        For :func:`lu_solve`.
    """
    getrf = sla.lapack.zgetrf if np.iscomplexobj(a) else sla.lapack.dgetrf
    lu, piv, info = getrf(a, overwrite_a=True)
    if info < 0:  # pragma: no cover - a wrong argument, not a singular matrix
        raise ValueError(f"getrf: illegal argument {-info}")
    return lu, piv


def lu_solve(lu_piv, b: np.ndarray) -> np.ndarray:
    """Solve with the factors of :func:`lu_factor` (LAPACK getrs)."""
    lu, piv = lu_piv
    getrs = sla.lapack.zgetrs if np.iscomplexobj(lu) else sla.lapack.dgetrs
    x, info = getrs(lu, piv, b)
    if info != 0:  # pragma: no cover
        raise ValueError(f"getrs: illegal argument {-info}")
    return x

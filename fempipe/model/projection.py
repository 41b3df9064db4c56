"""Transfer of a state between discretizations: the L2 projection of theta.

Seeds a computation on one discretization with the result of another (a refined shooting,
a convergence study's members, an error estimate's refined run).
"""

from __future__ import annotations

import numpy as np

from fempipe.model.discretization import Discretization

__all__ = ["project"]


def project(src: Discretization, q: np.ndarray, dst: Discretization) -> np.ndarray:
    r"""Coefficients on ``dst`` of the L2 projection of theta = ``src``\ (q), ``G c = \int phi_i
    theta`` (exact for a refinement); ``q`` (src.n,) or (src.n, m) (states as columns)."""
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    q = np.asarray(q, dtype=float)
    theta = src.evaluate(q, dst.quad.x)
    w = dst.quad.w if theta.ndim == 1 else dst.quad.w[:, None]
    rhs = dst.Phi.T @ (w * theta)
    if sp.issparse(dst.gram):
        return np.asarray(spla.spsolve(dst.gram.tocsc(), rhs)).reshape(rhs.shape)
    return np.linalg.solve(np.asarray(dst.gram), rhs)

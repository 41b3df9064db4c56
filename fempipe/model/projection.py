"""Transfer of a state between discretizations: the L2 projection of theta.

Used wherever the result of one discretization seeds a computation on
another: a limit cycle shot on a refined mesh from a coarse one, the members
of a convergence study started from one seed, the refined run of an error
estimate started from the coarse state.
"""

from __future__ import annotations

import numpy as np

from .discretization import Discretization

__all__ = ["project"]


def project(src: Discretization, q: np.ndarray, dst: Discretization) -> np.ndarray:
    """Coefficients on ``dst`` of the L2 projection of theta = ``src``\\ (q).

    Solves ``G c = \\int phi_i theta`` with the Gram matrix G of ``dst`` and
    its quadrature.  When the space of ``src`` lies in that of ``dst`` (a
    mesh and its refinement, the first N of more modes) and the quadrature of
    ``dst`` integrates its functions exactly (elements) or to round-off
    (modes), theta is transferred exactly.

    Parameters
    ----------
    src, dst : Discretization
    q : ndarray, shape (src.n,) or (src.n, m)
        One state or m states (columns).

    Returns
    -------
    ndarray, shape (dst.n,) or (dst.n, m)
    """
    import scipy.sparse as sp
    import scipy.sparse.linalg as spla

    q = np.asarray(q, dtype=float)
    theta = src.evaluate(q, dst.quad.x)
    w = dst.quad.w if theta.ndim == 1 else dst.quad.w[:, None]
    rhs = dst.Phi.T @ (w * theta)
    if sp.issparse(dst.gram):
        return np.asarray(spla.spsolve(dst.gram.tocsc(), rhs)).reshape(rhs.shape)
    return np.linalg.solve(np.asarray(dst.gram), rhs)

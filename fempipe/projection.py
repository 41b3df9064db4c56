"""Transfer of a state between discretisations: the L2 projection of theta.

Used wherever the result of one discretisation seeds a computation on
another (a limit cycle shot on a refined mesh from a coarse one, the members
of a convergence study started from one seed).
"""

from __future__ import annotations

import numpy as np

from .discretization import Discretization

__all__ = ["project"]


def project(src: Discretization, q: np.ndarray, dst: Discretization) -> np.ndarray:
    """Coefficients on ``dst`` of the L2 projection of theta = ``src``\\ (q).

    Minimises ``\\int_0^1 (theta_dst - theta_src)^2 dxi`` summed by the Gauss
    rule of ``dst`` (a weighted least-squares problem, so it does not need a
    Gram matrix that ``dst`` might assemble with another rule).

    Parameters
    ----------
    src, dst : Discretization
    q : ndarray, shape (src.n,)

    Returns
    -------
    ndarray, shape (dst.n,)
    """
    x, w = dst.quad.x, dst.quad.w
    theta = src.evaluate(np.asarray(q, dtype=float), x)
    Phi = dst.Phi.toarray() if dst.sparse else np.asarray(dst.Phi)
    sw = np.sqrt(w)
    return np.linalg.lstsq(Phi * sw[:, None], theta * sw, rcond=None)[0]

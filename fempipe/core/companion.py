"""The first-order (companion) form of a quadratic eigenproblem.

With z = (x, lambda x), (lambda^2 M + lambda C + K) x = 0 is A z = lambda B z with
A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]], or the standard problem of B^{-1} A.  Linear
algebra only, shared by the stability analysis and the Hopf normal forms so that their
matrices come from the same floating-point operations.  Derivation: docs/theory/stability.md.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
import scipy.linalg as sla

__all__ = ["first_order_pencil", "first_order_matrix"]


def first_order_pencil(K, C, M) -> tuple[np.ndarray, np.ndarray]:
    """The pencil (A, B) of (lambda^2 M + lambda C + K) x = 0 in first-order form.

    Parameters
    ----------
    K, C, M : ndarray, shape (n, n)
        Dense stiffness, damping and mass (real or complex).

    Returns
    -------
    A, B : ndarray, shape (2n, 2n)
        ``[[0, I], [-K, -C]]`` and ``[[I, 0], [0, M]]``, no arithmetic beyond negations.

    Examples
    --------
    >>> import numpy as np
    >>> A, B = first_order_pencil(np.eye(1), np.zeros((1, 1)), np.eye(1))
    >>> A.tolist(), B.tolist()
    ([[0.0, 1.0], [-1.0, -0.0]], [[1.0, 0.0], [0.0, 1.0]])
    """
    n = K.shape[0]
    Z, I = np.zeros((n, n)), np.eye(n)
    A = np.block([[Z, I], [-K, -C]])
    B = np.block([[I, Z], [Z, M]])
    return A, B


def first_order_matrix(
    K, C, M, *, factor: Literal["cholesky", "lu"] = "cholesky", mass_factor: tuple | None = None
) -> np.ndarray:
    """B^{-1} A = [[0, I], [-M^{-1} K, -M^{-1} C]], without forming M^{-1}.

    Parameters
    ----------
    K, C, M : ndarray, shape (n, n)
        Dense real stiffness, damping and mass.
    factor : {'cholesky', 'lu'}
        One Cholesky of an SPD M for both blocks, or one LU solve per block (they differ by
        round-off).
    mass_factor : tuple, optional
        ``scipy.linalg.cho_factor(M)`` if the caller has it (``"cholesky"`` only).

    Examples
    --------
    >>> import numpy as np
    >>> first_order_matrix(8.0 * np.eye(1), 2.0 * np.eye(1), 4.0 * np.eye(1)).tolist()
    [[0.0, 1.0], [-2.0, -0.5]]
    """
    n = K.shape[0]
    if factor == "cholesky":
        cf = sla.cho_factor(M) if mass_factor is None else mass_factor
        out = np.zeros((2 * n, 2 * n))
        out[:n, n:] = np.eye(n)
        out[n:] = -sla.cho_solve(cf, np.hstack([K, C]))
        return out
    if factor == "lu":
        if mass_factor is not None:
            raise ValueError("mass_factor is a Cholesky factorisation: only with factor='cholesky'")
        return np.block([[np.zeros((n, n)), np.eye(n)], [-sla.solve(M, K), -sla.solve(M, C)]])
    raise ValueError(f"factor must be 'cholesky' or 'lu', got {factor!r}")

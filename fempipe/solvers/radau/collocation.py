"""The collocation polynomial of one Radau IIA step: the integrator's one dense output.

The cubic through (0, y_old) and the stages (:data:`NODES`), in three floating-point forms
equal to round-off, each kept because its users depend on its last bit: the increment form
(:meth:`Radau.dense <fempipe.solvers.radau.Radau.dense>`), the barycentric Lagrange form (the
extrapolation of the stage accelerations) and the plain Lagrange product (the tip extrema of
:mod:`fempipe.analyses.periodic`).

Derivation: docs/theory/numerics.md, "The collocation polynomial".
"""

from __future__ import annotations

import numpy as np

from .tableau import C

#: Nodes of the collocation polynomial on s = (t - t_old)/h: 0 and c_1, c_2, c_3 = 1.
NODES = np.r_[0.0, C]
#: Cubic through (0, 0) and (c_i, Z_i): coefficients of s, s^2, s^3 (rows) per Z_i.
INCREMENT_MATRIX = np.linalg.inv(np.vander(C, 4, increasing=True)[:, 1:])
#: Barycentric-like weights 1 / prod_{m != j} (x_j - x_m) of the nodes.
LAGRANGE_WEIGHTS = np.array(
    [1.0 / np.prod([NODES[j] - NODES[m] for m in range(4) if m != j]) for j in range(4)]
)


def increment_weights(s: float) -> np.ndarray:
    """Weights of Y_i - y_old at one s, shape (3,) (increment form)."""
    return np.array([s, s * s, s**3]) @ INCREMENT_MATRIX


def evaluate_increment(s: float, y_old: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """y(s) at one s in the increment form; y_old shape (n,), Y shape (3, n)."""
    return y_old + increment_weights(s) @ (Y - y_old)


def lagrange_weights(s: np.ndarray) -> np.ndarray:
    """Weights of (y_old, Y_1, Y_2, Y_3) at the points s, shape (m, 4) (barycentric form)."""
    d0, d1, d2, d3 = (np.asarray(s)[:, None] - NODES[None, :]).T
    d01, d23 = d0 * d1, d2 * d3
    L = np.empty((d0.shape[0], 4))
    L[:, 0], L[:, 1], L[:, 2], L[:, 3] = d1 * d23, d0 * d23, d01 * d3, d01 * d2
    L *= LAGRANGE_WEIGHTS
    return L


def evaluate_lagrange(s: np.ndarray, y_old: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """y at the points s, shape (m, n), in the barycentric Lagrange form."""
    L = lagrange_weights(s)
    return L[:, :1] * y_old + L[:, 1:] @ Y


def product_weights(s: np.ndarray) -> np.ndarray:
    """Weights of (y_old, Y_1, Y_2, Y_3) at the points s, shape (m, 4), in the plain product form
    ``prod_{m != j} (s - x_m)/(x_j - x_m)`` multiplied in the order m = 0..3.
    """
    s = np.atleast_1d(s)[:, None]
    L = np.ones((s.shape[0], 4))
    for j in range(4):
        for m in range(4):
            if m != j:
                L[:, j] *= (s[:, 0] - NODES[m]) / (NODES[j] - NODES[m])
    return L


def evaluate_product(s: np.ndarray, y_old: np.ndarray, Y: np.ndarray) -> np.ndarray:
    """y at the points s, shape (m, n), in the plain product form (:func:`product_weights`)."""
    return product_weights(s) @ np.vstack([y_old[None, :], Y])

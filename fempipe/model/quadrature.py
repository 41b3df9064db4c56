r"""Gauss quadrature on a partition of [0, 1] and the integration operators of Eq. (20).

Fields are values at the Gauss points of each cell; the integrals of Eq. (20) become
``cumulative`` (C f)_q = \int_0^{x_q} f and ``from_tip`` (C^R f)_q = \int_{x_q}^1 f, exact
for polynomials of degree ``n_g - 1`` per cell, O(n_q), and exact adjoints ``W C^R = C^T W``.

Derivation: docs/theory/weak_form.md, "The integration operators".
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import legendre

__all__ = ["LineQuadrature", "gauss_collocation_matrix", "lagrange_integrals"]


def lagrange_integrals(points: np.ndarray, s: np.ndarray) -> np.ndarray:
    r"""``P[m, q] = \int_0^{s_m} l_q(x) dx`` for the Lagrange basis on ``points`` (shape (k,), in
    [0, 1]) and upper limits ``s`` (shape (m,)); shape (m, k).
    """
    c = np.asarray(points, dtype=float)
    s = np.asarray(s, dtype=float)
    k = c.size
    # Legendre basis on [-1, 1] keeps the Vandermonde well conditioned.
    V = legendre.legvander(2.0 * c - 1.0, k - 1)  # V[p, j] = P_j(2 c_p - 1)
    # \int_0^{s} P_j(2x-1) dx = (1/2) \int_{-1}^{2s-1} P_j(u) du
    P = np.empty((s.size, k))
    for j in range(k):
        coef = np.zeros(k)
        coef[j] = 1.0
        P[:, j] = 0.5 * legendre.legval(2.0 * s - 1.0, legendre.legint(coef, lbnd=-1.0))
    return P @ np.linalg.inv(V)


def gauss_collocation_matrix(points: np.ndarray) -> np.ndarray:
    """Return ``a[p, q] = \\int_0^{c_p} l_q(x) dx`` on the reference cell [0, 1], shape (k, k)."""
    return lagrange_integrals(points, points)


class LineQuadrature:
    r"""Gauss--Legendre quadrature on cells of [0, 1] with integration operators.

    Parameters
    ----------
    edges : array_like, shape (n_cells + 1,)
        Strictly increasing cell boundaries from 0 to 1.
    n_gauss : int
        Gauss points per cell (>= 1).

    Attributes
    ----------
    x, w : ndarray, shape (n_q,)
        Points (cell by cell) and weights; ``w @ f`` integrates f over [0, 1].
    collocation : ndarray, shape (n_gauss, n_gauss)
        ``a[p, q] = \int_0^{c_p} l_q`` on the reference cell: the in-cell part of :meth:`cumulative`.
    """

    def __init__(self, edges: np.ndarray, n_gauss: int) -> None:
        edges = np.asarray(edges, dtype=float)
        if edges.ndim != 1 or edges.size < 2:
            raise ValueError("edges must be a 1-D array with at least two entries")
        if not np.all(np.diff(edges) > 0):
            raise ValueError("edges must be strictly increasing")
        if abs(edges[0]) > 1e-14 or abs(edges[-1] - 1.0) > 1e-14:
            raise ValueError("edges must start at 0 and end at 1")
        if int(n_gauss) < 1:
            raise ValueError(f"n_gauss must be >= 1, got {n_gauss}")
        self.edges = edges
        self.n_gauss = int(n_gauss)
        g, wg = legendre.leggauss(self.n_gauss)
        self.ref_points = 0.5 * (g + 1.0)
        self.ref_weights = 0.5 * wg
        self.h = np.diff(edges)
        self.n_cells = self.h.size
        self.x = (edges[:-1, None] + self.h[:, None] * self.ref_points[None, :]).ravel()
        self.w = (self.h[:, None] * self.ref_weights[None, :]).ravel()
        self.n_q = self.x.size
        self.collocation = gauss_collocation_matrix(self.ref_points)

    @classmethod
    def uniform(cls, n_cells: int, n_gauss: int) -> LineQuadrature:
        return cls(np.linspace(0.0, 1.0, int(n_cells) + 1), n_gauss)

    def _cells(self, f: np.ndarray) -> np.ndarray:
        """View f (n_q along axis 0) as (n_cells, n_gauss, ...)."""
        return f.reshape((self.n_cells, self.n_gauss) + f.shape[1:])

    def cell_integrals(self, f: np.ndarray) -> np.ndarray:
        """Integral of f over each cell; f has the quadrature index on axis 0."""
        fc = self._cells(np.asarray(f))
        return np.einsum("k,ck...->c...", self.ref_weights, fc) * self.h.reshape(
            (-1,) + (1,) * (fc.ndim - 2)
        )

    def at_edges(self, f: np.ndarray) -> np.ndarray:
        """``\\int_0^{x_e} f`` at every cell edge, shape (n_cells + 1, ...)."""
        totals = self.cell_integrals(f)
        out = np.zeros((self.n_cells + 1,) + totals.shape[1:], dtype=totals.dtype)
        np.cumsum(totals, axis=0, out=out[1:])
        return out

    def cumulative(self, f: np.ndarray) -> np.ndarray:
        r"""``(C f)_q = \int_0^{x_q} f``, quadrature index on axis 0; exact per cell, O(n_q)."""
        f = np.asarray(f)
        fc = self._cells(f)
        hs = self.h.reshape((-1,) + (1,) * (fc.ndim - 1))
        local = np.einsum("pq,cq...->cp...", self.collocation, fc) * hs
        start = self.at_edges(f)[:-1]
        return (local + start[:, None]).reshape(f.shape)

    def from_tip(self, f: np.ndarray) -> np.ndarray:
        """``(C^R f)_q = \\int_{x_q}^1 f``; the discrete adjoint of :meth:`cumulative`."""
        f = np.asarray(f)
        return self.integrate(f)[None] - self.cumulative(f)

    def integrate(self, f: np.ndarray) -> np.ndarray:
        """``\\int_0^1 f``; quadrature index on axis 0 of f."""
        return np.tensordot(self.w, np.asarray(f), axes=(0, 0))

    def cumulative_cells(self, f: np.ndarray) -> np.ndarray:
        """:meth:`cumulative` with the trailing axes flattened into one ``matmul`` (fast for many
        trailing axes, unlike the einsum; summed in another order)."""
        nc, ng = self.n_cells, self.n_gauss
        fc = f.reshape(nc, ng, -1)
        local = np.matmul(self.collocation, fc) * self.h[:, None, None]
        totals = (self.ref_weights @ fc) * self.h[:, None]
        start = np.cumsum(totals, axis=0) - totals
        return (local + start[:, None, :]).reshape(f.shape)

    def from_tip_cells(self, f: np.ndarray) -> np.ndarray:
        """:meth:`from_tip` (``\\int_{x_q}^1 f``) through :meth:`cumulative_cells`."""
        fc = f.reshape(f.shape[0], -1)
        return (self.w @ fc - self.cumulative_cells(fc)).reshape(f.shape)

    def cumulative_adjoint(self, g: np.ndarray) -> np.ndarray:
        """``C^T g`` of :meth:`cumulative_cells`, O(n_q) per column (docs/theory/weak_form.md)."""
        nc, ng = self.n_cells, self.n_gauss
        gc = g.reshape(nc, ng, -1)
        out = np.matmul(self.collocation.T, gc)
        s = gc.sum(axis=1)
        after = np.cumsum(s[::-1], axis=0)[::-1]
        after -= s
        for b in range(ng):
            out[:, b] += self.ref_weights[b] * after
        out *= self.h[:, None, None]
        return out.reshape(g.shape)

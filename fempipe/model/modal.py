"""The modal Galerkin discretization (the paper's Eq. (22)): :class:`Modal` and the beam modes.

The second implementation of :mod:`fempipe.model.discretization`'s contract: N global modes,
the paper's sine modes or the slopes of the clamped-free beam modes (:func:`beam_roots`,
:func:`beam_mode_slopes`), with their error orders (:data:`EXPECTED_ORDER`).

Derivation: docs/theory/convergence.md.
"""

from __future__ import annotations

import numpy as np

from fempipe.core.rootfinding import brentq
from fempipe.model.quadrature import LineQuadrature

__all__ = ["EXPECTED_ORDER", "Modal", "beam_mode_slopes", "beam_roots"]


class Modal:
    """Modal Galerkin discretization: N global modes of [0, 1] (docs/theory/convergence.md).

    ``basis="sine"``: the paper's sin(k_r xi), k_r = (2r - 1) pi / 2 (Eq. (22)), error ~ N^-3;
    ``basis="beam"``: the slopes of the clamped-free beam modes, exact for the straight pipe
    without flow and gravity, error ~ N^-4.

    Parameters
    ----------
    n_modes : int
        N >= 1.
    n_cells, n_gauss : int, optional
        Quadrature of the nonlinear integrals (default max(32, 4N) cells of 8 points: the
        error is the truncation alone).
    basis : {"sine", "beam"}
        Keyword only.  ``k`` holds the wavenumbers k_r or lambda_r.
    """

    #: The accepted values of ``basis``.
    BASES = ("sine", "beam")

    def __init__(
        self, n_modes: int = 4, n_cells: int | None = None, n_gauss: int = 8, *, basis: str = "sine"
    ) -> None:
        n_modes = int(n_modes)
        if n_modes < 1:
            raise ValueError(f"n_modes must be >= 1, got {n_modes}")
        if basis not in self.BASES:
            raise ValueError(f"basis must be one of {', '.join(self.BASES)}, got {basis!r}")
        self.n_modes = n_modes
        self.n = n_modes
        self.basis = basis
        self.quad = LineQuadrature.uniform(n_cells or max(32, 4 * n_modes), n_gauss)
        x = self.quad.x
        if basis == "sine":
            self.k = (2.0 * np.arange(1, n_modes + 1) - 1.0) * np.pi / 2.0
            self.Phi = np.sin(np.outer(x, self.k))
            self.dPhi = np.cos(np.outer(x, self.k)) * self.k
            self.tip = np.sin(self.k)
            # \int_0^1 phi_i' phi_j' = k_i^2 / 2 delta_ij (orthogonal cosines).
            self.K = np.diag(self.k**2 / 2.0)
        else:
            self.k = beam_roots(n_modes)
            self.Phi = beam_mode_slopes(self.k, x)
            self.dPhi = beam_mode_slopes(self.k, x, derivative=1)
            self.tip = beam_mode_slopes(self.k, [1.0])[0]
            # \int_0^1 psi_i' psi_j' = lambda_i^2 delta_ij (docs/theory/convergence.md).
            self.K = np.diag(self.k**2)
        # \int_0^1 phi_i phi_j (delta_ij / 2 for the sines); summed by the
        # quadrature like every integral of the nonlinear terms.
        self.gram = (self.Phi.T * self.quad.w) @ self.Phi
        self.sparse = False

    @property
    def name(self) -> str:
        return f"modal:{self.n_modes}" if self.basis == "sine" else f"modal-beam:{self.n_modes}"

    @property
    def expected_order(self) -> float:
        """Order p of the error ~ N^-p in tip values, v_cr and eigenvalues (:data:`EXPECTED_ORDER`)."""
        return EXPECTED_ORDER[self.basis]

    def evaluate(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """theta(xi) at arbitrary points in [0, 1]."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        if self.basis == "sine":
            return np.sin(np.outer(xi, self.k)) @ np.asarray(q)
        return beam_mode_slopes(self.k, xi) @ np.asarray(q)

    def basis_values(self, xi: np.ndarray) -> np.ndarray:
        """phi_r(xi) at arbitrary points, analytic, shape (m, N)."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        if self.basis == "sine":
            return np.sin(np.outer(xi, self.k))
        return beam_mode_slopes(self.k, xi)

    def refined(self, factor: int = 2) -> Modal:
        """Return the same basis with ``factor`` times as many modes (default quadrature)."""
        return Modal(int(factor) * self.n_modes, basis=self.basis)

    def to_dict(self) -> dict:
        return {
            "kind": "modal",
            "n_modes": self.n_modes,
            "n_dofs": self.n,
            "n_cells": self.quad.n_cells,
            "n_gauss": self.quad.n_gauss,
            "basis": self.basis,
        }

    def __repr__(self) -> str:
        return f"Modal(n_modes={self.n_modes}, basis={self.basis!r})"


#: Order p of the error ~ N^-p of a modal discretization in tip values, v_cr
#: and eigenvalues, per basis (docs, "Convergence of the two modal bases").
EXPECTED_ORDER = {"sine": 3.0, "beam": 4.0}


def beam_roots(n: int) -> np.ndarray:
    """The ``n`` roots lambda_r of cos(lambda) cosh(lambda) = -1 to machine precision (Brent)."""
    out = np.empty(int(n))
    for r in range(1, int(n) + 1):
        c = (2 * r - 1) * np.pi / 2.0
        out[r - 1] = brentq(lambda x: np.cos(x) + 1.0 / np.cosh(x), c - 0.4, c + 0.4, xtol=1e-300)
    return out


def beam_mode_slopes(lam: np.ndarray, xi: np.ndarray, derivative: int = 0) -> np.ndarray:
    """psi_r(xi) = phi_r'(xi) / lambda_r or its ``derivative`` (0 to 3), shape (len(xi), len(lam)).

    Accurate to round-off for any lambda (docs/theory/convergence.md, "The form without
    overflow"); ``lam`` from :func:`beam_roots`, ``xi`` in [0, 1].
    """
    if derivative not in (0, 1, 2, 3):
        raise ValueError(f"derivative must be 0, 1, 2 or 3, got {derivative}")
    lam = np.atleast_1d(np.asarray(lam, dtype=float))[None, :]
    xi = np.atleast_1d(np.asarray(xi, dtype=float))[:, None]
    e1 = np.exp(-lam)
    sl = np.sin(lam)
    c_over_d = (sl - np.cos(lam) - e1) / (1.0 - e1 * e1 + 2.0 * e1 * sl)
    lx = lam * xi
    C, S, E = np.cos(lx), np.sin(lx), np.exp(-lx)
    Ep, Em = np.exp(lam * (xi - 1.0)), np.exp(-lam * (xi + 1.0))
    if derivative == 0:
        return (C - E) + S + c_over_d * (Ep + Em - 2.0 * e1 * C)
    if derivative == 1:
        out = E + C - S + c_over_d * (Ep - Em + 2.0 * e1 * S)
    elif derivative == 2:
        out = -E - S - C + c_over_d * (Ep + Em + 2.0 * e1 * C)
    else:
        out = E - C + S + c_over_d * (Ep - Em - 2.0 * e1 * S)
    return out * lam**derivative

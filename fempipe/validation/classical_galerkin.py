"""The two discretizations of the classical linear theory (:mod:`fempipe.validation.classical`).

:class:`BeamGalerkin` (Paidoussis' clamped-free beam functions) and :class:`LegendreGalerkin`
(C^1 Legendre spectral elements cut at the springs) give the pencil of
(K + lambda C + lambda^2 M) x = 0, solved by :func:`quadratic_eigenvalues`.
Weak form and errors: docs/theory/independent.md.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq

from .straight_pipe import StraightPipe

# Clamped-free beam modes


@functools.cache
def cantilever_roots(n: int) -> np.ndarray:
    """The first ``n`` roots of cos(lambda) + 1/cosh(lambda) = 0, root r in [(r-1) pi, r pi]."""

    def f(x):
        return math.cos(x) + 1.0 / math.cosh(x)

    roots = [brentq(f, (r - 1) * math.pi + 1e-9, r * math.pi, xtol=1e-15) for r in range(1, n + 1)]
    return np.array(roots)


def beam_mode_coefficients(lam: np.ndarray):
    """a, b, s of phi = a e^{lam(x-1)} + b e^{-lam x} - cos(lam x) + s sin(lam x) (no overflow)."""
    em = np.exp(-lam)
    s = (1.0 + em * em + 2.0 * np.cos(lam) * em) / (1.0 - em * em + 2.0 * np.sin(lam) * em)
    # With the equivalent s = (sinh - sin)/(cosh + cos) (cos cosh = -1),
    # 1 - s = (e^{-lam} + cos + sin)/(cosh + cos), hence a = (1 - s) e^{lam}/2:
    a = (em + np.cos(lam) + np.sin(lam)) / (1.0 + em * em + 2.0 * np.cos(lam) * em)
    b = (1.0 + s) / 2.0
    return a, b, s


def beam_mode_values(n: int, x: np.ndarray, derivative: int = 0) -> np.ndarray:
    """The ``derivative``-th derivative (0-4) of the first ``n`` beam modes at ``x``, shape
    (len(x), n), normalized to int phi_r^2 = 1.
    """
    lam = cantilever_roots(n)
    a, b, s = beam_mode_coefficients(lam)
    x = np.asarray(x, dtype=float)[:, None]
    k = derivative
    lx = lam * x
    trig = -np.cos(lx + k * np.pi / 2) + s * np.sin(lx + k * np.pi / 2)
    return lam**k * (a * np.exp(lam * (x - 1.0)) + (-1) ** k * b * np.exp(-lx) + trig)


def gauss_cells(cells: int, points: int = 8):
    g, w = np.polynomial.legendre.leggauss(points)
    edges = np.linspace(0.0, 1.0, cells + 1)
    h = np.diff(edges)[:, None]
    x = (edges[:-1, None] + h * (g + 1.0) / 2.0).ravel()
    return x, (h * w / 2.0).ravel()


# Discretizations


#: Shifts of the reversed linearization (the second if the first is an eigenvalue).
_SHIFTS = (-1.0, -1.37)


def quadratic_eigenvalues(K: np.ndarray, C: np.ndarray, M: np.ndarray, vectors: bool = False):
    """The 2n roots of det(lambda^2 M + lambda C + K) = 0 (and the vectors), lambda = s + 1/nu.

    The companion of nu^2 K_s + nu C_s + M (K_s = K + s C + s^2 M, C_s = C + 2 s M) has a norm of
    the low modes' order, so a divergence or a coalescence keeps its accuracy however stiff the
    discretization; the next shift is used if s is an eigenvalue.
    """
    n = M.shape[0]
    for s in _SHIFTS:
        Ks = K + s * C + (s * s) * M
        try:
            X = np.linalg.solve(Ks, np.hstack([M, C + (2.0 * s) * M]))
        except np.linalg.LinAlgError:
            continue
        if np.all(np.isfinite(X)):
            break
    else:  # pragma: no cover - every shift an eigenvalue
        raise np.linalg.LinAlgError("the quadratic eigenproblem has an eigenvalue at every shift")
    A = np.zeros((2 * n, 2 * n), dtype=X.dtype)
    A[:n, n:] = np.eye(n)
    A[n:, :n] = -X[:, :n]
    A[n:, n:] = -X[:, n:]
    if not vectors:
        nu = np.linalg.eigvals(A)
        return s + 1.0 / nu[nu != 0.0]
    nu, Z = np.linalg.eig(A)
    keep = nu != 0.0
    return s + 1.0 / nu[keep], Z[:n, keep]


class BeamGalerkin:
    """Paidoussis' Galerkin method on ``n`` clamped-free beam modes."""

    name = "beam-mode Galerkin"

    def __init__(self, n: int) -> None:
        self.n = int(n)
        x, w = gauss_cells(max(32, 4 * self.n))
        self._x, self._w = x, w
        phi = beam_mode_values(self.n, x)
        d1 = beam_mode_values(self.n, x, 1)
        d2 = beam_mode_values(self.n, x, 2)
        pw = phi.T * w
        self.lam4 = cantilever_roots(self.n) ** 4
        self.gram = pw @ phi  # I to round-off
        self.b = pw @ d1
        self.c = pw @ d2
        self.e_free = (d1.T * (w * (1.0 - x))) @ d1  # int (1 - xi) phi_s' phi_r'
        self.e_tip = (d1.T * w) @ d1  # int phi_s' phi_r' (the end mass's tension)
        self.tip = beam_mode_values(self.n, np.array([1.0]))[0]

    def label(self) -> str:
        """``beam modes N = n``."""
        return f"beam modes N = {self.n}"

    def pencil(self, pipe: StraightPipe, mu_h_sign: float = 1.0):
        """``K0, Kv, C0, Cv, M`` of K = K0 + v^2 Kv, C = C0 + v Cv (K0 complex with ``mu_h``)."""
        L4 = np.diag(self.lam4)
        K0 = (1.0 + 1j * mu_h_sign * pipe.mu_h) * L4 if pipe.mu_h else L4.astype(float)
        K0 = K0 + pipe.sign * pipe.gamma * (self.e_free + pipe.end_mass * self.e_tip)
        for kappa, xs in pipe.springs:
            p = beam_mode_values(self.n, np.array([xs]))[0]
            K0 = K0 + kappa * np.outer(p, p)
        M = self.gram + pipe.end_mass * np.outer(self.tip, self.tip)
        C0 = pipe.mu * L4 + pipe.sigma * self.gram
        Cv = 2.0 * math.sqrt(pipe.beta) * self.b
        return K0, self.c, C0, Cv, M

    def solve(self, pieces, v: float) -> np.ndarray:
        """All 2n eigenvalues at flow velocity ``v`` (see :func:`quadratic_eigenvalues`)."""
        K0, Kv, C0, Cv, M = pieces
        return quadratic_eigenvalues(K0 + v * v * Kv, C0 + v * Cv, M)


def legendre_local_basis(p: int):
    """The C^1 basis on [-1, 1] as Legendre series: four Hermite cubics and bubbles psi_k'' = P_k."""
    from numpy.polynomial import Legendre, Polynomial

    hermite = [
        Polynomial([2.0, -3.0, 0.0, 1.0]) / 4.0,
        Polynomial([1.0, -1.0, -1.0, 1.0]) / 4.0,
        Polynomial([2.0, 3.0, 0.0, -1.0]) / 4.0,
        Polynomial([-1.0, -1.0, 1.0, 1.0]) / 4.0,
    ]
    basis = [h.convert(kind=Legendre) for h in hermite]
    basis += [Legendre.basis(k).integ(2, lbnd=-1.0) for k in range(2, p + 1)]
    return basis


class LegendreGalerkin:
    """Spectral elements: one per segment between springs, Hermite cubics plus ``p`` - 1 bubbles
    (psi'' = P_2 ... P_p), integrated exactly; the error falls faster than any power of p.
    """

    name = "Legendre spectral Galerkin"

    def __init__(self, p: int) -> None:
        self.p = int(p)
        if self.p < 2:
            raise ValueError(f"p must be >= 2, got {p}")
        self.n = self.p
        t, w = np.polynomial.legendre.leggauss(self.p + 6)
        basis = legendre_local_basis(self.p)
        # values and t-derivatives 0..2 at the Gauss points, shape (3, q, nb)
        self._t, self._w = t, w
        self._vals = np.array([[b.deriv(k)(t) if k else b(t) for b in basis] for k in range(3)])
        self._vals = self._vals.transpose(0, 2, 1)

    def label(self) -> str:
        """``Legendre p = p``."""
        return f"Legendre p = {self.p}"

    def pencil(self, pipe: StraightPipe, mu_h_sign: float = 1.0, acceleration: bool = False):
        """As :meth:`BeamGalerkin.pencil`, in the M-orthonormal modes of the bending stiffness;
        with ``acceleration``, a sixth piece Ka: the flow acceleration's stiffness, K = K0 + v^2 Kv
        + (dv/dtau) Ka (:mod:`.classical_pulsation`)."""
        nodes = [0.0, *sorted({x for _, x in pipe.springs if x < 1.0}), 1.0]
        S = len(nodes) - 1
        nb = self.p - 1  # bubbles per element
        ndof = 2 * S + S * nb  # (value, slope) at nodes 1..S, then the bubbles
        Kb, Kg, Kv, Ka, Cv, Mm = (np.zeros((ndof, ndof)) for _ in range(6))
        sg, g, G = pipe.sign, pipe.gamma, pipe.end_mass
        for e in range(S):
            a, b = nodes[e], nodes[e + 1]
            h = b - a
            xi = a + h * (self._t + 1.0) / 2.0
            wq = self._w * h / 2.0
            # Local functions: Hermite with xi-slope dofs (times h/2), then bubbles.
            scale = np.ones(4 + nb)
            scale[[1, 3]] = h / 2.0
            f0, f1, f2 = (self._vals[k] * scale * (2.0 / h) ** k for k in range(3))
            # Global indices of the local functions (-1: the clamped node 0).
            left = [2 * (e - 1), 2 * (e - 1) + 1] if e > 0 else [-1, -1]
            idx = np.array(left + [2 * e, 2 * e + 1] + list(2 * S + e * nb + np.arange(nb)))
            keep = idx >= 0
            ii = np.ix_(idx[keep], idx[keep])

            def integral(u, vv, weight, keep=keep):
                return ((u.T * weight) @ vv)[np.ix_(keep, keep)]

            Kb[ii] += integral(f2, f2, wq)
            Kg[ii] += integral(f1, f1, wq * (1.0 - xi + G))
            Kv[ii] += integral(f0, f2, wq)
            Ka[ii] += integral(f0, f2, wq * (1.0 - xi))
            Cv[ii] += integral(f0, f1, wq)
            Mm[ii] += integral(f0, f0, wq)
        tip = 2 * (S - 1)  # eta(1)
        Md = Mm.copy()
        Mm[tip, tip] += G
        Eb = (1.0 + 1j * mu_h_sign * pipe.mu_h) if pipe.mu_h else 1.0
        K0 = Eb * Kb + sg * g * Kg
        for kappa, xs in pipe.springs:
            k = nodes.index(xs) - 1
            K0[2 * k, 2 * k] += kappa
        C0 = pipe.mu * Kb + pipe.sigma * Md
        # Change to the M-orthonormal modes of (Kb, M), all of them: the same
        # space, with the stiff bubbles decoupled from the low modes (M = I).
        # Diagonal scaling first, for eigh's Cholesky.
        d = 1.0 / np.sqrt(np.diag(Mm))
        _, Q = sla.eigh(Kb * np.outer(d, d), Mm * np.outer(d, d))
        Q = d[:, None] * Q
        pieces = (K0, Kv, C0, 2.0 * math.sqrt(pipe.beta) * Cv, Mm)
        if acceleration:  # sqrt(beta) (dv/dtau) (1 - xi) eta'' (Paidoussis & Issid 1974)
            pieces += (math.sqrt(pipe.beta) * Ka,)
        return tuple(Q.T @ A @ Q for A in pieces)

    solve = BeamGalerkin.solve


def discretization(method: str = "galerkin", n: int | None = None):
    """``"galerkin"`` (:class:`BeamGalerkin`, N = 20) or ``"legendre"`` (:class:`LegendreGalerkin`,
    p = 24); ``n`` overrides N or p.
    """
    if method == "galerkin":
        return BeamGalerkin(20 if n is None else n)
    if method == "legendre":
        return LegendreGalerkin(24 if n is None else n)
    raise ValueError(f"method must be 'galerkin' or 'legendre', got {method!r}")

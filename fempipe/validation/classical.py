"""The classical linear theory of the straight pipe: an independent check of fempipe.

This module solves the textbook equation of small lateral motions eta(xi, tau)
of a cantilevered pipe conveying fluid (Paidoussis, *Fluid-Structure
Interactions: Slender Structures and Axial Flow*, vol. 1, Academic Press
1998, Sec. 3.3.5, Eqs. (3.70)-(3.71); Gregory & Paidoussis 1966; Paidoussis
1970), written here from that equation and nothing else of fempipe: it knows
neither the rotation angle theta nor the geometrically exact weak form of
:mod:`fempipe.model.operators`.  It is valid for the straight pipe only: hanging
(alpha = 0), standing (alpha = pi) or without gravity (gamma = 0).

The equation
------------
With fempipe's (and Paidoussis') scaling -- xi = x/L, tau = t (EI/(m+M))^(1/2)
/ L^2, v = (M/EI)^(1/2) U L, beta = M/(m+M), gamma = (m+M) g L^3/EI -- and the
variant parameters of :class:`fempipe.model.params.Params` (end mass Gamma =
M_e/((m+M) L), external damping sigma = c L^2/(EI (m+M))^(1/2), hysteretic
loss factor mu_h, springs kappa_s = k_s L^3/EI at xi_s), the hanging pipe
obeys

    E eta'''' + v^2 eta'' - (T eta')' + 2 sqrt(beta) v eta_dot' + sigma eta_dot
        + eta_ddot + sum_s kappa_s eta delta(xi - xi_s) = 0,

    T(xi) = s_g gamma (1 - xi + Gamma),

where E = 1 + mu d/dtau + i mu_h sgn(omega) is the bending operator
(Kelvin-Voigt mu and the hysteretic loss factor, the latter for harmonic
motion of frequency omega only), and s_g = +1 hanging, -1 standing.  T is the
tension of the pipe wall: the weight of the pipe below xi plus that of the end
mass (Paidoussis Eq. (3.69): (T - pA) = (m + M) g (L - x) for the hanging
pipe discharging to atmosphere; the end mass adds M_e g).  Since T' = -s_g
gamma, -(T eta')' = -s_g gamma (1 - xi + Gamma) eta'' + s_g gamma eta', the
form of Eq. (3.70).

The boundary conditions are eta = eta' = 0 at the clamp, and at the free end
the bending moment vanishes, E eta''(1) = 0, while the transverse force of the
pipe on the end mass accelerates it (Newton's second law for the point mass,
which carries neither fluid nor external damping):

    Gamma eta_ddot(1) = E eta'''(1) - T(1) eta'(1) - kappa_1 eta(1),

with kappa_1 a spring at xi_s = 1 (Paidoussis Eq. (3.118) for Gamma = 0, no
gravity: EI w''' - K w = 0).  The follower force of the discharging jet needs
no boundary term: with the pressure zero at the exit it is the v^2 eta'' of
the field equation.  An interior spring makes eta''' jump:
E [eta''']_{xi_s^-}^{xi_s^+} = -kappa_s eta(xi_s).

Two discretisations
-------------------
:class:`BeamGalerkin`
    Paidoussis' classical method: eta = sum_r q_r phi_r(xi) with the
    clamped-free beam eigenfunctions phi_r (cos lambda cosh lambda = -1,
    int phi_r^2 = 1).  Multiplying by phi_s and integrating by parts twice
    (the natural boundary conditions then carry the end mass, the tip tension
    and the tip spring) gives M q'' + C q' + K q = 0 with

    M = I + Gamma phi(1) phi(1)^T,
    C = mu diag(lambda^4) + 2 sqrt(beta) v b + sigma I,
    K = (1 + i mu_h) diag(lambda^4) + s_g gamma e + v^2 c + sum_s kappa_s phi(xi_s) phi(xi_s)^T,

    b_sr = int phi_s phi_r', c_sr = int phi_s phi_r'' (Paidoussis' b_sr, c_sr)
    and e_sr = int (1 - xi + Gamma) phi_s' phi_r' (by parts, Paidoussis'
    b_sr - c_sr + d_sr plus the end mass's Gamma (phi_s(1) phi_r'(1) - c_sr)).  The integrals
    are Gauss-Legendre sums on 4N cells of 8 points, with the modes evaluated
    in a form whose exponentials never exceed 1.  Every basis function has
    eta'''(1) = 0, which the solution does not when Gamma, kappa_1 or gravity
    with an end mass act there, nor at an interior spring.  Measured errors of
    v_cr for N = 10, 20, 40: plain pipe (gamma = 18.9) 2.1e-4, 1.3e-5,
    7.5e-7 (N^-4); an end mass (Gamma = 0.3) 9.1e-3, 2.5e-3, 6.6e-4 and a tip
    spring (kappa = 100) 2.0e-3, 7.2e-4, 2.1e-4 (N^-2); a spring at xi_s = 0.5
    1.0e-3, 1.1e-4, 1.5e-5 (N^-3).  Frequencies at v = 0 with an end mass
    converge as N^-3.
:class:`LegendreGalerkin`
    The same weak form on spectral elements: one element per segment between
    springs, C^1 (eta and eta' continuous at the nodes, where the springs
    sit), each with the Hermite cubics and bubbles whose second derivatives
    are the Legendre polynomials P_2 ... P_p; exact Gauss integration.  The
    solution is analytic on each element, so the error falls faster than any
    power of p whatever the variant: p = 12 ... 40 agree to about 1e-12 in
    v_cr.  The reference of the validation cases.

Both give a quadratic eigenproblem (K + lambda C + lambda^2 M) x = 0 for
eta ~ exp(lambda tau) (Re lambda > 0 unstable; Paidoussis' omega = -i
lambda, so his Re omega is Im lambda, the frequency), solved in first-order
(companion) form for nu = 1/(lambda + 1), which keeps the round-off at the
scale of the low modes (:func:`_quadratic_eigenvalues`).

Hysteretic damping
------------------
E = 1 + i mu_h sgn(omega) is not analytic in lambda.  An eigenvalue with
Im lambda > 0 is an eigenvalue of the problem with 1 + i mu_h, one with
Im lambda < 0 its complex conjugate (the problem with 1 - i mu_h is the
conjugate problem), and a real eigenvalue (omega = 0) one of the problem
without mu_h.  :func:`eigenvalues` returns exactly these; the eigenvalues of
the 1 + i mu_h problem in the lower half plane solve no consistent problem
and are dropped.

Stability
---------
An eigenvalue counts as unstable when Re lambda > ``tol`` max(1, |lambda|)
(round-off of an undamped problem is below it); only eigenvalues with
|lambda| < ``lam_max`` (the lowest eight or so modes, well resolved by every
discretisation used) decide.  :func:`critical_velocity` scans v on a grid
with that margin, then locates the first crossing with Brent's method: on the
largest Re lambda itself when it is negative below the crossing (a damped
system: the exact zero), otherwise on the margin (an undamped system, whose
real parts are zero to round-off below a coalescence; the margin then
crosses (tol |lambda| / c)^2 above it, Re lambda ~ c (v - v_cr)^(1/2)).
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass, replace

import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq
from threadpoolctl import threadpool_limits

__all__ = [
    "BeamGalerkin",
    "LegendreGalerkin",
    "Onset",
    "StraightPipe",
    "beam_mode_values",
    "cantilever_roots",
    "critical_velocity",
    "discretisation",
    "eigenvalues",
    "heavy_column_buckling",
    "large_damping_limit",
    "spectral_abscissa",
    "stiffness_roots",
    "tip_mass_frequencies",
    "tip_spring_divergence",
]

#: Relative size of a real part that counts as unstable (round-off of the
#: undamped problems on the modes that decide is below 1e-11 |lambda|).
TOL = 1e-9
#: Only eigenvalues with |lambda| below this decide stability: the lowest
#: eight modes of the cantilever (lambda_8^2 = 61.7 ... 545; 1000 > mode 9).
LAM_MAX = 1000.0


# ---------------------------------------------------------------------------
# The pipe


@dataclass(frozen=True)
class StraightPipe:
    """A straight cantilevered pipe: the parameters of the classical equation.

    Parameters
    ----------
    beta : float
        Mass ratio M/(m+M).
    gamma : float
        Gravity parameter (m+M) g L^3/EI >= 0.
    standing : bool
        False: hanging (gravity pulls towards the free end, alpha = 0); True:
        standing (alpha = pi, gravity compresses the pipe).
    mu : float
        Kelvin-Voigt damping (fempipe's mu; Paidoussis' alpha).
    end_mass : float
        Gamma = M_e/((m+M) L).
    sigma : float
        External viscous damping c L^2/(EI (m+M))^(1/2) (a force -c eta_dot
        per unit length on the pipe, not on the end mass).
    mu_h : float
        Hysteretic loss factor: EI -> EI (1 + i mu_h sgn(omega)).
    springs : tuple of (kappa, xi_s)
        Linear springs kappa = k L^3/EI at 0 < xi_s <= 1.
    """

    beta: float = 0.0
    gamma: float = 0.0
    standing: bool = False
    mu: float = 0.0
    end_mass: float = 0.0
    sigma: float = 0.0
    mu_h: float = 0.0
    springs: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "springs", tuple((float(k), float(x)) for k, x in self.springs if k != 0.0)
        )
        for k, x in self.springs:
            if not 0.0 < x <= 1.0 or k < 0.0:
                raise ValueError(f"a spring needs kappa >= 0 and 0 < xi_s <= 1, got {(k, x)}")
        if min(self.beta, self.gamma, self.mu, self.end_mass, self.sigma, self.mu_h) < 0.0:
            raise ValueError("beta, gamma, mu, end_mass, sigma and mu_h must be >= 0")

    @classmethod
    def from_params(cls, params) -> StraightPipe:
        """The straight pipe of a :class:`fempipe.model.params.Params` (alpha = 0 or pi, or gamma = 0).

        Raises
        ------
        ValueError
            If the pipe is inclined (its static state is curved: not this theory).
        """
        c = math.cos(params.alpha)
        if params.gamma != 0.0 and abs(abs(c) - 1.0) > 1e-14:
            raise ValueError(
                f"the classical theory needs a straight pipe: alpha = 0 or pi, or gamma = 0 "
                f"(got alpha = {params.alpha}, gamma = {params.gamma})"
            )
        return cls(
            beta=params.beta,
            gamma=params.gamma,
            standing=params.gamma != 0.0 and c < 0.0,
            mu=params.mu,
            end_mass=params.end_mass,
            sigma=params.external_damping,
            mu_h=params.hysteretic_damping,
            springs=tuple(params.springs),
        )

    @property
    def sign(self) -> float:
        """s_g: +1 hanging (tension), -1 standing (compression)."""
        return -1.0 if self.standing else 1.0


# ---------------------------------------------------------------------------
# Clamped-free beam modes


@functools.cache
def cantilever_roots(n: int) -> np.ndarray:
    """The first ``n`` roots lambda_r of cos(lambda) cosh(lambda) = -1.

    Written as cos(lambda) + 1/cosh(lambda) = 0 (no overflow); root r lies
    in [(r - 1) pi, r pi], where the left side changes sign once, and is
    found by Brent's method to 1e-15.
    """

    def f(x):
        return math.cos(x) + 1.0 / math.cosh(x)

    roots = [brentq(f, (r - 1) * math.pi + 1e-9, r * math.pi, xtol=1e-15) for r in range(1, n + 1)]
    return np.array(roots)


def _mode_coefficients(lam: np.ndarray):
    """a, b, s of phi = a e^{lam(x-1)} + b e^{-lam x} - cos(lam x) + s sin(lam x).

    phi_r = cosh - cos - s (sinh - sin) with s = (cosh lam + cos lam)/(sinh lam
    + sin lam); cosh(lam x) - s sinh(lam x) = a e^{lam (x - 1)} + b e^{-lam x}
    with a = (1 - s) e^{lam}/2 and b = (1 + s)/2, all written with e^{-lam}.
    """
    em = np.exp(-lam)
    s = (1.0 + em * em + 2.0 * np.cos(lam) * em) / (1.0 - em * em + 2.0 * np.sin(lam) * em)
    # With the equivalent s = (sinh - sin)/(cosh + cos) (cos cosh = -1),
    # 1 - s = (e^{-lam} + cos + sin)/(cosh + cos), hence a = (1 - s) e^{lam}/2:
    a = (em + np.cos(lam) + np.sin(lam)) / (1.0 + em * em + 2.0 * np.cos(lam) * em)
    b = (1.0 + s) / 2.0
    return a, b, s


def beam_mode_values(n: int, x: np.ndarray, derivative: int = 0) -> np.ndarray:
    """The ``derivative``-th derivative of the first ``n`` clamped-free beam modes at ``x``.

    Parameters
    ----------
    n : int
        Number of modes.
    x : array_like
        Points in [0, 1].
    derivative : int
        0 ... 4.

    Returns
    -------
    ndarray, shape (len(x), n)
        phi_r^(k)(x_j), with int_0^1 phi_r^2 = 1 (the textbook normalisation,
        |phi_r(1)| = 2).
    """
    lam = cantilever_roots(n)
    a, b, s = _mode_coefficients(lam)
    x = np.asarray(x, dtype=float)[:, None]
    k = derivative
    lx = lam * x
    trig = -np.cos(lx + k * np.pi / 2) + s * np.sin(lx + k * np.pi / 2)
    return lam**k * (a * np.exp(lam * (x - 1.0)) + (-1) ** k * b * np.exp(-lx) + trig)


def _gauss(cells: int, points: int = 8):
    g, w = np.polynomial.legendre.leggauss(points)
    edges = np.linspace(0.0, 1.0, cells + 1)
    h = np.diff(edges)[:, None]
    x = (edges[:-1, None] + h * (g + 1.0) / 2.0).ravel()
    return x, (h * w / 2.0).ravel()


# ---------------------------------------------------------------------------
# Discretisations


#: Shifts of the reversed linearisation (the second if the first is an eigenvalue).
_SHIFTS = (-1.0, -1.37)


def _quadratic_eigenvalues(K: np.ndarray, C: np.ndarray, M: np.ndarray) -> np.ndarray:
    """The 2n roots lambda of det(lambda^2 M + lambda C + K) = 0.

    With lambda = s + 1/nu (s = -1) the problem becomes
    nu^2 K_s + nu C_s + M = 0, K_s = K + s C + s^2 M, C_s = C + 2 s M, whose
    companion matrix [[0, I], [-K_s^-1 M, -K_s^-1 C_s]] has a norm of the
    order of the largest 1/|lambda - s|.  Its round-off therefore stays at the
    scale of the low modes whatever the discretisation: the direct companion
    of (q, q') has a norm of the order of the stiffest mode's omega^2 (and
    mu omega^2 with Kelvin-Voigt damping), whose round-off shifts an
    eigenvalue near zero (a divergence) by 1e-6 at 40 modes and splits the
    double eigenvalue of a coalescence (Beck's column) early.  K_s is
    singular only if s is an eigenvalue (then the next shift is used).
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
    nu = np.linalg.eigvals(A)
    return s + 1.0 / nu[nu != 0.0]


class BeamGalerkin:
    """Paidoussis' Galerkin method on ``n`` clamped-free beam modes (module docstring).

    Parameters
    ----------
    n : int
        Number of modes.
    """

    name = "beam-mode Galerkin"

    def __init__(self, n: int) -> None:
        self.n = int(n)
        x, w = _gauss(max(32, 4 * self.n))
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
        """The v-independent pieces of K(v) = K0 + v^2 Kv, C(v) = C0 + v Cv and M.

        Returns
        -------
        K0, Kv, C0, Cv, M : ndarray
            K0 complex when ``pipe.mu_h`` > 0 (1 + i mu_h_sign mu_h).
        """
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
        """All 2n eigenvalues at flow velocity ``v`` (see :func:`_quadratic_eigenvalues`)."""
        K0, Kv, C0, Cv, M = pieces
        return _quadratic_eigenvalues(K0 + v * v * Kv, C0 + v * Cv, M)


def _local_basis(p: int):
    """The C^1 basis of one element on t in [-1, 1], as Legendre series.

    Four Hermite cubics (value and d/dt at t = -1, value and d/dt at t = 1)
    and the bubbles psi_k, k = 2 ... p, with psi_k'' = P_k and
    psi_k(-1) = psi_k'(-1) = 0; psi_k(1) = psi_k'(1) = 0 follows from the
    orthogonality of P_k (k >= 2) to 1 and t.  The bending stiffness of the
    bubbles is therefore diagonal, int psi_j'' psi_k'' = 2/(2k + 1) delta_jk.
    """
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
    """A spectral-element Galerkin method on the weak form (module docstring).

    One element per segment between the springs (a spring sits on a node),
    each carrying polynomials of degree p + 2: the Hermite cubics (eta and
    eta' continuous at the nodes: C^1, conforming for the fourth-order
    problem) and p - 1 bubbles whose second derivatives are the Legendre
    polynomials P_2 ... P_p.  The integrands are polynomials, integrated
    exactly by Gauss-Legendre with p + 6 points; the solution is analytic on
    each element, so the error falls faster than any power of p.

    Parameters
    ----------
    p : int
        Highest Legendre degree of the bubbles' second derivatives (>= 2).
    """

    name = "Legendre spectral Galerkin"

    def __init__(self, p: int) -> None:
        self.p = int(p)
        if self.p < 2:
            raise ValueError(f"p must be >= 2, got {p}")
        self.n = self.p
        t, w = np.polynomial.legendre.leggauss(self.p + 6)
        basis = _local_basis(self.p)
        # values and t-derivatives 0..2 at the Gauss points, shape (3, q, nb)
        self._t, self._w = t, w
        self._vals = np.array([[b.deriv(k)(t) if k else b(t) for b in basis] for k in range(3)])
        self._vals = self._vals.transpose(0, 2, 1)

    def label(self) -> str:
        """``Legendre p = p``."""
        return f"Legendre p = {self.p}"

    def pencil(self, pipe: StraightPipe, mu_h_sign: float = 1.0):
        """K0, Kv, C0, Cv, M as :meth:`BeamGalerkin.pencil`, in the M-orthonormal modes of
        the bending stiffness."""
        nodes = [0.0, *sorted({x for _, x in pipe.springs if x < 1.0}), 1.0]
        S = len(nodes) - 1
        nb = self.p - 1  # bubbles per element
        ndof = 2 * S + S * nb  # (value, slope) at nodes 1..S, then the bubbles
        Kb, Kg, Kv, Cv, Mm = (np.zeros((ndof, ndof)) for _ in range(5))
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
        return tuple(Q.T @ A @ Q for A in pieces)

    solve = BeamGalerkin.solve


def discretisation(method: str = "galerkin", n: int | None = None):
    """A discretisation by name.

    Parameters
    ----------
    method : {"galerkin", "legendre"}
        Paidoussis' beam-mode Galerkin method (:class:`BeamGalerkin`, default
        N = 20) or the spectral elements (:class:`LegendreGalerkin`, default
        p = 24).
    n : int, optional
        N or p.
    """
    if method == "galerkin":
        return BeamGalerkin(20 if n is None else n)
    if method == "legendre":
        return LegendreGalerkin(24 if n is None else n)
    raise ValueError(f"method must be 'galerkin' or 'legendre', got {method!r}")


# ---------------------------------------------------------------------------
# Spectra and the critical velocity


def _one_thread(func):
    """Run ``func`` with one BLAS thread: the matrices are small (up to ~200),
    and threads only contend (measured 10-20x slower on a loaded 2-core machine)."""

    @functools.wraps(func)
    def wrapper(*args, **kwargs):
        with threadpool_limits(limits=1, user_api="blas"):
            return func(*args, **kwargs)

    return wrapper


class _Problem:
    """A pipe on a discretisation, with the v-independent matrices formed once."""

    def __init__(self, pipe: StraightPipe, disc) -> None:
        self.pipe, self.disc = pipe, disc
        self.pieces = disc.pencil(pipe, 1.0)
        self.real_pieces = disc.pencil(replace(pipe, mu_h=0.0)) if pipe.mu_h else None

    def eigenvalues(self, v: float) -> np.ndarray:
        lam = self.disc.solve(self.pieces, v)
        if self.real_pieces is None:
            return lam
        # Hysteretic: Im > 0 from the 1 + i mu_h problem, their conjugates,
        # and the real eigenvalues of the problem without mu_h.
        up = lam[lam.imag > 0.0]
        lam0 = self.disc.solve(self.real_pieces, v)
        real = lam0[np.abs(lam0.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam0))].real
        return np.concatenate([up, up.conj(), real.astype(complex)])


@_one_thread
def eigenvalues(
    pipe: StraightPipe, v: float, method: str = "galerkin", n: int | None = None
) -> np.ndarray:
    """The consistent eigenvalues lambda (eta ~ e^{lambda tau}) at flow velocity ``v``.

    Parameters
    ----------
    pipe : StraightPipe
    v : float
        Flow velocity.
    method, n : str, int
        The discretisation (:func:`discretisation`).

    Returns
    -------
    ndarray of complex
        Sorted by |lambda|; with hysteretic damping, those of the module
        docstring (Im > 0 from 1 + i mu_h, their conjugates, the real ones).
    """
    lam = _Problem(pipe, discretisation(method, n)).eigenvalues(v)
    return lam[np.argsort(np.abs(lam))]


def _abscissa(lam: np.ndarray, lam_max: float, tol: float):
    """max Re lambda - tol max(1, |lambda|) over |lambda| < lam_max, and its eigenvalue."""
    keep = lam[np.abs(lam) < lam_max]
    score = keep.real - tol * np.maximum(1.0, np.abs(keep))
    i = int(np.argmax(score))
    return float(score[i]), complex(keep[i])


@_one_thread
def spectral_abscissa(
    pipe: StraightPipe,
    v: float,
    method: str = "galerkin",
    n: int | None = None,
    lam_max: float = LAM_MAX,
    tol: float = TOL,
) -> tuple[float, complex]:
    """The stability margin max(Re lambda - tol max(1, |lambda|)) and the eigenvalue attaining it.

    Parameters
    ----------
    pipe : StraightPipe
    v : float
        Flow velocity.
    method, n : str, int
        The discretisation (:func:`discretisation`).
    lam_max, tol : float
        Only |lambda| < ``lam_max`` count; an unstable real part exceeds
        ``tol`` max(1, |lambda|) (module docstring).

    Returns
    -------
    margin : float
        Positive: unstable.
    lam : complex
        The eigenvalue attaining it.
    """
    return _abscissa(_Problem(pipe, discretisation(method, n)).eigenvalues(v), lam_max, tol)


@dataclass(frozen=True)
class Onset:
    """The first loss of stability found by :func:`critical_velocity`.

    Attributes
    ----------
    v_cr : float
        Critical flow velocity (nan if stable up to ``v_max``).
    lam : complex
        The crossing eigenvalue (Im lambda >= 0): its imaginary part is the
        frequency omega at the onset (0 for divergence).
    kind : str
        ``"flutter"``, ``"divergence"``, ``"unstable at v_min"`` or ``"stable"``.
    method : str
        The discretisation's label.
    """

    v_cr: float
    lam: complex
    kind: str
    method: str

    @property
    def frequency(self) -> float:
        """omega = Im lambda at the onset."""
        return abs(self.lam.imag)


@_one_thread
def critical_velocity(
    pipe: StraightPipe,
    v_max: float = 20.0,
    v_min: float = 0.0,
    method: str = "galerkin",
    n: int | None = None,
    step: float = 0.1,
    xtol: float = 1e-12,
    lam_max: float = LAM_MAX,
    tol: float = TOL,
) -> Onset:
    """The first flow velocity in [v_min, v_max] at which the straight pipe loses stability.

    Scan v with ``step``; in the first interval where the stability margin
    (:func:`spectral_abscissa`) turns positive, Brent's method to ``xtol``.
    A stability window narrower than ``step`` can be missed.

    Parameters
    ----------
    pipe : StraightPipe
    v_max, v_min : float
        The range of v.
    method, n : str, int
        The discretisation (:func:`discretisation`).
    step : float
        Scan step in v.
    xtol : float
        Brent's tolerance in v.
    lam_max, tol : float
        Which eigenvalues decide and the size of an unstable real part.
    """
    prob = _Problem(pipe, discretisation(method, n))
    label = prob.disc.label()

    def margin(v):
        return _abscissa(prob.eigenvalues(v), lam_max, tol)

    def abscissa(v):
        return _abscissa(prob.eigenvalues(v), lam_max, 0.0)[0]

    f0, lam0 = margin(v_min)
    if f0 > 0.0:
        return Onset(v_min, lam0, "unstable at v_min", label)
    grid = np.arange(v_min, v_max + step / 2, step)[1:]
    v_prev = v_min
    rtol = 4 * np.finfo(float).eps
    for v in grid:
        f, _ = margin(v)
        if f > 0.0:
            if abscissa(v_prev) < 0.0:
                # Damped below the onset: the exact zero of the largest real part.
                v_cr = brentq(abscissa, v_prev, v, xtol=xtol, rtol=rtol)
            else:
                # Undamped (real parts zero to round-off below): the margin.
                v_cr = brentq(lambda s: margin(s)[0], v_prev, v, xtol=xtol, rtol=rtol)
            # The crossing eigenvalue just above the onset.
            _, lam = margin(v_cr + 2 * xtol)
            lam = complex(lam.real, abs(lam.imag))
            kind = "flutter" if abs(lam.imag) > 1e-6 * max(1.0, abs(lam)) else "divergence"
            return Onset(float(v_cr), lam, kind, label)
        v_prev = v
    return Onset(float("nan"), complex("nan"), "stable", label)


# ---------------------------------------------------------------------------
# Closed forms the solvers are checked against


def _roots(f, a: float, b: float, n_grid: int = 4000, count: int | None = None) -> np.ndarray:
    """The sign changes of ``f`` on a grid of [a, b], refined by Brent's method."""
    x = np.linspace(a, b, n_grid)
    y = np.array([f(t) for t in x])
    idx = np.flatnonzero(np.sign(y[1:]) * np.sign(y[:-1]) < 0)
    roots = [brentq(f, x[i], x[i + 1], xtol=1e-15, rtol=1e-15) for i in idx[:count]]
    return np.array(roots)


def tip_mass_frequencies(end_mass: float, n: int = 3) -> np.ndarray:
    """Frequencies omega_r = l_r^2 of the gravity-free cantilever with a tip mass, at v = 0.

    The roots of 1 + cos l cosh l + Gamma l (cos l sinh l - sin l cosh l) = 0
    (Blevins, *Formulas for Natural Frequency and Mode Shape*, 1979:
    cantilever with a mass at the free end), divided by cosh l so that
    nothing overflows.
    """

    def f(x):
        return (
            1.0 / math.cosh(x)
            + math.cos(x)
            + end_mass * x * (math.cos(x) * math.tanh(x) - math.sin(x))
        )

    return _roots(f, 0.05, (n + 1) * math.pi, count=n) ** 2


def heavy_column_buckling(end_mass: float) -> float:
    """gamma at which the standing column (v = 0) buckles under its weight and the end mass's.

    With y = eta' and s = 1 + Gamma - xi, the static equation integrates to
    y'' + gamma s y = 0, y = 0 at the clamp (s = 1 + Gamma), dy/ds = 0 at the
    free end (s = Gamma), whose solutions are y = s^(1/2) [A J_(1/3)(z) +
    B J_(-1/3)(z)], z = (2/3) gamma^(1/2) s^(3/2).  The smallest gamma with a
    nontrivial (A, B); for Gamma = 0 it is Greenhill's J_(-1/3)((2/3)
    gamma^(1/2)) = 0, gamma = 7.8373.
    """
    from scipy.special import jv, jvp

    if end_mass == 0.0:
        return float(_roots(lambda g: jv(-1.0 / 3.0, 2.0 / 3.0 * math.sqrt(g)), 1.0, 12.0)[0])

    def y(s, nu, g):
        return math.sqrt(s) * jv(nu, 2.0 / 3.0 * math.sqrt(g) * s**1.5)

    def dy(s, nu, g):
        z = 2.0 / 3.0 * math.sqrt(g) * s**1.5
        return jv(nu, z) / (2.0 * math.sqrt(s)) + math.sqrt(g) * s * jvp(nu, z)

    def det(g):
        top, tip = 1.0 + end_mass, end_mass
        return y(top, 1 / 3, g) * dy(tip, -1 / 3, g) - y(top, -1 / 3, g) * dy(tip, 1 / 3, g)

    return float(_roots(det, 1e-3, 8.0, count=1)[0])


def tip_spring_divergence(kappa: float) -> float:
    """The divergence velocity of the gravity-free cantilever with a spring kappa at its tip.

    The smallest positive root of u^3 + kappa (sin u - u cos u) = 0
    (Paidoussis 1998, Eq. (3.119), after Chen 1971a); nan when there is none
    below 3 pi (small kappa: no divergence).  kappa -> infinity gives the
    clamped-pinned pipe, tan u = u, u = 4.4934.
    """
    r = _roots(lambda u: u**3 + kappa * (math.sin(u) - u * math.cos(u)), 0.1, 3 * math.pi, count=1)
    return float(r[0]) if r.size else float("nan")


@_one_thread
def stiffness_roots(pipe: StraightPipe, v: float, p: int = 16, nu_max: float = 1e4) -> np.ndarray:
    """The roots nu of K(v) x = nu M x (no damping, no Coriolis), |nu| < ``nu_max``.

    When the damping is sigma times the mass (beta = 0, no Kelvin-Voigt, no end
    mass), each nu = a + ib gives lambda^2 + sigma lambda + nu = 0, whose roots
    are stable iff a > 0 and b^2 < sigma^2 a: the whole damped problem follows
    from these roots, and for sigma -> infinity stability needs only a > 0.
    """
    K0, Kv, _, _, M = LegendreGalerkin(p).pencil(replace(pipe, sigma=0.0, mu=0.0, beta=0.0))
    nu = np.linalg.eigvals(np.linalg.solve(M, K0 + v * v * Kv))
    return nu[np.abs(nu) < nu_max]


def large_damping_limit(pipe: StraightPipe, v_max: float, p: int = 16, step: float = 0.05) -> float:
    """The v_cr of ``pipe`` as its external damping sigma -> infinity (damping = sigma M).

    The first v at which a root nu of :func:`stiffness_roots` has Re nu < 0,
    by a scan and Brent's method; nan if none up to ``v_max``.
    """

    def f(v):
        return float(np.min(stiffness_roots(pipe, v, p).real))

    vs = np.arange(0.0, v_max + step / 2, step)
    prev = vs[0]
    for v in vs[1:]:
        if f(v) < 0.0:
            return float(brentq(f, prev, v, xtol=1e-13))
        prev = v
    return float("nan")

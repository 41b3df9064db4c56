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

Two discretizations
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

Both are in :mod:`fempipe.validation.classical_galerkin`; the closed forms
the solvers are checked against (Greenhill's column, the tip-mass
frequencies, the tip-spring divergence, the limit of large external damping)
are in :mod:`fempipe.validation.classical_limits`.  This module re-exports
them: ``fempipe.validation.classical`` is the one name to use.

Both give a quadratic eigenproblem (K + lambda C + lambda^2 M) x = 0 for
eta ~ exp(lambda tau) (Re lambda > 0 unstable; Paidoussis' omega = -i
lambda, so his Re omega is Im lambda, the frequency), solved in first-order
(companion) form for nu = 1/(lambda + 1), which keeps the round-off at the
scale of the low modes (:func:`~fempipe.validation.classical_galerkin.quadratic_eigenvalues`).

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
discretization used) decide.  :func:`critical_velocity` scans v on a grid
with that margin, then locates the first crossing with Brent's method: on the
largest Re lambda itself when it is negative below the crossing (a damped
system: the exact zero), otherwise on the margin (an undamped system, whose
real parts are zero to round-off below a coalescence; the margin then
crosses (tol |lambda| / c)^2 above it, Re lambda ~ c (v - v_cr)^(1/2)).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from fempipe.core.parallel import single_blas

from .classical_galerkin import (
    BeamGalerkin,
    LegendreGalerkin,
    beam_mode_values,
    cantilever_roots,
    discretization,
)
from .classical_limits import (
    heavy_column_buckling,
    large_damping_limit,
    stiffness_roots,
    tip_mass_frequencies,
    tip_spring_divergence,
)

__all__ = [
    "BeamGalerkin",
    "LegendreGalerkin",
    "Onset",
    "StraightPipe",
    "beam_mode_values",
    "cantilever_roots",
    "critical_velocity",
    "discretization",
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
# Spectra and the critical velocity


class _Problem:
    """A pipe on a discretization, with the v-independent matrices formed once."""

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


@single_blas
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
        The discretization (:func:`discretization`).

    Returns
    -------
    ndarray of complex
        Sorted by |lambda|; with hysteretic damping, those of the module
        docstring (Im > 0 from 1 + i mu_h, their conjugates, the real ones).
    """
    lam = _Problem(pipe, discretization(method, n)).eigenvalues(v)
    return lam[np.argsort(np.abs(lam))]


def _abscissa(lam: np.ndarray, lam_max: float, tol: float):
    """max Re lambda - tol max(1, |lambda|) over |lambda| < lam_max, and its eigenvalue."""
    keep = lam[np.abs(lam) < lam_max]
    score = keep.real - tol * np.maximum(1.0, np.abs(keep))
    i = int(np.argmax(score))
    return float(score[i]), complex(keep[i])


@single_blas
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
        The discretization (:func:`discretization`).
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
    return _abscissa(_Problem(pipe, discretization(method, n)).eigenvalues(v), lam_max, tol)


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
        The discretization's label.
    """

    v_cr: float
    lam: complex
    kind: str
    method: str

    @property
    def frequency(self) -> float:
        """omega = Im lambda at the onset."""
        return abs(self.lam.imag)


@single_blas
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
        The discretization (:func:`discretization`).
    step : float
        Scan step in v.
    xtol : float
        Brent's tolerance in v.
    lam_max, tol : float
        Which eigenvalues decide and the size of an unstable real part.
    """
    prob = _Problem(pipe, discretization(method, n))
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

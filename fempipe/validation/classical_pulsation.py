"""The classical linear theory under a pulsating flow: Floquet multipliers of eta(xi, tau).

A flow v(tau) = v0 (1 + sigma sin(omega tau)) must be accelerated by a pressure gradient; with
the free end at ambient pressure the pipe carries the pressure M (dU/dt) (L - x), which adds
M (dU/dt) (L - x) w'' to the lateral equation (Paidoussis & Issid 1974; Paidoussis 1998,
Appendix A); its fluid-inertia and pressure-gradient terms in w' cancel.  In the variables of
Eqs. (3.70)-(3.71) (v = (M/EI)^(1/2) U L, tau = (EI/(m+M))^(1/2) t/L^2) the term is
sqrt(beta) (dv/dtau) (1 - xi) eta'': with the flow accelerating, the pipe is compressed as
Leipholz's column under a distributed tangential load (:func:`flutter_load`).  The matrices
are :class:`~.classical_galerkin.LegendreGalerkin`'s, the monodromy is integrated by scipy's
explicit DOP853 with error control (nothing of fempipe's weak form or of its Radau IIA).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from fempipe.core.parallel import single_blas

from .classical_galerkin import LegendreGalerkin
from .straight_pipe import StraightPipe

__all__ = ["ClassicalPulsation", "flutter_load", "leipholz_load"]


class ClassicalPulsation:
    """The straight pipe's eta(xi, tau) under v0 (1 + sigma sin(omega tau)) on Legendre
    spectral elements of degree ``p``.

    Parameters
    ----------
    pipe : StraightPipe
    v0 : float
        The mean flow.
    p : int
        Legendre degree (the stiffness of the discretization grows as p^8: DOP853's steps too).
    rtol : float
        DOP853's relative tolerance (the absolute one 1e-3 of it).
    acceleration : bool
        False: without the flow-acceleration term (to show what it changes).
    """

    def __init__(
        self, pipe: StraightPipe, v0: float, p: int = 8, rtol: float = 1e-10, acceleration=True
    ) -> None:
        K0, Kv, C0, Cv, M, Ka = LegendreGalerkin(p).pencil(pipe, acceleration=True)
        Ka = Ka if acceleration else 0.0 * Ka
        self.n, self.v0, self.rtol = M.shape[0], float(v0), float(rtol)
        # -M^-1 times K0, Kv, Ka (stiffness) and C0, Cv (damping)
        self.parts = (
            -np.linalg.solve(M, np.hstack([K0, Kv, Ka, C0, Cv]))
            .reshape(self.n, 5, self.n)
            .transpose(1, 0, 2)
        )

    def matrix(self, tau: float, sigma: float, omega: float) -> np.ndarray:
        """The first-order matrix A(tau) of (eta, eta_dot)."""
        n, (K0, Kv, Ka, C0, Cv) = self.n, self.parts
        v = self.v0 * (1.0 + sigma * math.sin(omega * tau))
        v_dot = self.v0 * sigma * omega * math.cos(omega * tau)
        A = np.zeros((2 * n, 2 * n))
        A[:n, n:] = np.eye(n)
        A[n:, :n] = K0 + v * v * Kv + v_dot * Ka
        A[n:, n:] = C0 + v * Cv
        return A

    @single_blas
    def monodromy(self, sigma: float, omega: float) -> np.ndarray:
        """The state-transition matrix over one period 2 pi / omega."""
        d = 2 * self.n

        def rhs(tau, y):
            return (self.matrix(tau, sigma, omega) @ y.reshape(d, d)).ravel()

        period = 2.0 * math.pi / omega
        kw = {"rtol": self.rtol, "atol": 1e-3 * self.rtol}
        sol = solve_ivp(rhs, (0.0, period), np.eye(d).ravel(), method="DOP853", **kw)
        if not sol.success:
            raise RuntimeError(f"DOP853 failed at sigma = {sigma}, omega = {omega}: {sol.message}")
        return sol.y[:, -1].reshape(d, d)

    def multipliers(self, sigma: float, omega: float) -> np.ndarray:
        """The Floquet multipliers, largest modulus first."""
        rho = np.linalg.eigvals(self.monodromy(sigma, omega))
        return rho[np.argsort(-np.abs(rho))]

    def critical_sigma(self, omega: float, sigma_max: float, xtol: float = 1e-10) -> float:
        """The amplitude in (0, ``sigma_max``) where the largest multiplier reaches modulus 1
        at ``omega`` (Brent's method; ValueError unless it is stable at 0, unstable at the top)."""

        def margin(s):
            return float(np.log(np.abs(self.multipliers(s, omega)[0])))

        return float(brentq(margin, 0.0, sigma_max, xtol=xtol, rtol=4 * np.finfo(float).eps))


def flutter_load(K0: np.ndarray, Ka: np.ndarray, M: np.ndarray, bracket=(1.0, 100.0)) -> float:
    """The least q in ``bracket`` at which M x'' + (K0 + q Ka) x = 0 flutters (two eigenvalues
    of M^-1 (K0 + q Ka) turn complex), by bisection to round-off; nan if none.

    With the classical Ka (no flow, no gravity, beta = 1) this is Leipholz's column, the
    cantilever under a uniform tangential load q (1 - xi) eta'' (q L^3/EI = 40.05).
    """

    def complex_pair(q: float) -> bool:
        nu = np.linalg.eigvals(np.linalg.solve(M, K0 + q * Ka))
        low = nu[np.argsort(np.abs(nu))][:4]  # the discretization's top modes stay apart
        return bool(np.any(np.abs(low.imag) > 1e-12 * np.abs(low)))

    lo, hi = bracket
    if complex_pair(lo) or not complex_pair(hi):
        return math.nan
    while hi - lo > 4 * np.finfo(float).eps * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if complex_pair(mid) else (mid, hi)
    return hi


def leipholz_load(p: int = 16) -> float:
    """Leipholz's flutter load by the classical flow-acceleration matrix (beta = 1, no gravity)."""
    K0, _, _, _, M, Ka = LegendreGalerkin(p).pencil(StraightPipe(beta=1.0), acceleration=True)
    return flutter_load(K0, Ka, M)

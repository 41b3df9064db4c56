"""Hill's method against the monodromy: the Floquet exponents of the pulsating straight pipe
from the frequency domain, sharing no code with the time stepping of the monodromy.

The reduced first-order system x' = A(tau) x, A = F0 + v F1 + v^2 F2 + (dv/dtau) F3 with
v = v0 (1 + sigma sin(omega tau)), has the Fourier coefficients A_k, |k| <= 2. A Floquet
solution x = exp(lambda tau) sum_n c_n exp(i n omega tau) makes (lambda + i n omega) c_n =
sum_m A_(n-m) c_m: the eigenvalues lambda of the truncated Hill matrix whose eigenvectors sit
in the central harmonics are the Floquet exponents, and exp(lambda 2 pi/omega) the multipliers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fempipe import FiniteElement, Params, PipeModel
from fempipe.analyses.parametric import PulsationPencil, ReducedPulsation, floquet_multipliers

HANGING = Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.005, v=6.0)


@pytest.fixture(scope="module")
def reduced():
    return ReducedPulsation(PulsationPencil.of(PipeModel(FiniteElement(6, 3), HANGING)), 6.0, 3)


def hill_multipliers(F: np.ndarray, v0: float, sigma: float, omega: float, harmonics: int):
    """exp(lambda T) for every eigenvalue lambda of the Hill matrix truncated at |n| <= harmonics.

    A converged exponent appears once per harmonic shift lambda + i k omega, which all give
    the same multiplier; the truncation's spurious eigenvalues give scattered ones.
    """
    d = F.shape[-1]
    sin1 = v0 * sigma * F[1] + 2 * v0**2 * sigma * F[2]  # the sin(omega tau) part of A
    cos1 = v0 * sigma * omega * F[3]
    cos2 = -0.5 * v0**2 * sigma**2 * F[2]
    coef = {
        0: F[0] + v0 * F[1] + v0**2 * (1 + 0.5 * sigma**2) * F[2],
        1: 0.5 * cos1 - 0.5j * sin1,
        -1: 0.5 * cos1 + 0.5j * sin1,
        2: 0.5 * cos2,
        -2: 0.5 * cos2,
    }
    orders = np.arange(-harmonics, harmonics + 1)
    H = np.zeros((orders.size * d, orders.size * d), dtype=complex)
    for i, n in enumerate(orders):
        for j, m in enumerate(orders):
            if abs(n - m) <= 2:
                H[i * d : (i + 1) * d, j * d : (j + 1) * d] = coef[n - m]
        H[i * d : (i + 1) * d, i * d : (i + 1) * d] -= 1j * n * omega * np.eye(d)
    return np.exp(np.linalg.eigvals(H) * 2 * math.pi / omega)


def copies(rho: np.ndarray, hill: np.ndarray, tol: float) -> np.ndarray:
    """How many of Hill's multipliers lie within tol of each multiplier in rho."""
    return (np.abs(rho[:, None] - hill[None, :]) < tol).sum(axis=1)


@pytest.mark.parametrize(("sigma", "omega"), [(0.2, 29.5), (0.3, 21.0)])
def test_hill_exponents_are_the_monodromy_multipliers(reduced, sigma, omega):
    """Every multiplier of the monodromy (Radau IIA, 512 steps) is Hill's (10 harmonics),
    found there at least once per harmonic, inside the principal region of the second mode
    (0.2, 29.5: |rho| > 1) and outside every region (0.3, 21.0).  Multipliers below 1e-3
    (the Kelvin-Voigt damped high modes) are left out: near 0 every tolerance matches."""
    rho = floquet_multipliers(reduced, sigma, omega, steps=512)
    rho = rho[np.abs(rho) > 1e-3]
    assert rho.size >= 6
    hill = hill_multipliers(reduced.F, reduced.v0, sigma, omega, 10)
    assert copies(rho, hill, 1e-8).min() >= 10
    assert (abs(rho[0]) > 1) == (sigma == 0.2)


def test_one_harmonic_is_not_enough(reduced):
    """The check can fail: truncated at |n| <= 1, Hill's matrix misses the multipliers."""
    rho = floquet_multipliers(reduced, 0.2, 29.5, steps=512)
    rho = rho[np.abs(rho) > 1e-3]
    hill = hill_multipliers(reduced.F, reduced.v0, 0.2, 29.5, 1)
    assert copies(rho, hill, 1e-8).min() == 0

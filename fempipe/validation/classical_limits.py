"""Closed forms the classical solvers are checked against: Blevins's tip-mass frequencies,
Greenhill's heavy column with an end weight, Chen's tip spring, the large-damping limit.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
from scipy.optimize import brentq

from fempipe.core.parallel import single_blas

from .classical_galerkin import LegendreGalerkin
from .straight_pipe import StraightPipe

# Closed forms the solvers are checked against


def _roots(f, a: float, b: float, n_grid: int = 4000, count: int | None = None) -> np.ndarray:
    """The sign changes of ``f`` on a grid of [a, b], refined by Brent's method."""
    x = np.linspace(a, b, n_grid)
    y = np.array([f(t) for t in x])
    idx = np.flatnonzero(np.sign(y[1:]) * np.sign(y[:-1]) < 0)
    roots = [brentq(f, x[i], x[i + 1], xtol=1e-15, rtol=1e-15) for i in idx[:count]]
    return np.array(roots)


def tip_mass_frequencies(end_mass: float, n: int = 3) -> np.ndarray:
    """omega_r = l_r^2 of the gravity-free cantilever with a tip mass at v = 0 (Blevins 1979).

    Roots of 1 + cos l cosh l + Gamma l (cos l sinh l - sin l cosh l) = 0, divided by cosh l.
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

    y = eta' solves y'' + gamma s y = 0 (s = 1 + Gamma - xi): y = s^(1/2) [A J_(1/3)(z) +
    B J_(-1/3)(z)], z = (2/3) gamma^(1/2) s^(3/2); Gamma = 0: Greenhill's gamma = 7.8373.
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
    """Divergence v of the gravity-free cantilever with a tip spring kappa: the smallest root of
    u^3 + kappa (sin u - u cos u) = 0 below 3 pi (Paidoussis 1998, Eq. (3.119)), else nan.
    """
    r = _roots(lambda u: u**3 + kappa * (math.sin(u) - u * math.cos(u)), 0.1, 3 * math.pi, count=1)
    return float(r[0]) if r.size else float("nan")


@single_blas
def stiffness_roots(pipe: StraightPipe, v: float, p: int = 16, nu_max: float = 1e4) -> np.ndarray:
    """The roots nu of K(v) x = nu M x (no damping, no Coriolis), |nu| < ``nu_max``.

    With damping sigma M, lambda^2 + sigma lambda + nu = 0 is stable iff a > 0 and b^2 < sigma^2 a
    (nu = a + ib): for sigma -> infinity only a > 0 is left.
    """
    K0, Kv, _, _, M = LegendreGalerkin(p).pencil(replace(pipe, sigma=0.0, mu=0.0, beta=0.0))
    nu = np.linalg.eigvals(np.linalg.solve(M, K0 + v * v * Kv))
    return nu[np.abs(nu) < nu_max]


def large_damping_limit(pipe: StraightPipe, v_max: float, p: int = 16, step: float = 0.05) -> float:
    """v_cr as sigma -> infinity: the first v with Re nu < 0 (:func:`stiffness_roots`), else nan."""

    def f(v):
        return float(np.min(stiffness_roots(pipe, v, p).real))

    vs = np.arange(0.0, v_max + step / 2, step)
    prev = vs[0]
    for v in vs[1:]:
        if f(v) < 0.0:
            return float(brentq(f, prev, v, xtol=1e-13))
        prev = v
    return float("nan")

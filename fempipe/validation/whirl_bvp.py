"""The whirl of the hanging pipe as a steady state in a rotating frame: an independent BVP.

At sin alpha = 0 a whirl turns the pipe's shape rigidly about e_1 at a rate omega; in the
turning frame the continuum (the strong form of :mod:`fempipe.model.three_d.model`, objective
Kelvin-Voigt damping) is a BVP in xi for 13 functions y = (r, t, t', G, Q) and omega, with a
phase condition.  v is left free and an amplitude fixed, continued until v is met
(:func:`solve_whirl_bvp`).  scipy's ``solve_bvp`` does the work; no fempipe code is shared.
Derivation: docs/theory/independent.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_bvp

__all__ = ["WhirlBVP", "solve_whirl_bvp", "whirl_rhs"]

E1 = np.array([1.0, 0.0, 0.0])


@dataclass(frozen=True)
class WhirlBVP:
    """A whirl of the continuum: ``v``, ``omega`` (about e_1), ``period``, tip ``radius`` from the
    vertical, ``tip`` r(1) at the phase condition; ``dissipation`` and ``supply`` (power lost to
    damping and the fluid, supplied by the follower force: equal in a whirl);
    ``rms_residual``, ``n_nodes``, ``sol(xi)`` -> y (13, n).
    """

    v: float
    omega: float
    period: float
    radius: float
    tip: np.ndarray
    dissipation: float
    supply: float
    rms_residual: float
    n_nodes: int
    sol: object


def whirl_rhs(xi, y, omega, *, v, beta, gamma, mu, alpha=0.0, sigma=0.0):
    """dy/dxi of y = (r, t, t', G, Q) (13, m) in the frame turning at omega (docs/theory/independent.md)."""
    r, t, p, G, Q = y[0:3], y[3:6], y[6:9], y[9:12], y[12]
    g = np.array([math.cos(alpha), 0.0, 0.0])[:, None]
    e1 = E1[:, None]
    r_perp = r * np.array([0.0, 1.0, 1.0])[:, None]
    rdd = -(omega**2) * r_perp
    td = omega * np.cross(e1, t, axis=0)
    rd = omega * np.cross(e1, r, axis=0)
    dG = -(rdd + 2.0 * v * math.sqrt(beta) * td + sigma * rd) + gamma * g
    c = mu * omega
    p2 = np.sum(p * p, axis=0)
    tt = np.sum(t * t, axis=0)
    b = G + c * Q * np.cross(t, p, axis=0)
    bn = b - t * np.sum(t * b, axis=0) / tt
    dp = -p2 * t + (bn - c * np.cross(t, bn, axis=0)) / (1.0 + c * c)
    return np.vstack([t, p, dp, dG, -p2[None]])


def _tip_force(yb, omega, v, gamma, end_mass, alpha):
    g = np.array([math.cos(alpha), 0.0, 0.0])
    rdd1 = -(omega**2) * yb[0:3] * np.array([0.0, 1.0, 1.0])
    return -gamma * end_mass * g + v * v * yb[3:6] + end_mass * rdd1


def _solve(xi, y, p, *, fixed_v, R, prm, tol, max_nodes, energy=None):
    """One solve_bvp: omega with v fixed, or (omega, v) with r_2(1) = R or Q(0) = ``energy``."""
    beta, gamma, mu, alpha, sigma, end_mass = (
        prm[k] for k in ("beta", "gamma", "mu", "alpha", "sigma", "end_mass")
    )

    def split(pp):
        return (pp[0], fixed_v) if fixed_v is not None else (pp[0], pp[1])

    def fun(x, yy, pp):
        om, v = split(pp)
        return whirl_rhs(x, yy, om, v=v, beta=beta, gamma=gamma, mu=mu, alpha=alpha, sigma=sigma)

    def bc(ya, yb, pp):
        om, v = split(pp)
        res = [ya[0:3], ya[3:6] - E1, yb[6:9], yb[12:13]]
        res.append(yb[9:12] - _tip_force(yb, om, v, gamma, end_mass, alpha))
        res.append(yb[2:3])  # phase: r_3(1) = 0
        if fixed_v is None:
            res.append(yb[1:2] - R if energy is None else ya[12:13] - energy)
        return np.concatenate(res)

    return solve_bvp(fun, bc, xi, y, p=p, tol=tol, max_nodes=max_nodes)


def _initial_guess(xi, amplitude, v, gamma, end_mass, slope=None):
    """A bent pipe under the straight pipe's axial force, shaped by ``slope`` or a sine."""
    if slope is None:
        slope = np.sin(0.5 * math.pi * xi) + 0j
    w = np.concatenate([[0.0], np.cumsum(0.5 * (slope[1:] + slope[:-1]) * np.diff(xi))])
    scale = amplitude / w[-1]  # complex: turns the tip onto e_2 (r_3(1) = 0)
    s = slope * scale
    t = np.vstack([np.sqrt(np.maximum(1.0 - np.abs(s) ** 2, 0.0)), s.real, s.imag])
    t /= np.linalg.norm(t, axis=0)
    p = np.gradient(t, xi, axis=1)
    r = np.vstack(
        [np.concatenate([[0.0], np.cumsum(0.5 * (c[1:] + c[:-1]) * np.diff(xi))]) for c in t]
    )
    y = np.zeros((13, xi.size))
    y[0:3], y[3:6], y[6:9] = r, t, p
    y[9] = v * v - gamma * (1.0 - xi + end_mass)
    y[12] = np.sum(p * p, axis=0)[::-1].cumsum()[::-1] * (xi[1] - xi[0])
    return y


def _result(res, v, prm) -> WhirlBVP:
    om = float(res.p[0])
    xi = np.linspace(0.0, 1.0, 2001)
    y = res.sol(xi)
    r, t, p = y[0:3], y[3:6], y[6:9]
    w = np.full(xi.size, xi[1] - xi[0])
    w[[0, -1]] *= 0.5
    rd = om * np.cross(E1[:, None], r, axis=0)
    kv = prm["mu"] * om**2 * float(w @ np.sum(p * p, axis=0))
    lost = v * math.sqrt(prm["beta"]) * float(rd[:, -1] @ rd[:, -1])
    lost += prm["sigma"] * float(w @ np.sum(rd * rd, axis=0))
    supply = -v * v * float(rd[:, -1] @ t[:, -1])
    tip = r[:, -1].copy()
    return WhirlBVP(
        v=float(v),
        omega=om,
        period=2.0 * math.pi / abs(om),
        radius=float(math.hypot(tip[1], tip[2])),
        tip=tip,
        dissipation=kv + lost,
        supply=supply,
        rms_residual=float(np.max(res.rms_residuals)),
        n_nodes=int(res.x.size),
        sol=res.sol,
    )


def solve_whirl_bvp(
    v: float,
    *,
    beta: float = 0.142,
    gamma: float = 18.9,
    mu: float = 5e-3,
    alpha: float = 0.0,
    end_mass: float = 0.0,
    sigma: float = 0.0,
    hopf: tuple[float, float] = (6.33, 15.7),
    slope: np.ndarray | None = None,
    start_radius: float = 0.01,
    max_step: float = 0.2,
    tol: float = 1e-8,
    max_nodes: int = 20000,
) -> WhirlBVP:
    """The whirl at flow velocity v, by continuation in amplitude from the Hopf point.

    Parameters
    ----------
    v : float
        Flow velocity of the whirl (above the Hopf point).
    beta, gamma, mu, alpha, end_mass, sigma : float
        The pipe (sin alpha must be 0).
    hopf : (v, omega)
        A guess of the Hopf point.
    slope : ndarray of complex, optional
        A guess of the critical mode's t_2 + i t_3 on ``np.linspace(0, 1, slope.size)``.
    start_radius, max_step : float
        Tip amplitude of the first whirl (v free); steps in Q(0) = int |t'|^2 (halved on
        failure) until v is passed, then v fixed.
    tol : float
        solve_bvp's tolerance of the final solve (100 tol on the way).
    max_nodes : int
    """
    if abs(math.sin(alpha)) > 1e-12:
        raise ValueError("a whirl needs an axisymmetric pipe: sin(alpha) = 0")
    prm = {"beta": beta, "gamma": gamma, "mu": mu, "alpha": alpha, "sigma": sigma}
    prm["end_mass"] = end_mass
    kw = {"prm": prm, "max_nodes": max_nodes}
    xi = np.linspace(0.0, 1.0, 101 if slope is None else len(slope))
    y = _initial_guess(xi, start_radius, hopf[0], gamma, end_mass, slope)
    p = np.array([hopf[1], hopf[0]], dtype=float)
    res = _solve(xi, y, p, fixed_v=None, R=start_radius, tol=100 * tol, **kw)
    if not res.success:
        raise RuntimeError(f"whirl BVP: no whirl of amplitude {start_radius} by the Hopf guess")
    # Away from the Hopf point the tip amplitude saturates (near r_2(1) = 0.39 for the paper's
    # pipe) while v grows fast: continue in the curvature energy Q(0) = \\int |t'|^2, which
    # grows with v, in steps of at most max_step (halved on failure), until v passes the
    # wanted one.
    sol, A, step = res, float(res.y[12, 0]), max_step
    lo = (A, float(sol.p[1]), sol)
    while sol.p[1] < v:
        trial = _solve(
            sol.x, sol.y, sol.p, fixed_v=None, R=None, energy=A + step, tol=100 * tol, **kw
        )
        if trial.success and abs(trial.p[1] - sol.p[1]) < 1.0:
            lo = (A, float(sol.p[1]), sol)
            sol, A, step = trial, A + step, min(max_step, 1.5 * step)
        else:
            step *= 0.5
            if step < 1e-4:
                raise RuntimeError(f"whirl BVP: continuation stuck at v = {sol.p[1]}")
    hi = (A, float(sol.p[1]), sol)
    # v(Q(0)) = v by the secant method between the bracketing whirls (never the trivial
    # solution, which the problem with v fixed also has)
    for _ in range(30):
        A = lo[0] + (v - lo[1]) * (hi[0] - lo[0]) / (hi[1] - lo[1])
        near = hi if abs(hi[1] - v) < abs(lo[1] - v) else lo
        res = _solve(near[2].x, near[2].y, near[2].p, fixed_v=None, R=None, energy=A, tol=tol, **kw)
        if not res.success:
            raise RuntimeError(f"whirl BVP at v = {v}: {res.message}")
        lo, hi = hi, (A, float(res.p[1]), res)
        if abs(res.p[1] - v) < 1e-11 * v:
            break
    v = float(res.p[1])
    return _result(res, v, prm)

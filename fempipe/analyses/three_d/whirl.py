"""Whirls of an axisymmetric pipe: periodic orbits that turn rigidly about the vertical.

At sin(alpha) = 0 the flutter is an O(2) Hopf point: standing waves (the planar cycles) and
rotating waves (whirls) branch together.  On a mesh the turn is a symmetry only to the
discretization error: the whirl is shot as a periodic orbit and :func:`find_whirl` measures
how rigid it is.  Measurements: docs/theory/space.md, "The whirl of the hanging pipe".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D

from ...solvers.radau import Radau
from ..limit_cycle import LimitCycle, largest_nontrivial, shoot

__all__ = [
    "Whirl",
    "find_whirl",
    "tangent_state",
    "tip_turn",
    "whirl_guess_from_cycle",
    "whirl_state",
]


@dataclass(frozen=True)
class Whirl:
    """A whirl of the 3-D model (a periodic orbit turning about e_1).

    Attributes
    ----------
    v, period, omega : float
        omega = 2 pi / T, right-handed about e_1.
    radius, radius_variation : float
        Time average of the tip's distance from the vertical and its (max - min) / radius.
    rotation_defect : float
        Largest distance between the centerline and that at tau = 0 turned by omega tau.
    multipliers : ndarray of complex
        The 8 largest Floquet multipliers.
    max_nontrivial, stable, cycle : float, bool, LimitCycle
        Without the one multiplier 1 (a whirl's time shift is its turn).
    """

    v: float
    omega: float
    period: float
    radius: float
    radius_variation: float
    rotation_defect: float
    multipliers: np.ndarray
    max_nontrivial: float
    stable: bool
    cycle: LimitCycle = field(repr=False)

    def to_dict(self) -> dict:
        """The numbers, JSON-ready."""
        return {
            "v": self.v,
            "omega": self.omega,
            "period": self.period,
            "radius": self.radius,
            "radius_variation": self.radius_variation,
            "rotation_defect": self.rotation_defect,
            "multipliers": [[float(z.real), float(z.imag)] for z in self.multipliers],
            "max_nontrivial": self.max_nontrivial,
            "stable": self.stable,
        }


def fit_l2(model: PipeModel3D, f: np.ndarray) -> np.ndarray:
    """The finite element function(s) nearest f (n_q or (n_q, k)) at the quadrature points (L2)."""
    Phi, w = model.disc.Phi, model.w
    Phi = Phi.toarray() if hasattr(Phi, "toarray") else np.asarray(Phi)
    return np.linalg.solve(Phi.T @ (w[:, None] * Phi), Phi.T @ (w * f.T).T)


def tangent_state(
    model: PipeModel3D, t: np.ndarray, t_dot: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """(U, U_dot) of a tangent field ``t`` and its rate ``t_dot`` (n_q, 3) at the quadrature
    points: the chart's gauge-free representative of t = (cos psi cos theta, cos psi sin
    theta, sin psi), a = rho sin(theta/2), b = -rho cos(theta/2), rho = tan(psi/2)."""
    t = t / np.linalg.norm(t, axis=1, keepdims=True)
    theta = np.arctan2(t[:, 1], t[:, 0])
    psi = np.arcsin(np.clip(t[:, 2], -1.0, 1.0))
    h = t[:, 0] ** 2 + t[:, 1] ** 2
    th_dot = (t[:, 0] * t_dot[:, 1] - t[:, 1] * t_dot[:, 0]) / h
    psi_dot = t_dot[:, 2] / np.sqrt(h)
    rho = np.tan(0.5 * psi)
    rho_dot = 0.5 * psi_dot / np.cos(0.5 * psi) ** 2
    s, c = np.sin(0.5 * theta), np.cos(0.5 * theta)
    u = np.column_stack([theta, rho * s, -rho * c])
    ud = np.column_stack(
        [th_dot, rho_dot * s + 0.5 * rho * c * th_dot, -rho_dot * c + 0.5 * rho * s * th_dot]
    )
    return fit_l2(model, u).T.ravel(), fit_l2(model, ud).T.ravel()


def whirl_state(
    model: PipeModel3D, tangent: Callable[[np.ndarray], np.ndarray], omega: float
) -> tuple[np.ndarray, np.ndarray]:
    """(U, U_dot) of the shape ``tangent(xi)`` (shape (3, m) at m points) turning at omega
    about e_1: t_dot = omega e_1 x t."""
    t = np.asarray(tangent(model.x), dtype=float).T
    t_dot = omega * np.cross([1.0, 0.0, 0.0], t)
    return tangent_state(model, t, t_dot)


def whirl_guess_from_cycle(model: PipeModel3D, cycle: LimitCycle, tau: float = 0.0):
    """(U, U_dot, period) of a whirl guessed from a planar cycle: theta(xi, tau) in the plane
    and psi = theta(xi, tau - T/4) out of it, to first order a rotating wave."""
    T = cycle.period
    n = model.n_theta
    Phi = model.disc.Phi
    pts = []
    for s in (tau, tau - 0.25 * T):
        k = float(np.mod(s, T))
        i = int(np.clip(np.searchsorted(cycle.orbit_t, k), 1, len(cycle.orbit_t) - 1))
        a = (k - cycle.orbit_t[i - 1]) / (cycle.orbit_t[i] - cycle.orbit_t[i - 1])
        q = (1 - a) * cycle.orbit_q[i - 1] + a * cycle.orbit_q[i]
        p = (1 - a) * cycle.orbit_qdot[i - 1] + a * cycle.orbit_qdot[i]
        pts.append((Phi @ q[:n], Phi @ p[:n]))
    (th, thd), (ps, psd) = pts
    t = np.column_stack([np.cos(ps) * np.cos(th), np.cos(ps) * np.sin(th), np.sin(ps)])
    t_dot = np.column_stack(
        [
            -np.sin(ps) * psd * np.cos(th) - np.cos(ps) * np.sin(th) * thd,
            -np.sin(ps) * psd * np.sin(th) + np.cos(ps) * np.cos(th) * thd,
            np.cos(ps) * psd,
        ]
    )
    return (*tangent_state(model, t, t_dot), T)


def _step_ends(model: PipeModel3D, cycle: LimitCycle, rtol: float):
    """tau and U at the step ends of one period (the dense output between them is of lower
    order, too rough for the measures of rigidity)."""
    stepper = Radau(PipeDynamics3D(model), cycle.q0, cycle.qdot0, 0.0, rtol=rtol)
    ends = [(0.0, np.array(cycle.q0, dtype=float))]
    ends += [(t, q) for t, q, _ in stepper.steps(cycle.period)]
    return np.array([t for t, _ in ends]), np.array([q for _, q in ends])


def _radius_statistics(ts: np.ndarray, rad: np.ndarray) -> tuple[float, float]:
    """(time average, (max - min) / time average) of the tip radius at the times ``ts``."""
    mean = float(np.trapezoid(rad, ts) / (ts[-1] - ts[0]))
    return mean, float((rad.max() - rad.min()) / mean)


def _rotation_defect(model: PipeModel3D, ts: np.ndarray, Us: np.ndarray, omega: float) -> float:
    r0 = model.centerline(Us[0])
    worst = 0.0
    for tau, U in zip(ts, Us, strict=True):
        c, s = math.cos(omega * tau), math.sin(omega * tau)
        rot = np.column_stack([r0[:, 0], c * r0[:, 1] - s * r0[:, 2], s * r0[:, 1] + c * r0[:, 2]])
        worst = max(worst, float(np.max(np.linalg.norm(model.centerline(U) - rot, axis=1))))
    return worst


def tip_turn(tips: dict) -> tuple[np.ndarray, np.ndarray]:
    """(distance from the vertical, unwrapped angle) of the tip from ``tips`` of a sequence of
    states, in the pipe's frame (eta_tip, Y_tip): the angle grows for a turn right-handed about
    e_1 whatever the inclination."""
    eta, y = np.asarray(tips["eta_tip"]), np.asarray(tips["Y_tip"])
    return np.hypot(eta, y), np.unwrap(np.arctan2(y, eta))


def find_whirl(
    model: PipeModel3D,
    U0: np.ndarray,
    Ud0: np.ndarray,
    period: float,
    *,
    rtol: float = 1e-8,
    tol: float = 1e-7,
    max_iter: int = 15,
) -> Whirl:
    """Shoot a whirl from a guess and measure it.

    Parameters
    ----------
    model : PipeModel3D
        At an axisymmetric inclination (sin alpha = 0, else ValueError).
    U0, Ud0, period : ndarray, ndarray, float
        The guess (:func:`whirl_state`, :func:`whirl_guess_from_cycle`).
    rtol, tol, max_iter
        As :func:`~fempipe.analyses.limit_cycle.shoot` (ShootingError).
    """
    if abs(math.sin(model.params.alpha)) > 1e-12:
        raise ValueError("a whirl needs an axisymmetric pipe: sin(alpha) = 0")
    cycle = shoot(PipeDynamics3D(model), U0, Ud0, period, rtol=rtol, tol=tol, max_iter=max_iter)
    ts, Us = _step_ends(model, cycle, rtol)
    rad, ang = tip_turn(model.tip_coordinates(Us))
    turn = ang[-1] - ang[0]
    omega = math.copysign(2.0 * math.pi / cycle.period, turn)
    if abs(abs(turn) - 2.0 * math.pi) > 0.5:
        omega = math.nan  # not one turn a period: no whirl
    mu = np.asarray(cycle.floquet_multipliers)
    largest = largest_nontrivial(mu)
    mean, variation = _radius_statistics(ts, rad)
    defect = _rotation_defect(model, ts, Us, omega) if math.isfinite(omega) else math.nan
    return Whirl(
        v=float(model.params.v),
        omega=omega,
        period=float(cycle.period),
        radius=mean,
        radius_variation=variation,
        rotation_defect=defect,
        multipliers=mu[np.argsort(-np.abs(mu))[:8]],
        max_nontrivial=largest,
        stable=largest < 1.0,
        cycle=cycle,
    )

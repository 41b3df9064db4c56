"""The nonlinear response inside a principal region: the period-doubled orbit of the straight pipe.

Where the straight state loses stability through a multiplier -1 (the principal region of
odd order), an orbit of period 2T (T = 2 pi / omega) branches off it.  It is a fixed point
of the 2T map of Eq. (20) with the pulsating flow, found by Newton's method (the monodromy
from the integrator's sensitivity; non-autonomous: no phase condition) and continued by
pseudo-arclength in omega at fixed sigma (:func:`continue_subharmonic`) or in sigma at fixed
omega (:func:`continue_subharmonic_in_sigma`), from the region's edge by branch switching
along the critical eigenvector.  theta -> -theta maps the orbit onto itself shifted by T.
The criticality of each edge is read from the branch's first step and the stability of its
small orbit.  Derivation and measured branches: docs/theory/parametric.md.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.dynamics import PulsatingFlow
from fempipe.analyses.stability import compute_spectrum
from fempipe.core.errors import SolverError
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.kinematics import compute_tip
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import IntegrationError, Radau

from .floquet import PulsationPencil, ReducedPulsation
from .regions import Candidate, ParametricRegion, locate_region

__all__ = [
    "SubharmonicBranch",
    "SubharmonicOrbit",
    "continue_subharmonic",
    "continue_subharmonic_in_sigma",
    "locate_principal_region",
]


@dataclass(frozen=True)
class SubharmonicOrbit:
    """One orbit of period 2T on the branch.

    ``amplitude`` is max |theta(1)| over the orbit; ``x_tip``, ``z_tip`` the (min, max) of the
    tip's coordinates; ``multipliers`` those of its 2T map, largest modulus first; ``q0``,
    ``qdot0`` its state at tau = 0; ``iterations`` and ``residual`` of Newton's method.
    """

    omega: float
    sigma: float
    amplitude: float
    x_tip: tuple[float, float]
    z_tip: tuple[float, float]
    multipliers: np.ndarray
    stable: bool
    iterations: int
    residual: float
    q0: np.ndarray
    qdot0: np.ndarray

    @property
    def period(self) -> float:
        """2T = 4 pi / omega (its out-of-plane multipliers:
        :func:`~fempipe.analyses.three_d.compute_out_of_plane_floquet` with the flow)."""
        return 4 * math.pi / self.omega


@dataclass(frozen=True)
class SubharmonicBranch:
    """The branch of 2T orbits from one edge of a principal region.

    ``parameter`` is "omega" or "sigma"; ``edge`` its value where the branch starts;
    ``inward`` the sign of the parameter's change into the region (+1 or -1);
    ``criticality`` "supercritical" (into the region, stable), "subcritical" (out of it,
    unstable) or "undetermined"; ``stop`` why the continuation ended.
    """

    parameter: str
    v0: float
    edge: float
    inward: int
    criticality: str
    points: tuple[SubharmonicOrbit, ...]
    stop: str
    cpu_seconds: float

    @property
    def values(self) -> np.ndarray:
        """The parameter along the branch."""
        return np.array([getattr(p, self.parameter) for p in self.points])

    @property
    def amplitudes(self) -> np.ndarray:
        return np.array([p.amplitude for p in self.points])

    def to_dict(self) -> dict:
        return {
            "parameter": self.parameter,
            "v0": self.v0,
            "edge": self.edge,
            "inward": self.inward,
            "criticality": self.criticality,
            "stop": self.stop,
            "cpu_seconds": self.cpu_seconds,
            "points": [
                {
                    "omega": p.omega,
                    "sigma": p.sigma,
                    "amplitude": p.amplitude,
                    "x_tip": list(p.x_tip),
                    "z_tip": list(p.z_tip),
                    "multiplier_max": float(abs(p.multipliers[0])),
                    "stable": p.stable,
                    "iterations": p.iterations,
                    "residual": p.residual,
                }
                for p in self.points
            ],
        }


def locate_principal_region(
    model: PipeModel, v0: float, sigma: float, mode: int = 2, *, steps: int = 128
) -> ParametricRegion | None:
    """The principal region (order 1) of ``mode`` with its edges at ``sigma`` (the modes
    numbered as :func:`~fempipe.analyses.stability.compute_spectrum` does)."""
    model = model.with_params(replace(model.params, v=float(v0)))
    mean = compute_spectrum(model, np.zeros(model.n))
    lam = next(complex(x) for x, k in zip(mean.lam, mean.mode, strict=True) if int(k) == mode)
    reduced = ReducedPulsation(PulsationPencil.of(model), v0, pairs=max(3, mode + 1))
    nominal = 2.0 * lam.imag
    region, _ = locate_region(
        reduced,
        Candidate("principal", 1, (mode,), nominal),
        (0.85 * nominal, 1.15 * nominal),
        [sigma],
        limits=(0.5 * nominal, 1.5 * nominal),
        steps=steps,
    )
    return region


class _PeriodMap:
    """x -> x(periods T) of Eq. (20) with fixed steps T / steps (a smooth map whose
    sensitivity is its exact Jacobian), and the tip's samples along the way."""

    def __init__(self, model: PipeModel, steps: int, rtol: float, atol: float) -> None:
        self.model, self.steps, self.rtol, self.atol = model, steps, rtol, atol
        self.n = model.n
        self.count = 0

    def __call__(self, x, sigma, omega, periods=2, sensitivity=True):
        n, T = self.n, 2 * math.pi / omega
        self.count += 1
        stepper = Radau(
            PipeDynamics(self.model, PulsatingFlow(self.model.params.v, sigma, omega)),
            x[:n],
            x[n:],
            0.0,
            rtol=self.rtol,
            atol=self.atol,
            h_fixed=T / self.steps,
            sensitivity=sensitivity,
        )
        qs = [x[:n]] + [q for _, q, _ in stepper.steps(periods * T)]
        return np.r_[stepper.q, stepper.qdot], stepper.sensitivity_matrix, np.array(qs)


def _extremes(model: PipeModel, qs: np.ndarray) -> tuple[float, tuple, tuple]:
    """max |theta(1)| (a parabola through the largest sample and its neighbours on the closed
    orbit), and the (min, max) of X_tip and Z_tip."""
    tips = compute_tip(model.disc, qs[:-1], model.params.alpha)
    th = np.abs(tips["theta_tip"])
    k = int(np.argmax(th))
    a, b, c = th[k - 1], th[k], th[(k + 1) % th.size]
    curv = a - 2 * b + c
    peak = b - 0.125 * (c - a) ** 2 / curv if curv < 0 else b
    X, Z = tips["X_tip"], tips["Z_tip"]
    return float(peak), (float(X.min()), float(X.max())), (float(Z.min()), float(Z.max()))


def _continue(
    model: PipeModel,
    v0: float,
    parameter: str,
    fixed: float,
    start: float,
    *,
    direction: int,
    bounds: tuple[float, float],
    first_step: float,
    ds: float,
    ds_max: float,
    max_points: int,
    max_amplitude: float,
    steps: int,
    rtol: float,
    atol: float,
    tol: float,
    max_iterations: int,
) -> SubharmonicBranch:
    if direction not in (1, -1):
        raise ValueError(f"direction must be +1 or -1, got {direction}")
    cpu0 = time.process_time()
    model = model.with_params(replace(model.params, v=float(v0)))
    n = model.n
    flow = _PeriodMap(model, steps, rtol, atol)

    def sw(p: float) -> tuple[float, float]:
        return (fixed, p) if parameter == "omega" else (p, fixed)

    omega_ref = start if parameter == "omega" else fixed
    # the norm of the continuation: q, qdot / omega, and the parameter relative to the edge
    weight = np.r_[np.ones(n), np.full(n, 1.0 / omega_ref), 1.0 / abs(start)]

    def dot(a, b):
        return float(np.sum(weight**2 * a * b))

    def evaluate(y):
        end, S, qs = flow(y[:-1], *sw(y[-1]))
        return end - y[:-1], S, qs

    def d_parameter(y, G):
        h = 1e-6 * max(abs(y[-1]), 1e-3)
        end, _, _ = flow(y[:-1], *sw(y[-1] + h), sensitivity=False)
        return (end - y[:-1] - G) / h

    def bordered(y, G, S, row):
        """[[S - I, dG/dp], [row]]: Newton's matrix and the tangent's."""
        return np.block([[S - np.eye(2 * n), d_parameter(y, G)[:, None]], [row[None, :]]])

    def correct(y, row, target):
        """Newton on G(y) = 0, row . y = target: (y, iterations, residual, S, qs, G) or None."""
        for it in range(max_iterations + 1):
            try:
                G, S, qs = evaluate(y)
            except (IntegrationError, ValueError):  # a predictor too far off: halve the step
                return None
            res = math.sqrt(dot(np.r_[G, 0.0], np.r_[G, 0.0]))
            size = math.sqrt(dot(np.r_[y[:-1], 0.0], np.r_[y[:-1], 0.0]))
            if res <= tol * max(size, 1e-6):
                return y, it, res, S, qs, G
            if it == max_iterations or not np.all(np.isfinite(G)):
                return None
            y = y + np.linalg.solve(bordered(y, G, S, row), -np.r_[G, row @ y - target])
        return None

    # the trivial state's multipliers on either side of the edge: which side is inside
    def largest(p):
        _, S, _ = flow(np.zeros(2 * n), *sw(p), periods=1)
        return np.linalg.eigvals(S)

    delta = 1e-4 * abs(start)
    inward = (
        1 if np.abs(largest(start + delta)).max() > np.abs(largest(start - delta)).max() else -1
    )
    # branch switching along the eigenvector of the multiplier -1 of the T map
    _, S1, _ = flow(np.zeros(2 * n), *sw(start), periods=1)
    rho, V = np.linalg.eig(S1)
    k = int(np.argmin(np.abs(rho + 1)))
    if abs(rho[k].imag) > 1e-8 or abs(rho[k] + 1) > 0.05:
        raise ValueError(
            f"no multiplier -1 of the straight state at {parameter} = {start:g} "
            f"(nearest {rho[k]:.4g}): not the edge of a principal region"
        )
    phi = np.real(V[:, k])
    phi *= (
        direction * np.sign(model.disc.tip @ phi[:n]) / math.sqrt(dot(np.r_[phi, 0], np.r_[phi, 0]))
    )
    tangent = np.r_[phi, 0.0]
    row = weight**2 * tangent
    found = correct(np.r_[first_step * phi, start], row, first_step)
    if found is None:
        raise SolverError(
            f"the first 2T orbit off the edge {parameter} = {start:g} did not converge"
        )
    points: list[SubharmonicOrbit] = []
    stop = f"{max_points} points"
    y, step = found[0], ds
    while True:
        y, it, res, S, qs, G = found
        amp, xt, zt = _extremes(model, qs)
        mult = np.linalg.eigvals(S)
        mult = mult[np.argsort(-np.abs(mult))]
        sigma, omega = sw(float(y[-1]))
        points.append(
            SubharmonicOrbit(
                omega=omega,
                sigma=sigma,
                amplitude=amp,
                x_tip=xt,
                z_tip=zt,
                multipliers=mult,
                stable=bool(abs(mult[0]) < 1.0),
                iterations=it,
                residual=res,
                q0=y[:n].copy(),
                qdot0=y[n : 2 * n].copy(),
            )
        )
        if not bounds[0] <= y[-1] <= bounds[1]:
            stop = f"{parameter} left [{bounds[0]:g}, {bounds[1]:g}]"
            break
        if amp > max_amplitude:
            stop = f"amplitude above {max_amplitude:g}"
            break
        if len(points) > 2 and amp < 0.5 * points[0].amplitude:
            stop = "back to the straight state"
            break
        if len(points) == max_points:
            break
        # the tangent: the null vector of [S - I, G_p] continuing the previous direction
        new = np.linalg.solve(bordered(y, G, S, weight**2 * tangent), np.r_[np.zeros(2 * n), 1.0])
        tangent = new / math.sqrt(dot(new, new))
        while True:
            guess = y + step * tangent
            found = correct(guess, weight**2 * tangent, float(weight**2 * tangent @ guess))
            if found is not None:
                step = min(ds_max, step * (1.5 if found[1] <= 3 else 1.0))
                break
            step *= 0.5
            if step < 1e-3 * ds:
                stop = "Newton failed at the least step"
                break
        if found is None:
            break
    # the first step's direction (omega - omega_edge ~ amplitude^2, the same sign) and the
    # stability of the small orbit after it (at the first, a multiplier is 1 to O(amplitude^2))
    small = points[min(1, len(points) - 1)]
    moved = math.copysign(1.0, getattr(small, parameter) - getattr(points[0], parameter))
    if len(points) == 1:
        moved = math.copysign(1.0, getattr(small, parameter) - start)
    if moved == inward and small.stable:
        criticality = "supercritical"
    elif moved != inward and not small.stable:
        criticality = "subcritical"
    else:
        criticality = "undetermined"
    return SubharmonicBranch(
        parameter=parameter,
        v0=float(v0),
        edge=float(start),
        inward=inward,
        criticality=criticality,
        points=tuple(points),
        stop=stop,
        cpu_seconds=time.process_time() - cpu0,
    )


def continue_subharmonic(
    model: PipeModel,
    v0: float,
    sigma: float,
    omega_start: float,
    *,
    direction: int = 1,
    omega_bounds: tuple[float, float] | None = None,
    first_step: float = 1e-3,
    ds: float = 0.02,
    ds_max: float = 0.1,
    max_points: int = 40,
    max_amplitude: float = 1.5,
    steps: int = 128,
    rtol: float = 1e-8,
    atol: float = 1e-8,
    tol: float = 1e-8,
    max_iterations: int = 8,
) -> SubharmonicBranch:
    """The branch of 2T orbits from the edge ``omega_start`` of a principal region, in omega.

    Parameters
    ----------
    model : PipeModel
        The straight pipe (alpha = 0; its v is replaced by ``v0``).
    v0, sigma : float
        The mean flow and the pulsation's amplitude (fixed).
    omega_start : float
        An edge of the region at ``sigma`` (:func:`locate_principal_region`).
    direction : int
        Sign of the first step along the critical eigenvector (-1: the mirror orbit).
    omega_bounds : (float, float), optional
        Stop outside (default 0.5 and 1.5 times ``omega_start``).
    first_step, ds, ds_max : float
        The first orbit's eigenvector component; first and largest arclength steps.
    max_points, max_amplitude : int, float
        Stop after this many orbits, or when max |theta(1)| exceeds this (rad).
    steps, rtol, atol : int, float, float
        Fixed Radau IIA steps per period T; the tolerances of its stage equations.
    tol : float
        Newton stops when |x(2T) - x(0)| <= tol max(|x(0)|, 1e-6).

    Raises
    ------
    ValueError, SolverError
        No multiplier -1 at ``omega_start``; the first orbit does not converge.
    """
    bounds = omega_bounds or (0.5 * omega_start, 1.5 * omega_start)
    return _continue(
        model, v0, "omega", float(sigma), float(omega_start), direction=direction,
        bounds=bounds, first_step=first_step, ds=ds, ds_max=ds_max, max_points=max_points,
        max_amplitude=max_amplitude, steps=steps, rtol=rtol, atol=atol, tol=tol,
        max_iterations=max_iterations,
    )  # fmt: skip


def continue_subharmonic_in_sigma(
    model: PipeModel,
    v0: float,
    omega: float,
    sigma_start: float,
    *,
    direction: int = 1,
    sigma_bounds: tuple[float, float] = (0.0, 1.0),
    first_step: float = 1e-3,
    ds: float = 0.02,
    ds_max: float = 0.1,
    max_points: int = 40,
    max_amplitude: float = 1.5,
    steps: int = 128,
    rtol: float = 1e-8,
    atol: float = 1e-8,
    tol: float = 1e-8,
    max_iterations: int = 8,
) -> SubharmonicBranch:
    """The branch of 2T orbits from the edge ``sigma_start`` (the critical sigma at
    ``omega``), in sigma at fixed omega; the parameters as :func:`continue_subharmonic`."""
    return _continue(
        model, v0, "sigma", float(omega), float(sigma_start), direction=direction,
        bounds=sigma_bounds, first_step=first_step, ds=ds, ds_max=ds_max,
        max_points=max_points, max_amplitude=max_amplitude, steps=steps, rtol=rtol,
        atol=atol, tol=tol, max_iterations=max_iterations,
    )  # fmt: skip

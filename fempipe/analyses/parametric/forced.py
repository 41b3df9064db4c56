"""The periodic response of a bent pipe to a pulsating flow, and its Floquet multipliers.

For 0 < alpha < pi the pulsation moves the pipe: a periodic solution of period 2 pi / omega
near the static state, found by Newton on the period map (non-autonomous: no phase
condition); at sigma = 0 the static state.  Its multipliers in the plane are those of the
period map; out of the plane those of the linear out-of-plane motion about it
(:class:`~fempipe.model.out_of_plane.motion.OutOfPlaneVariation`), integrated with it.
Derivation: docs/theory/parametric.md.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fempipe.analyses.dynamics import PulsatingFlow
from fempipe.analyses.statics import solve_sagged
from fempipe.core.errors import SolverError
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.kinematics import compute_tip
from fempipe.model.out_of_plane.motion import OutOfPlaneVariation
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import Radau

__all__ = ["ForcedResponse", "solve_forced_response"]


@dataclass(frozen=True)
class ForcedResponse:
    """The periodic response to a pulsating flow: the state ``q0``, ``qdot0`` at phase 0,
    the ``period`` 2 pi / omega, the in-plane Floquet ``multipliers`` (largest first), the
    Newton ``iterations``, the relative ``residual`` |x(T) - x(0)| and the ``amplitude``
    (max - min) / 2 of theta(1); ``out_of_plane_multipliers`` if asked for (else None)."""

    q0: np.ndarray
    qdot0: np.ndarray
    period: float
    multipliers: np.ndarray
    iterations: int
    residual: float
    amplitude: float
    out_of_plane_multipliers: np.ndarray | None = None


def _period_map(problem, x: np.ndarray, T: float, steps: int, rtol: float):
    n = problem.n
    # The error control sees the state, not the sensitivity (on the straight pipe the state is
    # exactly zero): the steps are also bounded, T / steps at most.
    h = T / steps
    stepper = Radau(
        problem, x[:n], x[n:], 0.0, rtol=rtol, max_step=h, first_step=h, sensitivity=True
    )
    model = problem.model
    m, alpha = model.n, model.params.alpha
    tips = [compute_tip(model.disc, x[:m], alpha)["theta_tip"]]
    for _, q, _ in stepper.steps(T):
        tips.append(compute_tip(model.disc, q[:m], alpha)["theta_tip"])
    return np.r_[stepper.q, stepper.qdot], stepper.sensitivity_matrix, tips


def _largest_first(S: np.ndarray) -> np.ndarray:
    rho = np.linalg.eigvals(S)
    return rho[np.argsort(-np.abs(rho))]


def solve_forced_response(
    model: PipeModel,
    sigma: float,
    omega: float,
    *,
    guess: tuple[np.ndarray, np.ndarray] | None = None,
    steps: int = 128,
    rtol: float = 1e-8,
    tol: float = 1e-9,
    max_iterations: int = 12,
    out_of_plane: bool = False,
) -> ForcedResponse:
    """The periodic response of ``model`` (mean flow ``model.params.v``) to the pulsation.

    Parameters
    ----------
    model : PipeModel
    sigma, omega : float
        Amplitude (0 <= sigma <= 1) and frequency (> 0) of the pulsation.
    guess : (q0, qdot0), optional
        A starting state (default the static state at the mean flow).
    steps, rtol : int, float
        At least this many Radau IIA steps per period; the integrator's tolerance.
    tol : float
        Newton stops when |x(T) - x(0)| <= tol max(1, |x(0)|) (else SolverError).
    out_of_plane : bool
        Also the multipliers of the motion out of the plane (the planar motion and its
        variation integrated together; springs = () required).
    """
    if omega <= 0:
        raise ValueError(f"omega must be > 0, got {omega}")
    flow = PulsatingFlow(model.params.v, sigma, omega)
    n = model.n
    problem = OutOfPlaneVariation(model, flow) if out_of_plane else PipeDynamics(model, flow)
    x = np.r_[solve_sagged(model).q, np.zeros(n)] if guess is None else np.r_[guess[0], guess[1]]
    # the state integrated: (q, psi, q', psi') with psi = 0 out of the plane
    planar = np.r_[0:n, problem.n : problem.n + n]
    T = 2 * math.pi / omega
    for iteration in range(max_iterations + 1):
        y = np.zeros(2 * problem.n)
        y[planar] = x
        end, S, tips = _period_map(problem, y, T, steps, rtol)
        r = end[planar] - x
        residual = float(np.linalg.norm(r) / max(1.0, np.linalg.norm(x)))
        S_in = S[np.ix_(planar, planar)]
        if residual <= tol:
            out = None
            if out_of_plane:
                psi = np.setdiff1d(np.arange(2 * problem.n), planar)
                out = _largest_first(S[np.ix_(psi, psi)])
            amplitude = 0.5 * (max(tips) - min(tips))
            return ForcedResponse(
                x[:n].copy(),
                x[n:].copy(),
                T,
                _largest_first(S_in),
                iteration,
                residual,
                amplitude,
                out,
            )
        if iteration == max_iterations:
            break
        x = x + np.linalg.solve(S_in - np.eye(2 * n), -r)
    raise SolverError(
        f"the periodic response at sigma = {sigma:g}, omega = {omega:g} did not converge in "
        f"{max_iterations} Newton steps (residual {residual:.2e}; the period map is singular "
        "where a multiplier is 1)"
    )

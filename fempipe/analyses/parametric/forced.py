"""The periodic response of a bent pipe to a pulsating flow, and its Floquet multipliers.

For 0 < alpha < pi the pulsation moves the pipe: a periodic solution of period 2 pi / omega
near the static state, found by Newton on the period map (non-autonomous: no phase
condition); at sigma = 0 the static state.  Derivation: docs/theory/parametric.md.
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
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import Radau

__all__ = ["ForcedResponse", "solve_forced_response"]


@dataclass(frozen=True)
class ForcedResponse:
    """The periodic response to a pulsating flow: the state ``q0``, ``qdot0`` at phase 0,
    the ``period`` 2 pi / omega, the in-plane Floquet ``multipliers`` (largest first), the
    Newton ``iterations``, the relative ``residual`` |x(T) - x(0)| and the ``amplitude``
    (max - min) / 2 of theta(1)."""

    q0: np.ndarray
    qdot0: np.ndarray
    period: float
    multipliers: np.ndarray
    iterations: int
    residual: float
    amplitude: float


def _period_map(
    model: PipeModel, flow: PulsatingFlow, x: np.ndarray, T: float, steps: int, rtol: float
):
    n = model.n
    # The error control sees the state, not the sensitivity (on the straight pipe the state is
    # exactly zero): the steps are also bounded, T / steps at most.
    h = T / steps
    problem = PipeDynamics(model, flow)
    stepper = Radau(
        problem, x[:n], x[n:], 0.0, rtol=rtol, max_step=h, first_step=h, sensitivity=True
    )
    alpha = model.params.alpha
    tips = [compute_tip(model.disc, x[:n], alpha)["theta_tip"]]
    for _, q, _ in stepper.steps(T):
        tips.append(compute_tip(model.disc, q, alpha)["theta_tip"])
    return np.r_[stepper.q, stepper.qdot], stepper.sensitivity_matrix, tips


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
    """
    if omega <= 0:
        raise ValueError(f"omega must be > 0, got {omega}")
    flow = PulsatingFlow(model.params.v, sigma, omega)
    n = model.n
    x = np.r_[solve_sagged(model).q, np.zeros(n)] if guess is None else np.r_[guess[0], guess[1]]
    T = 2 * math.pi / omega
    for iteration in range(max_iterations + 1):
        end, S, tips = _period_map(model, flow, x, T, steps, rtol)
        r = end - x
        residual = float(np.linalg.norm(r) / max(1.0, np.linalg.norm(x)))
        if residual <= tol:
            rho = np.linalg.eigvals(S)
            rho = rho[np.argsort(-np.abs(rho))]
            amplitude = 0.5 * (max(tips) - min(tips))
            return ForcedResponse(
                x[:n].copy(), x[n:].copy(), T, rho, iteration, residual, amplitude
            )
        if iteration == max_iterations:
            break
        x = x + np.linalg.solve(S - np.eye(2 * n), -r)
    raise SolverError(
        f"the periodic response at sigma = {sigma:g}, omega = {omega:g} did not converge in "
        f"{max_iterations} Newton steps (residual {residual:.2e}; the period map is singular "
        "where a multiplier is 1)"
    )

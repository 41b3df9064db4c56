"""The 3-D pipe's equations of motion as the integrator's problem.

:class:`PipeDynamics3D` is to :class:`~fempipe.model.three_d.model.PipeModel3D` what
:class:`~fempipe.model.dynamics_problem.PipeDynamics` is to the planar model: the Radau
integrator, shooting and the Floquet multipliers run on it unchanged.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from fempipe.model.dynamics_problem import ModelDynamics
from fempipe.model.three_d.model import PipeModel3D

__all__ = ["PipeDynamics3D"]


class _VelocityDerivative:
    """dR/dv of the stages by one :meth:`PipeModel3D.velocity_derivative`."""

    def __init__(self, model: PipeModel3D) -> None:
        self.model = model

    def __call__(self, Q: np.ndarray, P: np.ndarray, Acc: np.ndarray) -> np.ndarray:
        return self.model.velocity_derivative(np.atleast_2d(Q), np.atleast_2d(P))


class PipeDynamics3D(ModelDynamics):
    """The 3-D weak form as an implicit second-order problem; ``flow`` tau -> (v, v_dot) optional (rule 9)."""

    #: the three stage Jacobians of the sensitivity are one evaluation of the weak form
    #: with S = 3 (:meth:`PipeModel3D.jacobians`), cheaper than three evaluations of one
    prefers_batched_stage_jacobians = True

    def __init__(
        self, model: PipeModel3D, flow: Callable[[float], tuple[float, float]] | None = None
    ) -> None:
        self.model = model
        self.flow = flow
        self.n = model.n
        self.autonomous = flow is None
        self.parameter_derivative = _VelocityDerivative(model) if flow is None else None
        # The weak form takes S states at once (a last axis): the three stages
        # of a Newton iteration are one evaluation (rule 6).
        self.stage_residuals = self._stage_residuals if flow is None else None
        self.stage_jacobians = self._stage_jacobians if flow is None else None
        # Contract rule 7: at planar states the in-plane (theta) and out-of-plane (a, b)
        # unknowns decouple exactly (mirror symmetry e_3 -> -e_3): the integrator then
        # factors and propagates the sensitivity block by block.
        nt = model.n_theta
        self.decoupled_blocks = (np.arange(nt), np.arange(nt, 3 * nt))

    def _stage_residuals(self, Q, P, A) -> np.ndarray:
        return self.model.residual(np.atleast_2d(Q), np.atleast_2d(P), np.atleast_2d(A))

    def _stage_jacobians(self, Q, P, A):
        return self.model.jacobians(np.atleast_2d(Q), np.atleast_2d(P), np.atleast_2d(A))

    def solve_acceleration(self, model, q, qdot, v_dot: float) -> np.ndarray:
        """:meth:`PipeModel3D.acceleration`."""
        return model.acceleration(q, qdot, v_dot)

    def describe(self) -> str:
        """The flow velocity, for error messages (rule 14)."""
        return f"v = {self.model.params.v:.6g} (3-D)"

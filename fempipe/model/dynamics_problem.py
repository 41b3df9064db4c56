"""The pipe's equations of motion as the integrator's problem: Eq. (20) in residual form.

:class:`PipeDynamics` implements :class:`fempipe.solvers.radau.contract.ImplicitSecondOrderProblem`
(whose docstring numbers the rules cited here) for a :class:`~fempipe.model.plane.operators.PipeModel`
with a steady or unsteady flow.  :func:`refuse_hysteretic` is the refusal every time-domain
entry point makes first.  Method: docs/theory/numerics.md, "Time integration".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.linalg as sla

from fempipe.model.plane.batched import StageKernels
from fempipe.model.plane.operators import PipeModel

__all__ = [
    "BATCHED_STAGES_MAX",
    "ModelDynamics",
    "PipeDynamics",
    "acceleration",
    "refuse_hysteretic",
]

#: Up to this n_q * n the three stage Jacobians of the sensitivity are one
#: batched evaluation (S = 3 in :meth:`StageKernels.jacobians`), beyond it three
#: (its (n_q, 2, S, n) temporaries outgrow the call overhead saved): with one BLAS
#: thread one call is cheaper than three up to P3:16 (n_q n = 4608) and dearer from
#: P3:20 (7200) on.
BATCHED_STAGES_MAX = 4608


def refuse_hysteretic(params, where: str) -> None:
    """ValueError (naming ``where``) if ``params`` has hysteretic damping: EI (1 + i mu_h
    sgn(omega)) is defined for harmonic motion only, a time integration would drop it."""
    mu_h = getattr(params, "hysteretic_damping", 0.0)
    if mu_h:
        raise ValueError(
            f"{where}: hysteretic damping (mu_h = {mu_h:g}) has no time-domain meaning: "
            "EI (1 + i mu_h sgn(omega)) acts on harmonic motion only; use it in the linear "
            "stability problem (compute_spectrum, find_critical_velocity, map_stability) or set "
            "hysteretic_damping = 0"
        )


def acceleration(model: PipeModel, q: np.ndarray, qdot: np.ndarray, v_dot: float = 0.0):
    """q'' from Eq. (20): solve ``M(q) q'' = -R(q, q', 0)``; shape (n,)."""
    M = model.mass_matrix(q)
    r = model.residual(q, qdot, None, v_dot)
    return -sla.cho_solve(sla.cho_factor(M), r)


class _PerStageVelocityDerivative:
    """dR/dv = 2 v follower(v=1) + coriolis(v=1) of the stages one by one (no kernels)."""

    def __init__(self, model: PipeModel) -> None:
        self.v = model.params.v
        self.unit = model.with_params(replace(model.params, v=1.0))

    def __call__(self, Q: np.ndarray, P: np.ndarray, Acc: np.ndarray) -> np.ndarray:
        out = np.empty(Q.shape)
        for i in range(Q.shape[0]):
            fl = self.unit.fields(Q[i], P[i])
            out[i] = 2.0 * self.v * self.unit.follower(fl) + self.unit.coriolis(fl)
        return out


class ModelDynamics:
    """The integrator's problem of a model, steady or unsteady flow: a subclass sets ``model``
    and ``flow`` and implements :meth:`solve_acceleration`."""

    model: PipeModel
    flow: Callable[[float], tuple[float, float]] | None

    def model_at(self, t: float):
        """The model with the flow velocity at tau = t, and v_dot there."""
        if self.flow is None:
            return self.model, 0.0
        v, v_dot = self.flow(t)
        return self.model.with_params(self.model.params.with_flow(v)), float(v_dot)

    def residual(self, t: float, q, qdot, qddot) -> np.ndarray:
        """R(t, q, q', q''), shape (n,) (rule 2)."""
        m, vd = self.model_at(t)
        return m.residual(q, qdot, qddot, vd)

    def jacobians(self, t: float, q, qdot, qddot):
        """(dR/dq, dR/dq', dR/dq''), dense (n, n) each (rule 3)."""
        m, vd = self.model_at(t)
        return m.jacobians(q, qdot, qddot, vd)

    def acceleration(self, t: float, q, qdot) -> np.ndarray:
        """q'' with R(t, q, q', q'') = 0 (rule 4)."""
        m, vd = self.model_at(t)
        return self.solve_acceleration(m, q, qdot, vd)

    def solve_acceleration(self, model, q, qdot, v_dot: float) -> np.ndarray:
        """q'' of ``model`` at (q, q') with the flow acceleration v_dot."""
        raise NotImplementedError


class PipeDynamics(ModelDynamics):
    """Eq. (20) of a pipe model as an implicit second-order problem.

    ``model`` supplies ``residual``, ``jacobians`` and ``mass_matrix``; ``flow`` (tau -> (v,
    v_dot), rule 9) replaces the steady ``model.params.v``.  The optional members of rules 6-8
    (``stage_residuals``, ``stage_jacobians``: the batched
    :class:`~fempipe.model.plane.batched.StageKernels`; ``prefers_batched_stage_jacobians`` up to
    :data:`BATCHED_STAGES_MAX`; ``parameter_derivative``) exist for steady flow only.
    """

    def __init__(
        self, model: PipeModel, flow: Callable[[float], tuple[float, float]] | None = None
    ) -> None:
        refuse_hysteretic(model.params, "time integration (Radau)")
        self.model = model
        self.flow = flow
        self.n = model.n
        self.autonomous = flow is None
        kernels = StageKernels.for_model(model) if flow is None else None
        self.stage_residuals = kernels.residual if kernels is not None else None
        self.stage_jacobians = kernels.jacobians if kernels is not None else None
        self.prefers_batched_stage_jacobians = (
            kernels is not None and model.quad.n_q * model.n <= BATCHED_STAGES_MAX
        )
        self.parameter_derivative = None
        if flow is None:
            self.parameter_derivative = (
                kernels.velocity_derivative
                if kernels is not None
                else _PerStageVelocityDerivative(model)
            )

    def solve_acceleration(self, model, q, qdot, v_dot: float) -> np.ndarray:
        """:func:`acceleration`."""
        return acceleration(model, q, qdot, v_dot)

    def describe(self) -> str:
        """The parameter an error message names: the flow velocity v (rule 14)."""
        return f"v = {self.model.params.v:.6g}"

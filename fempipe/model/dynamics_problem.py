"""The pipe's equations of motion as the integrator's problem: Eq. (20) in residual form.

:class:`PipeDynamics` implements the contract
:class:`fempipe.solvers.radau.contract.ImplicitSecondOrderProblem` (its
docstring numbers the rules cited here) for a
:class:`~fempipe.model.operators.PipeModel` with a steady or an unsteady
flow: the residual and Jacobians of the model, the acceleration q'' of
Eq. (20), and, for steady flow, the batched stage kernels of
:mod:`fempipe.model.batched` and dR/dv.  :func:`refuse_hysteretic` is the
refusal every time-domain entry point makes first.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np
import scipy.linalg as sla

from .batched import StageKernels
from .operators import PipeModel

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
    """Raise ValueError if ``params`` has hysteretic damping: it has no time-domain meaning.

    The loss factor mu_h multiplies EI by 1 + i mu_h sgn(omega), which is
    defined for harmonic motion only (the linear stability problem,
    :func:`fempipe.analyses.stability.hysteretic.hysteretic_roots`); a time integration
    would silently drop it.  Every time-domain entry point (:class:`PipeDynamics`
    and so :class:`fempipe.solvers.radau.Radau` and
    :func:`fempipe.analyses.dynamics.simulate`, the shooting and attractor
    search of :mod:`fempipe.analyses.limit_cycle`, the sweeps of
    :mod:`fempipe.analyses.bifurcation`) calls this first.

    Parameters
    ----------
    params : Params
    where : str
        The refusing function, named in the message.

    Raises
    ------
    ValueError
        If ``params.hysteretic_damping > 0``.
    """
    mu_h = getattr(params, "hysteretic_damping", 0.0)
    if mu_h:
        raise ValueError(
            f"{where}: hysteretic damping (mu_h = {mu_h:g}) has no time-domain meaning: "
            "EI (1 + i mu_h sgn(omega)) acts on harmonic motion only; use it in the linear "
            "stability problem (spectrum, critical_velocity, stability_map) or set "
            "hysteretic_damping = 0"
        )


def acceleration(model: PipeModel, q: np.ndarray, qdot: np.ndarray, v_dot: float = 0.0):
    """q'' from Eq. (20): solve ``M(q) q'' = -R(q, q', 0)`` (R is linear in q'').

    Returns
    -------
    ndarray, shape (n,)
    """
    M = model.mass_matrix(q)
    r = model.residual(q, qdot, None, v_dot)
    return -sla.cho_solve(sla.cho_factor(M), r)


class _PerStageVelocityDerivative:
    """dR/dv of the stages one by one, for the models :class:`StageKernels` does not know.

    dR/dv = 2 v follower_1 + coriolis_1 with the terms at v = 1 (exact: R is
    quadratic in v).
    """

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
    """What the integrator's problem of a model with a steady or unsteady flow shares.

    A subclass sets ``model`` and ``flow`` and says how to solve R = 0 for q''
    (:meth:`solve_acceleration`); the model supplies ``residual(q, q', q'',
    v_dot)``, ``jacobians(q, q', q'', v_dot)`` and ``with_params``.
    """

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
    """Eq. (20) of a pipe model as an implicit second-order problem (the integrator's contract).

    Parameters
    ----------
    model : PipeModel
        Supplies ``residual``, ``jacobians`` and ``mass_matrix``.
    flow : PulsatingFlow or callable tau -> (v, v_dot), optional
        Unsteady flow: ``model.params.v`` is replaced by ``flow(tau)`` and the
        flow-acceleration term gets v_dot (rule 9).  Default: the steady
        ``model.params.v`` (an autonomous problem, rule 5).

    Attributes
    ----------
    n : int
        Number of degrees of freedom.
    autonomous : bool
        ``flow is None``.
    stage_residuals, stage_jacobians : callable or None
        The batched kernels (:class:`~fempipe.model.batched.StageKernels`) of a
        plain pipe with steady flow, else None (rule 6).
    prefers_batched_stage_jacobians : bool
        The kernels exist and n_q n <= :data:`BATCHED_STAGES_MAX` (rule 7).
    parameter_derivative : callable or None
        ``(Q, P, A) -> dR/dv`` of the stages, steady flow only (rule 8).

    Raises
    ------
    ValueError
        If the model has hysteretic damping (:func:`refuse_hysteretic`, rule 11).
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

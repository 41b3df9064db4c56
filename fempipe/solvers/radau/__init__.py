"""The variable-step Radau IIA integrator of the equations of motion, in residual form.

Integrates R(q, q', q''; v(tau), v'(tau)) = 0 (Eq. (20)) with the analytic Jacobians, given
through a written contract (:mod:`~fempipe.solvers.radau.contract`; the pipe's side is
:class:`fempipe.model.dynamics_problem.PipeDynamics`): 3-stage, L-stable, order 5, with
RADAU5's Newton iteration, error estimate and step-size controller.  Modules: ``contract``,
``integrator`` (:class:`Radau`), ``collocation`` (the dense output), ``tableau``, ``lapack``.

Derivation: docs/theory/numerics.md, "Time integration".
"""

from .collocation import NODES
from .contract import ImplicitSecondOrderProblem
from .integrator import IntegrationError, Radau, Stats, StepRecord, predict_factor
from .tableau import A2, MU_REAL, A, C, E

__all__ = [
    "A",
    "A2",
    "C",
    "E",
    "MU_REAL",
    "NODES",
    "ImplicitSecondOrderProblem",
    "IntegrationError",
    "Radau",
    "StepRecord",
    "Stats",
    "predict_factor",
]

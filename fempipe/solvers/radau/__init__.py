"""The variable-step Radau IIA integrator of the equations of motion, in residual form.

The discrete equations of motion are the weak form of Eq. (20),
R(q, q', q''; v(tau), v'(tau)) = M(q) q'' + ... = 0, with the analytic Jacobians
``(dR/dq, dR/dq', M)`` of :meth:`fempipe.model.operators.PipeModel.jacobians`, given to the
integrator through a written contract (:mod:`~fempipe.solvers.radau.contract`; the pipe's
side is :class:`fempipe.model.dynamics_problem.PipeDynamics`).  The 3-stage Radau IIA
collocation method is L-stable and of order 5, which the stiff finite-element system needs;
its stage equations are solved for the stage accelerations, with RADAU5's Newton iteration,
error estimate and step-size controller.  :mod:`fempipe.analyses.dynamics` drives it.

Modules: :mod:`~fempipe.solvers.radau.contract` (the problem's protocol and the
integrator's guarantees, numbered rules); :mod:`~fempipe.solvers.radau.integrator`
(:class:`Radau`, :class:`~fempipe.solvers.radau.integrator.StepRecord`,
:class:`IntegrationError`); :mod:`~fempipe.solvers.radau.collocation` (the collocation
polynomial of a step, the one dense output); :mod:`~fempipe.solvers.radau.tableau` and
:mod:`~fempipe.solvers.radau.lapack` (the tableau with RADAU5's constants; LU through LAPACK).

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

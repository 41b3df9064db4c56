"""What the integrator asks of a problem, and what it guarantees: the written contract.

:class:`~fempipe.solvers.radau.Radau` integrates any :class:`ImplicitSecondOrderProblem`
(the pipe's: :class:`fempipe.model.dynamics_problem.PipeDynamics`).  The rules, numbered as
the code and the tests cite them; in full in docs/development.md, "The integrator's contract":

1. Equation: R(t, q, q', q'') = 0, affine in q'', M = dR/dq'' symmetric positive definite.
2. Residual: ``residual(t, q, qdot, qddot)`` is pure; a non-finite value fails the iteration.
3. Jacobians: ``jacobians(t, q, qdot, qddot) -> (K, D, M)``, dense, consistent with rule 2.
4. Acceleration: ``acceleration(t, q, qdot)`` solves R = 0 for q''.
5. Autonomy: ``autonomous``; only an autonomous problem may provide rules 6-8.
6. Batched stages (optional): ``stage_residuals``, ``stage_jacobians``, equal to rules 2, 3.
7. Batching and structure (optional): ``prefers_batched_stage_jacobians``, ``decoupled_blocks``.
8. Parameter derivative (optional): ``parameter_derivative``, dR/dp of the stages.
9. Time-dependent parameters: the problem evaluates its own at t.
10. No other access: the integrator uses only these members and ``describe()``; no model.
11. Validation belongs to the problem: refusals happen when it is built.
12. Error control: RADAU5's embedded estimate, Gustafsson's controller, halving on failure.
13. Outputs: ``t, q, qdot, qddot``, ``last``, ``dense(t)``, the sensitivities, ``stats``.
14. Failures: :class:`~fempipe.solvers.radau.IntegrationError`, naming ``describe()``.
15. Reproducibility: bit-reproducible steps and outputs, under one BLAS thread.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Protocol, runtime_checkable

import numpy as np

__all__ = ["ImplicitSecondOrderProblem"]

StageFunction = Callable[[np.ndarray, np.ndarray, np.ndarray], np.ndarray]


@runtime_checkable
class ImplicitSecondOrderProblem(Protocol):
    """R(t, q, q', q'') = 0: the problem :class:`~fempipe.solvers.radau.Radau` integrates.

    Members by the module's rules: ``n`` (1), ``autonomous`` (5), ``stage_residuals`` and
    ``stage_jacobians`` (6, ``(Q, P, A)`` of shape (S, n)), ``prefers_batched_stage_jacobians``
    and ``decoupled_blocks`` (7), ``parameter_derivative`` (8).
    """

    n: int
    autonomous: bool
    stage_residuals: StageFunction | None
    stage_jacobians: Callable[..., tuple[np.ndarray, np.ndarray, np.ndarray]] | None
    prefers_batched_stage_jacobians: bool
    parameter_derivative: StageFunction | None

    def residual(self, t: float, q: np.ndarray, qdot: np.ndarray, qddot: np.ndarray) -> np.ndarray:
        """R(t, q, q', q''), shape (n,) (rule 2)."""
        ...

    def jacobians(
        self, t: float, q: np.ndarray, qdot: np.ndarray, qddot: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """(dR/dq, dR/dq', dR/dq''), dense (n, n) each (rule 3)."""
        ...

    def acceleration(self, t: float, q: np.ndarray, qdot: np.ndarray) -> np.ndarray:
        """q'' solving R = 0, shape (n,) (rule 4)."""
        ...

    def describe(self) -> str:
        """A short description for error messages, e.g. ``"v = 7"`` (rule 14)."""
        ...

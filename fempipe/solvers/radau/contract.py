"""What the integrator asks of a problem, and what it guarantees: the written contract.

:class:`~fempipe.solvers.radau.Radau` integrates an implicit second-order
system given as an object that satisfies :class:`ImplicitSecondOrderProblem`.
The pipe's implementation is :class:`fempipe.model.dynamics_problem.PipeDynamics`
(in the model layer; the integrator imports nothing from it).

The problem
-----------
1. **Equation.** The problem is R(t, q, q', q'') = 0 with q in R^n,
   ``n = problem.n``.  R is affine in q'', and M = dR/dq'' is symmetric
   positive definite at every state the integrator visits.
2. **Residual.** ``problem.residual(t, q, qdot, qddot) -> ndarray (n,)`` is a
   pure function of its arguments: it does not modify them and returns a
   new array.  A non-finite value is allowed; the integrator treats it as a
   failed Newton iteration (the step is then halved).
3. **Jacobians.** ``problem.jacobians(t, q, qdot, qddot) -> (K, D, M)``
   returns dense (n, n) arrays dR/dq, dR/dq', dR/dq'', consistent with
   rule 2 to round-off.  They are evaluated at the start of a step and kept
   (frozen) while Newton converges fast enough.
4. **Acceleration.** ``problem.acceleration(t, q, qdot) -> qddot``, shape (n,),
   solves R = 0 for q''.  It is called at the initial state and to refine a
   rejected step's error estimate.
5. **Autonomy.** ``problem.autonomous`` is True when R does not depend on t.
   Only autonomous problems may provide rules 6-8 (the members are None
   otherwise); the integrator ignores them for a non-autonomous problem.
6. **Batched stages (optional).** ``problem.stage_residuals(Q, P, A) -> (S, n)``
   and ``problem.stage_jacobians(Q, P, A) -> ((S, n, n),) * 3`` take S states
   as rows of (S, n) arrays, or are None.  If present they equal rules 2 and
   3 applied row by row, to round-off, and the integrator uses them whenever
   present (every Newton iteration's three stage residuals, and every
   Jacobian, with S = 1 for one state): the choice, and so the floating-point
   result, is the problem's.
7. **Batching size and structure (optional).**
   ``problem.prefers_batched_stage_jacobians`` (bool) says whether the three
   stage Jacobians of the sensitivity are one call of ``stage_jacobians`` with
   S = 3 (True) or three calls.  ``problem.decoupled_blocks`` (absent or None,
   or index arrays partitioning range(n)) names groups of unknowns that
   decouple at some states (the 3-D pipe's in-plane and out-of-plane unknowns
   at planar states): where the Jacobians have exactly zero entries between
   the groups, the integrator factors the Newton matrices and propagates the
   sensitivity group by group (the same result to round-off, for sum n_b^3
   instead of n^3 operations).
8. **Parameter derivative (optional).** ``problem.parameter_derivative(Q, P, A)
   -> (S, n)`` is dR/dp of the states for the problem's one continuation
   parameter p (the pipe: the flow velocity v), or None.  It is needed only
   for ``velocity_sensitivity``.
9. **Time-dependent parameters.** A non-autonomous problem evaluates its own
   parameters at t; the integrator passes only t.
10. **No other access.** The integrator uses only the members named in
    rules 1-9 and ``problem.describe()`` (rule 14).  It reads no
    discretization, quadrature or parameter attribute, never modifies the
    problem, and imports nothing from :mod:`fempipe.model`.
11. **Validation belongs to the problem.** Refusals (the pipe's hysteretic
    damping, which has no time-domain meaning) happen when the problem is
    built, not in the integrator.

What the integrator guarantees
------------------------------
12. **Error control and step acceptance.** With error control (no
    ``h_fixed``), a step is accepted when RADAU5's embedded error estimate of
    (q, q'), in the RMS norm scaled by ``atol + rtol |y|``, is at most 1; a
    rejected step is retried with a step from the predictive (Gustafsson)
    controller, and a step whose Newton iteration does not converge (or gives
    a non-finite residual) is halved.  With ``h_fixed`` every step has that
    size and no error is estimated.
13. **Outputs.** After each accepted step the integrator exposes ``t, q, qdot,
    qddot`` (:meth:`~fempipe.solvers.radau.Radau.steps` yields copies),
    ``last``, a :class:`~fempipe.solvers.radau.integrator.StepRecord`
    ``(t_old, h, q_old, p_old, Q, P, A)`` of the step, ``dense(t)``, the
    collocation polynomial of ``last`` (:mod:`~fempipe.solvers.radau.collocation`,
    its one dense output), ``sensitivity_matrix`` (d(q, q')/d(q0, q0') of the
    discrete flow map), ``velocity_sensitivity`` (d(q, q')/dp at fixed initial
    state, rule 8) and the counters ``stats``.
14. **Failures.** :class:`~fempipe.solvers.radau.IntegrationError` ``(message,
    t, h)`` when the step falls below round-off (the message names the
    problem by ``problem.describe()``) or a fixed step does not converge.  It
    is picklable.
15. **Reproducibility.** For the same problem, options and initial state, the
    step sequence and all outputs are bit-reproducible;
    :meth:`~fempipe.solvers.radau.Radau.steps` runs under one BLAS thread.
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

    The rules are numbered in the module docstring.

    Attributes
    ----------
    n : int
        Number of unknowns (rule 1).
    autonomous : bool
        R does not depend on t (rule 5).
    stage_residuals : callable or None
        ``(Q, P, A) -> (S, n)`` (rule 6).
    stage_jacobians : callable or None
        ``(Q, P, A) -> (dR/dq, dR/dq', dR/dq'')``, each (S, n, n) (rule 6).
    prefers_batched_stage_jacobians : bool
        Rule 7.
    parameter_derivative : callable or None
        ``(Q, P, A) -> dR/dp``, (S, n) (rule 8).
    decoupled_blocks : sequence of index arrays or None, optional
        Rule 7.
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

"""The variable-step Radau IIA integrator of the equations of motion, in residual form.

The discrete equations of motion are the weak form of Eq. (20),

    R(q, q', q''; v(tau), v'(tau)) = M(q) q'' + (stiffness, gravity, follower,
                                     Kelvin-Voigt, centripetal, Coriolis,
                                     flow-acceleration terms) = 0,

with the analytic Jacobians ``(dR/dq, dR/dq', M)`` of
:meth:`fempipe.model.operators.PipeModel.jacobians`, given to the integrator
through a written contract (:mod:`~fempipe.solvers.radau.contract`; the pipe's
side is :class:`fempipe.model.dynamics_problem.PipeDynamics`).
:mod:`fempipe.analyses.dynamics` drives this integrator (trajectories,
unsteady flow, energy).

Why this integrator
-------------------
The finite-element system is stiff: the bending frequencies grow like h^-2
and the Kelvin--Voigt damping rates like mu h^-4 (about 2e6 for P3:16 at
mu = 5e-3).  An explicit method would need steps of that inverse size; an
A-stable method that is not L-stable (trapezoid, Gauss) lets the stiff
components ring.  The 3-stage Radau IIA collocation method is L-stable and of
order 5, and its stage equations can be written directly in residual form on
the second-order system, with the stage accelerations as unknowns:

    P_i = p0 + h sum_j a_ij A_j,   Q_i = q0 + c_i h p0 + h^2 sum_j (a^2)_ij A_j,
    R(t0 + c_i h, Q_i, P_i, A_i) = 0,   i = 1, 2, 3.

Newton's method with the Jacobian frozen at the start of the step decouples,
after diagonalising the Butcher matrix a = T diag(g_k) T^-1, into one real and
one complex n x n system ``M + h g_k D + h^2 g_k^2 K`` (K = dR/dq, D = dR/dq'):
no inverse mass matrix is ever formed, and the factorisations are reused over
Newton iterations and over steps while the step size is unchanged (Hairer &
Wanner's RADAU5 strategy, also that of ``scipy.integrate.Radau``).  The error
estimate and the step-size controller (predictive, Gustafsson) are RADAU5's,
transcribed to the second-order form (see ``Radau._error``).

Measured (``validation/dynamics_acceptance.py``; alpha = 0, v = 10, static
state + 0.01 rad in mode 1, tau in [0, 2], rtol = 1e-6): 778, 709, 692, 693
steps on P3 with 8, 16, 32, 64 elements (the stiffest rates grow 4096x) and
871 on the 4-mode Galerkin model.  The step is set by the accuracy of the
physical oscillation; the stiff components are damped by L-stability, not
resolved.  Without Kelvin-Voigt damping (mu = 0) the h^-2 bending modes are
undamped, the error control must follow them and the step count does grow
with the mesh: use mu > 0 (as the paper) or the modal model there.

Modules
-------
:mod:`~fempipe.solvers.radau.contract`
    The problem's protocol and the integrator's guarantees (numbered rules).
:mod:`~fempipe.solvers.radau.integrator`
    :class:`Radau`, :class:`~fempipe.solvers.radau.integrator.StepRecord`,
    :class:`IntegrationError`.
:mod:`~fempipe.solvers.radau.collocation`
    The collocation polynomial of a step (the one dense output).
:mod:`~fempipe.solvers.radau.tableau`, :mod:`~fempipe.solvers.radau.lapack`
    The Radau IIA tableau with RADAU5's constants; LU through LAPACK.
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

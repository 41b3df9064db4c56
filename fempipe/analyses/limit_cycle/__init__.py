"""Attractors of Eq. (20): equilibria, periodic orbits (limit cycles), non-periodic motion.

The post-flutter motion of the paper (Section 5, Figs. 7-12) is a limit cycle.
This module finds it in three stages:

1. **Integration past the transient** with :class:`fempipe.solvers.radau.Radau`,
   recording a Poincare section of the tip motion: the upward crossings of
   the tip's lateral displacement eta(1) through a level (the static value,
   about which the Hopf cycle is born).  The full state at each crossing is
   kept.
2. **Recurrence**: the smallest n for which the section points x_k and
   x_{k-n} agree gives a period-n candidate (n distinct points on the
   section: period-1, period-2, ...).  Equilibria are recognized when the
   state comes close to a linearly stable static state (the criterion of
   :func:`fempipe.analyses.stability.linearly_stable`, as for ``spectrum`` and
   ``critical``) and keeps approaching it; motion without recurrence until ``t_max`` is reported as non-periodic.
   When the returns approach each other fast (the distance falls more than
   2x per return, as the 0.15 per period of the paper's cycle at v = 10), the
   integration goes on until they are within ``start_tol`` (1e-3): a period
   of plain integration costs about a third of a shooting iteration, and
   Newton's method from there needs one step and the check.  Near a Hopf
   point, where the returns approach slowly, the shooting starts at
   ``recurrence_tol`` (2e-2).
3. **Shooting**: Newton's method on ``phi_T(x0) - x0 = 0`` with the phase
   condition ``eta_tip(x0) = level``, unknowns (x0, T).  The Jacobian uses the
   monodromy matrix, the exact derivative of the discrete Radau flow map
   (accumulated step by step from the stage Jacobians, see
   :meth:`fempipe.solvers.radau.Radau._accumulate_sensitivity`), so Newton converges
   quadratically and the eigenvalues of the matrix are the Floquet multipliers
   to the integration accuracy.  One multiplier is 1 (the phase along the
   orbit); the cycle is stable when all others are inside the unit circle.
   The converged iterate (residual below the tolerance) is always one whose
   monodromy was integrated; one more Newton step with that matrix polishes
   it to O(residual^2), checked by a plain period, so the reported orbit is
   the cycle to the integration accuracy and the multipliers are those of a
   state one converged step from it.  The tip extrema are taken on
   the quintic Hermite interpolant through (q, q', q'') at the steps
   (:func:`~fempipe.analyses.limit_cycle.tips.tip_extrema` on a
   :class:`~fempipe.analyses.limit_cycle.tips.QuinticOrbit`), as accurate as
   the steps themselves.

Accuracy and cost (P3:16, the paper's beta, gamma, mu, alpha = 0, v = 10;
``fempipe.bench.dynamics``): with the default ``shoot_rtol`` 1e-5 the period
is within 4e-9 and the tip extrema within 2e-7 (relative) of a cycle shot
with ``shoot_rtol`` 1e-10; at v = 7, 12 and at alpha = pi/2, v = 10 within
5e-8 and 5e-7.  The error control of Radau IIA bounds an embedded
lower-order estimate and is conservative: rtol 1e-5 gives 55 steps per
period, rtol 1e-7 172 for errors 100x below what is needed.

The package's modules: :mod:`~fempipe.analyses.limit_cycle.results` (what
is returned), :mod:`~fempipe.analyses.limit_cycle.tips` (tip coordinates and
their extrema over a period), :mod:`~fempipe.analyses.limit_cycle.shooting`
(:func:`shoot`) and :mod:`~fempipe.analyses.limit_cycle.attractor`
(:func:`find_attractor`).
"""

from .attractor import MAX_WAITS, find_attractor, recurrence
from .results import Attractor, LimitCycle, ShootingError, state_distance
from .shooting import shoot
from .tips import TIP_KEYS, tip_coordinates, tip_extrema

__all__ = [
    "TIP_KEYS",
    "MAX_WAITS",
    "LimitCycle",
    "Attractor",
    "ShootingError",
    "tip_coordinates",
    "tip_extrema",
    "state_distance",
    "recurrence",
    "shoot",
    "find_attractor",
]

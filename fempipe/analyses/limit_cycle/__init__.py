"""Attractors of Eq. (20): equilibria, periodic orbits (limit cycles), non-periodic motion.

The post-flutter motion of the paper (Section 5, Figs. 7-12) is a limit cycle.
:func:`find_attractor` finds the attractor reached from an initial state in three stages:
integration past the transient with a Poincare section of the tip motion, recognition of an
equilibrium or of a recurrence of the section, and :func:`shoot`: Newton's method on the
period map with the phase condition, whose Jacobian is the monodromy matrix of the discrete
Radau flow, so that its eigenvalues are the Floquet multipliers.  The tip extrema over a
period are taken on the quintic Hermite interpolant through (q, q', q'') at the steps,
as accurate as the steps themselves.

Modules: :mod:`~fempipe.analyses.limit_cycle.results` (what is returned),
:mod:`~fempipe.analyses.limit_cycle.tips` (tip coordinates and their extrema over a period),
:mod:`~fempipe.analyses.limit_cycle.shooting` (:func:`shoot`) and
:mod:`~fempipe.analyses.limit_cycle.attractor` (:func:`find_attractor`).

The stages, the shooting and the measured accuracy: docs/theory/numerics.md, "Attractors and
limit cycles".
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

"""Attractors of Eq. (20): equilibria, periodic orbits (limit cycles), non-periodic motion.

The post-flutter motion of the paper (Section 5, Figs. 7-12) is a limit cycle.
:func:`find_attractor` integrates past the transient with a Poincare section of the tip
motion, recognizes an equilibrium or a recurrence of the section, and calls :func:`shoot`:
Newton's method on the period map of a planar or 3-D dynamics problem, whose Jacobian is the
monodromy matrix of the discrete Radau flow (its eigenvalues are the Floquet multipliers).
:mod:`~fempipe.analyses.limit_cycle.tips` takes the tip extrema over a period.

The stages, the shooting and the measured accuracy: docs/theory/numerics.md, "Attractors and
limit cycles".
"""

from .attractor import MAX_WAITS, find_attractor, recurrence
from .results import Attractor, LimitCycle, ShootingError, largest_nontrivial, state_distance
from .shooting import shoot
from .tips import TIP_KEYS, TIP_KEYS_3D, section_value, tip_extrema

__all__ = [
    "TIP_KEYS",
    "TIP_KEYS_3D",
    "MAX_WAITS",
    "LimitCycle",
    "Attractor",
    "ShootingError",
    "largest_nontrivial",
    "section_value",
    "tip_extrema",
    "state_distance",
    "recurrence",
    "shoot",
    "find_attractor",
]

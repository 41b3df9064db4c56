"""Attractors of Eq. (20): equilibria, periodic orbits (limit cycles), non-periodic motion.

:func:`find_attractor` integrates past the transient with a Poincare section of the tip
motion and hands a recurrence to :func:`shoot` (Newton on the period map, the monodromy of
the discrete Radau flow its Jacobian).  Details: docs/theory/numerics.md, "Attractors and
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

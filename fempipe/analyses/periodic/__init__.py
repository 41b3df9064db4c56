"""Branches of periodic orbits of Eq. (20) by pseudo-arclength continuation in v.

From every Hopf point (a flutter event) the family of orbits is followed in v, stable and
unstable alike, with Floquet multipliers and special points (folds, period doublings,
Neimark-Sacker points); ``points`` holds every diagram's store and driver.

Derivation: docs/theory/numerics.md, "Branches of periodic orbits".
"""

from .branch import (
    GRID_RTOL_FACTOR,
    MAX_ANGLE,
    MAX_PERIOD_RATIO,
    MIN_DV_DS,
    CycleBranchPolicy,
    continue_cycles,
)
from .diagram import N_MULTIPLIERS, CycleDiagram, compute_cycle_diagram, cycle_point_dict
from .hopf import find_hopf_points, static_points
from .problem import MONODROMY_AT_ORBIT, MONODROMY_NEAR, CycleCorrector, OrbitProblem
from .results import (
    MIN_SWING,
    CycleBranch,
    CycleContinuationError,
    CyclePoint,
    CycleSpecialPoint,
    HopfPoint,
)
from .special import NEAR_ONE, special_points

__all__ = [
    "HopfPoint",
    "CyclePoint",
    "CycleSpecialPoint",
    "CycleBranch",
    "CycleContinuationError",
    "find_hopf_points",
    "continue_cycles",
    "static_points",
    "compute_cycle_diagram",
    "CycleDiagram",
    "cycle_point_dict",
    "special_points",
    "CycleCorrector",
    "CycleBranchPolicy",
    "OrbitProblem",
    "GRID_RTOL_FACTOR",
    "MAX_ANGLE",
    "MAX_PERIOD_RATIO",
    "MIN_DV_DS",
    "MIN_SWING",
    "MONODROMY_AT_ORBIT",
    "MONODROMY_NEAR",
    "N_MULTIPLIERS",
    "NEAR_ONE",
]

"""Branches of periodic orbits of Eq. (20) by pseudo-arclength continuation in v.

A flutter event of the static branch (:mod:`fempipe.analyses.stability`) is a Hopf point,
where a family of periodic orbits is born.  This package follows that family in v, stable and
unstable orbits alike, which a sweep of attractors (:mod:`fempipe.analyses.bifurcation`)
cannot see: single shooting with a phase condition and Keller's pseudo-arclength condition in
a weighted metric (or a fixed v, to land on every requested value), the exact monodromy and
d phi_T/dv of the discrete Radau flow, and the Floquet multipliers, with folds of cycles,
period doublings and Neimark-Sacker points located between points.

Modules: :mod:`~fempipe.analyses.periodic.results` (Hopf points, orbits, branches),
:mod:`~fempipe.analyses.periodic.hopf` (the Hopf points and the equilibria of the static
branch), :mod:`~fempipe.analyses.periodic.problem` (the shooting problem and its
corrector), :mod:`~fempipe.analyses.periodic.branch` (the continuation of one branch,
:func:`continue_cycles`, on the engine of :mod:`fempipe.solvers.continuation`),
:mod:`~fempipe.analyses.periodic.special` (the special points) and
:mod:`~fempipe.analyses.periodic.diagram` (the diagram over alpha, :func:`compute_cycle_diagram`).

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

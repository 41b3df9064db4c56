"""Pseudo-arclength continuation: one engine for every branch of the package.

:mod:`~fempipe.solvers.continuation.protocol` (what the engine asks of a problem and its
policy), :mod:`~fempipe.solvers.continuation.engine` (the loop, :func:`continue_curve`),
:mod:`~fempipe.solvers.continuation.keller` (Keller's method, :class:`KellerPolicy`) and
:mod:`~fempipe.solvers.continuation.linalg` (a solve with the determinant's sign).  Users:
:func:`fempipe.analyses.statics.continue_static`, :func:`fempipe.analyses.periodic.continue_cycles`.
"""

from .engine import continue_curve
from .keller import (
    CurveEvent,
    CurvePoint,
    KellerPolicy,
    KellerStep,
    correct,
    interpolate_zero,
    locate,
    normalize,
    tangent,
)
from .linalg import permutation_sign, solve_with_determinant
from .protocol import (
    BorderedSolution,
    ContinuationError,
    ContinuationPolicy,
    ContinuationProblem,
    CorrectorError,
    SharpTurnError,
)

__all__ = [
    "BorderedSolution",
    "ContinuationError",
    "ContinuationPolicy",
    "ContinuationProblem",
    "CorrectorError",
    "CurveEvent",
    "CurvePoint",
    "KellerPolicy",
    "KellerStep",
    "SharpTurnError",
    "continue_curve",
    "correct",
    "interpolate_zero",
    "locate",
    "normalize",
    "permutation_sign",
    "solve_with_determinant",
    "tangent",
]

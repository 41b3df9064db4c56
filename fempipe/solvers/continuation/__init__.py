"""Pseudo-arclength continuation: one engine for every branch of the package.

* :mod:`~fempipe.solvers.continuation.protocol` -- what the engine asks of a
  problem (:class:`ContinuationProblem`: the residual, its derivatives, the
  bordered solve, the inner product) and of a problem's policy
  (:class:`ContinuationPolicy`: predictor, corrector, acceptance, step
  control, landing, detection of special points);
* :mod:`~fempipe.solvers.continuation.engine` -- the loop
  (:func:`continue_curve`);
* :mod:`~fempipe.solvers.continuation.keller` -- Keller's method with the
  exact tangent (:class:`KellerPolicy`), the static branches' policy;
* :mod:`~fempipe.solvers.continuation.linalg` -- a linear solve that also
  gives the sign of the determinant (the test function of branch points).

The static branches of the pipe (in v, gamma, alpha) are
:func:`fempipe.analyses.statics.continue_static`; the branches of periodic orbits
:func:`fempipe.analyses.periodic.continue_cycles`.
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

"""Static large deformation (Eq. (31a)): the gravity-loaded state and paths in a parameter.

Three layers, each usable on its own:

* :mod:`~fempipe.analyses.statics.equilibrium` -- one equilibrium by Newton's method
  (:func:`solve_static`, :class:`NewtonError`, :class:`StaticSolution`; the iteration is
  :func:`fempipe.solvers.newton.newton`);
* :mod:`~fempipe.analyses.statics.branches` -- pseudo-arclength continuation with fold and
  bifurcation detection and branch switching (:func:`continue_static`, :func:`switch_branch`,
  :class:`Branch`), on the problem :class:`~fempipe.analyses.statics.family.StaticFamily`
  (the pipe models along v, gamma or alpha) and the engine of
  :mod:`fempipe.solvers.continuation`;
* :mod:`~fempipe.analyses.statics.loading` -- the state a pipe reaches when gravity is
  switched on (:func:`solve_sagged`) and the states along a list of parameter values
  (:func:`solve_path`), what ``fempipe static`` computes.

Every solver uses only the model's static residual, Jacobian, parameter derivative, terms and
gravity load and the discretization's Gram matrix, so it runs unchanged on finite elements
and on sine modes.  The names of the first two layers are importable from here too.
"""

from .branches import Branch, BranchPoint, SpecialPoint, continue_static, switch_branch
from .equilibrium import NewtonError, StaticSolution, solve_static
from .family import CONTINUATION_PARAMETERS, StaticFamily
from .loading import solve_path, solve_sagged

__all__ = [
    "NewtonError",
    "StaticSolution",
    "BranchPoint",
    "Branch",
    "SpecialPoint",
    "StaticFamily",
    "solve_static",
    "solve_path",
    "solve_sagged",
    "continue_static",
    "switch_branch",
    "CONTINUATION_PARAMETERS",
]

"""Static large deformation (Eq. (31a)): equilibria, branches and paths in a parameter.

One equilibrium by Newton's method (:func:`solve_static`, .equilibrium), branches by
pseudo-arclength continuation with folds, bifurcations and branch switching
(:func:`continue_static`, :func:`switch_branch`, .branches), the gravity-loaded state and
paths (:func:`solve_sagged`, :func:`solve_path`, .loading).  They use only the model's
static terms and the Gram matrix, so they run on finite elements and modes alike.
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

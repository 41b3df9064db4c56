"""fempipe: finite elements and modal Galerkin for the soft pipe conveying fluid.

The geometrically exact model of Chen, Hu, Dai & Wang (Appl. Math. Mech.
41(9) 1381-1400, 2020), Eq. (20), discretised by 1-D Lagrange finite
elements on a scikit-fem MeshLine or by the paper's sine modes.
"""

from .discretization import FiniteElement, Modal, parse_discretization
from .errors import ParamError, SolverError
from .kinematics import shape, tip_values
from .operators import PipeModel
from .params import Params, PipeSI
from .stability import critical_velocity, spectrum, stability_analysis
from .static import NewtonError, continuation, solve_path, solve_static, switch_branch

__version__ = "0.1.0"

__all__ = [
    "FiniteElement",
    "Modal",
    "NewtonError",
    "ParamError",
    "Params",
    "PipeModel",
    "PipeSI",
    "continuation",
    "critical_velocity",
    "parse_discretization",
    "shape",
    "solve_path",
    "solve_static",
    "SolverError",
    "spectrum",
    "stability_analysis",
    "switch_branch",
    "tip_values",
]

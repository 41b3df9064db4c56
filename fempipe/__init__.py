"""fempipe: finite elements and modal Galerkin for the soft pipe conveying fluid.

The geometrically exact model of Chen, Hu, Dai & Wang (Appl. Math. Mech. 41(9) 1381-1400,
2020), Eq. (20), discretized by 1-D Lagrange finite elements on a scikit-fem MeshLine or by
the paper's sine modes, and the pipe in three dimensions.  The public names, by what their
users do (the API reference groups them alike):

* the model: :class:`Params`, :class:`PipeSI`, :func:`parse_discretization`,
  :class:`PipeModel`, :func:`shape`, :func:`compute_tip`;
* statics (Eq. (31a)): :func:`solve_static`, :func:`solve_path`, :func:`continue_static`;
* linear stability (Eqs. (31b)-(33)): :func:`compute_spectrum`, :func:`find_critical_velocity`
  (in and out of the plane), :func:`map_stability`;
* dynamics: :func:`simulate`, :func:`find_attractor`, :func:`shoot`, :func:`continue_cycles`,
  :func:`compute_bifurcation_diagram`; in three dimensions :class:`PipeModel3D`,
  :func:`simulate_3d`, :func:`compute_out_of_plane_floquet`, :func:`find_whirl`;
* studies: :func:`run_study`, :func:`compare_values` and the error estimates.

They are loaded on first use (PEP 562), so ``import fempipe`` and the start of the ``fempipe``
command do not pay for numpy, scipy and scikit-fem until a computation needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from fempipe.core.version import __version__ as __version__  # re-exported

#: public name -> submodule that defines it, by the user's task
_LAZY: dict[str, str] = {
    # The model: parameters, discretizations, the pipe's residual, the centerline
    "Params": "model.params",
    "PipeSI": "model.params",
    "FiniteElement": "model.discretization",
    "Modal": "model.discretization",
    "parse_discretization": "model.discretization",
    "PipeModel": "model.plane.operators",
    "OutOfPlaneModel": "model.out_of_plane.model",
    "build_out_of_plane_model": "model.out_of_plane.model",
    "OutOfPlaneMotion": "model.out_of_plane.motion",
    "compute_shape": "model.kinematics",
    "compute_tip": "model.kinematics",
    "ParamError": "core.errors",
    "SolverError": "core.errors",
    # Statics: equilibria, paths and branches (Eq. (31a))
    "solve_static": "analyses.statics",
    "StaticSolution": "analyses.statics",
    "NewtonError": "analyses.statics",
    "solve_sagged": "analyses.statics",
    "solve_path": "analyses.statics",
    "continue_static": "analyses.statics",
    "switch_branch": "analyses.statics",
    "Branch": "analyses.statics",
    # Linear stability (Eqs. (31b)-(33)), in the plane and out of it
    "compute_spectrum": "analyses.stability",
    "trace_root_locus": "analyses.stability",
    "analyse_stability": "analyses.stability",
    "find_critical_velocity": "analyses.stability",
    "StabilityResult": "analyses.stability",
    "map_stability": "analyses.stability",
    "StabilityInPlanes": "analyses.stability",
    # Time integration (Eq. (20))
    "simulate": "analyses.dynamics",
    "simulate_steps": "analyses.dynamics",
    "make_initial_state": "analyses.dynamics",
    "Trajectory": "analyses.dynamics",
    "PulsatingFlow": "analyses.dynamics",
    "IntegrationError": "analyses.dynamics",
    # Limit cycles, attractors, their continuation and bifurcation diagrams
    "shoot": "analyses.limit_cycle",
    "find_attractor": "analyses.limit_cycle",
    "LimitCycle": "analyses.limit_cycle",
    "Attractor": "analyses.limit_cycle",
    "ShootingError": "analyses.limit_cycle",
    "find_hopf_points": "analyses.periodic",
    "continue_cycles": "analyses.periodic",
    "CycleBranch": "analyses.periodic",
    "compute_cycle_diagram": "analyses.periodic",
    "CycleDiagram": "analyses.periodic",
    "compute_bifurcation_diagram": "analyses.bifurcation",
    "compute_parametric_chart": "analyses.parametric",
    # The pipe in three dimensions
    "PipeModel3D": "model.three_d.model",
    "simulate_3d": "analyses.three_d",
    "Motion3D": "analyses.three_d",
    "compute_out_of_plane_floquet": "analyses.three_d",
    "classify_3d": "analyses.three_d",
    "compute_diagram_3d": "analyses.three_d.diagram",
    "hopf_normal_form_3d": "analyses.three_d",
    "HopfNormalForm": "analyses.stability.hopf",
    "find_whirl": "analyses.three_d",
    "Whirl": "analyses.three_d",
    # Studies: convergence, a user's values against fempipe, error estimates
    "run_study": "studies.convergence",
    "ConvergenceStudy": "studies.convergence",
    "Quantity": "studies.convergence",
    "estimate_order": "studies.convergence",
    "extrapolate_richardson": "studies.convergence",
    "compare_values": "studies.compare",
    "Comparison": "studies.compare",
    "ErrorEstimate": "studies.error_estimate",
    "estimate_errors": "studies.estimates",
}

#: The layer subpackages, loaded on first attribute access
#: (``import fempipe; fempipe.analyses.statics.solve_static``).
_SUBMODULES = frozenset(
    {
        "core",
        "model",
        "solvers",
        "analyses",
        "studies",
        "io",
        "plotting",
        "validation",
        "bench",
        "cli",
    }
)

__all__ = [
    "Params",
    "PipeSI",
    "FiniteElement",
    "Modal",
    "parse_discretization",
    "PipeModel",
    "OutOfPlaneModel",
    "build_out_of_plane_model",
    "OutOfPlaneMotion",
    "compute_shape",
    "compute_tip",
    "ParamError",
    "SolverError",
    "solve_static",
    "StaticSolution",
    "NewtonError",
    "solve_sagged",
    "solve_path",
    "continue_static",
    "switch_branch",
    "Branch",
    "compute_spectrum",
    "trace_root_locus",
    "analyse_stability",
    "find_critical_velocity",
    "StabilityResult",
    "map_stability",
    "StabilityInPlanes",
    "simulate",
    "simulate_steps",
    "make_initial_state",
    "Trajectory",
    "PulsatingFlow",
    "IntegrationError",
    "shoot",
    "find_attractor",
    "LimitCycle",
    "Attractor",
    "ShootingError",
    "find_hopf_points",
    "continue_cycles",
    "CycleBranch",
    "compute_cycle_diagram",
    "CycleDiagram",
    "compute_bifurcation_diagram",
    "compute_parametric_chart",
    "PipeModel3D",
    "simulate_3d",
    "Motion3D",
    "compute_out_of_plane_floquet",
    "classify_3d",
    "compute_diagram_3d",
    "hopf_normal_form_3d",
    "HopfNormalForm",
    "find_whirl",
    "Whirl",
    "run_study",
    "ConvergenceStudy",
    "Quantity",
    "estimate_order",
    "extrapolate_richardson",
    "compare_values",
    "Comparison",
    "ErrorEstimate",
    "estimate_errors",
]

if TYPE_CHECKING:  # static analysers and IDEs see the eager imports
    from fempipe.analyses.bifurcation import compute_bifurcation_diagram
    from fempipe.analyses.dynamics import (
        IntegrationError,
        PulsatingFlow,
        Trajectory,
        make_initial_state,
        simulate,
        simulate_steps,
    )
    from fempipe.analyses.limit_cycle import (
        Attractor,
        LimitCycle,
        ShootingError,
        find_attractor,
        shoot,
    )
    from fempipe.analyses.parametric import compute_parametric_chart
    from fempipe.analyses.periodic import (
        CycleBranch,
        CycleDiagram,
        compute_cycle_diagram,
        continue_cycles,
        find_hopf_points,
    )
    from fempipe.analyses.stability import (
        StabilityInPlanes,
        StabilityResult,
        analyse_stability,
        compute_spectrum,
        find_critical_velocity,
        map_stability,
        trace_root_locus,
    )
    from fempipe.analyses.stability.hopf import HopfNormalForm
    from fempipe.analyses.statics import (
        Branch,
        NewtonError,
        StaticSolution,
        continue_static,
        solve_path,
        solve_sagged,
        solve_static,
        switch_branch,
    )
    from fempipe.analyses.three_d import (
        Motion3D,
        Whirl,
        classify_3d,
        compute_out_of_plane_floquet,
        find_whirl,
        hopf_normal_form_3d,
        simulate_3d,
    )
    from fempipe.analyses.three_d.diagram import compute_diagram_3d
    from fempipe.core.errors import ParamError, SolverError
    from fempipe.model.discretization import FiniteElement, Modal, parse_discretization
    from fempipe.model.kinematics import compute_shape, compute_tip
    from fempipe.model.out_of_plane.model import OutOfPlaneModel, build_out_of_plane_model
    from fempipe.model.out_of_plane.motion import OutOfPlaneMotion
    from fempipe.model.params import Params, PipeSI
    from fempipe.model.plane.operators import PipeModel
    from fempipe.studies.compare import Comparison, compare_values
    from fempipe.studies.convergence import (
        ConvergenceStudy,
        Quantity,
        estimate_order,
        extrapolate_richardson,
        run_study,
    )
    from fempipe.studies.error_estimate import ErrorEstimate
    from fempipe.studies.estimates import estimate_errors


def __getattr__(name: str) -> object:
    """Load a public name (or a layer subpackage, :data:`_SUBMODULES`) on first access."""
    module = _LAZY.get(name)
    if module is not None:
        value = getattr(importlib.import_module(f"{__name__}.{module}"), name)
        globals()[name] = value  # later accesses skip this function
        return value
    if name in _SUBMODULES:
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__) | _SUBMODULES)

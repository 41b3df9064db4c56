"""fempipe: finite elements and modal Galerkin for the soft pipe conveying fluid.

The geometrically exact model of Chen, Hu, Dai & Wang (Appl. Math. Mech.
41(9) 1381-1400, 2020), Eq. (20), discretised by 1-D Lagrange finite
elements on a scikit-fem MeshLine or by the paper's sine modes.

The public names are loaded on first use (PEP 562 module ``__getattr__``), so
``import fempipe`` and the start of the ``fempipe`` command do not pay for
numpy, scipy, scikit-fem and the solvers (0.6 CPU-s on a 2-core x86_64
machine; ``fempipe bench --only startup``) until a computation needs them.
"""

from __future__ import annotations

import importlib
import sys
import types
from typing import TYPE_CHECKING

__version__ = "0.1.0"

#: public name -> submodule that defines it
_LAZY: dict[str, str] = {
    "FiniteElement": "discretization",
    "Modal": "discretization",
    "parse_discretization": "discretization",
    "ParamError": "errors",
    "SolverError": "errors",
    "shape": "kinematics",
    "tip_values": "kinematics",
    "PipeModel": "operators",
    "OutOfPlaneModel": "out_of_plane",
    "Params": "params",
    "PipeSI": "params",
    "critical_velocity": "stability",
    "spectrum": "stability",
    "stability_analysis": "stability",
    "spatial_critical_velocity": "stability",
    "spatial_stability_analysis": "stability",
    "NewtonError": "static",
    "continuation": "static",
    "solve_path": "static",
    "solve_static": "static",
    "switch_branch": "static",
}

#: Submodules that ``import fempipe`` used to load eagerly, so that
#: ``import fempipe; fempipe.static.solve_static`` keeps working.
_SUBMODULES = frozenset(
    {
        "discretization",
        "equilibrium",
        "errors",
        "kinematics",
        "operators",
        "parallel",
        "params",
        "quadrature",
        "stability",
        "static",
    }
)

__all__ = [
    "FiniteElement",
    "Modal",
    "NewtonError",
    "OutOfPlaneModel",
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
    "spatial_critical_velocity",
    "spatial_stability_analysis",
    "spectrum",
    "stability_analysis",
    "switch_branch",
    "tip_values",
]

if TYPE_CHECKING:  # static analysers and IDEs see the eager imports
    from .discretization import FiniteElement, Modal, parse_discretization
    from .errors import ParamError, SolverError
    from .kinematics import shape, tip_values
    from .operators import PipeModel
    from .out_of_plane import OutOfPlaneModel
    from .params import Params, PipeSI
    from .stability import (
        critical_velocity,
        spatial_critical_velocity,
        spatial_stability_analysis,
        spectrum,
        stability_analysis,
    )
    from .static import NewtonError, continuation, solve_path, solve_static, switch_branch


def __getattr__(name: str) -> object:
    """Load a public name (or an eagerly-loaded-before submodule) on first access."""
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


class _Package(types.ModuleType):
    """The package's module type: a public name is never shadowed by a submodule.

    ``fempipe.continuation`` is the function of :mod:`fempipe.static`, but
    there is also a submodule ``fempipe/continuation.py``; importing it makes
    the import system bind it on the package (``setattr``), which would hide
    the function from :func:`__getattr__`.  The eager ``__init__`` bound the
    function last; this keeps that.
    """

    def __setattr__(self, name: str, value: object) -> None:
        if name in _LAZY and isinstance(value, types.ModuleType):
            return
        super().__setattr__(name, value)


sys.modules[__name__].__class__ = _Package

"""fempipe: finite elements and modal Galerkin for the soft pipe conveying fluid.

The geometrically exact model of Chen, Hu, Dai & Wang (Appl. Math. Mech.
41(9) 1381-1400, 2020), Eq. (20), discretised by 1-D Lagrange finite
elements on a scikit-fem MeshLine or by the paper's sine modes.

The package is layered, lowest first: ``core`` < ``model`` < ``solvers`` <
``analyses`` (statics < stability < dynamics < limit_cycle < bifurcation,
periodic) < ``studies`` < ``io`` < ``plotting`` < ``validation`` < ``bench`` <
``cli`` < this facade.  A module imports from its own layer or lower ones,
never higher, and no private name of another module.  The layers are written
down once, with what each holds, in :mod:`fempipe.core.layers`
(``tests/test_layering.py`` keeps them).

The public names are loaded on first use (PEP 562 module ``__getattr__``), so
``import fempipe`` and the start of the ``fempipe`` command do not pay for
numpy, scipy, scikit-fem and the solvers (0.6 CPU-s on a 2-core x86_64
machine; ``fempipe bench --only startup``) until a computation needs them.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING

from fempipe.core.version import __version__ as __version__  # re-exported

#: public name -> submodule that defines it
_LAZY: dict[str, str] = {
    "FiniteElement": "model.discretization",
    "Modal": "model.discretization",
    "parse_discretization": "model.discretization",
    "ParamError": "core.errors",
    "SolverError": "core.errors",
    "shape": "model.kinematics",
    "tip_values": "model.kinematics",
    "PipeModel": "model.operators",
    "OutOfPlaneModel": "model.out_of_plane",
    "Params": "model.params",
    "PipeSI": "model.params",
    "critical_velocity": "analyses.stability",
    "spectrum": "analyses.stability",
    "stability_analysis": "analyses.stability",
    "spatial_critical_velocity": "analyses.stability",
    "spatial_stability_analysis": "analyses.stability",
    "NewtonError": "analyses.statics",
    "continuation": "analyses.statics",
    "solve_path": "analyses.statics",
    "solve_static": "analyses.statics",
    "switch_branch": "analyses.statics",
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
    from fempipe.analyses.stability import (
        critical_velocity,
        spatial_critical_velocity,
        spatial_stability_analysis,
        spectrum,
        stability_analysis,
    )
    from fempipe.analyses.statics import (
        NewtonError,
        continuation,
        solve_path,
        solve_static,
        switch_branch,
    )
    from fempipe.core.errors import ParamError, SolverError
    from fempipe.model.discretization import FiniteElement, Modal, parse_discretization
    from fempipe.model.kinematics import shape, tip_values
    from fempipe.model.operators import PipeModel
    from fempipe.model.out_of_plane import OutOfPlaneModel
    from fempipe.model.params import Params, PipeSI


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

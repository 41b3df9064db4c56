"""Linear stability of the static states: spectra, critical velocities, events.

The linearization of Eq. (20) about a static state is Eq. (31b), discretized as Eq. (32)
with M^d, C^d, K^d of Eqs. (33a)-(33c), the Jacobians of the pipe's residual; its quadratic
eigenproblem is solved in first-order form.  Eigenvalues are reported as lambda (Re lambda >
0 unstable) and as the paper's Omega = -i lambda.  Only the modes a discretization resolves
are reported (:func:`resolution`), with mode numbers that name one physical eigenvalue
whatever the mesh, carried by continuity along the static branch; one criterion decides
stability (:func:`linearly_stable`, :data:`STABILITY_TOL`).

The main names: :func:`spectrum`, :func:`root_locus`, :func:`stability_analysis` (every
event along a branch and the branches born at pitchforks), :func:`critical_velocity`,
:func:`stability_map` (Fig. 6), and in both planes :func:`spatial_stability_analysis`,
:func:`spatial_critical_velocity` and :func:`spatial_root_locus`.  Modules: ``linear``,
``eigensolvers``, ``hysteretic``, ``canonical``, ``classified``, ``criterion``, ``spectra``,
``tracking``, ``events``, ``chunked_branch``, ``branch_analysis``, ``analysis``,
``spatial``, ``maps`` and ``hopf`` (the Hopf criticality of the flutter events).

Derivation, the rules for resolved modes, mode numbers and events: docs/theory/stability.md.
"""

from fempipe.core.parallel import run_tasks

from .analysis import critical_velocity, stability_analysis
from .canonical import RESOLUTION_TOL, Resolution, cantilever_frequencies, resolution
from .classified import STABILITY_TOL
from .criterion import growth_rate, linearly_stable
from .events import BranchStability, StabilityEvent, StabilityResult
from .linear import linearized_matrices
from .maps import StabilityMap, root_loci, stability_map
from .spatial import (
    SpatialStability,
    spatial_critical_velocity,
    spatial_stability_analysis,
)
from .spectra import ModeShape, Spectrum, mode_shape, spectrum
from .tracking import RootLocus, root_locus, spatial_root_locus

__all__ = [
    "RESOLUTION_TOL",
    "STABILITY_TOL",
    "Resolution",
    "Spectrum",
    "ModeShape",
    "RootLocus",
    "StabilityEvent",
    "BranchStability",
    "StabilityResult",
    "StabilityMap",
    "SpatialStability",
    "spatial_stability_analysis",
    "spatial_critical_velocity",
    "cantilever_frequencies",
    "resolution",
    "linearized_matrices",
    "spectrum",
    "growth_rate",
    "linearly_stable",
    "mode_shape",
    "root_locus",
    "spatial_root_locus",
    "root_loci",
    "stability_analysis",
    "critical_velocity",
    "stability_map",
    "run_tasks",
]

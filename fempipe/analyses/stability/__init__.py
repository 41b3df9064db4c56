"""Linear stability of the static states: spectra, critical velocities, events.

The linearization of Eq. (20) about a static state is Eq. (31b), discretized as Eq. (32)
(M^d, C^d, K^d of Eqs. (33a)-(33c)); its quadratic eigenproblem is solved in first-order
form.  Eigenvalues are lambda (Re lambda > 0 unstable) and the paper's Omega = -i lambda.
Only resolved modes are reported (:func:`resolution`), numbered by continuity along the
static branch; one criterion decides stability (:func:`linearly_stable`).  Every analysis
takes ``planes``: the motion in the plane of the static state and/or out of it.

Main names: :func:`compute_spectrum`, :func:`trace_root_locus`, :func:`analyse_stability`,
:func:`find_critical_velocity`, :func:`map_stability` (Fig. 6); ``hopf`` gives the Hopf
criticality of the flutter events.

Derivation, resolved modes, mode numbers and events: docs/theory/stability.md.
"""

from .analysis import analyse_stability, find_critical_velocity
from .canonical import RESOLUTION_TOL, Resolution, cantilever_frequencies, resolution
from .classified import STABILITY_TOL
from .criterion import growth_rate, linearly_stable
from .events import BranchStability, StabilityEvent, StabilityInPlanes, StabilityResult
from .linear import PLANES, linearized_matrices
from .maps import StabilityMap, map_stability, trace_root_loci
from .spectra import ModeShape, Spectrum, compute_spectrum, mode_shape
from .tracking import RootLocus, trace_root_locus

__all__ = [
    "PLANES",
    "RESOLUTION_TOL",
    "STABILITY_TOL",
    "Resolution",
    "Spectrum",
    "ModeShape",
    "RootLocus",
    "StabilityEvent",
    "BranchStability",
    "StabilityResult",
    "StabilityInPlanes",
    "StabilityMap",
    "cantilever_frequencies",
    "resolution",
    "linearized_matrices",
    "compute_spectrum",
    "growth_rate",
    "linearly_stable",
    "mode_shape",
    "trace_root_locus",
    "trace_root_loci",
    "analyse_stability",
    "find_critical_velocity",
    "map_stability",
]

"""Linear stability of the static states: spectra, critical velocities, events.

Eq. (31b) about a static state, discretized as Eq. (32) (Eqs. (33a)-(33c)), solved in
first-order form; lambda with Re lambda > 0 unstable, the paper's Omega = -i lambda.  Only
resolved modes count, numbered by continuity from v = 0; every analysis takes ``planes``
(in the plane of the static state and/or out of it).

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

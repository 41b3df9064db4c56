"""The pipe in three dimensions: which planar motions survive out of the plane, and the 3-D motion.

:func:`~fempipe.analyses.three_d.floquet.compute_out_of_plane_floquet` computes the Floquet
multipliers of out-of-plane perturbations of a planar limit cycle;
:func:`~fempipe.analyses.three_d.verdict.classify_3d` says whether a planar attractor survives
in three dimensions; :func:`~fempipe.analyses.three_d.motion.simulate_3d` integrates the 3-D
model to its attractor; :func:`~fempipe.analyses.three_d.whirl.find_whirl` shoots the whirl of
an axisymmetric pipe; :mod:`~fempipe.analyses.three_d.onset` is the Hopf normal form out of
the plane and :mod:`~fempipe.analyses.three_d.diagram` sweeps the 3-D attractors against v
(a diagram: it ranks with the bifurcation diagrams, not imported here).
Docs: docs/theory/space.md.
"""

from fempipe.analyses.three_d.floquet import OutOfPlaneFloquet, compute_out_of_plane_floquet
from fempipe.analyses.three_d.motion import Motion3D, simulate_3d
from fempipe.analyses.three_d.onset import hopf_normal_form_3d
from fempipe.analyses.three_d.verdict import classify_3d
from fempipe.analyses.three_d.whirl import Whirl, find_whirl, whirl_state

__all__ = [
    "Motion3D",
    "OutOfPlaneFloquet",
    "Whirl",
    "classify_3d",
    "compute_out_of_plane_floquet",
    "find_whirl",
    "hopf_normal_form_3d",
    "simulate_3d",
    "whirl_state",
]

"""The pipe in three dimensions: which planar motions survive out of the plane, and the 3-D motion.

:mod:`~fempipe.analyses.space.floquet` computes the Floquet multipliers of
out-of-plane perturbations of a planar limit cycle on the 3-D model
(:mod:`fempipe.model.space`); :func:`~fempipe.analyses.space.verdict.three_dimensional_verdict`
says whether a planar attractor survives in three dimensions;
:func:`~fempipe.analyses.space.whirl.find_whirl` shoots the whirl of an axisymmetric pipe
(a periodic orbit turning rigidly about the vertical).
"""

from .floquet import OutOfPlaneFloquet, out_of_plane_floquet
from .motion import SpaceMotion, simulate_space
from .verdict import three_dimensional_verdict
from .whirl import Whirl, find_whirl, whirl_state

__all__ = [
    "OutOfPlaneFloquet",
    "SpaceMotion",
    "Whirl",
    "find_whirl",
    "out_of_plane_floquet",
    "simulate_space",
    "three_dimensional_verdict",
    "whirl_state",
]

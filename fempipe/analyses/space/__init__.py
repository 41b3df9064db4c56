"""The pipe in three dimensions: which planar motions survive out of the plane, and the 3-D motion.

:mod:`~fempipe.analyses.space.floquet` computes the Floquet multipliers of
out-of-plane perturbations of a planar limit cycle on the 3-D model
(:mod:`fempipe.model.space`); :func:`~fempipe.analyses.space.verdict.three_dimensional_verdict`
says whether a planar attractor survives in three dimensions;
:func:`~fempipe.analyses.space.whirl.find_whirl` shoots the whirl of an axisymmetric pipe
(a periodic orbit turning rigidly about the vertical);
:func:`~fempipe.analyses.space.onset.space_hopf_normal_form` is the Hopf normal form where
the planar static state loses stability out of its plane; and
:func:`~fempipe.analyses.space.diagram.space_diagram` sweeps the 3-D attractors against v.
"""

from .diagram import space_diagram
from .floquet import OutOfPlaneFloquet, out_of_plane_floquet
from .motion import SpaceMotion, simulate_space
from .onset import SpaceHopfNormalForm, space_hopf_normal_form
from .verdict import three_dimensional_verdict
from .whirl import Whirl, find_whirl, whirl_state

__all__ = [
    "OutOfPlaneFloquet",
    "SpaceHopfNormalForm",
    "SpaceMotion",
    "Whirl",
    "find_whirl",
    "out_of_plane_floquet",
    "simulate_space",
    "space_diagram",
    "space_hopf_normal_form",
    "three_dimensional_verdict",
    "whirl_state",
]

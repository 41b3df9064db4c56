"""The pipe in three dimensions: which planar motions survive out of the plane, and the 3-D motion.

:mod:`~fempipe.analyses.space.floquet` computes the Floquet multipliers of
out-of-plane perturbations of a planar limit cycle on the 3-D model
(:mod:`fempipe.model.space`).
"""

from .floquet import OutOfPlaneFloquet, out_of_plane_floquet

__all__ = ["OutOfPlaneFloquet", "out_of_plane_floquet"]

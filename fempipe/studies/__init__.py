"""Layer 4, the studies: one analysis repeated to judge its accuracy.

Mesh and mode convergence (:mod:`~fempipe.studies.convergence`), a user's
results against fempipe (:mod:`~fempipe.studies.compare`) and a posteriori
error estimates (:mod:`~fempipe.studies.error_estimate`), attached to
results by :mod:`~fempipe.studies.estimates`.
"""

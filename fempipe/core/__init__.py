"""Layer 0, the core: no physics, nothing of the pipe.

Errors (:mod:`~fempipe.core.errors`), worker processes and BLAS limits
(:mod:`~fempipe.core.parallel`), Brent's root finder
(:mod:`~fempipe.core.rootfinding`) and the optimal assignment of eigenvalues
(:mod:`~fempipe.core.matching`).  The layers are listed in :mod:`fempipe`.
"""

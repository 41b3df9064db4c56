"""Layer 0, the core: no physics, nothing of the pipe.

Errors (:mod:`~fempipe.core.errors`), worker processes and BLAS limits
(:mod:`~fempipe.core.parallel`), Brent's root finder
(:mod:`~fempipe.core.rootfinding`), the optimal assignment of eigenvalues
(:mod:`~fempipe.core.matching`), the first-order (companion) form of a
quadratic eigenproblem (:mod:`~fempipe.core.companion`), atomic file writing
(:mod:`~fempipe.core.files`), the version (:mod:`~fempipe.core.version`) and
the order of the layers themselves (:mod:`~fempipe.core.layers`).
"""

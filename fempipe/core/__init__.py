"""Layer 0, the core: no physics, nothing of the pipe.

Errors, worker processes and BLAS limits, Brent's root finder, the optimal assignment of
eigenvalues, the companion form of a quadratic eigenproblem, dual numbers, atomic files, the
version and the order of the layers.
"""

"""Layer 2, the solvers: algorithms that know the model only by a written contract.

Newton's method with a line search (:mod:`~fempipe.solvers.newton`),
pseudo-arclength continuation (:mod:`~fempipe.solvers.continuation`) and the
Radau IIA integrator (:mod:`~fempipe.solvers.radau`).
"""

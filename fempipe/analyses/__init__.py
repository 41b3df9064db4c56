"""Layer 3, the analyses: what a user asks of the pipe.

In their own order (a later one may use an earlier one): statics
(:mod:`~fempipe.analyses.statics`), linear stability
(:mod:`~fempipe.analyses.stability`), time integration
(:mod:`~fempipe.analyses.dynamics`), limit cycles
(:mod:`~fempipe.analyses.limit_cycle`), bifurcation diagrams
(:mod:`~fempipe.analyses.bifurcation`) and branches of periodic orbits
(:mod:`~fempipe.analyses.periodic`).
"""

"""Layer 1, the model: Eq. (20) of the paper, discretized.

Parameters, quadrature, the two discretizations behind one contract, the weak forms of
the physical terms, the pipe's residual and Jacobians (in the plane, out of it, in 3-D),
batched stages, the equations of motion as the integrator's problem, the centerline and
transfers between discretizations.  Derivations: docs/theory/.
"""

"""Layer 1, the model: Eq. (20) of the paper, discretized.

Parameters (:mod:`~fempipe.model.params`), quadrature
(:mod:`~fempipe.model.quadrature`), the two discretizations behind one
interface (:mod:`~fempipe.model.discretization`: :mod:`~fempipe.model.finite_element`,
:mod:`~fempipe.model.modal`), the weak forms of the physical terms
(:mod:`~fempipe.model.weak_form`, :mod:`~fempipe.model.local_terms`,
:mod:`~fempipe.model.nonlocal_terms`, :mod:`~fempipe.model.variants`,
:mod:`~fempipe.model.springs`) and the pipe's residual and Jacobians
(:mod:`~fempipe.model.operators`, out of the plane
:mod:`~fempipe.model.out_of_plane`), the same at several states in one call
(:mod:`~fempipe.model.batched`), the equations of motion as the time
integrator's problem (:mod:`~fempipe.model.dynamics_problem`), the centerline
(:mod:`~fempipe.model.kinematics`) and transfers between discretizations
(:mod:`~fempipe.model.projection`).
"""

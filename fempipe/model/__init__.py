"""Layer 1, the model: Eq. (20) of the paper, discretised.

Parameters (:mod:`~fempipe.model.params`), quadrature
(:mod:`~fempipe.model.quadrature`), the two discretisations behind one
interface (:mod:`~fempipe.model.discretization`), the weak forms of the
physical terms and the pipe's residual and Jacobians
(:mod:`~fempipe.model.operators`, out of the plane
:mod:`~fempipe.model.out_of_plane`), the centreline
(:mod:`~fempipe.model.kinematics`) and transfers between discretisations
(:mod:`~fempipe.model.projection`).
"""

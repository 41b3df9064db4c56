"""The variant terms of the pipe: an end mass and external viscous damping.

Zero by default (:class:`~fempipe.model.params.Params`; docs, "Variants of
the pipe"); the springs are :mod:`fempipe.model.springs`.  The derivations
are in :mod:`fempipe.model.weak_form`.
"""

from __future__ import annotations

import numpy as np

from .weak_form import Fields, WeakForm

__all__ = ["EndMassTerms", "ExternalDampingTerm"]


class EndMassTerms(WeakForm):
    """The end mass Gamma at xi = 1: its weight and its inertia."""

    def _end_vector(self, fl: Fields) -> np.ndarray:
        """``b_i = \\int_0^1 phi_i n = (C phi_i n)(1)``, shape (n, 2): d r(1) / d q_i."""
        return self._test(fl.normal)

    def end_mass_gravity(self, fl: Fields) -> np.ndarray:
        """Weight of the end mass: ``gamma Gamma \\int phi_i sin(theta + alpha)``.

        The gravity term of Eq. (20) with its lever arm 1 - xi (the pipe's
        weight beyond xi, Eq. (19) scaling) raised by Gamma, the end mass
        beyond every section: the gradient of gamma Gamma (cos alpha - X_g(1)).
        """
        p = self.params
        if not p.end_mass:
            return np.zeros(self.n)
        return p.gamma * p.end_mass * self._test(np.sin(fl.theta + p.alpha))

    def end_mass_inertia(self, fl: Fields) -> np.ndarray:
        """Inertia of the end mass: ``Gamma b_i . r_ddot(1)``.

        With r_ddot(1) = \\int_0^1 (theta_ddot n - theta_dot^2 t) the tip's
        acceleration, the inertia force field n . \\int_xi^1 r_ddot of Eq. (20)
        becomes n . (\\int_xi^1 r_ddot + Gamma r_ddot(1)); its weak form is this
        term: the theta_ddot part Gamma b b^T q'' (in :meth:`mass_matrix`) and
        the centripetal part -Gamma b . \\int theta_dot^2 t.  It is the Lagrange
        derivative of the end mass's kinetic energy (Gamma/2) |r_dot(1)|^2.
        """
        G = self.params.end_mass
        if not G:
            return np.zeros(self.n)
        acc = self.quad.integrate(
            fl.theta_ddot[:, None] * fl.normal - fl.theta_dot[:, None] ** 2 * fl.tangent
        )
        return G * (self._end_vector(fl) @ acc)


class ExternalDampingTerm(WeakForm):
    """External viscous damping sigma along the whole pipe."""

    def external_damping(self, fl: Fields) -> np.ndarray:
        """External viscous damping: ``sigma \\int phi_i n . C^R C(theta_dot n)``.

        The force -sigma r_dot per unit length on the centerline, r_dot =
        C(theta_dot n) its whole velocity (not only the lateral part), does
        the virtual work -sigma \\int_0^1 r_dot . delta r with delta r =
        C(delta theta n); exchanging the integrals gives the inertia projection
        with r_ddot replaced by r_dot, so this term is sigma M_pipe(q) q'
        (``M_pipe`` the mass matrix without end mass).  Its power is
        sigma \\int_0^1 |r_dot|^2 (:func:`fempipe.analyses.dynamics.power_terms`).
        """
        sigma = self.params.external_damping
        if not sigma:
            return np.zeros(self.n)
        return sigma * self._project(self.quad.cumulative(fl.theta_dot[:, None] * fl.normal), fl)

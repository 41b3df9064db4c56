"""The variant terms of the pipe: an end mass and external viscous damping.

Zero by default; the springs are :mod:`fempipe.model.plane.springs`.  Derivation:
docs/theory/variants.md.
"""

from __future__ import annotations

import numpy as np

from fempipe.model.weak_form import Fields, WeakForm

__all__ = ["EndMassTerms", "ExternalDampingTerm"]


class EndMassTerms(WeakForm):
    """The end mass Gamma at xi = 1: its weight and its inertia."""

    def _end_vector(self, fl: Fields) -> np.ndarray:
        """``b_i = \\int_0^1 phi_i n = (C phi_i n)(1)``, shape (n, 2): d r(1) / d q_i."""
        return self._test(fl.normal)

    def end_mass_gravity(self, fl: Fields) -> np.ndarray:
        r"""Weight of the end mass: ``gamma Gamma \int phi_i sin(theta + alpha)``."""
        p = self.params
        if not p.end_mass:
            return np.zeros(self.n)
        return p.gamma * p.end_mass * self._test(np.sin(fl.theta + p.alpha))

    def end_mass_inertia(self, fl: Fields) -> np.ndarray:
        r"""Inertia of the end mass: ``Gamma b_i . r_ddot(1)``, r_ddot(1) = \int_0^1 (theta_ddot n - theta_dot^2 t)."""
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
        r"""External viscous damping: ``sigma \int phi_i n . C^R C(theta_dot n)`` = sigma M_pipe(q) q'."""
        sigma = self.params.external_damping
        if not sigma:
            return np.zeros(self.n)
        return sigma * self._project(self.quad.cumulative(fl.theta_dot[:, None] * fl.normal), fl)

"""The local terms of Eq. (20): bending, Kelvin-Voigt, gravity, the follower force (docs/theory/weak_form.md)."""

from __future__ import annotations

import numpy as np
import scipy.sparse as sp

from fempipe.model.weak_form import Fields, WeakForm, scale_rows

__all__ = ["LocalTerms"]


class LocalTerms(WeakForm):
    """Bending, Kelvin-Voigt, gravity and follower terms of Eq. (20) and their q-derivatives."""

    def bending(self, q: np.ndarray) -> np.ndarray:
        """Eq. (20) -theta'': ``K q`` with K_ij = \\int phi_i' phi_j'."""
        return np.asarray(self.disc.K @ q)

    def kelvin_voigt(self, qdot: np.ndarray) -> np.ndarray:
        """Eq. (20) -mu theta_dot'': ``mu K q'``."""
        return self.params.mu * np.asarray(self.disc.K @ qdot)

    def gravity(self, fl: Fields) -> np.ndarray:
        """Eq. (20) gamma (1 - xi) sin(theta + alpha)."""
        p = self.params
        return p.gamma * self._test((1.0 - self.x) * np.sin(fl.theta + p.alpha))

    def _gravity_weight(self, fl: Fields) -> np.ndarray:
        """d(gravity + end_mass_gravity)/dq = ``Phi^T diag(d) Phi`` with this d."""
        p = self.params
        return p.gamma * self.w * (1.0 - self.x + p.end_mass) * np.cos(fl.theta + p.alpha)

    def gravity_jacobian(self, fl: Fields):
        """d(gravity + end_mass_gravity)/dq, sparse for finite elements."""
        Phi = self.disc.Phi
        return Phi.T @ scale_rows(self._gravity_weight(fl), Phi)

    def follower(self, fl: Fields) -> np.ndarray:
        """Eq. (20) v^2 sin(theta(1) - theta): the jet's reaction at the free end, Eq. (14)."""
        # v * v, not v**2: a product overflows to inf (caught by the solvers as
        # a non-finite residual) where a power raises OverflowError.
        return self.params.v * self.params.v * self._test(np.sin(fl.theta_tip - fl.theta))

    def _follower_weights(self, fl: Fields) -> tuple[np.ndarray, np.ndarray]:
        """d(follower)/dq = ``Phi^T diag(d) Phi + tip_col tip^T`` as (d, tip_col): theta(1) adds a rank-one column."""
        v2 = self.params.v * self.params.v
        c = np.cos(fl.theta_tip - fl.theta)
        return -v2 * self.w * c, v2 * self._test(c)

    def follower_jacobian(self, fl: Fields):
        d, tip_col = self._follower_weights(fl)
        Phi = self.disc.Phi
        local = Phi.T @ scale_rows(d, Phi)
        if sp.issparse(local):
            tip = sp.csr_matrix(self.disc.tip)
            return local + sp.csr_matrix(tip_col[:, None]) @ tip
        return local + np.outer(tip_col, self.disc.tip)

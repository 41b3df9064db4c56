r"""The nonlocal terms of Eq. (20): inertia, centripetal, Coriolis, flow acceleration.

Each is a projection ``\int phi_i n . C^R F``; the pipe's mass matrix is here too
(docs/theory/weak_form.md).
"""

from __future__ import annotations

import numpy as np

from fempipe.model.weak_form import Fields, WeakForm

__all__ = ["NonlocalTerms"]


class NonlocalTerms(WeakForm):
    """Inertia, centripetal, Coriolis and flow-acceleration terms of Eq. (20)."""

    def inertia(self, fl: Fields) -> np.ndarray:
        """The theta_ddot terms of Eq. (20)'s double integrals, ``M_pipe(q) q''`` (end mass apart)."""
        return self._project(self.quad.cumulative(fl.theta_ddot[:, None] * fl.normal), fl)

    def centripetal(self, fl: Fields) -> np.ndarray:
        """Eq. (20) theta_dot^2 terms of the double integrals (N_2 of Eq. (24e))."""
        return self._project(-self.quad.cumulative(fl.theta_dot[:, None] ** 2 * fl.tangent), fl)

    def coriolis(self, fl: Fields) -> np.ndarray:
        """Eq. (20) 2 v sqrt(beta) [sin theta \\int theta_dot sin + cos theta \\int theta_dot cos]."""
        p = self.params
        return 2.0 * p.v * np.sqrt(p.beta) * self._project(fl.theta_dot[:, None] * fl.normal, fl)

    def flow_acceleration(self, fl: Fields, v_dot: float) -> np.ndarray:
        """Eq. (20) v_dot sqrt(beta) [-sin theta \\int cos + cos theta \\int sin]."""
        if v_dot == 0.0:
            return np.zeros(self.n)
        return v_dot * np.sqrt(self.params.beta) * self._project(fl.tangent, fl)

    def _pipe_mass(self, fl: Fields) -> np.ndarray:
        """``\\int_0^1 (C phi_i n).(C phi_j n)``: the pipe's own mass matrix."""
        B = self.quad.cumulative(self._phi_field(fl.normal))  # (n_q, 2, n)
        M = np.einsum("qcj,qck->jk", B * self.w[:, None, None], B)
        return 0.5 * (M + M.T)

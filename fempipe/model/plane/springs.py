"""Linear springs tying centerline points to their undeformed positions.

A variant term of Eq. (20); each spring (kappa, xi_s) is integrated over [0, xi_s] by a Gauss
rule of its own (:class:`PartRule`).  Derivation: docs/theory/variants.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fempipe.model.weak_form import WeakForm, as_dense, scale_rows

__all__ = ["PartRule", "SpringTerms"]


@dataclass(frozen=True)
class PartRule:
    """A Gauss rule on [0, xi_s] with the basis at its points: ``x``, ``w`` (shape (m,)), ``Phi``
    (shape (m, n)) and ``at_node`` (xi_s is a cell edge of the model's quadrature).
    """

    x: np.ndarray
    w: np.ndarray
    Phi: np.ndarray | sp.csr_matrix
    at_node: bool


class SpringTerms(WeakForm):
    """The springs of ``params.springs``: force, Jacobian, forces on the pipe."""

    _part_rules: dict[float, PartRule]

    def _part_rule(self, xi_s: float) -> PartRule:
        """The Gauss rule on [0, xi_s], cached per position (exact for finite elements, docs/theory/variants.md)."""
        rule = self._part_rules.get(xi_s)
        if rule is not None:
            return rule
        quad, Phi = self.quad, self.disc.Phi
        edges = quad.edges
        k = int(np.argmin(np.abs(edges - xi_s)))
        at_node = abs(edges[k] - xi_s) <= 1e-13
        if at_node:
            m = k * quad.n_gauss
            x, w = quad.x[:m], quad.w[:m]
            P = Phi[:m]
        else:
            c = int(np.searchsorted(edges, xi_s, side="right")) - 1  # cell with xi_s inside
            m = c * quad.n_gauss
            h = xi_s - edges[c]
            xp = edges[c] + h * quad.ref_points
            x = np.concatenate([quad.x[:m], xp])
            w = np.concatenate([quad.w[:m], h * quad.ref_weights])
            Pp = self.disc.basis_values(xp)
            P = (
                sp.vstack([Phi[:m], sp.csr_matrix(Pp)]).tocsr()
                if sp.issparse(Phi)
                else (np.vstack([np.asarray(Phi)[:m], np.asarray(Pp)]))
            )
        rule = PartRule(x=x, w=w, Phi=P.tocsr() if sp.issparse(P) else P, at_node=at_node)
        self._part_rules[xi_s] = rule
        return rule

    def part_rule(self, xi_s: float) -> PartRule:
        """The Gauss rule on [0, xi_s] with the basis at its points (see :meth:`_part_rule`)."""
        return self._part_rule(xi_s)

    def spring_forces(self, q: np.ndarray) -> list[np.ndarray]:
        """Per spring, its force on the pipe ``-kappa (r(xi_s) - (xi_s, 0))``, shape (2,)."""
        return [-kappa * d for kappa, _r, _t, _n, _b, d in self._spring_states(q)]

    def _spring_states(self, q: np.ndarray):
        """Per spring (kappa, rule, t, n, b_s, d): d = r(xi_s) - (xi_s, 0), b_s = d r(xi_s) / d q."""
        q = np.asarray(q)
        out = []
        for kappa, xi_s in self.params.springs:
            rule = self._part_rule(xi_s)
            th = rule.Phi @ q
            s, c = np.sin(th), np.cos(th)
            t = np.stack([c, s], axis=1)
            nrm = np.stack([-s, c], axis=1)
            # r(xi_s) - (xi_s, 0) = \int_0^xi_s (cos theta - 1, sin theta): the rule
            # integrates 1 to xi_s, and 1 - cos = 2 sin^2(theta/2) has no
            # cancellation, so the force vanishes at the straight pipe exactly
            # (as bending and the follower term do: Newton's test measures it
            # as it is).
            d = rule.w @ np.stack([-2.0 * np.sin(0.5 * th) ** 2, s], axis=1)
            b = np.asarray(rule.Phi.T @ (rule.w[:, None] * nrm))
            out.append((kappa, rule, t, nrm, b, d))
        return out

    def spring(self, q: np.ndarray) -> np.ndarray:
        r"""Springs: ``sum kappa \int_0^xi_s phi_i n . (r(xi_s) - (xi_s, 0))``, the gradient of
        (kappa/2) |r(xi_s) - (xi_s, 0)|^2.
        """
        r = np.zeros(self.n)
        for kappa, _rule, _t, _n, b, d in self._spring_states(q):
            r = r + kappa * (b @ d)
        return r

    def spring_jacobian(self, q: np.ndarray, dense: bool = False):
        """d(spring)/dq, symmetric: ``kappa (b_s b_s^T - Phi_s^T diag(w_s t . d) Phi_s)``; sparse for
        finite elements unless ``dense``.
        """
        n = self.n
        sparse = self.disc.sparse and not dense
        J = sp.csr_matrix((n, n)) if sparse else np.zeros((n, n))
        for kappa, rule, t, _nrm, b, d in self._spring_states(q):
            wt = -kappa * rule.w * (t @ d)
            local = rule.Phi.T @ scale_rows(wt, rule.Phi)  # banded for finite elements
            if sparse:
                B = sp.csr_matrix(b)
                J = J + local + kappa * (B @ B.T)
            else:
                J = J + as_dense(local) + kappa * (b @ b.T)
        return J.tocsr() if sparse else J

"""Linear springs tying centerline points to their undeformed positions.

The spring term of Eq. (20)'s variants (:mod:`fempipe.model.weak_form`):
each spring (kappa, xi_s) is integrated over [0, xi_s] with a Gauss rule of
its own (:class:`PartRule`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .weak_form import WeakForm, as_dense, scale_rows

__all__ = ["PartRule", "SpringTerms"]


@dataclass(frozen=True)
class PartRule:
    """A Gauss rule on [0, xi_s] with the basis at its points (one per spring position).

    Attributes
    ----------
    x, w : ndarray, shape (m,)
        Points and weights; ``w @ f`` integrates f over [0, xi_s].
    Phi : ndarray or scipy.sparse.csr_matrix, shape (m, n)
        phi_j at the points.
    at_node : bool
        Whether xi_s is a cell edge of the model's quadrature (the rule is
        then its restriction to the cells before xi_s).
    """

    x: np.ndarray
    w: np.ndarray
    Phi: np.ndarray | sp.csr_matrix
    at_node: bool


class SpringTerms(WeakForm):
    """The springs of ``params.springs``: force, Jacobian, forces on the pipe."""

    _part_rules: dict[float, PartRule]

    def _part_rule(self, xi_s: float) -> PartRule:
        """The Gauss rule on [0, xi_s] (cached per position).

        The cells of the model's quadrature before xi_s keep their points; if
        xi_s lies inside a cell, the part [x_c, xi_s] of that cell gets a Gauss
        rule of as many points, with the basis evaluated there
        (``disc.basis_values``).  For finite elements every part is inside
        one element, where theta is a polynomial: the rule is then as exact as
        the model's own on whole cells, whatever xi_s.
        """
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
        """Per spring: (kappa, rule, t, n, b_s, d) with d = r(xi_s) - (xi_s, 0) and
        ``b_s[i] = \\int_0^xi_s phi_i n = d r(xi_s) / d q_i``."""
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
        """Springs: ``sum kappa \\int_0^xi_s phi_i n . (r(xi_s) - (xi_s, 0))``.

        Each spring (kappa, xi_s) ties the centerline point r(xi_s) =
        \\int_0^xi_s t (local frame of Eq. (5): r = (xi + varsigma, eta)) to its
        undeformed position (xi_s, 0) with the isotropic potential
        (kappa/2) |r(xi_s) - (xi_s, 0)|^2, kappa = k L^3/EI; this term is its
        gradient.  In strong form it is a point force at xi_s: theta'' jumps
        there by kappa n(xi_s) . (r(xi_s) - (xi_s, 0)) (a kink of theta').  The
        integrals over [0, xi_s] use :meth:`_part_rule`.
        """
        r = np.zeros(self.n)
        for kappa, _rule, _t, _n, b, d in self._spring_states(q):
            r = r + kappa * (b @ d)
        return r

    def spring_jacobian(self, q: np.ndarray, dense: bool = False):
        """d(spring)/dq, symmetric: ``kappa (b_s b_s^T - Phi_s^T diag(w_s t . d) Phi_s)``.

        Sparse for finite elements unless ``dense``; b_s b_s^T is a dense
        block on the dofs of [0, xi_s].
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

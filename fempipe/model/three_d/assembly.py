"""What the Jacobians of the 3-D weak form need of a discretization, made once per discretization.

:class:`Seeds`: the bases, the integration operators with their transposes and the test
seeds of :func:`fempipe.core.dual.pullback`; :meth:`Seeds.assemble` turns a pull-back into
the Jacobian of :class:`fempipe.model.three_d.model.PipeModel3D`.
"""

from __future__ import annotations

import weakref

import numpy as np
import scipy.sparse as sp

from fempipe.model.discretization import Discretization
from fempipe.model.weak_form import as_dense

__all__ = ["KINDS", "Seeds"]

_SEEDS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


#: The pointwise quantities the local derivatives are taken with respect to, in
#: order (3 components each): (field, basis, block of unknowns).
KINDS = (
    ("u", "Phi", "q"),
    ("u_prime", "dPhi", "q"),
    ("u_dot", "Phi", "qdot"),
    ("u_dot_prime", "dPhi", "qdot"),
    ("u_ddot", "Phi", "qddot"),
)


class Seeds:
    """Phi, dPhi, tip, the integration operators C, C^R and the integral over the pipe as dense
    matrices with their transposes, and the seeds ``seed[q, c', (c, i)] = test_i(q) w_q delta_cc'``
    of the weak form's two parts.
    """

    def __init__(self, disc: Discretization) -> None:
        quad = disc.quad
        self.Phi = as_dense(disc.Phi)
        self.dPhi = as_dense(disc.dPhi)
        self.tip = np.asarray(disc.tip, dtype=float)
        # (op, op^T as a matrix): the integrals and the matrices that pull derivatives back
        eye = np.eye(quad.n_q)
        self.ops = {
            "C": (quad.cumulative_cells, quad.cumulative_adjoint(eye)),
            "CR": (quad.from_tip_cells, np.ascontiguousarray(quad.from_tip_cells(eye).T)),
            "int": (lambda f: quad.integrate(f)[None], quad.w[:, None].copy()),
        }
        nt = self.Phi.shape[1]
        self._tests_S: dict[int, tuple] = {}
        self.tests = []
        for B in (self.Phi, self.dPhi):
            seed = np.zeros((quad.n_q, 3, 3, nt))
            for c in range(3):
                seed[:, c, c, :] = B * quad.w[:, None]
            self.tests.append(seed.reshape(quad.n_q, 3, 3 * nt))
        # Phi^T and dPhi^T, sparse when the discretization's are (elements), dense else
        self.transposed = {
            name: (sp.csr_matrix(B.T) if sp.issparse(getattr(disc, name)) else B.T.copy())
            for name, B in (("Phi", self.Phi), ("dPhi", self.dPhi))
        }
        # dU(1)/dU of the three fields, as columns of (U, U_dot, U_ddot)
        self.tip_der = np.zeros((1, 3, 9 * nt))
        for c in range(3):
            self.tip_der[0, c, c * nt : (c + 1) * nt] = self.tip

    def tests_for(self, S: int) -> tuple:
        """:attr:`tests` repeated for S states, contiguous (kept: made once per S)."""
        t = self._tests_S.get(S)
        if t is None:
            t = self._tests_S[S] = tuple(
                np.ascontiguousarray(np.repeat(x[:, None], S, 1)) for x in self.tests
            )
        return t

    @classmethod
    def of(cls, disc: Discretization) -> Seeds:
        s = _SEEDS.get(disc)
        if s is None:
            s = _SEEDS[disc] = cls(disc)
        return s

    def assemble(self, W: np.ndarray, G: np.ndarray | None, blocks) -> np.ndarray:
        """The Jacobian (S, R, len(blocks) 3 nt) from a pullback (W, G): W (n_q, S, 15, R) times the
        bases of :data:`KINDS`, plus G (S, R, 9 nt) through the tip values.
        """
        nt = self.Phi.shape[1]
        n_q, S, _, R = W.shape
        W5 = W.reshape(n_q, S, len(KINDS), 3, R)
        # node first: out[j, s, block, c, r] = dR_r / d(the block's field c at node j)
        out = np.zeros((nt, S, len(blocks), 3, R))
        for basis in ("Phi", "dPhi"):
            kinds = [k for k, (_f, b, blk) in enumerate(KINDS) if b == basis and blk in blocks]
            if not kinds:
                continue
            at = [blocks.index(KINDS[k][2]) for k in kinds]
            sel = W5[:, :, kinds] if len(kinds) > 1 else W5[:, :, kinds[0] : kinds[0] + 1]
            part = self.transposed[basis] @ sel.reshape(n_q, -1)
            out[:, :, at] += part.reshape((nt,) + sel.shape[1:])
        # (j, s, block, c, r) -> (s, r, block, c, j): column block 3 nt + c nt + j
        out = out.transpose(1, 4, 2, 3, 0).reshape(S, R, len(blocks) * 3 * nt)
        if G is not None:
            N = 3 * nt
            cols = [("q", "qdot", "qddot").index(b) for b in blocks]
            out += np.concatenate([G[:, :, j * N : (j + 1) * N] for j in cols], axis=2)
        return out

"""The weak form of Eq. (20), one operator per physical term: the shared part.

The residual R(q, q', q'') is a sum of terms with analytic derivatives, grouped by kind:
:class:`~fempipe.model.plane.local_terms.LocalTerms`, :class:`~fempipe.model.plane.nonlocal_terms.NonlocalTerms`,
:mod:`~fempipe.model.plane.variants` and :class:`~fempipe.model.plane.springs.SpringTerms`, summed by
:class:`~fempipe.model.plane.operators.PipeModel`.  This module holds what they share:
:class:`Fields`, the test integral and the projection n . C^R.

Derivation and the table of terms: docs/theory/weak_form.md; variants: docs/theory/variants.md.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from fempipe.model.discretization import Discretization
from fempipe.model.params import Params
from fempipe.model.quadrature import LineQuadrature

__all__ = ["Fields", "WeakForm", "as_dense", "scale_rows"]


@dataclass(frozen=True)
class Fields:
    """theta, theta_dot, theta_ddot (shape (n_q,)), ``theta_tip`` = theta(1), ``tangent``
    t = (cos theta, sin theta) and ``normal`` n = (-sin theta, cos theta) (shape (n_q, 2)).
    """

    theta: np.ndarray
    theta_dot: np.ndarray
    theta_ddot: np.ndarray
    theta_tip: float
    tangent: np.ndarray
    normal: np.ndarray


def scale_rows(d: np.ndarray, A):
    """diag(d) @ A for dense or sparse A."""
    if sp.issparse(A):
        return sp.diags(d) @ A
    return d[:, None] * A


def as_dense(A) -> np.ndarray:
    """A as a dense float array (sparse matrices converted)."""
    return A.toarray() if sp.issparse(A) else np.asarray(A, dtype=float)


_DENSE_FORMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _dense_forms(disc: Discretization) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, K) of ``disc`` as dense arrays, computed once per discretization."""
    forms = _DENSE_FORMS.get(disc)
    if forms is None:
        forms = _DENSE_FORMS[disc] = (as_dense(disc.Phi), as_dense(disc.K))
    return forms


class WeakForm:
    r"""What the terms of ``PipeModel`` share: the fields, the test integral (``test_matrix @ f``
    is ``\int phi_i f``), the projection."""

    disc: Discretization
    params: Params
    quad: LineQuadrature
    x: np.ndarray
    w: np.ndarray
    test_matrix: np.ndarray | sp.spmatrix

    @property
    def n(self) -> int:
        return self.disc.n

    def fields(self, q, qdot=None, qddot=None) -> Fields:
        """theta, its rates and the local frame at the quadrature points."""
        Phi = self.disc.Phi
        theta = Phi @ np.asarray(q)
        zero = np.zeros_like(theta)
        th_d = Phi @ np.asarray(qdot) if qdot is not None else zero
        th_dd = Phi @ np.asarray(qddot) if qddot is not None else zero
        s, c = np.sin(theta), np.cos(theta)
        return Fields(
            theta=theta,
            theta_dot=th_d,
            theta_ddot=th_dd,
            theta_tip=float(self.disc.tip @ np.asarray(q)),
            tangent=np.stack([c, s], axis=1),
            normal=np.stack([-s, c], axis=1),
        )

    def _test(self, f: np.ndarray) -> np.ndarray:
        """``\\int phi_i f`` for f at the quadrature points."""
        return np.asarray(self.test_matrix @ f)

    def _project(self, F: np.ndarray, fl: Fields) -> np.ndarray:
        """``\\int phi_i n . C^R F`` for a vector field F, shape (n_q, 2)."""
        G = self.quad.from_tip(F)
        return self._test(np.einsum("qc,qc->q", fl.normal, G))

    def _project_jac(self, dF: np.ndarray, fl: Fields) -> np.ndarray:
        """Derivative of ``\\int phi_i n . C^R F`` through F: dF shape (n_q, 2, n)."""
        G = self.quad.from_tip(dF)
        return self._test(np.einsum("qc,qcj->qj", fl.normal, G))

    def _normal_weight(self, F: np.ndarray, fl: Fields) -> np.ndarray:
        r"""The d of ``Phi^T diag(d) Phi``, the derivative of ``\int phi_i n . C^R F`` through n(theta)."""
        return -np.einsum("qc,qc->q", fl.tangent, self.quad.from_tip(F)) * self.w

    @property
    def _Phi_dense(self) -> np.ndarray:
        """Phi as a dense array, cached per discretization (shared by :meth:`with_params` models)."""
        return _dense_forms(self.disc)[0]

    @property
    def _K_dense(self) -> np.ndarray:
        """The bending matrix K as a dense array, cached like :attr:`_Phi_dense`."""
        return _dense_forms(self.disc)[1]

    def _phi_field(self, coef: np.ndarray) -> np.ndarray:
        """(coef[:, c] * Phi) stacked as shape (n_q, 2, n)."""
        Phi = self._Phi_dense
        return coef[:, :, None] * Phi[:, None, :]

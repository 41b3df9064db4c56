"""The weak form of Eq. (20), one operator per physical term: the shared part.

The discrete residual R(q, q', q'') is a sum of one term per physical effect: bending,
Kelvin-Voigt, gravity, the follower force, inertia, centripetal, Coriolis, flow acceleration,
and the variants of the pipe (end mass, external damping, springs; zero by default).  Each
term supplies its analytic derivatives with respect to q, q' and q'', which Newton's method,
the stability matrices (Eqs. (31b)-(33)) and the time integrators all use.

The terms are grouped by kind, one method per term, named after it:
:class:`~fempipe.model.local_terms.LocalTerms` (bending, Kelvin-Voigt, gravity, follower),
:class:`~fempipe.model.nonlocal_terms.NonlocalTerms` (inertia, centripetal, Coriolis, flow
acceleration), :mod:`~fempipe.model.variants` (end mass, external damping) and
:class:`~fempipe.model.springs.SpringTerms`.  This module holds what they share
(:class:`Fields`, the test integral and the projection n . C^R);
:class:`~fempipe.model.operators.PipeModel` sums them (residual, Jacobians, mass matrix).

Derivation and the table of terms: docs/theory/weak_form.md; the variants:
docs/theory/variants.md.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp

from .discretization import Discretization
from .params import Params
from .quadrature import LineQuadrature

__all__ = ["Fields", "WeakForm", "as_dense", "scale_rows"]


@dataclass(frozen=True)
class Fields:
    """theta, its time derivatives and the local frame at the quadrature points.

    Attributes
    ----------
    theta, theta_dot, theta_ddot : ndarray, shape (n_q,)
    theta_tip : float
        theta(1).
    tangent : ndarray, shape (n_q, 2)
        t = (cos theta, sin theta).
    normal : ndarray, shape (n_q, 2)
        n = (-sin theta, cos theta).
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
    """A as a dense array (sparse matrices converted)."""
    return A.toarray() if sp.issparse(A) else np.asarray(A)


_DENSE_FORMS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _dense_forms(disc: Discretization) -> tuple[np.ndarray, np.ndarray]:
    """(Phi, K) of ``disc`` as dense arrays, computed once per discretization."""
    forms = _DENSE_FORMS.get(disc)
    if forms is None:
        forms = _DENSE_FORMS[disc] = (as_dense(disc.Phi), as_dense(disc.K))
    return forms


class WeakForm:
    """What the terms of the weak form share: the fields, the test integral, the projection.

    The base of the term classes (:mod:`fempipe.model.local_terms`,
    :mod:`~fempipe.model.nonlocal_terms`, :mod:`~fempipe.model.variants`,
    :mod:`~fempipe.model.springs`) and so of
    :class:`~fempipe.model.operators.PipeModel`, which sets the attributes.

    Attributes
    ----------
    disc : Discretization
    params : Params
    quad : LineQuadrature
        ``disc.quad``.
    x, w : ndarray, shape (n_q,)
        Quadrature points and weights.
    test_matrix : ndarray or scipy.sparse matrix, shape (n, n_q)
        ``Phi^T W`` (W = diag(w)): ``test_matrix @ f`` is ``\\int phi_i f`` for f
        at the quadrature points, the test integral of every term.
    """

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
        """Derivative of ``\\int phi_i n . C^R F`` through n(theta) (dn = -t dtheta):
        ``Phi^T diag(d) Phi`` with the d returned here."""
        return -np.einsum("qc,qc->q", fl.tangent, self.quad.from_tip(F)) * self.w

    @property
    def _Phi_dense(self) -> np.ndarray:
        """Phi as a dense array, cached per discretization: the dense Jacobians use it
        every call, on models made by :meth:`with_params` (which share the discretization)."""
        return _dense_forms(self.disc)[0]

    @property
    def _K_dense(self) -> np.ndarray:
        """The bending matrix K as a dense array, cached like :attr:`_Phi_dense`."""
        return _dense_forms(self.disc)[1]

    def _phi_field(self, coef: np.ndarray) -> np.ndarray:
        """(coef[:, c] * Phi) stacked as shape (n_q, 2, n)."""
        Phi = self._Phi_dense
        return coef[:, :, None] * Phi[:, None, :]

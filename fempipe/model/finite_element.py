"""Lagrange finite elements of any degree on a scikit-fem line mesh: :class:`FiniteElement`.

The package's discretization behind the contract of :mod:`fempipe.model.discretization`
(the other is :class:`~fempipe.model.modal.Modal`).  Derivation: docs/theory/weak_form.md.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from fempipe.model.quadrature import LineQuadrature

if TYPE_CHECKING:  # imported where used: importing fempipe does not load scipy
    import scipy.sparse as sp

__all__ = ["FiniteElement"]


class FiniteElement:
    """Lagrange finite elements of degree ``degree`` (1 to 10) on a line mesh of [0, 1].

    ``n_elements`` uniform elements, or the increasing ``nodes`` from 0 to 1 of a graded mesh.
    ``n_gauss`` points per element (default ``2 * degree``, >= 2) keep the nodal
    superconvergence O(h^(2k)) of P_k.  ``K`` and ``gram`` are assembled by scikit-fem on the
    same Gauss rule as the nonlinear terms; theta(0) = 0 removes the ``clamp`` dofs.
    """

    def __init__(
        self,
        n_elements: int = 16,
        degree: int = 2,
        nodes: np.ndarray | None = None,
        n_gauss: int | None = None,
    ) -> None:
        import scipy.sparse as sp
        from skfem import Basis, BilinearForm, ElementLineP1, ElementLineP2, MeshLine

        degree = int(degree)
        if not 1 <= degree <= 10:
            raise ValueError(f"degree must be an integer from 1 to 10, got {degree}")
        if nodes is None:
            if int(n_elements) < 1:
                raise ValueError(f"n_elements must be >= 1, got {n_elements}")
            nodes = np.linspace(0.0, 1.0, int(n_elements) + 1)
        nodes = np.asarray(nodes, dtype=float)
        if nodes.ndim != 1 or nodes.size < 2 or not np.all(np.diff(nodes) > 0):
            raise ValueError("nodes must be a strictly increasing 1-D array of >= 2 points")
        if abs(nodes[0]) > 1e-12 or abs(nodes[-1] - 1.0) > 1e-12:
            raise ValueError("nodes must start at 0 and end at 1")
        nodes = nodes.copy()
        nodes[0], nodes[-1] = 0.0, 1.0
        self.degree = degree
        self.nodes = nodes
        self.n_elements = nodes.size - 1
        self.n_gauss = int(n_gauss) if n_gauss is not None else max(2, 2 * degree)
        if self.n_gauss < degree + 1:
            raise ValueError(
                f"n_gauss must be >= degree + 1 = {degree + 1} so that the integration "
                f"operators are exact for P{degree}, got {self.n_gauss}"
            )
        element = {1: ElementLineP1, 2: ElementLineP2}.get(degree)
        element = element() if element is not None else _element_line_pp(degree)
        self.quad = LineQuadrature(nodes, self.n_gauss)
        self.mesh = MeshLine(nodes).with_boundaries(
            {"clamp": lambda x: x[0] == 0.0, "free_end": lambda x: x[0] == 1.0}
        )
        # The reference cell of MeshLine is [0, 1], that of LineQuadrature too.
        self.basis = Basis(
            self.mesh, element, quadrature=(self.quad.ref_points[None, :], self.quad.ref_weights)
        )
        N_all = self.basis.N
        self.n_all = N_all
        self.free = self.basis.complement_dofs(self.basis.get_dofs("clamp"))
        self.n = self.free.size
        # The basis was built on the package's Gauss rule, so its shape-function
        # values at its own quadrature points *are* Phi at the Gauss points, cell
        # by cell in the order of LineQuadrature.x: no point location is needed
        # (basis.probes, for arbitrary points, searches every cell for every
        # point, O(n_q n_el)).
        values = np.array([np.asarray(self.basis.basis[k][0]) for k in range(self.basis.Nbfun)])
        n_el, n_qp = values.shape[1:]
        rows = np.broadcast_to(np.arange(n_el * n_qp).reshape(n_el, n_qp), values.shape)
        cols = np.broadcast_to(self.basis.element_dofs[:, :, None], values.shape)
        Phi_all = sp.csr_matrix(
            (values.ravel(), (rows.ravel(), cols.ravel())), shape=(n_el * n_qp, N_all)
        )
        self.Phi = Phi_all[:, self.free]
        grads = np.array(
            [np.asarray(self.basis.basis[k][0].grad[0]) for k in range(self.basis.Nbfun)]
        )
        dPhi_all = sp.csr_matrix(
            (grads.ravel(), (rows.ravel(), cols.ravel())), shape=(n_el * n_qp, N_all)
        )
        self.dPhi = dPhi_all[:, self.free]
        # A Lagrange vertex dof is the value of theta there: theta(1) is the
        # dof of the free end.
        tip = np.zeros(N_all)
        tip[self.basis.get_dofs("free_end").all()] = 1.0
        self.tip = tip[self.free]

        @BilinearForm
        def bending(u, v, w):
            return u.grad[0] * v.grad[0]

        @BilinearForm
        def l2(u, v, w):
            return u * v

        self.K = bending.assemble(self.basis)[self.free][:, self.free].tocsr()
        self.gram = l2.assemble(self.basis)[self.free][:, self.free].tocsr()
        self.sparse = True

    @property
    def name(self) -> str:
        return f"P{self.degree}:{self.n_elements}"

    def full(self, q: np.ndarray) -> np.ndarray:
        """All scikit-fem dofs, the clamped one set to zero; shape (N,) or (N, m)."""
        q = np.asarray(q)
        out = np.zeros((self.n_all,) + q.shape[1:], dtype=q.dtype)
        out[self.free] = q
        return out

    def evaluate(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """theta(xi) at arbitrary points in [0, 1]."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        P = self.basis.probes(xi[None, :])
        return P @ self.full(q)

    def basis_values(self, xi: np.ndarray) -> sp.csr_matrix:
        """phi_j(xi) of the free dofs at a few arbitrary points, sparse, shape (m, n)."""
        import scipy.sparse as sp

        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        P = sp.csr_matrix(self.basis.probes(xi[None, :]))
        return P[:, self.free]

    def refined(self, factor: int = 2) -> FiniteElement:
        """Return a copy with every element split into ``factor`` equal parts."""
        factor = int(factor)
        x = self.nodes
        fine = (x[:-1, None] + np.diff(x)[:, None] * np.arange(factor)[None, :] / factor).ravel()
        return FiniteElement(degree=self.degree, nodes=np.append(fine, 1.0), n_gauss=self.n_gauss)

    def to_dict(self) -> dict:
        return {
            "kind": "fe",
            "element": f"P{self.degree}",
            "degree": self.degree,
            "n_elements": self.n_elements,
            "n_dofs": self.n,
            "n_gauss": self.n_gauss,
            "uniform": bool(np.allclose(np.diff(self.nodes), 1.0 / self.n_elements)),
        }

    def __repr__(self) -> str:
        return f"FiniteElement(degree={self.degree}, n_elements={self.n_elements})"


def _element_line_pp(degree: int):
    """scikit-fem's ``ElementLinePp(degree)`` with its value cache keyed by the points, not their number."""
    # The stock cache, keyed by the number of points only, breaks FiniteElement.evaluate at as
    # many points as a cell has Gauss points (scikit-fem 12.0.2).  Built on first use, so that
    # importing fempipe does not import scikit-fem; found by name when unpickled.
    # Build the class once: a second class of the same qualified name would make
    # every element made from the first one unpicklable.
    cls = globals().get("_ElementLinePp") or __getattr__("_ElementLinePp")
    return cls(degree)


def __getattr__(name: str):
    if name != "_ElementLinePp":
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    from skfem import ElementLinePp

    class _ElementLinePp(ElementLinePp):
        def lbasis(self, X, i):
            key = (X.shape, X.tobytes())
            if key != getattr(self, "_points_key", None):
                self.P, self.dP = self._reval_legendre(X[0, :], self.p)
                self._points_key = key
            return self.P[i], self.dP[i]

    _ElementLinePp.__module__ = __name__
    _ElementLinePp.__qualname__ = name
    globals()[name] = _ElementLinePp
    return _ElementLinePp

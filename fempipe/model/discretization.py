"""The two discretisations of theta(xi) behind one contract.

A discretisation represents theta = sum_j phi_j(xi) q_j with theta(0) = 0
built in, and supplies everything the solvers use (:class:`Discretization`;
nothing else is ever asked of it):

``n``          number of unknowns q_j;
``quad``       :class:`~fempipe.model.quadrature.LineQuadrature` (points, weights,
               integration operators);
``Phi``        basis values at the quadrature points, shape (n_q, n);
``tip``        phi_j(1), shape (n,);
``dPhi``       basis derivatives phi_j' at the quadrature points, shape
               (n_q, n) (the static curvature of the out-of-plane problem,
               :mod:`fempipe.model.out_of_plane`);
``K``          bending stiffness ``\\int phi_i' phi_j'``, shape (n, n);
``gram``       L2 Gram matrix ``\\int phi_i phi_j``, shape (n, n): the metric
               of theta (arclength of continuation, L2 projections);
``sparse``     whether ``Phi``, ``K`` and ``gram`` are scipy sparse matrices;
``name``       the CLI spelling (``P3:16``, ``modal:4``, ``modal-beam:4``;
               :func:`discretization_from_name` is the inverse);
``evaluate``   theta at arbitrary points, for post-processing;
``basis_values``
               phi_j at arbitrary points, shape (m, n), sparse for finite
               elements: the Gauss rule on [0, xi_s] of a spring inside a
               cell (:meth:`~fempipe.model.operators.PipeModel.spring`);
``to_dict``    a JSON-able description.

:class:`FiniteElement` is the package's point: 1-D Lagrange elements of any
degree on a scikit-fem ``MeshLine``.  :class:`Modal` is the paper's sine-mode
Galerkin method (Eq. (22)), phi_r = sin((2r - 1) pi xi / 2), or with
``basis="beam"`` the same method on the slopes of the clamped-free beam modes
(error N^-4 instead of N^-3, :data:`EXPECTED_ORDER`).  Solvers only use the
contract and never ask which one they have.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from .quadrature import LineQuadrature

if TYPE_CHECKING:  # imported where used: importing fempipe does not load scipy
    import scipy.sparse as sp

__all__ = [
    "EXPECTED_ORDER",
    "Discretization",
    "FiniteElement",
    "Modal",
    "beam_mode_slopes",
    "beam_roots",
    "discretization_from_name",
    "parse_discretization",
    "parse_fe_spec",
]


@runtime_checkable
class Discretization(Protocol):
    """What every solver of the package uses of a discretisation (module docstring)."""

    n: int
    quad: LineQuadrature
    Phi: np.ndarray | sp.csr_matrix
    dPhi: np.ndarray | sp.csr_matrix
    tip: np.ndarray
    K: np.ndarray | sp.csr_matrix
    gram: np.ndarray | sp.csr_matrix
    sparse: bool

    @property
    def name(self) -> str: ...

    def evaluate(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray: ...

    def basis_values(self, xi: np.ndarray) -> np.ndarray | sp.csr_matrix: ...

    def to_dict(self) -> dict: ...


class FiniteElement:
    """Lagrange finite elements of degree ``degree`` on a line mesh of [0, 1].

    Parameters
    ----------
    n_elements : int, optional
        Number of uniform elements (ignored if ``nodes`` is given).
    degree : int
        Polynomial degree (1 to 10).  P1, P2 use scikit-fem's ``ElementLineP1``,
        ``ElementLineP2``; higher degrees ``ElementLinePp``.
    nodes : array_like, optional
        Mesh nodes for graded meshes; must start at 0, end at 1, increase.
    n_gauss : int, optional
        Gauss points per element for all integrals.  The default ``2 * degree``
        (at least 2) keeps the nodal superconvergence O(h^(2k)) of P_k in the
        static tip values and eigenvalues: the integration operators interpolate
        at the n_g Gauss points, so their local error is O(h^(n_g + 1)), and
        the Gauss sums themselves are exact to degree 2 n_g - 1.

    Notes
    -----
    scikit-fem assembles with the package's own Gauss rule (passed to
    ``Basis`` as ``quadrature``), so its forms (``K``, ``gram``) and the
    nonlinear terms integrated on :attr:`quad` use the same points and weights.
    The Dirichlet condition theta(0) = 0 is imposed by removing the dofs of
    the boundary named ``clamp`` (``basis.get_dofs``); theta'(1) = 0 is
    natural in the weak form.
    """

    def __init__(
        self,
        n_elements: int = 16,
        degree: int = 2,
        nodes: np.ndarray | None = None,
        n_gauss: int | None = None,
    ) -> None:
        import scipy.sparse as sp
        from skfem import (
            Basis,
            BilinearForm,
            ElementLineP1,
            ElementLineP2,
            MeshLine,
        )

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
        """phi_j(xi) of the free dofs at arbitrary points, sparse, shape (m, n).

        ``basis.probes`` locates every point in every cell (O(m n_el)): meant
        for a few points, built once (the Gauss rule of a part cell).
        """
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


class Modal:
    """Modal Galerkin discretisation: N global modes of [0, 1] (module docstring).

    Two bases, both with theta(0) = 0 and theta'(1) = 0 built in:

    ``basis="sine"`` (default): the paper's modes, Eq. (22),
        phi_r(xi) = sin(k_r xi), k_r = (2r - 1) pi / 2, r = 1..N: the
        clamped-free string modes.  They also have theta''(0) = 0, which the
        true solution does not, so the method converges as N^-3 (README,
        "Conventions and derivations").  K = diag(k_r^2 / 2).
    ``basis="beam"``: the slopes of the clamped-free Euler-Bernoulli beam modes,
        psi_r(xi) = phi_r'(xi) / lambda_r with
        phi_r = cosh(lambda_r xi) - cos(lambda_r xi)
        - s_r (sinh(lambda_r xi) - sin(lambda_r xi)),
        s_r = (cosh lambda_r + cos lambda_r) / (sinh lambda_r + sin lambda_r)
        and cos(lambda_r) cosh(lambda_r) = -1 (:func:`beam_roots`).  theta =
        w' for the beam deflection w, so psi_r also has theta''(1) = 0 (no
        shear force at the free end, which the true solution satisfies) and
        theta'''(0) = 0 (from w(0) = 0 and w'''' = lambda^4 w) instead of
        theta''(0) = 0.  The psi_r are the exact modes of the straight pipe
        without flow and gravity, so the frequencies of the linear problem at
        v = gamma = 0 are exact.  With ``\\int phi_r^2 = 1`` (the textbook
        normalisation of phi_r), integrating by parts twice with the beam's
        boundary conditions gives ``\\int psi_i' psi_j' =
        \\int phi_i'' phi_j'' / (lambda_i lambda_j) = lambda_i^2 delta_ij``:
        K = diag(lambda_r^2).  The Gram matrix is not diagonal.  The modes
        are evaluated in a form without overflow or cancellation
        (:func:`beam_mode_slopes`).

    Parameters
    ----------
    n_modes : int
        N >= 1.
    n_cells, n_gauss : int, optional
        The quadrature used for the nonlinear integrals.  The default
        (max(32, 4N) cells of 8 Gauss points) integrates either basis and
        the nonlinear terms to near round-off (for the beam modes also their
        boundary layer e^{-lambda_r xi}: at N = 64, lambda_N h = 0.78), so
        the error measured is the modal truncation alone.
    basis : {"sine", "beam"}
        Keyword only.

    Attributes
    ----------
    k : ndarray, shape (N,)
        Wavenumbers of the modes: k_r = (2r - 1) pi / 2 (sine) or
        lambda_r (beam).
    """

    #: The accepted values of ``basis``.
    BASES = ("sine", "beam")

    def __init__(
        self,
        n_modes: int = 4,
        n_cells: int | None = None,
        n_gauss: int = 8,
        *,
        basis: str = "sine",
    ) -> None:
        n_modes = int(n_modes)
        if n_modes < 1:
            raise ValueError(f"n_modes must be >= 1, got {n_modes}")
        if basis not in self.BASES:
            raise ValueError(f"basis must be one of {', '.join(self.BASES)}, got {basis!r}")
        self.n_modes = n_modes
        self.n = n_modes
        self.basis = basis
        self.quad = LineQuadrature.uniform(n_cells or max(32, 4 * n_modes), n_gauss)
        x = self.quad.x
        if basis == "sine":
            self.k = (2.0 * np.arange(1, n_modes + 1) - 1.0) * np.pi / 2.0
            self.Phi = np.sin(np.outer(x, self.k))
            self.dPhi = np.cos(np.outer(x, self.k)) * self.k
            self.tip = np.sin(self.k)
            # \int_0^1 phi_i' phi_j' = k_i^2 / 2 delta_ij (orthogonal cosines).
            self.K = np.diag(self.k**2 / 2.0)
        else:
            self.k = beam_roots(n_modes)
            self.Phi = beam_mode_slopes(self.k, x)
            self.dPhi = beam_mode_slopes(self.k, x, derivative=1)
            self.tip = beam_mode_slopes(self.k, [1.0])[0]
            # \int_0^1 psi_i' psi_j' = lambda_i^2 delta_ij (class docstring).
            self.K = np.diag(self.k**2)
        # \int_0^1 phi_i phi_j (delta_ij / 2 for the sines); summed by the
        # quadrature like every integral of the nonlinear terms.
        self.gram = (self.Phi.T * self.quad.w) @ self.Phi
        self.sparse = False

    @property
    def name(self) -> str:
        return f"modal:{self.n_modes}" if self.basis == "sine" else f"modal-beam:{self.n_modes}"

    @property
    def expected_order(self) -> float:
        """Order p of the error ~ N^-p in tip values, v_cr and eigenvalues.

        :data:`EXPECTED_ORDER`: 3 for the sine modes, 4 for the beam modes
        (README, "Convergence of the two modal bases").
        """
        return EXPECTED_ORDER[self.basis]

    def evaluate(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray:
        """theta(xi) at arbitrary points in [0, 1]."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        if self.basis == "sine":
            return np.sin(np.outer(xi, self.k)) @ np.asarray(q)
        return beam_mode_slopes(self.k, xi) @ np.asarray(q)

    def basis_values(self, xi: np.ndarray) -> np.ndarray:
        """phi_r(xi) at arbitrary points, analytic, shape (m, N)."""
        xi = np.atleast_1d(np.asarray(xi, dtype=float))
        if self.basis == "sine":
            return np.sin(np.outer(xi, self.k))
        return beam_mode_slopes(self.k, xi)

    def refined(self, factor: int = 2) -> Modal:
        """Return the same basis with ``factor`` times as many modes (default quadrature)."""
        return Modal(int(factor) * self.n_modes, basis=self.basis)

    def to_dict(self) -> dict:
        return {
            "kind": "modal",
            "n_modes": self.n_modes,
            "n_dofs": self.n,
            "n_cells": self.quad.n_cells,
            "n_gauss": self.quad.n_gauss,
            "basis": self.basis,
        }

    def __repr__(self) -> str:
        return f"Modal(n_modes={self.n_modes}, basis={self.basis!r})"


#: Order p of the error ~ N^-p of a modal discretisation in tip values, v_cr
#: and eigenvalues, per basis (README, "Convergence of the two modal bases").
EXPECTED_ORDER = {"sine": 3.0, "beam": 4.0}


def beam_roots(n: int) -> np.ndarray:
    """lambda_r, r = 1..n: the roots of cos(lambda) cosh(lambda) = -1.

    Solved as cos(lambda) + 1 / cosh(lambda) = 0 (no overflow) by Brent's
    method in [c - 0.4, c + 0.4], c = (2r - 1) pi / 2, to machine precision:
    1.87510407, 4.69409113, 7.85475744, 10.99554073, ...  lambda_r - c is
    about (-1)^(r+1) 2 e^{-c}, below the rounding of c from r = 13 on.

    Parameters
    ----------
    n : int
        Number of roots, >= 0.

    Returns
    -------
    ndarray, shape (n,)
    """
    from fempipe.core.rootfinding import brentq

    out = np.empty(int(n))
    for r in range(1, int(n) + 1):
        c = (2 * r - 1) * np.pi / 2.0
        out[r - 1] = brentq(lambda x: np.cos(x) + 1.0 / np.cosh(x), c - 0.4, c + 0.4, xtol=1e-300)
    return out


def beam_mode_slopes(lam: np.ndarray, xi: np.ndarray, derivative: int = 0) -> np.ndarray:
    """psi_r(xi) = phi_r'(xi) / lambda_r or a derivative, shape (len(xi), len(lam)).

    phi_r is the clamped-free beam mode of :class:`Modal` (``basis="beam"``).
    With E = e^{-lambda xi}, E+ = e^{lambda (xi - 1)}, E- = e^{-lambda (xi + 1)},
    c = sin(lambda) - cos(lambda) - e^{-lambda} and
    D = 1 - e^{-2 lambda} + 2 e^{-lambda} sin(lambda), so that
    sinh(lambda) + sin(lambda) = e^lambda D / 2 and 1 - s = 2 c e^{-lambda} / D,
    the textbook form becomes, with C = cos(lambda xi), S = sin(lambda xi),

    ====================  =================================================
    psi                   (C - E) + S + (c/D) (E+ + E- - 2 e^{-lambda} C)
    psi' / lambda         E + C - S + (c/D) (E+ - E- + 2 e^{-lambda} S)
    psi'' / lambda^2      -E - S - C + (c/D) (E+ + E- + 2 e^{-lambda} C)
    psi''' / lambda^3     E - C + S + (c/D) (E+ - E- - 2 e^{-lambda} S)
    ====================  =================================================

    Every exponential is at most 1 and D >= 1 - 3 e^{-lambda_1} > 0.5, so
    the values are accurate to round-off for any lambda and |psi| < 4;
    psi(0) is exactly 0.  (The textbook form loses log10(cosh lambda) digits,
    all of them from lambda ~ 37, r = 12, on, and overflows from r = 226.)

    Parameters
    ----------
    lam : array_like, shape (N,)
        Roots of cos(lambda) cosh(lambda) = -1 (:func:`beam_roots`).
    xi : array_like, shape (m,)
        Points of [0, 1].
    derivative : int
        0 to 3.

    Returns
    -------
    ndarray, shape (m, N)
    """
    if derivative not in (0, 1, 2, 3):
        raise ValueError(f"derivative must be 0, 1, 2 or 3, got {derivative}")
    lam = np.atleast_1d(np.asarray(lam, dtype=float))[None, :]
    xi = np.atleast_1d(np.asarray(xi, dtype=float))[:, None]
    e1 = np.exp(-lam)
    sl = np.sin(lam)
    c_over_d = (sl - np.cos(lam) - e1) / (1.0 - e1 * e1 + 2.0 * e1 * sl)
    lx = lam * xi
    C, S, E = np.cos(lx), np.sin(lx), np.exp(-lx)
    Ep, Em = np.exp(lam * (xi - 1.0)), np.exp(-lam * (xi + 1.0))
    if derivative == 0:
        return (C - E) + S + c_over_d * (Ep + Em - 2.0 * e1 * C)
    if derivative == 1:
        out = E + C - S + c_over_d * (Ep - Em + 2.0 * e1 * S)
    elif derivative == 2:
        out = -E - S - C + c_over_d * (Ep + Em + 2.0 * e1 * C)
    else:
        out = E - C + S + c_over_d * (Ep - Em - 2.0 * e1 * S)
    return out * lam**derivative


_FE_RE = re.compile(r"^[Pp](\d+)\s*:\s*(\d+)$")


def parse_fe_spec(text: str) -> tuple[int, int]:
    """``(degree, n_elements)`` of a finite-element spelling ``Pk:n`` (e.g. ``"P3:16"``).

    Checked without building the mesh (the command line uses it to count the
    unknowns k n before any work).

    Raises
    ------
    ValueError
        With a message naming ``--fe`` and the allowed form.
    """
    m = _FE_RE.match(str(text).strip())
    if not m:
        raise ValueError(
            f"--fe expects Pk:n with degree k in 1..10 and n >= 1 elements (e.g. P2:16), "
            f"got {text!r}"
        )
    degree, n_el = int(m.group(1)), int(m.group(2))
    if not 1 <= degree <= 10:
        raise ValueError(f"--fe element degree must be 1..10, got P{degree}")
    if n_el < 1:
        raise ValueError(f"--fe number of elements must be >= 1, got {n_el}")
    return degree, n_el


def parse_discretization(
    fe: str | None = None, modal: int | str | None = None, basis: str = "sine"
) -> FiniteElement | Modal:
    """Build a discretisation from the CLI spellings ``--fe P2:16`` / ``--modal 4 [--basis beam]``.

    Parameters
    ----------
    fe : str, optional
        ``Pk:n``; the default :data:`DEFAULT_FE` when neither is given.
    modal : int or str, optional
        Number of modes N >= 1.
    basis : {"sine", "beam"}
        The modal basis (:class:`Modal`); only the default ``"sine"`` goes
        without ``modal``.

    Raises
    ------
    ValueError
        With a message naming the option and the allowed forms.
    """
    if basis not in Modal.BASES:
        raise ValueError(f"--basis expects one of {', '.join(Modal.BASES)}, got {basis!r}")
    if fe is not None and modal is not None:
        raise ValueError("--fe and --modal are mutually exclusive")
    if modal is not None:
        try:
            n = int(str(modal))
        except ValueError:
            raise ValueError(f"--modal expects a number of modes >= 1, got {modal!r}") from None
        if n < 1:
            raise ValueError(f"--modal expects a number of modes >= 1, got {n}")
        return Modal(n, basis=basis)
    if basis != "sine":
        raise ValueError(
            f"--basis {basis} chooses the modal basis and needs --modal N "
            "(finite elements have no --basis)"
        )
    degree, n_el = parse_fe_spec(fe if fe is not None else DEFAULT_FE)
    return FiniteElement(n_el, degree)


_NAME_RE = re.compile(r"^modal(?:-(sine|beam))?\s*:\s*(\d+)$")


def discretization_from_name(name: str) -> FiniteElement | Modal:
    """The inverse of ``disc.name``: ``"P3:16"``, ``"modal:4"`` or ``"modal-beam:4"``.

    Raises
    ------
    ValueError
        For any other spelling.
    """
    m = _NAME_RE.match(str(name).strip())
    if m:
        return Modal(int(m.group(2)), basis=m.group(1) or "sine")
    try:
        degree, n_el = parse_fe_spec(name)
    except ValueError:
        raise ValueError(
            f"a discretisation name is Pk:n, modal:N or modal-beam:N, got {name!r}"
        ) from None
    return FiniteElement(n_el, degree)


#: The default discretisation; its static tip error is below 1e-7 (see
#: ``tests/test_static.py::test_default_discretization_accuracy``).
DEFAULT_FE = "P3:16"


def _element_line_pp(degree: int):
    """scikit-fem's ``ElementLinePp(degree)`` with its value cache keyed by the points.

    ``ElementLinePp`` caches its Legendre values and reuses them whenever the
    next call has as many points along the second axis, whatever the points
    and the array's shape: :meth:`FiniteElement.evaluate` at exactly as many
    points as a cell has Gauss points (``basis.probes``, points shaped
    (1, m, 1), after the assembly's (1, m)) then fails with a broadcasting
    error (scikit-fem 12.0.2).  The subclass keys the cache by the shape and
    the values of the points.  It is built on first use, so that importing
    fempipe does not import scikit-fem, and found by name (module
    ``__getattr__``) when a discretisation is unpickled in a worker process.
    """
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

"""The two discretizations of theta(xi) behind one contract, and their CLI spellings.

A discretization represents theta = sum_j phi_j(xi) q_j with theta(0) = 0 built in and
supplies everything the solvers use (:class:`Discretization`, whose members are the whole
contract); solvers never ask which one they have.  :class:`FiniteElement` is the package's
point: 1-D Lagrange elements of any degree on a scikit-fem ``MeshLine``.  :class:`Modal` is
the paper's sine-mode Galerkin method (Eq. (22)), phi_r = sin((2r - 1) pi xi / 2), or with
``basis="beam"`` the same method on the slopes of the clamped-free beam modes (orders:
:data:`EXPECTED_ORDER`; docs/theory/convergence.md).

This module holds the contract and the CLI spellings (:func:`parse_discretization`,
:func:`discretization_from_name`); the two discretizations are in
:mod:`fempipe.model.finite_element` and :mod:`fempipe.model.modal` (re-exported here).
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from .finite_element import FiniteElement
from .modal import EXPECTED_ORDER, Modal, beam_mode_slopes, beam_roots
from .quadrature import LineQuadrature

if TYPE_CHECKING:  # imported where used: importing fempipe does not load scipy
    import scipy.sparse as sp

__all__ = [
    "EXPECTED_ORDER",
    "Discretization",
    "FiniteElement",
    "Modal",
    "DEFAULT_FE",
    "beam_mode_slopes",
    "beam_roots",
    "discretization_from_name",
    "parse_discretization",
    "parse_fe_spec",
]


@runtime_checkable
class Discretization(Protocol):
    """What every solver of the package uses of a discretization; nothing else is asked of it.

    Attributes
    ----------
    n : int
        Number of unknowns q_j.
    quad : LineQuadrature
        Points, weights and integration operators (:mod:`fempipe.model.quadrature`).
    Phi : ndarray or sparse matrix, shape (n_q, n)
        Basis values at the quadrature points.
    dPhi : ndarray or sparse matrix, shape (n_q, n)
        Basis derivatives phi_j' at the quadrature points (the static curvature of the
        out-of-plane problem, :mod:`fempipe.model.out_of_plane`).
    tip : ndarray, shape (n,)
        phi_j(1).
    K : ndarray or sparse matrix, shape (n, n)
        Bending stiffness ``\\int phi_i' phi_j'``.
    gram : ndarray or sparse matrix, shape (n, n)
        L2 Gram matrix ``\\int phi_i phi_j``: the metric of theta (arclength of
        continuation, L2 projections).
    sparse : bool
        Whether ``Phi``, ``K`` and ``gram`` are scipy sparse matrices.
    name : str
        The CLI spelling (``P3:16``, ``modal:4``, ``modal-beam:4``;
        :func:`discretization_from_name` is the inverse).

    Methods
    -------
    evaluate(q, xi)
        theta at arbitrary points, for post-processing.
    basis_values(xi)
        phi_j at arbitrary points, shape (m, n), sparse for finite elements: the Gauss rule
        on [0, xi_s] of a spring inside a cell
        (:meth:`~fempipe.model.operators.PipeModel.spring`).
    to_dict()
        A JSON-able description.
    """

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
    """Build a discretization from the CLI spellings ``--fe P2:16`` / ``--modal 4 [--basis beam]``.

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
            f"a discretization name is Pk:n, modal:N or modal-beam:N, got {name!r}"
        ) from None
    return FiniteElement(n_el, degree)


#: The default discretization; its static tip error is below 1e-7 (see
#: ``tests/test_static.py::test_default_discretization_accuracy``).
DEFAULT_FE = "P3:16"

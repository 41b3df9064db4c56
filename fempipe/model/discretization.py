"""The two discretizations of theta(xi) behind one contract, and their CLI spellings.

A discretization represents theta = sum_j phi_j(xi) q_j with theta(0) = 0 built in and
supplies all the solvers use (:class:`Discretization`).  :class:`FiniteElement`: Lagrange
elements of any degree (:mod:`fempipe.model.finite_element`); :class:`Modal`: the paper's
Galerkin method, Eq. (22), on sine or beam modes (:mod:`fempipe.model.modal`); both
re-exported here with :func:`parse_discretization` and :func:`discretization_from_name`.

Derivation: docs/theory/weak_form.md; orders: docs/theory/convergence.md.
"""

from __future__ import annotations

import re
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from fempipe.model.finite_element import FiniteElement
from fempipe.model.modal import EXPECTED_ORDER, Modal, beam_mode_slopes, beam_roots
from fempipe.model.quadrature import LineQuadrature

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
    r"""What every solver of the package uses of a discretization; nothing else is asked of it."""

    n: int  # number of unknowns q_j
    quad: LineQuadrature  # points, weights and integration operators
    Phi: np.ndarray | sp.csr_matrix  # phi_j at the quadrature points, shape (n_q, n)
    dPhi: np.ndarray | sp.csr_matrix  # phi_j' there
    tip: np.ndarray  # phi_j(1), shape (n,)
    K: np.ndarray | sp.csr_matrix  # bending stiffness \int phi_i' phi_j', shape (n, n)
    gram: np.ndarray | sp.csr_matrix  # \int phi_i phi_j, the metric of theta
    sparse: bool  # whether Phi, K and gram are sparse

    @property
    def name(self) -> str: ...  # the CLI spelling: P3:16, modal:4, modal-beam:4

    def evaluate(self, q: np.ndarray, xi: np.ndarray) -> np.ndarray: ...  # theta at xi

    def basis_values(self, xi: np.ndarray) -> np.ndarray | sp.csr_matrix: ...  # (m, n)

    def to_dict(self) -> dict: ...  # a JSON-able description


_FE_RE = re.compile(r"^[Pp](\d+)\s*:\s*(\d+)$")


def parse_fe_spec(text: str) -> tuple[int, int]:
    """``(degree, n_elements)`` of ``Pk:n`` without building the mesh; ValueError naming ``--fe``."""
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
    """Build a discretization from ``--fe Pk:n`` (:data:`DEFAULT_FE` when neither is given) or
    ``--modal N [--basis beam]``; ValueError naming the option and the allowed forms."""
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
    """The inverse of ``disc.name`` (``"P3:16"``, ``"modal:4"``, ``"modal-beam:4"``); ValueError otherwise."""
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

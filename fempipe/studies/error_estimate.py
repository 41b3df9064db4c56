"""Error estimates of reported numbers from one refinement (the Grid Convergence Index).

A number Q_h computed on a discretization (the coarse, reported value) is computed again on a
refined one (:func:`refine`: finite elements h-refined, the modal method with twice the modes,
plus one for an odd N), and its error is estimated by Roache's Grid Convergence Index for a
two-grid study, stated for the coarse grid (:func:`estimate`):

    err(Q_h) = max(Fs |Q_h - Q_{h/r}| r^p / (r^p - 1), floor),     Fs = 3,

with the refinement ratio r (:func:`refinement_ratio`), the theoretical order p of the error
(:func:`expected_order`; without one the bracket is 1) and the floor the solver's tolerance
on the value, below which a difference says nothing about the discretization.
:class:`ErrorEstimate` describes how an estimate was formed, for the JSON of the commands;
:mod:`fempipe.studies.estimates` attaches estimates to whole results, as ``fempipe static``,
``critical`` and ``simulate`` report them with ``--error-estimate``.

Derivation, references and the measured reliability: docs/cli/options.md, "Error estimates".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.model.discretization import FiniteElement, Modal

__all__ = [
    "RATIO",
    "SAFETY_FACTOR",
    "ErrorEstimate",
    "describe",
    "estimate",
    "expected_order",
    "match_events",
    "refine",
    "refinement_ratio",
]

#: Roache's safety factor for a study with two grids (docs/cli/options.md, "Error estimates").
SAFETY_FACTOR = 3.0
#: The refinement ratio of :func:`refine`: elements halved, modes doubled.
RATIO = 2.0
#: The order of the sine modes in N (docs, "Why the sine modes converge only
#: algebraically").
SINE_ORDER = 3.0


def _modal_basis(disc: Modal) -> str:
    """The name of a modal basis, ``"sine"`` for the paper's modes.

    Read from the attribute ``basis`` (a name) or, failing that, from
    ``to_dict()["basis"]``, so that a class without the attribute is the
    paper's sine basis.
    """
    basis = getattr(disc, "basis", None)
    if isinstance(basis, str):
        return basis
    basis = disc.to_dict().get("basis")
    return basis if isinstance(basis, str) else "sine"


def refine(disc):
    """The refined discretization of the estimate.

    Parameters
    ----------
    disc : FiniteElement or Modal

    Returns
    -------
    FiniteElement or Modal
        ``disc.refined(2)`` for finite elements (every element halved, the
        same degree and Gauss rule); ``Modal(2 N)`` for even N and
        ``Modal(2 N + 1)`` for odd N, with the same basis and Gauss points per
        cell, for the modal method (:func:`refinement_ratio`).

    Raises
    ------
    TypeError
        For another kind of discretization.

    Examples
    --------
    >>> from fempipe.model.discretization import FiniteElement
    >>> disc = FiniteElement(16, 3)
    >>> refine(disc).name, expected_order(disc)
    ('P3:32', 6.0)
    """
    if isinstance(disc, FiniteElement):
        return disc.refined(int(RATIO))
    if isinstance(disc, Modal):
        # 2N + 1 for odd N: the error of the sine modes alternates with the
        # parity of N, so an odd N is compared with an odd refinement (with
        # 2N the estimate missed the error at odd N, ratios down to 0.17).
        n = int(RATIO) * disc.n_modes + disc.n_modes % 2
        basis = _modal_basis(disc)
        if basis == "sine":
            return type(disc)(n, n_gauss=disc.quad.n_gauss)
        return type(disc)(n, n_gauss=disc.quad.n_gauss, basis=basis)
    raise TypeError(f"no refinement is defined for {type(disc).__name__}")


def refinement_ratio(disc) -> float:
    """r = h / h_refined (2 for elements) or N_refined / N (2, or (2N + 1)/N for odd N)."""
    if isinstance(disc, Modal):
        return refine(disc).n_modes / disc.n_modes
    return RATIO


def expected_order(disc, params=None) -> float | None:
    """The theoretical order p of the error in the refinement of :func:`refine`.

    Parameters
    ----------
    disc : FiniteElement or Modal
    params : Params, optional
        The case: some variants of the pipe lower the order (below).

    Returns
    -------
    float or None
        2k for Lagrange P_k elements (error ~ h^(2k) of tip values,
        eigenvalues and v_cr); 3 for the sine modes (error ~ N^-3); for
        another modal basis the class's ``expected_order`` if it states one,
        else None (unknown).  With ``params``: a spring inside an element
        makes the second derivative of theta jump inside it, and P_k then
        converges as h^3 at best (min(2k, 3)); every beam mode has
        theta''(1) = 0, which an end mass or a spring at the tip violates
        (order 2), and a continuous third derivative, which a spring inside
        the pipe violates (order 3).  The sine modes keep N^-3 (docs,
        "Variants of the pipe").
    """
    base = _paper_order(disc)
    if params is None or base is None:
        return base
    springs = [xi for kappa, xi in params.springs if kappa > 0.0]
    if isinstance(disc, FiniteElement):
        inside = any(not np.isclose(disc.nodes, xi, rtol=0.0, atol=1e-12).any() for xi in springs)
        return min(base, 3.0) if inside else base
    if _modal_basis(disc) == "beam":
        if params.end_mass > 0.0 or any(xi == 1.0 for xi in springs):
            return min(base, 2.0)
        if springs:
            return min(base, 3.0)
    return base


def _paper_order(disc) -> float | None:
    """The order for the paper's pipe (no variant)."""
    if isinstance(disc, FiniteElement):
        return 2.0 * disc.degree
    if isinstance(disc, Modal):
        stated = getattr(disc, "expected_order", None)
        if callable(stated):
            stated = stated()
        if stated is not None:
            return float(stated)
        return SINE_ORDER if _modal_basis(disc) == "sine" else None
    return None


def estimate(coarse, fine, order: float | None, ratio: float = RATIO, floor=0.0):
    """Grid Convergence Index of the coarse value: its error estimated from one refinement.

    ``max(Fs |coarse - fine| r^p / (r^p - 1), floor)`` with Fs =
    :data:`SAFETY_FACTOR`; without an order (None) the factor r^p / (r^p - 1) is 1.
    If the error of the coarse value is C h^p, |coarse - fine| r^p / (r^p - 1) is that
    error itself once the sequence is asymptotic; Fs = 3 is Roache's factor for two grids,
    where the observed order cannot be checked (docs/cli/options.md, "Error estimates").

    Parameters
    ----------
    coarse, fine : float or array_like
        The reported value and the value on the refined discretization
        (broadcast against each other).
    order : float or None
        Order p of the error in the refinement; None if unknown.
    ratio : float
        Refinement ratio r > 1.
    floor : float or array_like
        Smallest estimate: the solver's tolerance on the value.

    Returns
    -------
    float or ndarray
        A float for scalar input. NaN where a value is NaN.

    Raises
    ------
    ValueError
        If ``ratio <= 1`` or ``order <= 0``.

    Examples
    --------
    >>> estimate(1.0, 1.5, 2.0)  # 3 * 0.5 * 4 / 3
    2.0
    >>> estimate(1.0, 1.0, 2.0, floor=1e-10)  # below the solver's tolerance
    1e-10
    """
    if not ratio > 1.0:
        raise ValueError(f"the refinement ratio must be > 1, got {ratio}")
    if order is None:
        factor = 1.0
    else:
        if not order > 0:
            raise ValueError(f"the order must be > 0 (or None if unknown), got {order}")
        rp = float(ratio) ** float(order)
        factor = rp / (rp - 1.0)
    c = np.asarray(coarse, dtype=float)
    f = np.asarray(fine, dtype=float)
    err = np.fmax(SAFETY_FACTOR * factor * np.abs(c - f), np.asarray(floor, dtype=float))
    err = np.where(np.isnan(c) | np.isnan(f), np.nan, err)
    return float(err) if err.ndim == 0 else err


@dataclass(frozen=True)
class ErrorEstimate:
    """How the error estimates of a result were formed (``"error_estimate"`` in the JSON).

    Attributes
    ----------
    method : {'h-refinement', 'N-doubling'}
    discretization, refined : str
        The reported discretization and the refined one (``P3:16``, ``P3:32``).
    safety_factor : float
    order : float or None
        The order p used (None: unknown, factor 1).
    ratio : float
    floor : str
        What sets the smallest estimate (the solver's tolerance).
    """

    method: str
    discretization: str
    refined: str
    safety_factor: float
    order: float | None
    ratio: float
    floor: str = ""

    @property
    def formula(self) -> str:
        """The formula, with this estimate's numbers."""
        fs, r = f"{self.safety_factor:g}", f"{self.ratio:g}"
        if self.order is None:
            return f"max({fs} |Q - Q_refined|, floor) (order unknown: factor 1)"
        p = f"{self.order:g}"
        return f"max({fs} |Q - Q_refined| {r}^{p} / ({r}^{p} - 1), floor)"

    def to_dict(self) -> dict:
        """``{"method", "discretization", "refined", "safety_factor", "order", "ratio",
        "formula", "floor", "reference"}``."""
        order = self.order
        if order is not None and float(order).is_integer():
            order = int(order)
        return {
            "method": self.method,
            "discretization": self.discretization,
            "refined": self.refined,
            "safety_factor": self.safety_factor,
            "order": order,
            "ratio": self.ratio,
            "formula": self.formula,
            "floor": self.floor,
            "reference": "Roache's Grid Convergence Index for two grids, of the coarse value",
        }


def describe(disc, refined=None, floor: str = "", params=None) -> ErrorEstimate:
    """The :class:`ErrorEstimate` of ``disc`` refined by :func:`refine`.

    Parameters
    ----------
    disc : FiniteElement or Modal
    refined : FiniteElement or Modal, optional
        ``refine(disc)`` if already built.
    floor : str
        What sets the floor of the estimates (stated in the JSON).
    params : Params, optional
        The case, for the order (:func:`expected_order`).
    """
    refined = refine(disc) if refined is None else refined
    return ErrorEstimate(
        method="h-refinement" if isinstance(disc, FiniteElement) else "N-doubling",
        discretization=disc.name,
        refined=refined.name,
        safety_factor=SAFETY_FACTOR,
        order=expected_order(disc, params),
        ratio=refinement_ratio(disc),
        floor=floor,
    )


def match_events(coarse, fine) -> tuple[list[int | None], list[int]]:
    """Pair the stability events of two runs by what they are, not by list position.

    Two events are the same when they have the same branch, type, mode and
    plane (``StabilityEvent`` attributes or dict keys ``branch``, ``type``,
    ``mode``, ``plane``, "in" when absent); the k-th such event of the coarse list (in its order: along
    each branch) is paired with the k-th of the refined list.

    Parameters
    ----------
    coarse, fine : sequence of StabilityEvent or dict

    Returns
    -------
    pairs : list of int or None
        For each coarse event, the index of its refined event, or None.
    unmatched : list of int
        Indices of the refined events that no coarse event is paired with.
    """

    def key(ev):
        get = ev.get if isinstance(ev, dict) else lambda k: getattr(ev, k)
        plane = ev.get("plane", "in") if isinstance(ev, dict) else getattr(ev, "plane", "in")
        return (get("branch"), get("type"), get("mode"), plane)

    available: dict = {}
    for j, ev in enumerate(fine):
        available.setdefault(key(ev), []).append(j)
    pairs: list[int | None] = []
    for ev in coarse:
        queue = available.get(key(ev))
        pairs.append(queue.pop(0) if queue else None)
    used = {j for j in pairs if j is not None}
    return pairs, [j for j in range(len(fine)) if j not in used]

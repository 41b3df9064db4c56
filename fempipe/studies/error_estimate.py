"""Error estimates of reported numbers from one refinement (Roache's Grid Convergence Index).

A number Q_h (the coarse, reported value) is computed again on the refined discretization
(:func:`refine`) and its error estimated for the coarse grid (:func:`estimate`):

    err(Q_h) = max(Fs |Q_h - Q_{h/r}| r^p / (r^p - 1), floor),     Fs = 3,

r the refinement ratio (:func:`refinement_ratio`), p the theoretical order
(:func:`expected_order`; without one the bracket is 1) and the floor the solver's tolerance
on the value.  :class:`ErrorEstimate` describes the method in the JSON;
:func:`fempipe.studies.estimates.estimate_errors` attaches the estimates to a result.
Derivation and measured reliability: docs/cli/options.md, "Error estimates".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.model.discretization import FiniteElement, Modal

#: Suffixes of the keys inserted beside a reported key ``Q``: ``Q_error``, ``Q_refined``.
ERROR, REFINED = "_error", "_refined"
#: The tip values of a static state (dimensionless, Eq. (28)), in table order.
STATIC_TIP_KEYS = ("theta_tip", "eta_tip", "X_tip", "Z_tip", "varsigma_tip")
#: Roache's safety factor for a study with two grids (docs/cli/options.md, "Error estimates").
SAFETY_FACTOR = 3.0
#: The refinement ratio of :func:`refine`: elements halved, modes doubled.
RATIO = 2.0
#: The order of the sine modes in N (docs/theory/convergence.md).
SINE_ORDER = 3.0


def _modal_basis(disc: Modal) -> str:
    """The name of a modal basis (attribute or ``to_dict()["basis"]``), ``"sine"`` by default."""
    basis = getattr(disc, "basis", None)
    if isinstance(basis, str):
        return basis
    basis = disc.to_dict().get("basis")
    return basis if isinstance(basis, str) else "sine"


def refine(disc):
    """The refined discretization: every element halved, or 2N (2N + 1 for odd N) modes.

    The degree, basis and Gauss rule are kept.  Raises TypeError for another discretization.

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
        # 2N + 1 for odd N: the error of the sine modes alternates with the parity of N.
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

    2k for P_k elements, 3 for the sine modes, a modal class's ``expected_order``, else None.
    With ``params`` (docs/theory/variants.md): a spring inside an element gives min(2k, 3);
    for beam modes an end mass or a spring at the tip gives 2, a spring inside 3.
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
        stated = stated() if callable(stated) else stated
        if stated is not None:
            return float(stated)
        return SINE_ORDER if _modal_basis(disc) == "sine" else None
    return None


def estimate(coarse, fine, order: float | None, ratio: float = RATIO, floor=0.0):
    """Grid Convergence Index of the coarse value: ``max(Fs |coarse - fine| r^p / (r^p - 1), floor)``.

    Parameters
    ----------
    coarse, fine : float or array_like
        The reported and the refined value (broadcast; NaN gives NaN).
    order : float or None
        Order p of the error; None if unknown (factor 1).
    ratio : float
        Refinement ratio r > 1.
    floor : float or array_like
        Smallest estimate: the solver's tolerance on the value.

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
    c, f = np.asarray(coarse, dtype=float), np.asarray(fine, dtype=float)
    err = np.fmax(SAFETY_FACTOR * factor * np.abs(c - f), np.asarray(floor, dtype=float))
    err = np.where(np.isnan(c) | np.isnan(f), np.nan, err)
    return float(err) if err.ndim == 0 else err


@dataclass(frozen=True)
class ErrorEstimate:
    """How the error estimates of a result were formed (``"error_estimate"`` in the JSON).

    ``method`` is 'h-refinement' or 'N-doubling'; ``discretization`` and ``refined`` name
    the two discretizations; ``order`` is p (None: unknown); ``floor`` says what sets the
    smallest estimate.
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
        """The JSON entry, with the formula and the reference."""
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
    """The :class:`ErrorEstimate` of ``disc`` refined to ``refined`` (default :func:`refine`);
    ``floor`` says what sets the floor, ``params`` the case (:func:`expected_order`)."""
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
    """Pair the stability events of two runs by branch, type, mode and plane, not by position.

    The k-th coarse event of a kind is paired with the k-th refined one (``StabilityEvent``
    or dict; plane "in" when absent).

    Returns
    -------
    pairs : list of int or None
        For each coarse event, the index of its refined event, or None.
    unmatched : list of int
        The refined events no coarse event is paired with.
    """

    def key(ev):
        get = ev.get if isinstance(ev, dict) else lambda k: getattr(ev, k)
        plane = ev.get("plane", "in") if isinstance(ev, dict) else getattr(ev, "plane", "in")
        return (get("branch"), get("type"), get("mode"), plane)

    available: dict = {}
    for j, ev in enumerate(fine):
        available.setdefault(key(ev), []).append(j)
    pairs = [queue.pop(0) if (queue := available.get(key(ev))) else None for ev in coarse]
    used = {j for j in pairs if j is not None}
    return pairs, [j for j in range(len(fine)) if j not in used]

"""The results of the stability analysis: events, branches, one parameter point.

:class:`StabilityEvent` (a change of stability, or a fold, on a static
branch), :class:`BranchStability` (one branch and its stability along it)
and :class:`StabilityResult` (every branch of one parameter point);
:class:`~fempipe.analyses.stability.branch_analysis.BranchAnalysis` computes
them (docs/theory/stability.md, "Stability events").
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.model.params import Params

# ---------------------------------------------------------------------------
# Stability events along branches
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class StabilityEvent:
    """A change of stability, or a fold, on a static branch.

    Attributes
    ----------
    v : float
        Flow velocity, located to 1e-10 (Brent) for crossings; folds to the
        continuation's 1e-10 in arclength.
    type : {'flutter', 'divergence', 'restabilization', 'mode_restabilization', 'fold'}
        As v increases: a complex pair crosses to Re lambda > 0 (flutter), a
        real root does (divergence), an eigenvalue crosses back and the
        branch is stable above the event (restabilization), an eigenvalue
        crosses back while another one stays unstable, so the branch is not
        stable above the event (mode_restabilization: a per-mode event, the
        system does not restabilize); or the branch turns back in v (fold).
        ``stable_before`` and ``stable_after`` say what the whole system does.
    branch : str
        Branch name (``"primary"``, ``"B1+"``, ...).
    frequency : float
        Im lambda = Re Omega at the crossing (0 for real roots and folds).
    mode : int or None
        Number of the crossing mode (carried by continuity along the branch).
    eigenvalue : complex
        lambda at the crossing.
    at_start : bool
        The instability was already present at the start of the branch's
        v-range (the event is listed at that v).
    stable_before, stable_after : bool
        Stability of the branch just below / above the event in v (for a fold:
        on the branch piece arriving at / leaving the fold, in branch order),
        in the event's plane.
    plane : {'in', 'out'}
        The motion that loses (or regains) stability: in the plane of the
        static state (Eq. (32)) or out of it (:mod:`fempipe.model.out_of_plane`).
    """

    v: float
    type: str
    branch: str
    frequency: float
    mode: int | None
    eigenvalue: complex = 0j
    at_start: bool = False
    stable_before: bool = True
    stable_after: bool = True
    plane: str = "in"

    def to_dict(self) -> dict:
        """The contract of ``fempipe critical --json``: v, type, branch, frequency, mode,
        stable_before, stable_after (the whole system of the event's plane just below
        and above the event), plane."""
        return {
            "v": self.v,
            "type": self.type,
            "branch": self.branch,
            "frequency": self.frequency,
            "mode": self.mode,
            "stable_before": self.stable_before,
            "stable_after": self.stable_after,
            "plane": self.plane,
        }

    def details(self) -> dict:
        d = self.to_dict()
        d.update(
            {
                "eigenvalue": [float(self.eigenvalue.real), float(self.eigenvalue.imag)],
                "at_start": self.at_start,
            }
        )
        return d


@dataclass(frozen=True)
class BranchStability:
    """One static branch and its stability along it (arclength order).

    Attributes
    ----------
    name : str
    parent : str or None
        Branch it bifurcates from.
    born_at : float or None
        v of the branch point it starts from.
    v, theta_tip, max_real : ndarray, shape (m,)
        At every sample (continuation points plus inserted ones).
    n_unstable : ndarray of int, shape (m,)
        Resolved eigenvalues with Re lambda > 0 (a complex pair counts 2).
    events : tuple of StabilityEvent
    folds, bifurcations : tuple of float
        v of the folds and branch points located by the continuation.
    end_reason : str
        Why the continuation stopped (see :class:`fempipe.analyses.statics.Branch`).
    """

    name: str
    parent: str | None
    born_at: float | None
    v: np.ndarray
    theta_tip: np.ndarray
    max_real: np.ndarray
    n_unstable: np.ndarray
    events: tuple
    folds: tuple
    bifurcations: tuple
    end_reason: str

    def to_dict(self, samples: bool = False) -> dict:
        d = {
            "name": self.name,
            "parent": self.parent,
            "born_at": self.born_at,
            "v_min": float(self.v.min()),
            "v_max": float(self.v.max()),
            "folds": list(self.folds),
            "bifurcations": list(self.bifurcations),
            "end_reason": self.end_reason,
            "events": [e.details() for e in self.events],
        }
        if samples:
            d["samples"] = {
                "v": self.v.tolist(),
                "theta_tip": self.theta_tip.tolist(),
                "max_real": self.max_real.tolist(),
                "n_unstable": self.n_unstable.tolist(),
            }
        return d


@dataclass(frozen=True)
class StabilityResult:
    """Stability of the static branches of one parameter point over a v-range.

    Attributes
    ----------
    params : Params
        (v is the start of the range.)
    discretization : dict
    v_range : (float, float)
    v_cr : float or None
        First v at which the primary branch is not stable (the start of the
        range if it is unstable there); None if stable throughout.
    critical : StabilityEvent or None
        The event that defines v_cr.
    v_flutter : float or None
        First flutter on the primary branch (Fig. 6 plots this; it equals v_cr
        except where divergence or a fold comes first, e.g. alpha = pi).
    events : tuple of StabilityEvent
        All branches, by branch then v.
    branches : tuple of BranchStability
    n_spectra : int
        Eigenproblems solved (diagnostic).
    plane : {'in', 'out'}
        The motion analysed: in the plane of the static states or out of it.
    """

    params: Params
    discretization: dict
    v_range: tuple[float, float]
    v_cr: float | None
    critical: StabilityEvent | None
    v_flutter: float | None
    events: tuple
    branches: tuple
    n_spectra: int
    plane: str = "in"

    def to_dict(self, samples: bool = False) -> dict:
        p = self.params.to_dict()
        p.pop("v", None)
        return {
            "v_cr": self.v_cr,
            "events": [e.to_dict() for e in self.events],
            "critical": None if self.critical is None else self.critical.details(),
            "v_flutter": self.v_flutter,
            "v_range": list(self.v_range),
            "params": p,
            "discretization": self.discretization,
            "branches": [b.to_dict(samples) for b in self.branches],
            "n_spectra": self.n_spectra,
        }

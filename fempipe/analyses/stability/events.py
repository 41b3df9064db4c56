"""The results of the stability analysis: events, branches, one parameter point in one
plane (:class:`StabilityResult`) or in both (:class:`StabilityInPlanes`).

Definitions: docs/theory/stability.md, "Stability events".
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.model.params import Params

_EVENT_KEYS = "v type branch frequency mode stable_before stable_after plane".split()


@dataclass(frozen=True)
class StabilityEvent:
    """A change of stability, or a fold, on a static branch.

    Attributes
    ----------
    v : float
        Flow velocity, located to 1e-10.
    type : {'flutter', 'divergence', 'restabilization', 'mode_restabilization', 'fold'}
        As v increases (docs/theory/stability.md, "Stability events").
    branch : str
        Branch name (``"primary"``, ``"B1+"``, ...).
    frequency, mode, eigenvalue : float, int or None, complex
        Im lambda at the crossing (0 for real roots and folds), the mode number, lambda.
    at_start : bool
        Unstable already at the start of the branch's v-range (listed at that v).
    stable_before, stable_after : bool
        Stability of the whole branch just below / above the event, in the event's plane.
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
        """The contract of ``fempipe critical --json``."""
        return {k: getattr(self, k) for k in _EVENT_KEYS}

    def details(self) -> dict:
        z = self.eigenvalue
        return self.to_dict() | {
            "eigenvalue": [float(z.real), float(z.imag)],
            "at_start": self.at_start,
        }


@dataclass(frozen=True)
class BranchStability:
    """One static branch and its stability along it (arclength order).

    Attributes
    ----------
    name, parent, born_at : str, str or None, float or None
        The branch, the one it bifurcates from and the v of that branch point.
    n_unstable : ndarray of int, shape (m,)
        Unstable resolved eigenvalues (a complex pair counts 2) at the samples ``v``.
    end_reason : str
        Why the continuation stopped (:class:`fempipe.analyses.statics.Branch`).
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
    v_cr, critical : float or None, StabilityEvent or None
        First v at which the primary branch is not stable (None if stable) and its event.
    v_flutter : float or None
        First flutter on the primary branch (Fig. 6).
    events, branches : tuple of StabilityEvent, tuple of BranchStability
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


#: Two critical velocities closer than this (relative to max(1, v)) are the same loss of
#: stability: the events are located to 1e-10 in v.
SAME_V = 1e-9


def first_of(in_plane: StabilityEvent | None, out_of_plane: StabilityEvent | None):
    """The earlier of two critical events; the in-plane one when they coincide (:data:`SAME_V`)."""
    if out_of_plane is None:
        return in_plane
    if in_plane is None:
        return out_of_plane
    if out_of_plane.v < in_plane.v - SAME_V * max(1.0, abs(in_plane.v)):
        return out_of_plane
    return in_plane


@dataclass(frozen=True)
class StabilityInPlanes:
    """The static branches' stability in (``in_plane``) and out of (``out_of_plane``) their plane,
    two :class:`StabilityResult` along the same branches (``planes=("in", "out")``).
    """

    in_plane: StabilityResult
    out_of_plane: StabilityResult

    @property
    def critical(self) -> StabilityEvent | None:
        """The first loss of stability of the primary branch in either plane."""
        return first_of(self.in_plane.critical, self.out_of_plane.critical)

    @property
    def v_cr(self) -> float | None:
        c = self.critical
        return None if c is None else float(c.v)

    @property
    def v_flutter(self) -> float | None:
        """The first flutter of the primary branch in either plane."""
        vs = [v for v in (self.in_plane.v_flutter, self.out_of_plane.v_flutter) if v is not None]
        return min(vs) if vs else None

    @property
    def events(self) -> tuple:
        """Both planes' events by branch then v (the folds once, with the in-plane events)."""
        order = {b.name: i for i, b in enumerate(self.in_plane.branches)}
        evs = list(self.in_plane.events) + [e for e in self.out_of_plane.events if e.type != "fold"]
        return tuple(sorted(evs, key=lambda e: (order.get(e.branch, len(order)), e.v)))

    @property
    def n_spectra(self) -> int:
        return self.in_plane.n_spectra + self.out_of_plane.n_spectra

    def first_instability(self) -> dict | None:
        """``{"v", "plane", "type", "frequency"}`` of :attr:`critical`, or None."""
        c = self.critical
        if c is None:
            return None
        return {"v": c.v, "plane": c.plane, "type": c.type, "frequency": c.frequency}

    def to_dict(self, samples: bool = False) -> dict:
        """The contract of ``fempipe critical --json``."""
        d = self.in_plane.to_dict(samples)
        c = self.critical
        d["v_cr"] = self.v_cr
        d["critical"] = None if c is None else c.details()
        d["v_flutter"] = self.v_flutter
        d["events"] = [e.to_dict() for e in self.events]
        d["n_spectra"] = self.n_spectra
        d["first_instability"] = self.first_instability()
        planes = {"in_plane": self.in_plane, "out_of_plane": self.out_of_plane}
        for k, r in planes.items():
            d[f"v_cr_{k}"] = r.v_cr
            d[f"frequency_{k}"] = None if r.critical is None else r.critical.frequency
        for k, r in planes.items():
            d[f"v_flutter_{k}"] = r.v_flutter
        for k, r in planes.items():
            d[f"critical_{k}"] = None if r.critical is None else r.critical.details()
        d["branches_out_of_plane"] = [b.to_dict(samples) for b in self.out_of_plane.branches]
        return d

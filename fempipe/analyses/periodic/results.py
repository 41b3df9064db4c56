"""The results of a continuation of periodic orbits: Hopf points, orbits, branches.

An orbit's Floquet multipliers are by decreasing modulus; :func:`nontrivial_multipliers`
removes the trivial one (closest to 1).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fempipe.core.errors import SolverError

__all__ = [
    "MIN_SWING",
    "CycleBranch",
    "CycleContinuationError",
    "CyclePoint",
    "CycleSpecialPoint",
    "HopfPoint",
    "nontrivial_multipliers",
    "swing",
]

#: An orbit whose eta_tip swings (max - min) less than this is back at an equilibrium.
MIN_SWING = 2e-3


class CycleContinuationError(SolverError):
    """A branch of periodic orbits could not be continued; ``branch`` holds its finished part."""

    def __init__(self, message: str, branch: CycleBranch | None = None) -> None:
        super().__init__(message)
        self.branch = branch

    def __reduce__(self):
        return type(self), (str(self), self.branch)


@dataclass(frozen=True)
class HopfPoint:
    """A Hopf point of the static branch: a flutter-type event with its eigenvector
    z = (q, i omega q), A z = i omega z, unit RMS of its q part."""

    v: float
    omega: float
    event_type: str
    q_static: np.ndarray = field(repr=False)
    eigenvector: np.ndarray = field(repr=False)

    def to_dict(self, state: bool = False) -> dict:
        d = {"v": self.v, "omega": self.omega, "type": self.event_type}
        if state:
            d["q_static"] = [float(x) for x in self.q_static]
            d["eigenvector_re"] = [float(x) for x in self.eigenvector.real]
            d["eigenvector_im"] = [float(x) for x in self.eigenvector.imag]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> HopfPoint:
        z = np.asarray(d["eigenvector_re"]) + 1j * np.asarray(d["eigenvector_im"])
        return cls(d["v"], d["omega"], d["type"], np.asarray(d["q_static"], dtype=float), z)


@dataclass(frozen=True)
class CyclePoint:
    """One periodic orbit of a branch: its state on the phase section, tips, Floquet multipliers
    (by modulus, the trivial one included), ``source`` ``"grid"`` or ``"continuation"``, Newton's
    integrations and residual, the last period's steps and the corrector's rejected ones.
    """

    v: float
    period: float
    q0: np.ndarray = field(repr=False)
    qdot0: np.ndarray = field(repr=False)
    tip: dict = field(default_factory=dict)
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex), repr=False)
    stable: bool = False
    source: str = "continuation"
    iterations: int = 0
    residual: float = 0.0
    steps: int = 0
    rejected_steps: int = 0
    wall_time: float = 0.0

    @property
    def max_multiplier(self) -> float:
        """Largest modulus of the non-trivial multipliers."""
        mu = nontrivial_multipliers(self.multipliers)
        return float(np.max(np.abs(mu))) if mu.size else 0.0

    def to_dict(self, state: bool = False) -> dict:
        d = {
            "v": self.v,
            "period": self.period,
            "tip": self.tip,
            "multipliers": [[float(z.real), float(z.imag)] for z in self.multipliers],
            "stable": self.stable,
            "source": self.source,
            "iterations": self.iterations,
            "residual": self.residual,
            "steps": self.steps,
            "rejected_steps": self.rejected_steps,
            "wall_time": self.wall_time,
        }
        if state:
            d["q0"] = [float(x) for x in self.q0]
            d["qdot0"] = [float(x) for x in self.qdot0]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> CyclePoint:
        mu = np.array([complex(a, b) for a, b in d["multipliers"]], dtype=complex)
        kw = {k: d[k] for k in cls.__dataclass_fields__ if k not in ("q0", "qdot0", "multipliers")}
        return cls(**kw, q0=np.asarray(d["q0"]), qdot0=np.asarray(d["qdot0"]), multipliers=mu)


@dataclass(frozen=True)
class CycleSpecialPoint:
    """A bifurcation of periodic orbits on a branch: ``type`` fold, period_doubling or
    neimark_sacker, its v and period, after the branch point ``index``."""

    v: float
    type: str
    period: float
    index: int

    def to_dict(self) -> dict:
        return {"v": self.v, "type": self.type, "period": self.period, "index": self.index}


@dataclass(frozen=True)
class CycleBranch:
    """A branch of periodic orbits born at a Hopf point (``name`` ``"H1"``, ``"H2"``, ... by
    increasing v_H): its points in arclength order, special points, why it ended, its
    accepted and rejected steps and integrations over all correctors."""

    name: str
    hopf: HopfPoint
    points: tuple
    special_points: tuple
    end_reason: str
    steps: int
    rejected_steps: int
    newton_iterations: int
    wall_time: float

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "hopf": self.hopf.to_dict(),
            "special_points": [s.to_dict() for s in self.special_points],
            "end_reason": self.end_reason,
            "n_points": len(self.points),
            "steps": self.steps,
            "rejected_steps": self.rejected_steps,
            "newton_iterations": self.newton_iterations,
            "wall_time": self.wall_time,
        }


def nontrivial_multipliers(mu: np.ndarray) -> np.ndarray:
    """The multipliers without the trivial one (the one closest to 1)."""
    if mu.size < 2:
        return mu[:0]
    return np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))


def swing(pt: CyclePoint) -> float:
    """max - min of eta_tip over the orbit."""
    lo, hi = pt.tip["eta_tip"]
    return hi - lo

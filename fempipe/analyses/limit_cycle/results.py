"""What the limit-cycle search returns: :class:`LimitCycle`, :class:`Attractor`, :class:`ShootingError`.

Also the distance between two states (:func:`state_distance`) and the largest non-trivial
Floquet multiplier (:func:`largest_nontrivial`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fempipe.core.errors import SolverError

from ..dynamics import Trajectory

__all__ = [
    "NEUTRAL_TOLERANCE",
    "ShootingError",
    "LimitCycle",
    "Attractor",
    "largest_nontrivial",
    "state_distance",
]

#: At an axisymmetric alpha a second multiplier this close to 1 is the rotation's (exactly 1
#: in the continuum; measured 1.0e-3 off on P3:4); a whirl has no second one.
NEUTRAL_TOLERANCE = 2e-2


class ShootingError(SolverError):
    """Newton's method on the periodic orbit did not converge (or found an equilibrium)."""

    def __init__(self, message: str, iterations: int, residual: float) -> None:
        super().__init__(message)
        self.iterations = iterations
        self.residual = residual

    def __reduce__(self):
        # Rebuilt from all the constructor's arguments (pickling across processes).
        return type(self), (str(self), self.iterations, self.residual)


def state_distance(dq: np.ndarray, dp: np.ndarray, timescale: float):
    """RMS distance of two states along the last axis (differences ``dq``, ``dp``), the
    velocities scaled by ``timescale`` (T / 2 pi for an orbit of period T)."""
    d = np.sqrt(np.mean(dq**2, axis=-1) + np.mean((dp * timescale) ** 2, axis=-1))
    return float(d) if d.ndim == 0 else d


def largest_nontrivial(mu, axisymmetric: bool = False) -> float:
    """The largest modulus of the Floquet multipliers ``mu`` without the trivial ones.

    The phase's (closest to 1) always; for a 3-D cycle at an axisymmetric alpha also the
    rotation's second 1, when one lies within :data:`NEUTRAL_TOLERANCE` of 1 (a whirl, which
    the rotation maps onto its own time shift, has only the phase's).
    """
    mu = np.asarray(mu)
    near = np.argsort(np.abs(mu - 1.0), kind="stable")
    rotation = axisymmetric and mu.size > 1 and abs(mu[near[1]] - 1.0) < NEUTRAL_TOLERANCE
    drop = 2 if rotation else 1
    others = np.delete(mu, near[:drop])
    return float(np.max(np.abs(others))) if others.size else 0.0


@dataclass(frozen=True)
class LimitCycle:
    """A periodic orbit computed by shooting.

    Attributes
    ----------
    period : float
        Period T in tau (the whole orbit, n section crossings).
    q0, qdot0, level : ndarray, ndarray, float
        State on the orbit where the section variable is ``level`` (upward).
    floquet_multipliers, stable : ndarray, bool
        By decreasing modulus; the non-trivial ones inside the unit circle.
    orbit_t, orbit_q, orbit_qdot : ndarray
        The orbit at equally spaced times over one period.
    """

    period: float
    q0: np.ndarray
    qdot0: np.ndarray
    level: float = math.nan
    tip: dict = field(default_factory=dict)
    floquet_multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex))
    stable: bool = True
    iterations: int = 0
    residual: float = 0.0
    orbit_t: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    orbit_q: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    orbit_qdot: np.ndarray = field(default_factory=lambda: np.zeros(0), repr=False)
    steps: int = 0
    total_steps: int = 0
    rejected_steps: int = 0
    wall_time: float = 0.0

    @property
    def max_nontrivial_multiplier(self) -> float:
        """:func:`largest_nontrivial` without the rotation's multiplier."""
        return largest_nontrivial(self.floquet_multipliers)

    def to_dict(self, n_multipliers: int = 6) -> dict:
        mu = self.floquet_multipliers[:n_multipliers]
        return {
            "period": self.period,
            "tip": self.tip,
            "floquet_multipliers": [[float(z.real), float(z.imag)] for z in mu],
            "max_nontrivial_multiplier": self.max_nontrivial_multiplier,
            "stable": self.stable,
            "newton_iterations": self.iterations,
            "residual": self.residual,
            "level": self.level,
        }


@dataclass(frozen=True)
class Attractor:
    """The attractor reached from an initial state: ``kind`` ``"equilibrium"``, ``"periodic"``
    or ``"non-periodic"``, its cycle if shot, the end state (q, qdot) at ``t_end``."""

    kind: str
    period: float | None
    period_n: int | None
    tip: dict
    cycle: LimitCycle | None
    q: np.ndarray
    qdot: np.ndarray
    params: object
    t_end: float
    stats: dict
    trajectory: Trajectory | None = field(default=None, repr=False)
    message: str = ""

    def to_dict(self) -> dict:
        d = {
            "attractor": self.kind,
            "period": self.period,
            "period_n": self.period_n,
            "tip": self.tip,
            "floquet_multipliers": (
                self.cycle.to_dict()["floquet_multipliers"] if self.cycle is not None else None
            ),
            "max_nontrivial_multiplier": (
                self.cycle.max_nontrivial_multiplier if self.cycle is not None else None
            ),
            "params": self.params.to_dict(),
            "t_transient": self.t_end,
            "message": self.message,
        }
        d.update(self.stats)
        return d

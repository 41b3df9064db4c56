"""What the limit-cycle search returns: :class:`LimitCycle`, :class:`Attractor`, :class:`ShootingError`.

Also the one distance between two states that the search, the shooting and
the CLI's display use (:func:`state_distance`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fempipe.core.errors import SolverError

from ..dynamics import Trajectory

__all__ = ["ShootingError", "LimitCycle", "Attractor", "state_distance"]


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
    """RMS distance of two states; velocities scaled by a time scale (period / 2 pi).

    Parameters
    ----------
    dq, dp : ndarray, shape (..., n)
        Differences of the positions and of the velocities.
    timescale : float
        Multiplies the velocity differences (T / 2 pi for an orbit of period T).

    Returns
    -------
    float or ndarray
        Along the last axis: a float for one pair of states, an array for stacked ones.
    """
    d = np.sqrt(np.mean(dq**2, axis=-1) + np.mean((dp * timescale) ** 2, axis=-1))
    return float(d) if d.ndim == 0 else d


@dataclass(frozen=True)
class LimitCycle:
    """A periodic orbit computed by shooting.

    Attributes
    ----------
    period : float
        Period T in units of tau (of the whole orbit, n section crossings).
    q0, qdot0 : ndarray, shape (n,)
        State on the orbit where eta_tip = ``level`` (upward).
    level : float
        Section level of eta_tip.
    tip : dict
        ``{"eta_tip": [min, max], "X_tip": [...], "Z_tip": [...]}`` on the orbit.
    floquet_multipliers : ndarray, complex
        Eigenvalues of the monodromy matrix, by decreasing modulus: that of
        the converged Newton iterate, one polishing step (below the shooting
        tolerance) from ``q0``, ``qdot0`` (see :func:`~fempipe.analyses.limit_cycle.shoot`).
    stable : bool
        All multipliers except the trivial one (closest to 1) inside the unit circle.
    iterations : int
        Newton iterations (period integrations; the polishing step included).
    residual : float
        Final RMS of phi_T(x0) - x0 (q in rad, q' scaled by T / 2 pi).
    orbit_t, orbit_q, orbit_qdot : ndarray
        The orbit sampled at 200 equally spaced times over one period.
    steps : int
        Integration steps over the last period.
    total_steps, rejected_steps : int
        Steps (accepted, rejected) over all Newton iterations.
    wall_time : float
        Seconds spent in the shooting.
    """

    period: float
    q0: np.ndarray
    qdot0: np.ndarray
    level: float
    tip: dict
    floquet_multipliers: np.ndarray
    stable: bool
    iterations: int
    residual: float
    orbit_t: np.ndarray = field(repr=False)
    orbit_q: np.ndarray = field(repr=False)
    orbit_qdot: np.ndarray = field(repr=False)
    steps: int = 0
    total_steps: int = 0
    rejected_steps: int = 0
    wall_time: float = 0.0

    @property
    def max_nontrivial_multiplier(self) -> float:
        mu = self.floquet_multipliers
        if mu.size < 2:
            return 0.0
        trivial = int(np.argmin(np.abs(mu - 1.0)))
        return float(np.max(np.abs(np.delete(mu, trivial))))

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
    """The attractor reached from an initial state.

    Attributes
    ----------
    kind : str
        ``"equilibrium"``, ``"periodic"`` or ``"non-periodic"``.
    period : float or None
        Period of the periodic orbit.
    period_n : int or None
        Number of distinct section points (1 for period-1, 2 for period-2, ...).
    tip : dict
        ``{"eta_tip": [min, max], "X_tip": [...], "Z_tip": [...]}`` on the attractor.
    cycle : LimitCycle or None
    q, qdot : ndarray, shape (n,)
        A state on the attractor (to start the next point of a sweep from).
    params : Params
    t_end : float
        Time integrated before the attractor was recognized.
    stats : dict
        Integration diagnostics summed over the transient and the shooting.
    trajectory : Trajectory or None
        The transient, if recorded.
    """

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

"""Periodic orbits of the 3-D model by Newton shooting: the planar shooting on the 3-D model.

:class:`SpaceShooter` is :class:`fempipe.analyses.limit_cycle.shooting.Shooter`
(the same bordered Newton iteration on the monodromy matrix of the same
integrator) with the 3-D model's phase condition (:func:`section_value`, eta_tip + Y_tip), tip extrema (eta_tip, X_tip, Z_tip, Y_tip)
and two changes the symmetries ask for:

* at an axisymmetric inclination (sin alpha = 0) every orbit turned about the
  vertical is an orbit: the monodromy has a second multiplier 1, the bordered
  Newton matrix is singular along that rotation, and the step is the
  minimum-norm least-squares solution (the orbit is fixed up to the
  rotation, which the step does not move);
* the stability verdict leaves out that second multiplier 1 as well as the
  phase's (when one lies within :data:`NEUTRAL_TOLERANCE` of 1: a whirl, whose
  rotation is its own time shift, has only the phase's), and the gauge's
  (:mod:`fempipe.model.space`), which are far inside the unit circle.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from ...model.space import SpaceModel
from ...model.space_dynamics import SpaceDynamics
from ..limit_cycle.results import LimitCycle
from ..limit_cycle.shooting import Shooter
from ..limit_cycle.tips import QuinticOrbit

__all__ = [
    "SpaceShooter",
    "largest_nontrivial",
    "section_value",
    "shoot_space",
    "space_tip_extrema",
]

TIP3_KEYS = ("eta_tip", "X_tip", "Z_tip", "Y_tip")

#: At an axisymmetric alpha a second multiplier this close to 1 is the rotation's (exactly 1
#: in the continuum; measured 1.0e-3 off on P3:4); a whirl has no second one.
NEUTRAL_TOLERANCE = 2e-2


def section_value(model: SpaceModel, U: np.ndarray) -> float:
    """eta_tip + Y_tip, the tip's displacement along e_2 + e_3: the section variable of the 3-D
    motion.  It is eta_tip for a planar motion, and it oscillates at the period of the
    out-of-plane swing where eta_tip alone swings at twice that frequency (a horizontal pipe
    fluttering sideways traces a figure eight) or not at all."""
    d = model.tip_coordinates(U)
    return d["eta_tip"] + d["Y_tip"]


def space_tip_extrema(model: SpaceModel, orbit: QuinticOrbit, per_step: int = 16) -> dict:
    """``[min, max]`` of the tip coordinates over the orbit, sampled ``per_step`` times a step
    on the quintic interpolant and refined by a parabola through the extreme sample."""
    ts = np.concatenate(
        [
            (orbit.t[:-1, None] + orbit.h[:, None] * np.arange(per_step) / per_step).ravel(),
            orbit.t[-1:],
        ]
    )
    tips = model.tip_coordinates(orbit(ts))
    out = {}
    for k in TIP3_KEYS:
        y = tips[k]
        pair = []
        for sign in (-1.0, 1.0):
            i = int(np.argmax(sign * y))
            if 0 < i < y.size - 1:
                y0, y1, y2 = y[i - 1], y[i], y[i + 1]
                den = y0 - 2 * y1 + y2
                # the vertex of the parabola through three equally spaced samples
                vertex = y1 - 0.125 * (y2 - y0) ** 2 / den if den != 0 else y1
                pair.append(float(vertex if sign * vertex >= sign * y1 else y1))
            else:
                pair.append(float(y[i]))
        out[k] = pair
    return out


class SpaceShooter(Shooter):
    """The planar :class:`Shooter` on a :class:`SpaceModel`."""

    def __init__(self, model: SpaceModel, level: float, **options) -> None:
        super().__init__(model, level, **options)
        self.axisymmetric = abs(math.sin(model.params.alpha)) < 1e-12

    def problem(self) -> SpaceDynamics:
        return SpaceDynamics(self.model)

    def phase(self, q: np.ndarray) -> float:
        return section_value(self.model, q)

    def phase_gradient(self, q: np.ndarray) -> np.ndarray:
        g = self.model.tip_position_gradient(q)
        return g[1] + g[2]

    def tips(self, ends: list) -> dict:
        return space_tip_extrema(self.model, QuinticOrbit(*zip(*ends, strict=True)))

    def newton_step(self, q, p, stepper, g):
        if not self.axisymmetric:
            return super().newton_step(q, p, stepper, g)
        n = self.n
        J = np.zeros((2 * n + 1, 2 * n + 1))
        J[: 2 * n, : 2 * n] = self.Phi - np.eye(2 * n)
        J[: 2 * n, -1] = np.concatenate([stepper.qdot, stepper.qddot])
        J[-1, :n] = self.phase_gradient(q)
        rhs = -np.concatenate([stepper.q - q, stepper.qdot - p, [g]])
        dx = np.linalg.lstsq(J, rhs, rcond=1e-10)[0]
        return dx if np.all(np.isfinite(dx)) else None

    def converged(self, best, dx) -> LimitCycle:
        cycle = super().converged(best, dx)
        return replace(
            cycle, stable=largest_nontrivial(cycle.floquet_multipliers, self.axisymmetric) < 1.0
        )


def largest_nontrivial(mu: np.ndarray, axisymmetric: bool) -> float:
    """The largest modulus of the 3-D Floquet multipliers ``mu`` without the trivial ones.

    The phase's 1 always; at an axisymmetric alpha also the rotation's second 1 of a cycle
    the rotation moves, when one lies within :data:`NEUTRAL_TOLERANCE` of 1 (a whirl, which
    the rotation maps onto its own time shift, has only the phase's).
    """
    mu = np.asarray(mu)
    near = np.argsort(np.abs(mu - 1.0))
    drop = 1
    if axisymmetric and mu.size > 1 and abs(mu[near[1]] - 1.0) < NEUTRAL_TOLERANCE:
        drop = 2
    others = np.delete(mu, near[:drop])
    return float(np.max(np.abs(others))) if others.size else 0.0


def shoot_space(
    model: SpaceModel,
    U0: np.ndarray,
    Ud0: np.ndarray,
    period: float,
    *,
    level: float | None = None,
    rtol: float = 1e-7,
    tol: float = 1e-6,
    max_iter: int = 12,
) -> LimitCycle:
    """A periodic orbit of the 3-D model by Newton shooting from (U0, Ud0, period).

    As :func:`fempipe.analyses.limit_cycle.shoot`; ``tip`` has Y_tip too, and
    ``floquet_multipliers`` are the 3-D monodromy's (6 n of them: the planar
    and out-of-plane perturbations' and the gauge's), all of them, from the
    exact derivative of the discrete flow map.  Along a planar orbit the
    integrator computes that matrix block by block (in-plane, out-of-plane:
    the Jacobians decouple exactly there), elsewhere whole.
    """
    U0 = np.array(U0, dtype=float)
    level = section_value(model, U0) if level is None else float(level)
    shooter = SpaceShooter(
        model, level, rtol=rtol, tol=tol, n_samples=200, reuse_monodromy=False, polish=True
    )
    return shooter.run(U0, np.array(Ud0, dtype=float), float(period), max_iter)

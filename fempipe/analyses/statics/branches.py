"""Branches of static equilibria (Eq. (31a)) by pseudo-arclength continuation, with folds,
bifurcation points and branch switching at pitchforks.

Keller's policy of :mod:`fempipe.solvers.continuation` on the problem
:class:`~fempipe.analyses.statics.family.StaticFamily`; the pipe's own here: convergence by
force balance, landing exactly on the requested value (or on v = 0, gamma = 0 when the branch
leaves the physical range).  Folds are sign changes of the tangent's parameter component,
bifurcation points of the bordered Jacobian's determinant.  docs/theory/numerics.md.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.sparse as sp

from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.continuation import (
    CurveEvent,
    CurvePoint,
    KellerPolicy,
    KellerStep,
    continue_curve,
    correct,
    normalize,
)
from fempipe.solvers.continuation import tangent as curve_tangent

from .equilibrium import NewtonError, solve_static
from .family import StaticFamily

__all__ = [
    "BranchPoint",
    "Branch",
    "SpecialPoint",
    "StaticBranchPolicy",
    "continue_static",
    "switch_branch",
]


@dataclass(frozen=True)
class BranchPoint(CurvePoint):
    """One point of a branch: ``q``, ``value``, the unit ``tangent``, the corrector's
    ``iterations`` and ``residual_norm``, and ``det_sign`` (it flips at bifurcations)."""


@dataclass(frozen=True)
class SpecialPoint(CurveEvent):
    """A ``"fold"`` or a ``"bifurcation"`` (a pitchfork at alpha = 0, pi) located on a
    branch, in its segment [index, index + 1]."""

    def to_dict(self, parameter: str) -> dict:
        return {"type": self.kind, parameter: self.value}


@dataclass
class Branch:
    """A branch of static states traced in ``parameter`` ("v", "gamma" or "alpha"): its
    ``points``, the folds and bifurcations in ``special``, the step counts and
    ``end_reason`` ("stop", "returned to v = 0" or "max_steps")."""

    parameter: str
    base: Params
    points: list[BranchPoint] = field(default_factory=list)
    special: list[SpecialPoint] = field(default_factory=list)
    steps: int = 0
    rejected_steps: int = 0
    end_reason: str = "max_steps"

    @property
    def values(self) -> np.ndarray:
        return np.array([p.value for p in self.points])

    @property
    def states(self) -> np.ndarray:
        return np.array([p.q for p in self.points])

    @property
    def folds(self) -> list[SpecialPoint]:
        return [s for s in self.special if s.kind == "fold"]

    @property
    def bifurcations(self) -> list[SpecialPoint]:
        return [s for s in self.special if s.kind == "bifurcation"]


class StaticBranchPolicy(KellerPolicy):
    """Keller's policy with the pipe's convergence test (force balance), landing on ``stop``
    (or on 0 for v, gamma) by Newton at fixed parameter, and errors."""

    point_type = BranchPoint
    event_type = SpecialPoint

    def __init__(self, family: StaticFamily, first: BranchPoint, stop: float, **options) -> None:
        super().__init__(family, first, **options)
        self.family = family
        self.stop = stop
        self.going_up = stop >= first.value

    def converged(self, y: np.ndarray) -> float | None:
        return self.family.balanced(y, self.tol)

    def stalled(self, step: KellerStep) -> Exception:
        parameter, prev = self.family.parameter, step.previous
        return NewtonError(
            f"continuation in {parameter} stalled at {parameter}={prev.value:.8g}: "
            f"arclength step fell below {self.ds_min:g}",
            params=replace(self.family.model.params, **{parameter: prev.value}),
            iterations=0,
            residual=float("nan"),
        )

    def land(self, step: KellerStep, new: BranchPoint) -> BranchPoint:
        prev, stop, parameter = step.previous, self.stop, self.family.parameter
        crossed = (new.value - stop) * (1 if self.going_up else -1) >= 0
        left = parameter in ("v", "gamma") and new.value < 0 <= prev.value
        if crossed or left:
            target = stop if crossed else 0.0
            end = solve_static(
                self.family.at(target), q0=interp_state(prev, new, target), tol=self.tol
            )
            t_end, s_end, _ = curve_tangent(self.family, np.append(end.q, target), new.tangent)
            new = BranchPoint(end.q, target, t_end, end.iterations, end.residual_norm, s_end)
            self.end_reason = "stop" if crossed else f"returned to {parameter} = 0"
        return new

    def finish(self, reason: str, h: float) -> Branch:
        self.end_reason = reason
        family = self.family
        fields = (family.model.params, self.points, self.events, self.steps, self.rejected_steps)
        return Branch(family.parameter, *fields, reason)


def interp_state(a: CurvePoint, b: CurvePoint, value: float) -> np.ndarray:
    """The state at parameter ``value`` interpolated linearly between a and b."""
    if b.value == a.value:
        return b.q
    s = (value - a.value) / (b.value - a.value)
    return a.q + s * (b.q - a.q)


def continue_static(
    model: PipeModel,
    parameter: str = "v",
    stop: float = 10.0,
    q0: np.ndarray | None = None,
    ds: float = 0.1,
    ds_min: float = 1e-6,
    ds_max: float = 0.5,
    max_steps: int = 2000,
    tol: float = 1e-10,
    direction: int | None = None,
    detect: bool = True,
    locate_tol: float = 1e-10,
    tangent: np.ndarray | None = None,
    callback: Callable[[BranchPoint], None] | None = None,
) -> Branch:
    """Pseudo-arclength continuation of static states in ``parameter`` from ``model.params``
    to exactly ``stop``, folds and bifurcation points located by bisection in arclength.

    Parameters
    ----------
    model : PipeModel
    parameter : {'v', 'gamma', 'alpha'}
    stop : float
        Target parameter value (may be below the start value).
    q0 : ndarray, optional
        Initial guess for the first point.
    ds, ds_min, ds_max : float
        Initial, minimal and maximal arclength steps.
    direction, tangent : {+1, -1}, ndarray, optional
        Initial direction (default: towards ``stop``), or tangent (branch switching).
    callback : callable, optional
        Called with each accepted :class:`BranchPoint`.

    Raises
    ------
    NewtonError
        If the first point does not converge, or the step falls below ``ds_min``.
    """
    family = StaticFamily(model, parameter)
    n = model.n
    start_value = float(getattr(model.params, parameter))
    if parameter in ("v", "gamma") and stop < 0:
        raise ValueError(f"stop must be >= 0 for {parameter}, got {stop}")
    first = solve_static(model, q0=q0, tol=tol)
    if tangent is None:
        sgn = direction if direction is not None else (1 if stop >= start_value else -1)
        t0 = np.zeros(n + 1)
        t0[n] = float(sgn)
    else:
        t0 = normalize(family, np.asarray(tangent, dtype=float))
    t, sign, _ = curve_tangent(family, np.append(first.q, start_value), t0)
    pt = BranchPoint(first.q, start_value, t, first.iterations, first.residual_norm, sign)
    options = dict(ds_min=ds_min, ds_max=ds_max, max_steps=max_steps, tol=tol, detect=detect)
    policy = StaticBranchPolicy(
        family, pt, stop, locate_tol=locate_tol, callback=callback, **options
    )
    if callback:
        callback(pt)
    return continue_curve(policy, ds)


def switch_branch(
    model: PipeModel,
    point: SpecialPoint,
    parameter: str,
    stop: float,
    ds: float = 0.05,
    **kwargs,
) -> tuple[Branch, Branch]:
    """The two branches leaving the bifurcation ``point`` along +phi and -phi, continued to
    ``stop``: phi the null vector of [dR/dq, dR/dlambda] orthogonal to the known tangent
    (the mirror-image buckled branches at alpha = 0, pi)."""
    family = StaticFamily(model, parameter)
    n = model.n
    J = family.at(point.value).static_jacobian(point.q)
    Rl = family.dR_dlambda(point.q, point.value)
    # the null space of [J, R_lambda] (dimension 2 at a simple branch point)
    _, _, Vt = np.linalg.svd(np.hstack([J.toarray() if sp.issparse(J) else J, Rl[:, None]]))
    N2 = Vt[-2:].T
    # less its component along the known tangent, in the arclength metric
    t0, dot = point.tangent, family.inner
    cand = [c - dot(c, t0) / dot(t0, t0) * t0 for c in (N2[:, 0], N2[:, 1])]
    phi = normalize(family, max(cand, key=lambda c: dot(c, c)))
    tol = kwargs.get("tol", 1e-10)
    out = []
    for sgn in (1.0, -1.0):
        y0 = np.append(point.q, point.value) + sgn * ds * phi
        res = correct(family, y0, sgn * phi, lambda y: family.balanced(y, tol))
        if res is None:
            raise NewtonError(
                f"branch switching failed at {parameter}={point.value:.8g}",
                params=family.at(point.value).params,
                iterations=0,
                residual=float("nan"),
            )
        y = res[0]
        start = family.at(float(y[n]))
        out.append(continue_static(start, parameter, stop, y[:n], ds, tangent=sgn * phi, **kwargs))
    return out[0], out[1]

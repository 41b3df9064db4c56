"""Keller's pseudo-arclength method with the exact tangent, for any problem.

On a :class:`~fempipe.solvers.continuation.protocol.ContinuationProblem`: :func:`tangent`
(from the bordered system, with the sign and log|det| of the bordered matrix),
:func:`correct` (Newton on ``[F(y); <t, y - y_pred>] = 0``) and :func:`locate` (bisection in
arclength for a test function's zero).  :class:`KellerPolicy` is the engine's policy built
from them, used by the static branches (:mod:`fempipe.analyses.statics`).

Derivation: docs/theory/numerics.md, "Pseudo-arclength continuation".
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from .protocol import ContinuationError, ContinuationProblem, CorrectorError, SharpTurnError


@dataclass(frozen=True)
class CurvePoint:
    """One point of a continuation branch."""

    q: np.ndarray  # the state x
    value: float  # the parameter lambda
    tangent: np.ndarray  # unit tangent (dq, dlambda) in the arclength norm
    iterations: int
    residual_norm: float
    det_sign: int  # sign of det of the bordered Jacobian; flips at bifurcations


@dataclass(frozen=True)
class CurveEvent:
    """A fold (``kind="fold"``) or a branch point (``"bifurcation"``) located on a branch."""

    kind: str
    value: float
    q: np.ndarray
    tangent: np.ndarray
    index: int  # the branch segment [index, index + 1] that contains it


@dataclass(frozen=True)
class KellerStep:
    """A predicted step: from ``previous`` along its tangent by ``h``."""

    previous: CurvePoint
    h: float
    y_pred: np.ndarray


def normalize(problem: ContinuationProblem, t: np.ndarray) -> np.ndarray:
    """``t / ||t||`` in the problem's inner product."""
    return t / np.sqrt(problem.inner(t, t))


def tangent(
    problem: ContinuationProblem, y: np.ndarray, t_prev: np.ndarray
) -> tuple[np.ndarray, int, float]:
    """The unit tangent at y oriented along ``t_prev``; sign and log|det| of the
    bordered matrix (bordered with the row of ``t_prev``)."""
    rhs = np.zeros(y.size)
    rhs[-1] = 1.0
    sol = problem.solve_bordered(
        problem.derivatives(y), problem.dual(t_prev), rhs, determinant=True
    )
    t = normalize(problem, sol.z)
    if problem.inner(t, t_prev) < 0:
        t = -t
    return t, sol.det_sign, sol.log_abs_det


def correct(
    problem: ContinuationProblem,
    y_pred: np.ndarray,
    t: np.ndarray,
    converged: Callable[[np.ndarray], float | None],
    max_iter: int = 12,
) -> tuple[np.ndarray, int, float] | None:
    """Newton on [F(y); <t, y - y_pred>] = 0 from ``y_pred`` until the step is below ``1e-10 (1 +
    ||y||)`` and ``converged(y)`` is not None: (y, iterations, residual norm), or None."""
    y = y_pred.copy()
    for it in range(1, max_iter + 1):
        r = problem.residual(y)
        g = np.append(r, problem.inner(t, y - y_pred))
        dy = problem.solve_bordered(problem.derivatives(y), problem.dual(t), -g).z
        if not np.all(np.isfinite(dy)):
            return None
        y = y + dy
        step = np.sqrt(abs(problem.inner(dy, dy)))
        if step < 1e-10 * (1.0 + np.sqrt(problem.inner(y, y))):
            rn = converged(y)
            if rn is not None:
                return y, it, rn
        if step > 1e3:
            return None
    return None


def locate(
    problem: ContinuationProblem,
    a: CurvePoint,
    b: CurvePoint,
    f: Callable,
    corrector: Callable[[np.ndarray, np.ndarray], tuple | None],
    locate_tol: float,
):
    """Bisection in arclength along the secant from a, for a sign change of f, to ``locate_tol``.

    ``f(y, t, sign, logdet)`` is continuous along the branch; ``corrector(y_pred, t)`` is
    :func:`correct` with the branch's test.  Where the corrector fails near a branch point the
    zero of f's linear interpolant is taken (docs/theory/numerics.md).  Returns (y, t) or None.
    """
    ya = np.append(a.q, a.value)
    yb = np.append(b.q, b.value)
    chord = yb - ya
    length = np.sqrt(problem.inner(chord, chord))
    if length == 0:
        return None
    direction = chord / length
    t_ref = a.tangent

    def evaluate(y):
        t, sign, logdet = tangent(problem, y, t_ref)
        return t, f(y, t, sign, logdet)

    # The bracket's ends: (position along the chord, state, tangent, f).
    lo = (0.0, ya, *evaluate(ya))
    hi = (length, yb, *evaluate(yb))
    best = None
    while hi[0] - lo[0] > locate_tol:
        mid = 0.5 * (lo[0] + hi[0])
        res = corrector(ya + mid * direction, direction)
        if res is None:
            return interpolate_zero(problem, lo, hi)
        y = res[0]
        t, fm = evaluate(y)
        best = (y, t)
        if np.sign(fm) == np.sign(lo[3]):
            lo = (mid, y, t, fm)
        else:
            hi = (mid, y, t, fm)
    return best


def interpolate_zero(problem: ContinuationProblem, lo: tuple, hi: tuple):
    """The zero of f interpolated linearly between the bracket's ends
    ``(s, y, t, f)`` (f of opposite signs): its state and unit tangent."""
    f_lo, f_hi = lo[3], hi[3]
    w = f_lo / (f_lo - f_hi) if f_lo != f_hi else 0.5
    y = lo[1] + w * (hi[1] - lo[1])
    t = normalize(problem, lo[2] + w * (hi[2] - lo[2]))
    return y, t


class KellerPolicy:
    """Pseudo-arclength continuation with the exact tangent (the static branches' policy).

    Keeps ``points``, ``events``, ``steps`` and ``rejected_steps``; subclasses choose
    :attr:`point_type`, :attr:`event_type`, :meth:`converged`, :meth:`land`, :meth:`stalled`.

    Parameters
    ----------
    problem : ContinuationProblem
    first : CurvePoint
        The converged first point with its tangent.
    ds_min, ds_max : float
        Smallest and largest arclength step.
    max_steps : int
        Attempted steps before the branch ends.
    tol : float
        Tolerance of :meth:`converged`.
    detect, locate_tol : bool, float
        Locate folds and branch points, to this bracket in arclength.
    callback : callable, optional
        Called with each accepted point.
    """

    point_type = CurvePoint
    event_type = CurveEvent

    def __init__(
        self,
        problem: ContinuationProblem,
        first: CurvePoint,
        *,
        ds_min: float = 1e-6,
        ds_max: float = 0.5,
        max_steps: int = 2000,
        tol: float = 1e-10,
        detect: bool = True,
        locate_tol: float = 1e-10,
        callback: Callable[[Any], None] | None = None,
    ) -> None:
        self.problem = problem
        self.points = [first]
        self.events: list = []
        self.ds_min, self.ds_max, self.max_steps = ds_min, ds_max, max_steps
        self.tol, self.detect_events, self.locate_tol = tol, detect, locate_tol
        self.callback = callback
        self.steps = self.rejected_steps = self.attempts = 0
        self.end_reason: str | None = None

    # -- the choices a subclass may change ------------------------------------
    def converged(self, y: np.ndarray) -> float | None:
        """The residual norm of a converged point, None if it is not one."""
        rn = float(np.linalg.norm(self.problem.residual(y)))
        return rn if rn <= self.tol else None

    def corrector(self, y_pred: np.ndarray, t: np.ndarray) -> tuple | None:
        """:func:`correct` with :meth:`converged`."""
        return correct(self.problem, y_pred, t, self.converged)

    def stalled(self, step: KellerStep) -> Exception:
        """The error raised when the step falls below ``ds_min``."""
        return ContinuationError(
            f"continuation stalled at {step.previous.value:.8g}: "
            f"arclength step fell below {self.ds_min:g}"
        )

    # -- the policy protocol ---------------------------------------------------
    def stop_before(self) -> str | None:
        if self.attempts >= self.max_steps:
            return "max_steps"
        self.attempts += 1
        return None

    def predict(self, h: float) -> KellerStep:
        prev = self.points[-1]
        y_prev = np.append(prev.q, prev.value)
        return KellerStep(prev, h, y_prev + h * prev.tangent)

    def correct(self, step: KellerStep):
        res = self.corrector(step.y_pred, step.previous.tangent)
        if res is None:
            raise CorrectorError("no convergence")
        y, its, rn = res
        n = y.size - 1
        t_new, sign, _ = tangent(self.problem, y, step.previous.tangent)
        return self.point_type(y[:n], float(y[n]), t_new, its, rn, sign)

    def accept(self, step: KellerStep, point) -> None:
        # Refuse steps that turn too sharply: they may jump branches.
        if (
            self.problem.inner(point.tangent, step.previous.tangent) < 0.8
            and step.h > self.ds_min * 4
        ):
            raise SharpTurnError("the branch turned too sharply")

    def reject(self, step: KellerStep, h: float, failure: CorrectorError) -> float:
        self.rejected_steps += 1
        h *= 0.5
        if not isinstance(failure, SharpTurnError) and h < self.ds_min:
            raise self.stalled(step)
        return h

    def land(self, step: KellerStep, point):
        return point

    def detect(self, step: KellerStep, point) -> None:
        """Locate a fold (t_lambda changes sign) or a bifurcation (det sign flip)
        between the last point and ``point``."""
        if not self.detect_events:
            return
        problem, a, b = self.problem, step.previous, point
        n = a.q.size
        idx = len(self.points) - 1
        if a.tangent[n] * b.tangent[n] < 0:
            found = locate(
                problem, a, b, lambda y, t, s, logdet: t[n], self.corrector, self.locate_tol
            )
            if found is not None:
                y, t = found
                self.events.append(self.event_type("fold", float(y[n]), y[:n], t, idx))
        if a.det_sign != b.det_sign:
            # At a fold the bordered determinant keeps its sign; a flip is a branch point.
            # The test function is the determinant itself (relative to its value at a,
            # so that it neither overflows nor underflows): continuous and linear
            # through a simple branch point, which the interpolation of locate needs.
            _, _, logdet_a = tangent(problem, np.append(a.q, a.value), a.tangent)
            found = locate(
                problem,
                a,
                b,
                lambda y, t, s, logdet: s * np.exp(logdet - logdet_a),
                self.corrector,
                self.locate_tol,
            )
            if found is not None:
                # The bordered matrix is singular at a branch point, so the tangent
                # computed there is meaningless; the chord of the bracketing
                # points is the known branch's direction to O(step^2).
                chord = np.append(b.q - a.q, b.value - a.value)
                y = found[0]
                self.events.append(
                    self.event_type(
                        "bifurcation", float(y[n]), y[:n], normalize(problem, chord), idx
                    )
                )
        self.events.sort(key=lambda s: (s.index, s.value))

    def append(self, point) -> None:
        self.points.append(point)
        self.steps += 1

    def next_step(self, step: KellerStep, point, h: float) -> float:
        its = point.iterations
        return min(self.ds_max, h * (1.5 if its <= 3 else (1.0 if its <= 5 else 0.5)))

    def notify(self, point, h: float) -> None:
        if self.callback:
            self.callback(point)

    def stop_after(self, step: KellerStep, point) -> str | None:
        return self.end_reason

    def finish(self, reason: str, h: float):
        """The policy itself, holding the branch (a subclass returns its own result)."""
        self.end_reason = reason
        return self

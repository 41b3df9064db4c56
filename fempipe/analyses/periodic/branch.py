"""A branch of periodic orbits from a Hopf point: :func:`continue_cycles`.

The engine of :mod:`fempipe.solvers.continuation` walks the branch with
:class:`CycleBranchPolicy`: the first step along the Hopf eigenvector, later ones along the
secant with a polynomial predictor (:func:`predict`), the chord-Newton corrector of
:class:`~fempipe.analyses.periodic.problem.CycleCorrector` (at fixed v where a requested v lies
ahead), steps refused when the secant turns by more than :data:`MAX_ANGLE`.

Method: docs/theory/numerics.md, "Branches of periodic orbits".
"""

from __future__ import annotations

import logging
import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from fempipe.core.parallel import single_blas_thread
from fempipe.model.dynamics_problem import refuse_hysteretic
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.continuation import CorrectorError, SharpTurnError, continue_curve

from .problem import MONODROMY_AT_ORBIT, MONODROMY_NEAR, CycleCorrector, Flow
from .results import (
    MIN_SWING,
    CycleBranch,
    CycleContinuationError,
    CyclePoint,
    HopfPoint,
    swing,
)
from .special import cycle_branch

__all__ = [
    "GRID_RTOL_FACTOR",
    "MAX_ANGLE",
    "MAX_PERIOD_RATIO",
    "MIN_DV_DS",
    "CycleBranchPolicy",
    "continue_cycles",
    "predict",
]

log = logging.getLogger(__name__)

#: Largest turn (rad) between two consecutive secants before the step is halved.
MAX_ANGLE = 0.5
#: The branch stops when the period exceeds this multiple of the Hopf period.
MAX_PERIOD_RATIO = 20.0
#: |dv/ds| below which v is not used as the local parameter (near folds).
MIN_DV_DS = 0.2
#: The orbits at the requested v are integrated this much more accurately than the
#: continuation's own steps, which only trace the branch (docs/theory/numerics.md).
GRID_RTOL_FACTOR = 0.5


@dataclass(frozen=True)
class CycleStep:
    """A predicted step of ``h`` from ``u_k`` along ``secant``; fixed v if ``tangent`` is None."""

    h: float
    u_k: np.ndarray
    secant: np.ndarray
    u_pred: np.ndarray
    tangent: np.ndarray | None
    source: str
    near: float
    t0: float


@dataclass(frozen=True)
class CorrectedOrbit:
    """The corrector's result (u, flow, monodromy, iterations, rejected) and its rtol."""

    got: tuple
    rtol: float

    @property
    def u(self) -> np.ndarray:
        return self.got[0]


@dataclass(frozen=True)
class AcceptedOrbit:
    """An accepted point of the branch: its :class:`CyclePoint`, u and last flow."""

    point: CyclePoint
    u: np.ndarray
    flow: Flow


class CycleBranchPolicy:
    """The :class:`~fempipe.solvers.continuation.ContinuationPolicy` of a branch of
    periodic orbits; holds the branch (``points``, their ``us``, the counters)."""

    def __init__(
        self,
        model: PipeModel,
        hopf: HopfPoint,
        v_range: tuple[float, float],
        values: Sequence[float],
        *,
        name: str,
        rtol: float,
        tol: float,
        xtol: float,
        ds_min: float,
        ds_max: float,
        max_steps: int,
        max_iter: int,
        on_point: Callable[[dict], None] | None,
    ) -> None:
        self.t_start = time.perf_counter()
        self.v_lo, self.v_hi = v_lo, v_hi = v_range
        self.grid = np.array(sorted(float(v) for v in values if v_lo <= v <= v_hi))
        self.cont = cont = CycleCorrector(model, hopf, rtol, tol, xtol, max_iter)
        self.name, self.hopf, self.on_point = name, hopf, on_point
        self.ds_min, self.ds_max, self.max_steps = ds_min, ds_max, max_steps
        self.n = n = model.n
        self.u_H = np.r_[hopf.q_static, np.zeros(n), cont.T_H, hopf.v]
        self.points: list[CyclePoint] = []
        self.seed = None  # the last flow with the sensitivity of the previous point, if any
        self.steps = self.rejected = 0
        self.wall_before, self.integ_before = 0.0, 0
        self.us = [self.u_H]
        # Rotate z so that Re z is the major axis of the ellipse Re(z e^{i omega tau})
        # in the metric: the first orbit starts on it and later ones stay there
        # (the phase section through a principal axis is orthogonal to the flow).
        w = cont.S[: 2 * n]
        a, b = w * hopf.eigenvector.real, w * hopf.eigenvector.imag
        psi = 0.5 * math.atan2(-2.0 * float(a @ b), float(a @ a - b @ b))
        z_hopf_dir = cont.S * np.r_[(hopf.eigenvector * np.exp(1j * psi)).real, 0.0, 0.0]
        z_hopf_dir /= np.linalg.norm(z_hopf_dir)
        self.z_hopf_dir = self.secant = z_hopf_dir

    def resume(self, state: dict) -> float:
        """Continue from the state written by ``on_point``; returns its step size."""
        self.points = [CyclePoint.from_dict(d) for d in state["points"]]
        self.steps, self.rejected = int(state["steps"]), int(state["rejected_steps"])
        self.integ_before = int(state["newton_iterations"])
        self.wall_before = float(state["wall_time"])
        self.us = [self.u_H] + [np.r_[p.q0, p.qdot0, p.period, p.v] for p in self.points]
        return float(state["ds"])

    def branch(self, reason: str, its: int, wall: float) -> CycleBranch:
        """The branch of the points so far."""
        return cycle_branch(
            self.name, self.hopf, self.points, reason, self.steps, self.rejected, its, wall
        )

    def state(self, ds: float, end_reason=None, error=None) -> dict:
        """The plain-JSON state of the branch, which ``resume`` accepts."""
        return {
            "name": self.name,
            "hopf": self.hopf.to_dict(),
            "points": [p.to_dict(state=True) for p in self.points],
            "ds": ds,
            "steps": self.steps,
            "rejected_steps": self.rejected,
            "newton_iterations": self.integ_before + self.cont.integrations,
            "wall_time": self.wall_before + time.perf_counter() - self.t_start,
            "end_reason": end_reason,
            "error": error,
        }

    # -- the policy protocol ---------------------------------------------------
    def stop_before(self) -> str | None:
        if self.steps >= self.max_steps:
            return f"max_steps ({self.max_steps}) reached"
        us = self.us
        u_k = us[-1]
        if len(us) == 1:
            tangent = self.z_hopf_dir
        else:
            d = self.cont.S * (us[-1] - us[-2])
            tangent = d / np.linalg.norm(d)
        self.secant = tangent
        t_v = tangent[-1]  # dv/ds (v weight 1)
        v_k = u_k[-1]
        if len(us) > 1 and abs(t_v) >= MIN_DV_DS:
            if (t_v > 0 and v_k >= self.v_hi - 1e-12) or (t_v < 0 and v_k <= self.v_lo + 1e-12):
                return "reached the end of the v range"
        return None

    def predict(self, ds: float) -> CycleStep:
        us, tangent, grid, S = self.us, self.secant, self.grid, self.cont.S
        u_k = us[-1]
        t_v = tangent[-1]
        v_k = u_k[-1]
        # A requested v ahead within 1.5 steps: land on it at fixed v.
        target = None
        if len(us) > 1 and abs(t_v) >= MIN_DV_DS:
            reach = v_k + 1.5 * ds * t_v
            lo_, hi_ = sorted((v_k, reach))
            ahead = grid[(grid > lo_ + 1e-9) & (grid < hi_ + 1e-12)]
            if ahead.size:
                target = float(ahead[0] if t_v > 0 else ahead[-1])
        t0 = time.perf_counter()
        if target is not None:
            h = (target - v_k) / t_v
            u_pred = predict(S, us, tangent, h)
            u_pred[-1] = target
            return CycleStep(h, u_k, tangent, u_pred, None, "grid", MONODROMY_AT_ORBIT, t0)
        h = ds
        u_pred = predict(S, us, tangent, h)
        return CycleStep(h, u_k, tangent, u_pred, tangent, "continuation", MONODROMY_NEAR, t0)

    def correct(self, step: CycleStep) -> CorrectedOrbit:
        cont, points = self.cont, self.points
        u_ref = step.u_k if len(self.us) > 1 else None
        rtol_k = cont.rtol_after(points[-1] if points else None)
        if step.source == "grid":
            rtol_k *= GRID_RTOL_FACTOR
        try:
            got = cont.correct(
                step.u_pred,
                step.tangent,
                u_ref,
                rtol_k,
                step.near,
                self.seed if step.source == "grid" else None,
            )
        except CorrectorError as first:
            # Newton can stall on the jumps of the adaptive step sequence: the same
            # step once more, ten times more accurately, before the step is halved.
            log.info(
                "%s: %s at v = %.6g; rtol %.1e", self.name, first, step.u_pred[-1], rtol_k / 10
            )
            self.rejected += 1
            got = cont.correct(step.u_pred, step.tangent, u_ref, rtol_k / 10, step.near)
        return CorrectedOrbit(got, rtol_k)

    def accept(self, step: CycleStep, new: CorrectedOrbit) -> None:
        d_new = self.cont.S * (new.u - step.u_k)
        # (From the equilibrium to the first orbit is no secant of the family.)
        if len(self.us) > 2:
            cosang = float(d_new @ step.secant) / max(np.linalg.norm(d_new), 1e-300)
            turn = math.acos(max(-1.0, min(1.0, cosang)))
            if turn > MAX_ANGLE:
                raise SharpTurnError(f"the branch turned by {turn:.2f} rad in one step")

    def reject(self, step: CycleStep, ds: float, failure: CorrectorError) -> float:
        self.rejected += 1
        ds = 0.5 * min(ds, abs(step.h))
        log.info(
            "%s: corrector failed at v = %.6g (%s); step %.3g",
            self.name,
            step.u_pred[-1],
            failure,
            ds,
        )
        if ds < self.ds_min:
            msg = (
                f"branch {self.name} of periodic orbits (from the Hopf point "
                f"v = {self.hopf.v:.6g}) cannot be continued beyond v = {step.u_k[-1]:.6g}: "
                f"the corrector failed at v = {step.u_pred[-1]:.6g} with the smallest step "
                f"ds = {self.ds_min:g} (step {self.steps + 1}; {failure})"
            )
            st = self.state(ds, end_reason="failed", error=msg)
            if self.on_point is not None:
                self.on_point(st)
            raise CycleContinuationError(
                msg, self.branch("failed", st["newton_iterations"], st["wall_time"])
            ) from None
        return ds

    def land(self, step: CycleStep, new: CorrectedOrbit) -> AcceptedOrbit:
        """Land on the requested v passed by the step, then the step's own point."""
        u, fl, mono, it, rej = new.got
        if step.source == "continuation" and self.grid.size:
            self._land_passed(step, u, new.rtol)
        pt = self.cont.point(u, fl, mono, it, rej, step.source, step.t0)
        return AcceptedOrbit(pt, u, fl)

    def _land_passed(self, step: CycleStep, u: np.ndarray, rtol_k: float) -> None:
        """Land at fixed v on the requested v this step passed (near the Hopf point or a
        fold, where v is no local parameter), from the secant of the orbits around them."""
        us, u_k, n, cont, name = self.us, step.u_k, self.n, self.cont, self.name
        v_k = u_k[-1]
        lo_, hi_ = sorted((v_k, u[-1]))
        crossed = self.grid[(self.grid > lo_ + 1e-9) & (self.grid < hi_ - 1e-9)]
        for vg in crossed if u[-1] > v_k else crossed[::-1]:
            t1 = time.perf_counter()
            w = (vg - v_k) / (u[-1] - v_k)
            ug = u_k + w * (u - u_k)
            if len(us) == 1:
                # From the Hopf point the amplitude grows like sqrt(v - v_H).
                ug[: 2 * n] = u_k[: 2 * n] + math.sqrt(w) * (u - u_k)[: 2 * n]
            ug[-1] = vg
            try:
                got = cont.correct(
                    ug, None, u_k if len(us) > 1 else None, rtol_k, MONODROMY_AT_ORBIT
                )
            except CorrectorError as exc:
                log.warning("%s: requested v = %.6g passed but not landed on (%s)", name, vg, exc)
                continue
            gpt = cont.point(*got, "grid", t1)
            if swing(gpt) < MIN_SWING:
                log.warning("%s: v = %.6g converged to the equilibrium", name, vg)
                continue
            self.points.append(gpt)
            us.append(got[0])

    def detect(self, step: CycleStep, new: AcceptedOrbit) -> None:
        return None  # special points come from the whole branch (special_points)

    def append(self, new: AcceptedOrbit) -> None:
        self.points.append(new.point)
        self.us.append(new.u)
        # A last flow with the sensitivity (at a requested v) seeds the
        # chord matrix of the next landing on a requested v.
        self.seed = new.flow if new.flow.monodromy is not None else None
        self.steps += 1

    def next_step(self, step: CycleStep, new: AcceptedOrbit, ds: float) -> float:
        it = new.point.iterations
        if it <= 4:
            ds = min(self.ds_max, 1.5 * max(ds, abs(step.h)))
        elif it > 5:
            ds = max(self.ds_min, 0.5 * ds)
        return ds

    def notify(self, new: AcceptedOrbit, ds: float) -> None:
        pt = new.point
        if self.on_point is not None:
            self.on_point(self.state(ds))
        log.info(
            "%s v=%.6g T=%.6g eta [%.4g, %.4g] %s %s (%d its)",
            self.name,
            pt.v,
            pt.period,
            *pt.tip["eta_tip"],
            "stable" if pt.stable else "unstable",
            pt.source,
            pt.iterations,
        )

    def stop_after(self, step: CycleStep, new: AcceptedOrbit) -> str | None:
        pt, points, v_lo, v_hi = new.point, self.points, self.v_lo, self.v_hi
        if swing(pt) < MIN_SWING and len(points) > 2:
            return f"returned to an equilibrium near v = {pt.v:.6g} (a Hopf point)"
        if pt.period > MAX_PERIOD_RATIO * self.cont.T_H:
            return f"period above {MAX_PERIOD_RATIO:g} T_H (homoclinic approach)"
        if not v_lo - 1e-12 <= pt.v <= v_hi + 1e-12 and len(points) > 1:
            inside = v_lo <= self.hopf.v <= v_hi
            prev_v = points[-2].v
            # Outside the range: stop once moving away from it.
            if inside or (pt.v - prev_v) * (pt.v - 0.5 * (v_lo + v_hi)) > 0:
                return "left the v range"
        return None

    def finish(self, reason: str, ds: float) -> CycleBranch:
        st = self.state(ds, end_reason=reason)
        if self.on_point is not None:
            self.on_point(st)
        return self.branch(reason, st["newton_iterations"], st["wall_time"])


def continue_cycles(
    model: PipeModel,
    hopf: HopfPoint,
    v_range: tuple[float, float],
    values: Sequence[float] = (),
    *,
    name: str = "H1",
    rtol: float = 1e-5,
    tol: float = 1e-6,
    xtol: float = 2e-7,
    ds: float = 0.1,
    ds_min: float = 1e-3,
    ds_max: float = 0.5,
    max_steps: int = 200,
    max_iter: int = 6,
    resume: dict | None = None,
    on_point: Callable[[dict], None] | None = None,
) -> CycleBranch:
    """Follow the periodic orbits born at a Hopf point by pseudo-arclength continuation. Eq. (20).

    Single shooting in (x0, T, v) with the exact monodromy, a Poincare phase condition and
    Keller's arclength condition (or v fixed on ``values``); docs/theory/numerics.md.

    Parameters
    ----------
    model : PipeModel
        Its v is ignored.
    hopf : HopfPoint
        Where the branch starts (:func:`find_hopf_points`).
    v_range : (float, float)
        The branch ends once it leaves this range.
    values : sequence of float
        v landed on every time the branch passes (``source="grid"``).
    name : str
    rtol : float
        Integration tolerance (smaller near a multiplier 1 and at ``values``).
    tol, xtol : float
        Newton tolerances on the RMS residual and on the correction.
    ds, ds_min, ds_max : float
        First, smallest and largest arclength step.
    max_steps, max_iter : int
        Steps of the branch, Newton iterations per corrector.
    resume : dict, optional
        An interrupted run's state (from ``on_point``) to continue from.
    on_point : callable, optional
        Called after every accepted point with the branch's plain-JSON state.

    Returns
    -------
    CycleBranch

    Raises
    ------
    CycleContinuationError
        The corrector failed at the smallest step (carries the finished branch).
    ValueError
        Bad arguments or hysteretic damping.
    """
    refuse_hysteretic(model.params, "continue_cycles")
    v_lo, v_hi = _checked_range(v_range, ds, ds_min, ds_max, tol, rtol)
    policy = CycleBranchPolicy(
        model,
        hopf,
        (v_lo, v_hi),
        values,
        name=name,
        rtol=rtol,
        tol=tol,
        xtol=xtol,
        ds_min=ds_min,
        ds_max=ds_max,
        max_steps=max_steps,
        max_iter=max_iter,
        on_point=on_point,
    )
    if resume is not None:
        ds = policy.resume(resume)
        if resume.get("end_reason") is not None:
            br = policy.branch(resume["end_reason"], policy.integ_before, policy.wall_before)
            if resume["end_reason"] == "failed":
                raise CycleContinuationError(resume["error"], br)
            return br
    with single_blas_thread():
        return continue_curve(policy, ds)


def _checked_range(v_range, ds, ds_min, ds_max, tol, rtol) -> tuple[float, float]:
    """``v_range`` as floats (v_min, v_max); ValueError for bad ranges, steps or tolerances."""
    v_lo, v_hi = (float(a) for a in v_range)
    if not v_lo < v_hi:
        raise ValueError(f"v_range must have v_min < v_max, got {v_range}")
    if not 0 < ds_min <= ds <= ds_max:
        raise ValueError(f"need 0 < ds_min <= ds <= ds_max, got {ds_min}, {ds}, {ds_max}")
    if not 0 < tol < 1 or not 0 < rtol < 1:
        raise ValueError(f"tol and rtol must lie in (0, 1), got {tol}, {rtol}")
    return v_lo, v_hi


def predict(S: np.ndarray, us: list, tangent: np.ndarray, h: float) -> np.ndarray:
    """The point at arclength h ahead: on the polynomial through the last four (or three)
    about evenly spaced points in chord length (h at most 1.5 gaps), else on the tangent."""
    for m in (4, 3):
        if len(us) < m:
            continue
        z = [S * u for u in us[-m:]]
        gaps = np.array([np.linalg.norm(z[k + 1] - z[k]) for k in range(m - 1)])
        if gaps.min() < 0.5 * gaps.max() or abs(h) > 1.5 * gaps[-1]:
            continue
        nodes = np.r_[0.0, np.cumsum(gaps)]
        s = nodes[-1] + h
        w = [
            math.prod((s - nodes[q]) / (nodes[j] - nodes[q]) for q in range(m) if q != j)
            for j in range(m)
        ]
        return sum(wj * zj for wj, zj in zip(w, z, strict=True)) / S
    return us[-1] + h * tangent / S

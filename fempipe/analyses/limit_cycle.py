"""Attractors of Eq. (20): equilibria, periodic orbits (limit cycles), non-periodic motion.

The post-flutter motion of the paper (Section 5, Figs. 7-12) is a limit cycle.
This module finds it in three stages:

1. **Integration past the transient** with :class:`fempipe.solvers.radau.Radau`,
   recording a Poincare section of the tip motion: the upward crossings of
   the tip's lateral displacement eta(1) through a level (the static value,
   about which the Hopf cycle is born).  The full state at each crossing is
   kept.
2. **Recurrence**: the smallest n for which the section points x_k and
   x_{k-n} agree gives a period-n candidate (n distinct points on the
   section: period-1, period-2, ...).  Equilibria are recognised when the
   state comes close to a linearly stable static state (the criterion of
   :func:`fempipe.analyses.stability.linearly_stable`, as for ``spectrum`` and
   ``critical``) and keeps approaching it; motion without recurrence until ``t_max`` is reported as non-periodic.
   When the returns approach each other fast (the distance falls more than
   2x per return, as the 0.15 per period of the paper's cycle at v = 10), the
   integration goes on until they are within ``start_tol`` (1e-3): a period
   of plain integration costs about a third of a shooting iteration, and
   Newton's method from there needs one step and the check.  Near a Hopf
   point, where the returns approach slowly, the shooting starts at
   ``recurrence_tol`` (2e-2).
3. **Shooting**: Newton's method on ``phi_T(x0) - x0 = 0`` with the phase
   condition ``eta_tip(x0) = level``, unknowns (x0, T).  The Jacobian uses the
   monodromy matrix, the exact derivative of the discrete Radau flow map
   (accumulated step by step from the stage Jacobians, see
   :meth:`fempipe.solvers.radau.Radau._accumulate_sensitivity`), so Newton converges
   quadratically and the eigenvalues of the matrix are the Floquet multipliers
   to the integration accuracy.  One multiplier is 1 (the phase along the
   orbit); the cycle is stable when all others are inside the unit circle.
   The converged iterate (residual below the tolerance) is always one whose
   monodromy was integrated; one more Newton step with that matrix polishes
   it to O(residual^2), checked by a plain period, so the reported orbit is
   the cycle to the integration accuracy and the multipliers are those of a
   state one converged step from it.  The tip extrema are taken on
   the quintic Hermite interpolant through (q, q', q'') at the steps
   (:func:`_cycle_tip_ranges`), as accurate as the steps themselves.

Accuracy and cost (P3:16, the paper's beta, gamma, mu, alpha = 0, v = 10;
``fempipe.bench.dynamics``): with the default ``shoot_rtol`` 1e-5 the period
is within 4e-9 and the tip extrema within 2e-7 (relative) of a cycle shot
with ``shoot_rtol`` 1e-10; at v = 7, 12 and at alpha = pi/2, v = 10 within
5e-8 and 5e-7.  The error control of Radau IIA bounds an embedded
lower-order estimate and is conservative: rtol 1e-5 gives 55 steps per
period, rtol 1e-7 172 for errors 100x below what is needed.
"""

from __future__ import annotations

import logging
import math
import time
import warnings
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

from fempipe.core.errors import SolverError
from fempipe.core.parallel import single_blas_thread
from fempipe.core.rootfinding import brentq
from fempipe.model.discretization import Discretization
from fempipe.model.dynamics_problem import refuse_hysteretic
from fempipe.model.kinematics import tip_values
from fempipe.model.operators import PipeModel
from fempipe.solvers.radau import IntegrationError, Radau

from .dynamics import Trajectory, initial_state
from .stability import linearly_stable

__all__ = [
    "TIP_KEYS",
    "LimitCycle",
    "Attractor",
    "ShootingError",
    "tip_coordinates",
    "shoot",
    "find_attractor",
]

log = logging.getLogger(__name__)

#: Tip coordinates recorded on attractors: eta(1) in the local frame,
#: X_g(1) (along gravity) and Z_g(1) (horizontal) in the global frame, Eq. (28).
TIP_KEYS = ("eta_tip", "X_tip", "Z_tip")

#: Returns within ``recurrence_tol`` that :func:`find_attractor` integrates past
#: (fast contraction, not yet within ``start_tol``) before it shoots anyway:
#: from 2e-2, eight returns contracting 2x reach 8e-5, far below start_tol = 1e-3.
MAX_WAITS = 8


class ShootingError(SolverError):
    """Newton's method on the periodic orbit did not converge (or found an equilibrium)."""

    def __init__(self, message: str, iterations: int, residual: float) -> None:
        super().__init__(message)
        self.iterations = iterations
        self.residual = residual

    def __reduce__(self):
        # Rebuilt from all the constructor's arguments (pickling across processes).
        return type(self), (str(self), self.iterations, self.residual)


def tip_coordinates(disc: Discretization, alpha: float, q: np.ndarray) -> dict:
    """The tip coordinates recorded on attractors (:data:`TIP_KEYS`) of one state
    (n,) or many (m, n): those of :func:`fempipe.model.kinematics.tip_values`."""
    tip = tip_values(disc, q, alpha)
    return {k: tip[k] for k in TIP_KEYS}


def _eta(disc: Discretization, q: np.ndarray) -> float:
    """eta_tip, the Poincare section coordinate (independent of alpha)."""
    return tip_values(disc, q, 0.0)["eta_tip"]


def _eta_gradient(disc: Discretization, q: np.ndarray) -> np.ndarray:
    """d eta_tip / dq = \\int phi_j cos theta: the phase condition's row of the Jacobian."""
    th = disc.Phi @ q
    return np.asarray(disc.Phi.T @ (disc.quad.w * np.cos(th)))


def _linearly_stable(model: PipeModel, q_static: np.ndarray) -> bool:
    """The equilibrium test's criterion: :func:`fempipe.analyses.stability.linearly_stable`,
    the decision of ``spectrum`` and ``critical``.

    A discretisation that resolves no mode gives no decision (None), which
    never lets the finder stop at an equilibrium: the attractor is then found
    by integration alone.
    """
    return linearly_stable(model, q_static) is True


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
        tolerance) from ``q0``, ``qdot0`` (see :func:`shoot`).
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
        Time integrated before the attractor was recognised.
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


# ---------------------------------------------------------------------------
def _sample_tip(
    disc: Discretization, alpha: float, stepper: Radau, samples: list, per_step: int = 8
) -> None:
    """Append tip coordinates sampled on the last step's collocation polynomial."""
    t_old, t = stepper.t_old, stepper.t
    ts = np.linspace(t_old, t, per_step + 1)[1:]
    qs = np.array([stepper.dense(s)[0] for s in ts[:-1]] + [stepper.q])
    samples.append((ts, tip_coordinates(disc, alpha, qs)))


def _refined_range(t: np.ndarray, y: np.ndarray) -> list[float]:
    """[min, max] of a densely sampled periodic signal, parabola-refined at the extremum."""
    out = []
    for k in (int(np.argmin(y)), int(np.argmax(y))):
        if 0 < k < y.size - 1 and t[k + 1] > t[k] > t[k - 1]:
            y0, y1, y2 = y[k - 1], y[k], y[k + 1]
            den = y0 - 2 * y1 + y2
            if den != 0:
                s = 0.5 * (y0 - y2) / den
                out.append(float(y1 - 0.25 * (y0 - y2) * s))
                continue
        out.append(float(y[k]))
    return [min(out[0], float(y.min())), max(out[1], float(y.max()))]


#: Quintic Hermite basis on [0, 1] for (y0, h y0', h^2 y0'', y1, h y1', h^2 y1''):
#: coefficients of s^0..s^5, one row per datum.
_QUINTIC = np.array(
    [
        [1.0, 0.0, 0.0, -10.0, 15.0, -6.0],
        [0.0, 1.0, 0.0, -6.0, 8.0, -3.0],
        [0.0, 0.0, 0.5, -1.5, 1.5, -0.5],
        [0.0, 0.0, 0.0, 10.0, -15.0, 6.0],
        [0.0, 0.0, 0.0, -4.0, 7.0, -3.0],
        [0.0, 0.0, 0.0, 0.5, -1.0, 0.5],
    ]
)


class _QuinticOrbit:
    """The quintic Hermite interpolant of q(t) through the accepted steps.

    ``t``, ``q``, ``p``, ``a``: times and (q, q', q'') at the step ends
    (shapes (m,), (m, n)).  The interpolant through q, q' and q'' at both ends
    of a step is accurate to O(h^6), like the step ends themselves; the
    integrator's own dense output (the collocation cubic) is only O(h^4)
    inside a step.
    """

    def __init__(self, t, q, p, a) -> None:
        t, q, p, a = (np.asarray(x, dtype=float) for x in (t, q, p, a))
        keep = np.concatenate([np.diff(t) > 0, [True]])  # no zero-length steps
        t, q, p, a = t[keep], q[keep], p[keep], a[keep]
        h = np.diff(t)[:, None]
        self.t, self.h = t, h[:, 0]
        self.data = np.stack(
            [q[:-1], h * p[:-1], h**2 * a[:-1], q[1:], h * p[1:], h**2 * a[1:]], axis=1
        )  # (steps, 6, n)

    def __call__(self, times: np.ndarray) -> np.ndarray:
        times = np.asarray(times, dtype=float)
        k = np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, self.h.size - 1)
        s = (times - self.t[k]) / self.h[k]
        basis = np.vander(s, 6, increasing=True) @ _QUINTIC.T  # (m, 6)
        return np.einsum("md,mdn->mn", basis, self.data[k])


def _cycle_tip_ranges(
    disc: Discretization, alpha: float, t, q, p, a, per_step: int = 8, fine: int = 32
) -> dict:
    """[min, max] of the tip coordinates over one computed period.

    The coordinates are sampled ``per_step`` times per step on the quintic
    interpolant (:class:`_QuinticOrbit`), then each extremum is sampled again
    ``fine`` times between the neighbours of its sample and parabola-refined
    there.  Measured: the collocation cubic with 8 samples per step and a
    parabola put eta_tip's maximum 4e-6 off the cycle's at v = 12 (alpha = 0,
    rtol 1e-5, a sharp peak); this is within 1e-8 of a run at rtol 1e-10.
    """
    orbit = _QuinticOrbit(t, q, p, a)
    s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
    ts = np.append((orbit.t[:-1, None] + orbit.h[:, None] * s[None, :]).ravel(), orbit.t[-1])
    coarse = tip_coordinates(disc, alpha, orbit(ts))
    out = {}
    for key in TIP_KEYS:
        y = coarse[key]
        rng = []
        for k, sign in ((int(np.argmin(y)), 1.0), (int(np.argmax(y)), -1.0)):
            lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, ts.size - 1)]
            tf = np.linspace(lo, hi, fine + 1)
            yf = tip_coordinates(disc, alpha, orbit(tf))[key]
            r = _refined_range(tf, yf)
            rng.append(r[0] if sign > 0 else r[1])
        out[key] = [min(rng[0], float(y.min())), max(rng[1], float(y.max()))]
    return out


def _tip_ranges(samples: list) -> dict:
    t = np.concatenate([s[0] for s in samples])
    return {k: _refined_range(t, np.concatenate([s[1][k] for s in samples])) for k in TIP_KEYS}


def _state_distance(dq: np.ndarray, dp: np.ndarray, timescale: float):
    """RMS distance of two states; velocities scaled by a time scale (period / 2 pi).

    Along the last axis: a float for one pair of states, an array for stacked ones.
    """
    d = np.sqrt(np.mean(dq**2, axis=-1) + np.mean((dp * timescale) ** 2, axis=-1))
    return float(d) if d.ndim == 0 else d


def shoot(
    model: PipeModel,
    q0: np.ndarray,
    qdot0: np.ndarray,
    period: float,
    *,
    level: float | None = None,
    rtol: float = 1e-7,
    tol: float = 1e-6,
    max_iter: int = 12,
    n_samples: int = 200,
    reuse_monodromy: bool = False,
    polish: bool = True,
) -> LimitCycle:
    """Compute a periodic orbit by Newton shooting with the monodromy matrix.

    Parameters
    ----------
    model : PipeModel
    q0, qdot0 : ndarray, shape (n,)
        Initial guess on or near the orbit.
    period : float
        Initial guess of the period.
    level : float, optional
        Phase condition eta_tip(q0) = level (default: eta_tip of the guess).
    rtol : float
        Integration tolerance; the orbit is accurate to about this level.
    tol : float
        Convergence when the RMS of phi_T(x0) - x0 (velocities scaled by
        T / 2 pi) is below ``tol``; must exceed the integration error.
    max_iter : int
    n_samples : int
        Samples of the orbit stored for plotting.
    reuse_monodromy : bool
        Chord-Newton: keep the monodromy matrix of an earlier iterate while
        the residual falls at least 4x per iteration (an iteration without the
        variational step costs about a third).  The Floquet multipliers are
        then those of the last iterate where the matrix was computed, within
        one Newton step of the orbit: good for telling stable from unstable,
        not for quoting digits.  Default False (exact multipliers).
    polish : bool
        Once converged with a residual between ``tol`` / 10 and ``tol``, take
        the next Newton step too and integrate one plain period (no
        monodromy) from there; its
        orbit, tips, period and residual are reported if its residual is
        smaller (it is O(residual^2) up to the integration's own noise).  The
        Floquet multipliers stay those of the converged iterate, one step
        (< ``tol``) from the reported state: the monodromy is not integrated
        again for a change of that order.  ``iterations`` counts the polish.

    Returns
    -------
    LimitCycle

    Raises
    ------
    ShootingError
        Naming v, the iterations and the last residual.
    ValueError
        If the model has hysteretic damping (no time-domain meaning).
    """
    refuse_hysteretic(model.params, "shoot")
    if not period > 0:
        raise ValueError(f"period must be > 0, got {period}")
    disc, alpha, n = model.disc, model.params.alpha, model.n
    q = np.array(q0, dtype=float)
    p = np.array(qdot0, dtype=float)
    T = float(period)
    level = _eta(disc, q) if level is None else float(level)
    res = math.inf
    t_start = time.perf_counter()
    total_steps = rejected = 0
    Phi = None
    res_prev = math.inf
    stale = False

    def one_period(q, p, T, sensitivity: bool):
        """Integrate (q, p) over T; the stepper, the step ends and the orbit samples."""
        stepper = Radau(model, q, p, 0.0, rtol=rtol, sensitivity=sensitivity)
        tt = np.linspace(0.0, T, n_samples)
        orbit_q, orbit_p, k = [q.copy()], [p.copy()], 1
        ends = [(0.0, q.copy(), p.copy(), stepper.qddot.copy())]
        for t_now, q_now, p_now in stepper.steps(T):
            ends.append((t_now, q_now, p_now, stepper.qddot.copy()))
            while k < n_samples and tt[k] <= t_now + 1e-12:
                a, b = stepper.dense(tt[k]) if tt[k] < t_now else (q_now, p_now)
                orbit_q.append(a)
                orbit_p.append(b)
                k += 1
        while len(orbit_q) < n_samples:
            orbit_q.append(stepper.q.copy())
            orbit_p.append(stepper.qdot.copy())
        return stepper, ends, tt, np.array(orbit_q), np.array(orbit_p)

    def newton_step(q, p, T, stepper, g):
        """(dq, dp, dT) of the bordered Newton system with the current Phi, or None."""
        J = np.zeros((2 * n + 1, 2 * n + 1))
        J[: 2 * n, : 2 * n] = Phi - np.eye(2 * n)
        J[: 2 * n, -1] = np.concatenate([stepper.qdot, stepper.qddot])
        J[-1, :n] = _eta_gradient(disc, q)
        rhs = -np.concatenate([stepper.q - q, stepper.qdot - p, [g]])
        try:
            # Near an equilibrium (a decaying oscillation, the Hopf point) the
            # bordered matrix is nearly singular; the step is still judged by
            # the next period's residual, and an orbit that collapses to the
            # equilibrium is refused below, so scipy's warning would only
            # reach the user's terminal as noise.
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sla.LinAlgWarning)
                dx = sla.solve(J, rhs)
        except (sla.LinAlgError, ValueError):
            return None
        return dx if np.all(np.isfinite(dx)) else None

    with single_blas_thread():
        for it in range(1, max_iter + 1):
            need = Phi is None or not reuse_monodromy or stale
            stepper, ends, tt, orbit_q, orbit_p = one_period(q, p, T, need)
            total_steps += stepper.stats.steps
            rejected += stepper.stats.rejected_steps
            scale = T / (2 * math.pi)
            res = _state_distance(stepper.q - q, stepper.qdot - p, scale)
            g = _eta(disc, q) - level
            log.debug("shooting it %d: T=%.10g residual %.3e phase %.3e", it, T, res, g)
            if need:
                Phi = stepper.sensitivity_matrix
            dx = newton_step(q, p, T, stepper, g)
            if res < tol and abs(g) < tol:
                tip = _cycle_tip_ranges(disc, alpha, *zip(*ends, strict=True))
                if max(hi - lo for lo, hi in tip.values()) < 2e-3:
                    # The equilibrium is a periodic orbit of any period, and
                    # Newton started near a decaying oscillation can stop on
                    # the way to it once A |1 - exp(sigma T)| < tol: measured
                    # A = 7e-6 at v_cr - 0.13.  Genuine Hopf cycles this small
                    # (A ~ 0.5 sqrt(v - v_cr) < 1e-3) exist only within 4e-6
                    # of v_cr, so tip swings below 2e-3 are not reported as cycles.
                    raise ShootingError(
                        f"shooting converged to an equilibrium at v = {model.params.v:.6g}",
                        iterations=it,
                        residual=res,
                    )
                mu = np.linalg.eigvals(Phi)
                mu = mu[np.argsort(-np.abs(mu))]
                best = (it, q, p, T, res, tip, stepper, tt, orbit_q, orbit_p)
                if polish and dx is not None and res > 0.1 * tol:
                    # The converged iterate is up to tol from the cycle (1.4e-7
                    # measured on four beam modes: the alpha = 0 cycle's
                    # eta_tip extrema 1.4e-7 asymmetric).  One more Newton step
                    # with the same matrix lands within O(res^2) of it; a plain
                    # period checks it and gives the orbit, tips and period.
                    # Below tol / 10 the iterate is as close as the shooting
                    # map's own integration error (its fixed point moves by
                    # ~1e-7 in the tips between runs at rtol 1e-5): no gain.
                    q2, p2, T2 = q + dx[:n], p + dx[n : 2 * n], T + dx[-1]
                    st2, ends2, tt2, oq2, op2 = one_period(q2, p2, T2, False)
                    total_steps += st2.stats.steps
                    rejected += st2.stats.rejected_steps
                    res2 = _state_distance(st2.q - q2, st2.qdot - p2, T2 / (2 * math.pi))
                    g2 = _eta(disc, q2) - level
                    log.debug("shooting polish: T=%.10g residual %.3e", T2, res2)
                    if res2 < res and abs(g2) < tol:
                        tip2 = _cycle_tip_ranges(disc, alpha, *zip(*ends2, strict=True))
                        best = (it + 1, q2, p2, T2, res2, tip2, st2, tt2, oq2, op2)
                it_, q_, p_, T_, res_, tip_, st_, tt_, oq_, op_ = best
                cycle = LimitCycle(
                    period=T_,
                    q0=q_,
                    qdot0=p_,
                    level=level,
                    tip=tip_,
                    floquet_multipliers=mu,
                    stable=True,
                    iterations=it_,
                    residual=res_,
                    orbit_t=tt_,
                    orbit_q=oq_,
                    orbit_qdot=op_,
                    steps=st_.stats.steps,
                    total_steps=total_steps,
                    rejected_steps=rejected,
                    wall_time=time.perf_counter() - t_start,
                )
                return _with_stability(cycle)
            # A chord iteration that does not cut the residual 4x: fresh matrix next time.
            stale = not need and res > res_prev / 4
            res_prev = res
            if dx is None:
                break
            # Trust region: a Newton step larger than ~0.3 rad RMS leaves the
            # neighbourhood where the linearised map means anything.
            size = _state_distance(dx[:n], dx[n : 2 * n], scale)
            lam = min(1.0, 0.3 / size) if size > 0 else 1.0
            q = q + lam * dx[:n]
            p = p + lam * dx[n : 2 * n]
            T = T + lam * dx[-1]
            if not T > 0:
                break
    raise ShootingError(
        f"shooting did not converge at v = {model.params.v:.6g}, alpha = {alpha:.6g}: "
        f"residual {res:.3e} after {it} Newton iterations",
        iterations=it,
        residual=res,
    )


def _with_stability(cycle: LimitCycle) -> LimitCycle:
    from dataclasses import replace

    return replace(cycle, stable=cycle.max_nontrivial_multiplier < 1.0)


# ---------------------------------------------------------------------------
def find_attractor(
    model: PipeModel,
    q0: np.ndarray | None = None,
    qdot0: np.ndarray | None = None,
    *,
    t_max: float = 300.0,
    rtol: float = 1e-5,
    shoot_rtol: float = 1e-5,
    shoot_tol: float = 1e-6,
    use_shooting: bool = True,
    recurrence_tol: float = 2e-2,
    start_tol: float = 1e-3,
    converged_tol: float = 1e-6,
    equilibrium_radius: float = 1e-2,
    n_max: int = 8,
    record: bool = False,
    perturbation: float = 0.01,
    callback: Callable[[float], None] | None = None,
) -> Attractor:
    """Integrate past the transient and classify the attractor.

    Parameters
    ----------
    model : PipeModel
    q0, qdot0 : ndarray, optional
        Initial state; default the static state plus ``perturbation`` rad in
        the first sine mode, at rest.
    t_max : float
        Longest integration (tau) before declaring the motion non-periodic.
    rtol : float
        Tolerance of the transient integration.
    shoot_rtol, shoot_tol : float
        Integration tolerance and Newton tolerance of the shooting.  The
        default 1e-5 gives the period to 5e-8 and the tip extrema to 5e-7
        (relative, measured at four flutter cycles; module docstring); it was
        1e-7, three times the steps per period for 100x more accuracy than
        the 1e-6 asked of the cycle.
    use_shooting : bool
        If False, a periodic orbit is accepted when successive section returns
        agree to ``converged_tol`` (plain long integration).
    recurrence_tol : float
        Section returns this close (RMS, rad) start the shooting if they
        approach each other slowly (the return distance falls less than 2x
        per return: near a bifurcation, where Newton's method is needed).
    start_tol : float
        Section returns that approach each other fast (more than 2x per
        return, measured on two successive returns) are integrated on until
        this close before the shooting starts: a period of plain integration
        costs about a third of a shooting iteration (which also integrates the
        monodromy matrix) and, at the 0.15 contraction per period of the
        paper's cycle at v = 10, gains more than Newton's first iteration
        does from 2e-2.  From 1e-3 Newton needs one step and the check.
    equilibrium_radius : float
        Within this RMS distance of a linearly stable static state, and still
        approaching it, the attractor is that equilibrium (its basin contains
        this neighbourhood as long as the linearisation dominates; the
        criterion also asks the distance to decrease).
    n_max : int
        Largest period-n looked for.
    record : bool
        Keep the transient trajectory (every step) in ``Attractor.trajectory``.
    callback : callable, optional
        Called with tau after every step.

    Returns
    -------
    Attractor

    Raises
    ------
    ValueError
        If the model has hysteretic damping (no time-domain meaning).
    """
    from fempipe.analyses.statics import NewtonError, solve_static

    refuse_hysteretic(model.params, "find_attractor")
    if not t_max > 0:
        raise ValueError(f"t_max must be > 0, got {t_max}")
    disc, alpha, n = model.disc, model.params.alpha, model.n
    guess = None if q0 is None else np.asarray(q0, dtype=float)
    try:
        q_s = solve_static(model, guess).q
    except NewtonError:
        try:
            q_s = solve_static(model).q
        except NewtonError:
            q_s = None
    stable = q_s is not None and _linearly_stable(model, q_s)
    if q0 is None:
        if q_s is None:
            raise ValueError("no initial state given and the static problem has no solution")
        q0, qdot0 = initial_state(model, 1, perturbation, q_static=q_s)
    qdot0 = np.zeros(n) if qdot0 is None else np.asarray(qdot0, dtype=float)
    level = _eta(disc, q_s) if q_s is not None else _eta(disc, np.asarray(q0))

    stepper = Radau(model, q0, qdot0, 0.0, rtol=rtol)
    stats = {"steps": 0, "rejected_steps": 0, "n_residual": 0, "n_jacobian": 0, "wall_time": 0.0}
    rec_t, rec_q, rec_p = [stepper.t], [stepper.q.copy()], [stepper.qdot.copy()]
    sec_t: list[float] = []
    sec_x: list[tuple[np.ndarray, np.ndarray]] = []
    sec_i: list[int] = []  # index into ``samples`` at each section point
    samples: list = []  # tip coordinates sampled on every step
    max_samples = 20000
    s_old = _eta(disc, stepper.q) - level
    next_eq_check = 0.5
    d_prev = _state_distance(np.asarray(q0) - q_s, qdot0, 0.05) if q_s is not None else math.inf
    tried_tol = recurrence_tol
    last_dist: dict[int, float] = {}  # return distance of period-n when last seen
    waits = 0  # returns within recurrence_tol not shot from because they contract fast
    level_time = 0.0
    result = None

    def finish(kind, period=None, period_n=None, tip=None, cycle=None, q=None, p=None, msg=""):
        st = stepper.stats
        stats.update(
            steps=stats["steps"] + st.steps,
            rejected_steps=stats["rejected_steps"] + st.rejected_steps,
            n_residual=stats["n_residual"] + st.n_residual,
            n_jacobian=stats["n_jacobian"] + st.n_jacobian,
            wall_time=stats["wall_time"] + st.wall_time,
        )
        traj = None
        if record:
            traj = Trajectory.recorded(rec_t, rec_q, rec_p, st, rtol)
        return Attractor(
            kind=kind,
            period=period,
            period_n=period_n,
            tip=tip,
            cycle=cycle,
            q=stepper.q.copy() if q is None else q,
            qdot=stepper.qdot.copy() if p is None else p,
            params=model.params,
            t_end=stepper.t,
            stats=stats,
            trajectory=traj,
            message=msg,
        )

    with single_blas_thread():
        while stepper.t < t_max:
            try:
                stepper.step(t_max)
            except IntegrationError as exc:
                raise IntegrationError(
                    f"{exc} (alpha = {alpha:.6g}, v = {model.params.v:.6g})", exc.t, exc.h
                ) from None
            if record:
                rec_t.append(stepper.t)
                rec_q.append(stepper.q.copy())
                rec_p.append(stepper.qdot.copy())
            if callback is not None:
                callback(stepper.t)
            _sample_tip(disc, alpha, stepper, samples, per_step=4)
            if len(samples) > max_samples:  # keep memory bounded on long runs
                drop = len(samples) - max_samples
                samples = samples[drop:]
                sec_i = [i - drop for i in sec_i]

            # -- equilibrium: close to a linearly stable static state and not
            # moving away from it (checked every 0.5 tau, about two flutter
            # periods, so that the exchange between q and q' averages out).
            if stepper.t >= next_eq_check:
                next_eq_check = stepper.t + 0.5
                if q_s is None or _state_distance(stepper.q - q_s, stepper.qdot, 0.05) > 0.3:
                    # Far from the known static state and almost at rest: maybe
                    # another equilibrium (e.g. a buckled branch at alpha = pi).
                    if np.sqrt(np.mean(stepper.qdot**2)) < 1e-3:
                        try:
                            q_new = solve_static(model, stepper.q).q
                            if _linearly_stable(model, q_new):
                                q_s, stable, d_prev = q_new, True, math.inf
                                level = _eta(disc, q_s)
                        except NewtonError:
                            pass
                if q_s is not None and stable:
                    d = _state_distance(stepper.q - q_s, stepper.qdot, 0.05)
                    if d < equilibrium_radius and d <= d_prev:
                        tv = tip_coordinates(disc, alpha, q_s)
                        tip = {k: [float(tv[k]), float(tv[k])] for k in TIP_KEYS}
                        result = finish("equilibrium", tip=tip, q=q_s.copy(), p=np.zeros(n))
                        break
                    d_prev = d if d < equilibrium_radius else math.inf

            # -- Poincare section: upward crossing of eta_tip through the level.
            # The static value is crossed by a Hopf cycle near onset; a cycle
            # that has drifted away from it is sectioned at its own mean
            # instead, once no crossing has happened for 3 tau (~10 periods).
            last_cross = max(sec_t[-1] if sec_t else 0.0, level_time)
            if stepper.t - last_cross > 3.0 and samples:
                t_recent = np.concatenate([s[0] for s in samples[-400:]])
                eta_recent = np.concatenate([s[1]["eta_tip"] for s in samples[-400:]])
                keep = t_recent >= stepper.t - 1.0
                level = float(np.mean(eta_recent[keep]))
                level_time = stepper.t
                sec_t, sec_x, sec_i = [], [], []
                s_old = _eta(disc, stepper.q) - level
                log.debug("section level moved to the mean eta_tip %.6g", level)
            s_new = _eta(disc, stepper.q) - level
            if s_old < 0.0 <= s_new:
                f = lambda tt, c=level: _eta(disc, stepper.dense(tt)[0]) - c  # noqa: E731
                t_c = stepper.t if s_new == 0 else brentq(f, stepper.t_old, stepper.t, xtol=1e-13)
                sec_t.append(t_c)
                sec_x.append(stepper.dense(t_c))
                sec_i.append(len(samples))
                found = _recurrence(sec_t, sec_x, n_max)
                if found is not None:
                    nn, dist = found
                    T_guess = sec_t[-1] - sec_t[-1 - nn]
                    qk, pk = sec_x[-1]
                    prev = last_dist.get(nn)
                    last_dist[nn] = dist
                    # Integrate on while the returns contract fast and are not
                    # yet within start_tol (the first return has no rate yet).
                    fast = prev is None or dist < 0.5 * prev
                    # At most MAX_WAITS such returns (a period-n that keeps
                    # changing its n never shows a rate: shoot as before then).
                    wait = fast and dist > start_tol and waits < MAX_WAITS
                    if use_shooting and dist < tried_tol and wait:
                        waits += 1
                    if use_shooting and dist < tried_tol and not wait:
                        try:
                            cyc = shoot(
                                model, qk, pk, T_guess, level=level, rtol=shoot_rtol, tol=shoot_tol
                            )
                        except (ShootingError, IntegrationError) as exc:
                            log.info("shooting failed, integrating on: %s", exc)
                            tried_tol = dist / 10.0
                        else:
                            stats["steps"] += cyc.total_steps
                            stats["rejected_steps"] += cyc.rejected_steps
                            stats["wall_time"] += cyc.wall_time
                            if cyc.stable:
                                result = finish(
                                    "periodic",
                                    period=cyc.period,
                                    period_n=nn,
                                    tip=cyc.tip,
                                    cycle=cyc,
                                    q=cyc.q0.copy(),
                                    p=cyc.qdot0.copy(),
                                )
                                break
                            tried_tol = dist / 10.0
                    elif not use_shooting and dist < converged_tol:
                        tip = _tip_ranges(samples[max(sec_i[-1 - nn] - 1, 0) :])
                        result = finish("periodic", period=T_guess, period_n=nn, tip=tip)
                        break
            s_old = s_new

    if result is None:
        tip = _tip_ranges(samples[len(samples) // 2 :]) if samples else None
        msg = f"no recurrence of the Poincare section within t_max = {t_max:g}"
        result = finish("non-periodic", tip=tip, msg=msg)
    return result


def _recurrence(sec_t: list, sec_x: list, n_max: int):
    """(n, d_n) for the smallest n whose return distance d_n = |x_k - x_{k-n}| is within
    a factor 2 of the smallest over n <= n_max; None before the second section point."""
    k = len(sec_x) - 1
    d = []
    for nn in range(1, min(n_max, k) + 1):
        T = sec_t[k] - sec_t[k - nn]
        (qa, pa), (qb, pb) = sec_x[k], sec_x[k - nn]
        d.append(_state_distance(qa - qb, pa - pb, T / (2 * math.pi * nn)))
    if not d:
        return None
    best = min(d)
    for nn, dn in enumerate(d, start=1):
        if dn <= 2.0 * best:
            return nn, dn
    return None  # pragma: no cover

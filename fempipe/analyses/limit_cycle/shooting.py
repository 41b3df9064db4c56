"""Newton shooting for a periodic orbit of a planar or 3-D dynamics problem (:func:`shoot`).

Unknowns (x0, T): ``phi_T(x0) - x0 = 0`` and ``section_value(x0) = level``, with the exact
monodromy of the discrete Radau flow (its eigenvalues the Floquet multipliers).  At an
axisymmetric inclination in 3-D the bordered matrix is singular along the rotation about the
vertical: the step is the minimum-norm least-squares one.

Derivation and accuracy: docs/theory/numerics.md, "Attractors and limit cycles".
"""

from __future__ import annotations

import logging
import math
import time
import warnings

import numpy as np
import scipy.linalg as sla

from fempipe.core.parallel import single_blas_thread
from fempipe.model.dynamics_problem import ModelDynamics
from fempipe.model.three_d.model import PipeModel3D
from fempipe.solvers.radau import Radau

from .results import LimitCycle, ShootingError, largest_nontrivial, state_distance
from .tips import QuinticOrbit, section_gradient, section_value, tip_extrema

__all__ = ["shoot", "Shooter"]

log = logging.getLogger(__name__)


def shoot(
    problem: ModelDynamics,
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
    problem : PipeDynamics or PipeDynamics3D
        An autonomous dynamics problem.
    q0, qdot0, period : ndarray, ndarray, float
        Initial guess of a state on the orbit and of the period.
    level : float, optional
        Phase condition section_value(q0) = level (default: that of the guess).
    rtol, tol, max_iter : float, float, int
        Integration tolerance; Newton's on the RMS of phi_T(x0) - x0 (q' scaled by T / 2 pi).
    n_samples : int
        Samples of the orbit stored.
    reuse_monodromy : bool
        Chord-Newton while the residual falls 4x per iteration.
    polish : bool
        Report one more Newton step's plain period if its residual is smaller.

    Returns
    -------
    LimitCycle
        In 3-D with Y_tip and all 6 n multipliers (ShootingError if Newton fails).
    """
    if not problem.autonomous:
        raise ValueError("shoot needs an autonomous problem (a steady flow)")
    if not period > 0:
        raise ValueError(f"period must be > 0, got {period}")
    q = np.array(q0, dtype=float)
    p = np.array(qdot0, dtype=float)
    level = section_value(problem.model, q) if level is None else float(level)
    shooter = Shooter(problem, level, rtol, tol, n_samples, reuse_monodromy, polish)
    return shooter.run(q, p, float(period), max_iter)


class Shooter:
    """The Newton iteration of :func:`shoot` on one problem and section level
    (``total_steps``, ``rejected``: the integration steps over all periods so far)."""

    def __init__(
        self, problem: ModelDynamics, level, rtol, tol, n_samples, reuse_monodromy, polish
    ) -> None:
        self.problem, self.model, self.n = problem, problem.model, problem.n
        self.level = level
        self.rtol, self.tol, self.n_samples = rtol, tol, n_samples
        self.reuse_monodromy, self.polish = reuse_monodromy, polish
        three_d = isinstance(self.model, PipeModel3D)
        #: the rotation about the vertical maps 3-D orbits to orbits
        self.axisymmetric = three_d and abs(math.sin(self.model.params.alpha)) < 1e-12
        # The 3-D tips: 16 samples a step on the quintic, a parabola through them.
        self.tip_options = {"per_step": 16, "fine": 0, "uniform": True} if three_d else {}
        self.t_start = time.perf_counter()
        self.total_steps = self.rejected = 0
        self.Phi = None

    def run(self, q: np.ndarray, p: np.ndarray, T: float, max_iter: int) -> LimitCycle:
        """Newton iterations from (q, p, T) until converged; raise ShootingError if not."""
        n, tol = self.n, self.tol
        res = res_prev = math.inf
        stale = False
        with single_blas_thread():
            for it in range(1, max_iter + 1):
                need = self.Phi is None or not self.reuse_monodromy or stale
                stepper, ends, tt, orbit_q, orbit_p = self.one_period(q, p, T, need)
                self.total_steps += stepper.stats.steps
                self.rejected += stepper.stats.rejected_steps
                scale = T / (2 * math.pi)
                res = state_distance(stepper.q - q, stepper.qdot - p, scale)
                g = section_value(self.model, q) - self.level
                log.debug("shooting it %d: T=%.10g residual %.3e phase %.3e", it, T, res, g)
                if need:
                    self.Phi = stepper.sensitivity_matrix
                dx = self.newton_step(q, p, stepper, g)
                if res < tol and abs(g) < tol:
                    best = (it, q, p, T, res, self.tips(ends), stepper, tt, orbit_q, orbit_p)
                    return self.converged(best, dx)
                # A chord iteration that does not cut the residual 4x: fresh matrix next time.
                stale = not need and res > res_prev / 4
                res_prev = res
                if dx is None:
                    break
                # Trust region: a Newton step larger than ~0.3 rad RMS leaves the
                # neighbourhood where the linearized map means anything.
                size = state_distance(dx[:n], dx[n : 2 * n], scale)
                lam = min(1.0, 0.3 / size) if size > 0 else 1.0
                q, p, T = q + lam * dx[:n], p + lam * dx[n : 2 * n], T + lam * dx[-1]
                if not T > 0:
                    break
        raise ShootingError(
            f"shooting did not converge at v = {self.model.params.v:.6g}, alpha = "
            f"{self.model.params.alpha:.6g}: residual {res:.3e} after {it} Newton iterations",
            iterations=it,
            residual=res,
        )

    def one_period(self, q: np.ndarray, p: np.ndarray, T: float, sensitivity: bool):
        """Integrate (q, p) over T; the stepper, the step ends and the orbit samples."""
        n_samples = self.n_samples
        stepper = Radau(self.problem, q, p, 0.0, rtol=self.rtol, sensitivity=sensitivity)
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

    def newton_step(self, q: np.ndarray, p: np.ndarray, stepper: Radau, g: float):
        """(dq, dp, dT) of the bordered Newton system with the current monodromy, or None."""
        n = self.n
        J = np.zeros((2 * n + 1, 2 * n + 1))
        J[: 2 * n, : 2 * n] = self.Phi - np.eye(2 * n)
        J[: 2 * n, -1] = np.concatenate([stepper.qdot, stepper.qddot])
        J[-1, :n] = section_gradient(self.model, q)
        rhs = -np.concatenate([stepper.q - q, stepper.qdot - p, [g]])
        if self.axisymmetric:
            dx = np.linalg.lstsq(J, rhs, rcond=1e-10)[0]
            return dx if np.all(np.isfinite(dx)) else None
        try:
            # Near an equilibrium (a decaying oscillation, the Hopf point) the matrix is
            # nearly singular; the next period's residual judges the step and an orbit
            # collapsing to the equilibrium is refused, so scipy's warning is only noise.
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", sla.LinAlgWarning)
                dx = sla.solve(J, rhs)
        except (sla.LinAlgError, ValueError):
            return None
        return dx if np.all(np.isfinite(dx)) else None

    def tips(self, ends: list) -> dict:
        """Tip extrema of one period on the quintic interpolant of its step ends."""
        orbit = QuinticOrbit(*zip(*ends, strict=True))
        return tip_extrema(self.model, orbit, **self.tip_options)

    def converged(self, best: tuple, dx: np.ndarray | None) -> LimitCycle:
        """The cycle of a converged iterate ``best`` = (it, q, p, T, res, tip, stepper, tt,
        orbit_q, orbit_p), polished by the Newton step ``dx`` if that helps."""
        it, q, p, T, res, tip = best[:6]
        if max(hi - lo for lo, hi in tip.values()) < 2e-3:
            # The equilibrium is a periodic orbit of any period, and Newton started near a
            # decaying oscillation can stop on the way to it once A |1 - exp(sigma T)| < tol
            # (A = 7e-6 at v_cr - 0.13).  Hopf cycles this small (A ~ 0.5 sqrt(v - v_cr))
            # exist only within 4e-6 of v_cr: tip swings below 2e-3 are not cycles.
            raise ShootingError(
                f"shooting converged to an equilibrium at v = {self.model.params.v:.6g}",
                iterations=it,
                residual=res,
            )
        mu = np.linalg.eigvals(self.Phi)
        mu = mu[np.argsort(-np.abs(mu))]
        if self.polish and dx is not None and res > 0.1 * self.tol:
            best = self.polished(best, dx)
        it_, q_, p_, T_, res_, tip_, st_, tt_, oq_, op_ = best
        return LimitCycle(
            period=T_,
            q0=q_,
            qdot0=p_,
            level=self.level,
            tip=tip_,
            floquet_multipliers=mu,
            stable=largest_nontrivial(mu, self.axisymmetric) < 1.0,
            iterations=it_,
            residual=res_,
            orbit_t=tt_,
            orbit_q=oq_,
            orbit_qdot=op_,
            steps=st_.stats.steps,
            total_steps=self.total_steps,
            rejected_steps=self.rejected,
            wall_time=time.perf_counter() - self.t_start,
        )

    def polished(self, best: tuple, dx: np.ndarray) -> tuple:
        """``best`` moved by one more Newton step if a plain period confirms it."""
        # The converged iterate is up to tol from the cycle; one more step with the same
        # matrix lands within O(res^2) of it, and a plain period checks it.  Below tol / 10
        # the iterate is as close as the map's own integration error: no gain.
        n = self.n
        it, q, p, T, res = best[:5]
        q2, p2, T2 = q + dx[:n], p + dx[n : 2 * n], T + dx[-1]
        st2, ends2, tt2, oq2, op2 = self.one_period(q2, p2, T2, False)
        self.total_steps += st2.stats.steps
        self.rejected += st2.stats.rejected_steps
        res2 = state_distance(st2.q - q2, st2.qdot - p2, T2 / (2 * math.pi))
        g2 = section_value(self.model, q2) - self.level
        log.debug("shooting polish: T=%.10g residual %.3e", T2, res2)
        if res2 < res and abs(g2) < self.tol:
            return (it + 1, q2, p2, T2, res2, self.tips(ends2), st2, tt2, oq2, op2)
        return best

"""The Radau IIA integrator: :class:`Radau`, its step record and its error.

Method: docs/theory/numerics.md, "Time integration"; what it asks of the problem and what
it guarantees: :mod:`fempipe.solvers.radau.contract`.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator
from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.core.parallel import single_blas_thread

from .collocation import evaluate_increment, evaluate_lagrange
from .contract import ImplicitSecondOrderProblem
from .lapack import lu_factor_blocks, lu_solve
from .sensitivity import chain_step, chain_step_blocks, step_derivative
from .tableau import (
    A2,
    EIGENVALUES,
    JACOBIAN_RATE,
    MAX_FACTOR,
    MIN_FACTOR,
    MU_REAL,
    NEWTON_MAXITER,
    T0,
    T1I,
    T1R,
    TI,
    A,
    C,
    E,
)

__all__ = ["IntegrationError", "Radau", "StepRecord", "Stats", "predict_factor"]


class IntegrationError(SolverError):
    """Time integration failed: says where (tau, step size) and why."""

    def __init__(self, message: str, t: float, h: float) -> None:
        super().__init__(message)
        self.t = t
        self.h = h

    def __reduce__(self):
        # Rebuilt from all the constructor's arguments (pickling across processes).
        return type(self), (str(self), self.t, self.h)


class StepRecord(NamedTuple):
    """One accepted step (rule 13), ``(t_old, h, q_old, p_old, Q, P, A)``: start, size, q and q'
    at t_old, and (shape (3, n)) q, q', q'' at the stages t_old + c_i h (the last: the end)."""

    t_old: float
    h: float
    q_old: np.ndarray
    p_old: np.ndarray
    Q: np.ndarray
    P: np.ndarray
    A: np.ndarray

    def dense(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(q, q') at tau = t: the collocation polynomial of the step (increment form)."""
        s = (t - self.t_old) / self.h
        return evaluate_increment(s, self.q_old, self.Q), evaluate_increment(s, self.p_old, self.P)


def _rms(x: np.ndarray) -> float:
    return math.sqrt(float(x @ x) / x.size)


def _checked(problem) -> ImplicitSecondOrderProblem:
    """``problem`` if it has every member of the contract, else a TypeError naming the missing ones."""
    if isinstance(problem, ImplicitSecondOrderProblem):
        return problem
    members = (
        "n",
        "autonomous",
        "stage_residuals",
        "stage_jacobians",
        "prefers_batched_stage_jacobians",
        "parameter_derivative",
        "residual",
        "jacobians",
        "acceleration",
        "describe",
    )
    missing = ", ".join(m for m in members if not hasattr(problem, m))
    raise TypeError(
        f"Radau integrates a dynamics problem (fempipe.solvers.radau.ImplicitSecondOrderProblem); "
        f"a {type(problem).__name__} has no {missing}: build one with "
        "fempipe.model.dynamics_problem.PipeDynamics(model) (a PipeModel3D: "
        "fempipe.model.three_d.dynamics.PipeDynamics3D(model))"
    )


@dataclass
class Stats:
    """Counters of an integration (:attr:`Radau.stats`)."""

    steps: int = 0
    rejected_steps: int = 0
    newton_failures: int = 0
    n_residual: int = 0
    n_jacobian: int = 0
    n_lu: int = 0
    wall_time: float = 0.0


class Radau:
    """Variable-step, L-stable Radau IIA (order 5) on R(t, q, q', q'') = 0.

    Parameters
    ----------
    problem : ImplicitSecondOrderProblem
        The residual and Jacobians by the rules of :mod:`fempipe.solvers.radau.contract`.
    q0, qdot0 : ndarray, shape (n,)
        Initial state (not modified), at time ``t0``.
    rtol, atol : float
        Local error tolerances on (q, q'); ``atol`` defaults to ``rtol``.
    max_step, first_step, h_fixed : float
        Largest step; first step (default from q''); fixed step without error control.
    sensitivity, velocity_sensitivity : bool
        Accumulate d(q, q')/d(q0, qdot0) (:attr:`sensitivity_matrix`, the monodromy over a
        period) and, with a ``parameter_derivative``, d(q, q')/dv (:attr:`velocity_sensitivity`).

    Notes
    -----
    :attr:`stats` counts ``steps``, ``rejected_steps``, ``newton_failures``, ``n_residual``,
    ``n_jacobian``, ``n_lu`` and ``wall_time``.
    """

    def __init__(
        self,
        problem: ImplicitSecondOrderProblem,
        q0: np.ndarray,
        qdot0: np.ndarray | None = None,
        t0: float = 0.0,
        *,
        rtol: float = 1e-6,
        atol: float | None = None,
        max_step: float = math.inf,
        first_step: float | None = None,
        h_fixed: float | None = None,
        sensitivity: bool = False,
        velocity_sensitivity: bool = False,
    ) -> None:
        problem = _checked(problem)
        n = problem.n
        q0 = np.array(q0, dtype=float)
        qdot0 = np.zeros(n) if qdot0 is None else np.array(qdot0, dtype=float)
        if q0.shape != (n,) or qdot0.shape != (n,):
            raise ValueError(f"q0 and qdot0 must have shape ({n},)")
        if not (np.all(np.isfinite(q0)) and np.all(np.isfinite(qdot0))):
            raise ValueError("q0 and qdot0 must be finite")
        if not (0 < rtol < 1):
            raise ValueError(f"rtol must satisfy 0 < rtol < 1, got {rtol}")
        atol = rtol if atol is None else float(atol)
        if atol <= 0:
            raise ValueError(f"atol must be > 0, got {atol}")
        if not max_step > 0:
            raise ValueError(f"max_step must be > 0, got {max_step}")
        if h_fixed is not None and not h_fixed > 0:
            raise ValueError(f"h_fixed must be > 0, got {h_fixed}")
        self.problem = problem
        self.n = n
        self.rtol, self.atol = float(rtol), atol
        # Newton tolerance on the stage increments, as RADAU5 / scipy.
        self.newton_tol = max(10 * np.finfo(float).eps / rtol, min(0.03, rtol**0.5))
        self.max_step = float(max_step)
        self.h_fixed = h_fixed
        self.stats = Stats()
        self.t = float(t0)
        self.q, self.qdot = q0, qdot0
        self.qddot = self._acceleration(self.t, q0, qdot0)
        self._jac = None  # (K, D, M) at the last Jacobian point
        self._current_jac = False
        self._lu = None  # (h, LU_real, LU_complex)
        self._h_old = None
        self._err_old = None
        # RADAU5's FACCON: the contraction factor theta / (1 - theta) of the
        # last converged Newton iteration, used to accept the first iterate
        # of the next step (see :meth:`_newton`).
        self._faccon = 1.0
        self._prev = None  # previous step (t_old, h, a_old, stage accelerations)
        self.last: StepRecord | None = None  # the last accepted step
        if h_fixed is not None:
            self.h = float(h_fixed)
        elif first_step is not None:
            self.h = float(first_step)
        else:
            # Local error of a 5th-order step ~ (h |q''|)... use the usual
            # d0/d1 heuristic on the acceleration, then let the controller work.
            d0 = np.sqrt(np.mean(np.r_[q0, qdot0] ** 2)) + 1e-3
            d1 = np.sqrt(np.mean(np.r_[qdot0, self.qddot] ** 2)) + 1e-12
            self.h = min(1e-2 * d0 / d1, 1e-2)
        self.h = min(self.h, self.max_step)
        # The optional members of contract rules 6-8, for autonomous problems only
        # (they take no time).
        autonomous = bool(problem.autonomous)
        self._residual3 = problem.stage_residuals if autonomous else None
        self._jacobians1 = problem.stage_jacobians if autonomous else None
        self._stages_batched = self._jacobians1 is not None and bool(
            problem.prefers_batched_stage_jacobians
        )
        # Contract rule 7: groups of unknowns that decouple at some states; used only
        # where the Jacobians' entries between them are exactly zero.
        blocks = getattr(problem, "decoupled_blocks", None)
        self._blocks = None if blocks is None else [np.asarray(b, dtype=np.intp) for b in blocks]
        # the sensitivity stays block diagonal while every step's Jacobians decouple
        self._split_sensitivity = self._blocks is not None
        self.sensitivity = bool(sensitivity)
        self.sensitivity_matrix = np.eye(2 * n) if sensitivity else None
        # d(q, q')/dv of the discrete flow map, steady flow only (a flow
        # history has no single v to differentiate by: no parameter_derivative).
        self._stage_residuals_v = (
            problem.parameter_derivative
            if autonomous and sensitivity and velocity_sensitivity
            else None
        )
        self.velocity_sensitivity = np.zeros(2 * n) if self._stage_residuals_v is not None else None

    def _acceleration(self, t, q, p):
        self.stats.n_residual += 1
        return self.problem.acceleration(t, q, p)

    def _jacobians(self, t, q, p, a):
        self.stats.n_jacobian += 1
        if self._jacobians1 is not None:
            Jq, Jqd, M = self._jacobians1(q[None], p[None], a[None])
            return Jq[0], Jqd[0], M[0]
        return self.problem.jacobians(t, q, p, a)

    def _decoupled(self, *mats) -> list | None:
        """The problem's ``decoupled_blocks`` if the matrices have no entry between them, else None."""
        blocks = self._blocks
        if blocks is None:
            return None
        for a in blocks:
            for b in blocks:
                if a is not b and any(np.any(m[..., a[:, None], b]) for m in mats):
                    return None
        return blocks

    def _factor(self, h: float):
        K, D, M = self._jac
        g0, g1 = EIGENVALUES[0].real, EIGENVALUES[1]
        blocks = self._decoupled(K, D, M)
        lu_r = lu_factor_blocks(M + h * g0 * D + (h * g0) ** 2 * K, blocks)
        lu_c = lu_factor_blocks(M + h * g1 * D + (h * g1) ** 2 * K, blocks)
        self.stats.n_lu += 1
        self._lu = (h, lu_r, lu_c)

    def _scale(self, q, p):
        return self.atol + self.rtol * np.abs(np.concatenate([q, p]))

    def _guess(self, t: float, h: float) -> np.ndarray:
        """Stage accelerations extrapolated from the previous step's polynomial."""
        if self._prev is None:
            return np.tile(self.qddot, (3, 1))
        t_old, h_old, a_old, acc = self._prev
        s = (t + h * C - t_old) / h_old
        # Lagrange extrapolation of the cubic through the 4 nodes (0, c_1, c_2, c_3).
        return evaluate_lagrange(s, a_old, acc)

    def _stages(self, h, acc):
        P = self.qdot[None, :] + h * (A @ acc)
        Q = self.q[None, :] + h * C[:, None] * self.qdot[None, :] + h * h * (A2 @ acc)
        return Q, P

    def _newton(self, t: float, h: float, acc: np.ndarray, scale: np.ndarray, max_iter=None):
        """Solve the stage equations; (converged, iterations, acc, rate), RADAU5's acceptance test."""
        max_iter = NEWTON_MAXITER if max_iter is None else max_iter
        _, lu_r, lu_c = self._lu
        n = self.n
        dnorm_old, rate = None, None
        faccon = max(self._faccon, np.finfo(float).eps) ** 0.8
        G = np.empty((3, n))
        for k in range(max_iter):
            Q, P = self._stages(h, acc)
            if self._residual3 is not None:
                G = self._residual3(Q, P, acc)
            else:
                for i in range(3):
                    G[i] = self.problem.residual(t + C[i] * h, Q[i], P[i], acc[i])
            self.stats.n_residual += 3
            # (a sum is finite only if every term is)
            if not math.isfinite(G.sum()):
                return False, k + 1, acc, rate
            W = TI @ G  # (3, n) complex
            dV0 = lu_solve(lu_r, W[0].real)
            dV1 = lu_solve(lu_c, W[1])
            dacc = -(T0 * dV0 + T1R * dV1.real - T1I * dV1.imag)
            # RMS of the increments of (Q, P), scaled: h^2 A^2 dacc and h A dacc.
            eq = (h * h) * (A2 @ dacc) / scale[:n]
            ep = h * (A @ dacc) / scale[n:]
            dnorm = math.sqrt((float(np.vdot(eq, eq)) + float(np.vdot(ep, ep))) / (6 * n))
            if dnorm_old is not None:
                rate = dnorm / dnorm_old
            if rate is not None and (
                rate >= 1 or rate ** (max_iter - k) / (1 - rate) * dnorm > self.newton_tol
            ):
                return False, k + 1, acc, rate
            acc = acc + dacc
            if rate is not None:
                faccon = rate / (1 - rate)
            if dnorm == 0 or (
                (rate is not None or self.h_fixed is None) and faccon * dnorm < self.newton_tol
            ):
                self._faccon = faccon
                return True, k + 1, acc, rate
            if self.h_fixed is not None and dnorm < 1e-3 * self.newton_tol:
                return True, k + 1, acc, rate
            dnorm_old = dnorm
        return False, max_iter, acc, rate

    def _error(self, t, h, Q, P, scale, refine: bool) -> float:
        """RADAU5's embedded error estimate in second-order form (docs/theory/numerics.md)."""
        K, D, M = self._jac
        _, lu_r, _ = self._lu
        Zq = Q - self.q[None, :]
        Zp = P - self.qdot[None, :]
        mu = MU_REAL
        g0 = 1.0 / mu

        def solve(f_q, f_p):
            r_q = f_q + E @ Zq / h
            r_p = f_p + E @ Zp / h
            rhs = M @ r_p + (mu / h) * (M @ r_q) + D @ r_q
            e_q = (h * g0) ** 2 * lu_solve(lu_r, rhs)
            return e_q, (mu / h) * e_q - r_q

        e_q, e_p = solve(self.qdot, self.qddot)
        err = _rms(np.concatenate([e_q, e_p]) / scale)
        if refine and err > 1:
            a = self._acceleration(t, self.q + e_q, self.qdot + e_p)
            e_q, e_p = solve(self.qdot + e_p, a)
            err = _rms(np.concatenate([e_q, e_p]) / scale)
        return err

    def step(self, t_bound: float = math.inf) -> None:
        """Advance by one accepted step, not beyond ``t_bound``; IntegrationError if h reaches round-off."""
        t0_wall = time.perf_counter()
        t = self.t
        h = min(self.h, self.max_step)
        h_old, err_old = self._h_old, self._err_old
        rejected = False
        if self._jac is None:
            self._jac = self._jacobians(t, self.q, self.qdot, self.qddot)
            self._current_jac = True
        while True:
            min_step = 10 * abs(np.nextafter(t, math.inf) - t)
            if h < min_step:
                raise IntegrationError(
                    f"time step {h:.3e} below round-off at tau = {t:.6g} "
                    f"({self.problem.describe()}); the motion may be diverging",
                    t=t,
                    h=h,
                )
            if t + h >= t_bound - min_step:
                h = t_bound - t
            if self._lu is None or self._lu[0] != h:
                self._factor(h)
            scale = self._scale(self.q, self.qdot)
            acc0 = self._guess(t, h)
            converged, n_iter, acc, rate = self._newton(t, h, acc0, scale)
            if not converged and not self._current_jac:
                self._jac = self._jacobians(t, self.q, self.qdot, self.qddot)
                self._current_jac = True
                self._factor(h)
                converged, n_iter, acc, rate = self._newton(t, h, acc0, scale)
            if not converged and self.h_fixed is not None:
                # A fixed step cannot be halved: retry from the constant
                # guess (extrapolated stiff accelerations can be far off) with
                # more iterations before giving up.
                acc0 = np.tile(self.qddot, (3, 1))
                converged, n_iter, acc, rate = self._newton(t, h, acc0, scale, max_iter=25)
            if not converged:
                if self.h_fixed is not None:
                    raise IntegrationError(
                        f"Newton did not converge with the fixed step {h:.3e} at tau = {t:.6g}",
                        t=t,
                        h=h,
                    )
                self.stats.newton_failures += 1
                h *= 0.5
                continue
            Q, P = self._stages(h, acc)
            if self.h_fixed is not None:
                err = 0.0
                break
            scale = self.atol + self.rtol * np.maximum(
                np.abs(np.concatenate([self.q, self.qdot])), np.abs(np.concatenate([Q[-1], P[-1]]))
            )
            err = self._error(t, h, Q, P, scale, refine=rejected or self._prev is None)
            safety = 0.9 * (2 * NEWTON_MAXITER + 1) / (2 * NEWTON_MAXITER + n_iter)
            if err > 1:
                factor = predict_factor(h, h_old, err, err_old)
                h *= max(MIN_FACTOR, safety * factor)
                rejected = True
                self.stats.rejected_steps += 1
                continue
            break

        if self.sensitivity:
            self._accumulate_sensitivity(t, h, Q, P, acc)
        self.last = StepRecord(t, h, self.q, self.qdot, Q, P, acc)
        self._prev = (t, h, self.qddot, acc)
        self.t = t + h
        self.q, self.qdot, self.qddot = Q[-1].copy(), P[-1].copy(), acc[-1].copy()
        self.stats.steps += 1
        if self.h_fixed is None:
            recompute_jac = n_iter > 2 and rate is not None and rate > JACOBIAN_RATE
            factor = min(MAX_FACTOR, safety * predict_factor(h, h_old, err, err_old))
            # RADAU5 keeps h (and the factorisations) for factor < 1.2; a
            # factor below 1 is applied here, so that the error stays controlled.
            if not recompute_jac and 1.0 <= factor < 1.2:
                factor = 1.0
            self._h_old, self._err_old = h, err
            self.h = min(h * factor, self.max_step)
            if recompute_jac:
                if self.sensitivity:
                    self._jac = self._stage3_jac  # evaluated at this very state
                else:
                    self._jac = self._jacobians(self.t, self.q, self.qdot, self.qddot)
                self._current_jac = True
                self._lu = None
            else:
                self._current_jac = False
        else:
            self.h = self.h_fixed
        self.stats.wall_time += time.perf_counter() - t0_wall

    def _accumulate_sensitivity(self, t, h, Q, P, acc) -> None:
        """Chain the exact derivative of the step map y0 -> y1 into the sensitivities."""
        if self._stages_batched:
            self.stats.n_jacobian += 3
            Ks, Ds, Ms = self._jacobians1(Q, P, acc)  # (3, n, n) each
        else:
            jac = [self._jacobians(t + C[i] * h, Q[i], P[i], acc[i]) for i in range(3)]
            Ks, Ds, Ms = (np.array([j[k] for j in jac]) for k in range(3))  # (3, n, n) each
        with_v = self._stage_residuals_v is not None
        dR_dv = self._stage_residuals_v(Q, P, acc) if with_v else None
        # The last stage is the end of the step (c_3 = 1): its Jacobians are
        # those at the next step's start, where step() may want them.
        self._stage3_jac = (Ks[2], Ds[2], Ms[2])
        if self._split_sensitivity and self._decoupled(Ks, Ds, Ms) is not None:
            self.sensitivity_matrix, dv = chain_step_blocks(
                h,
                Ks,
                Ds,
                Ms,
                dR_dv,
                self.sensitivity_matrix,
                self.velocity_sensitivity if with_v else None,
                self._blocks,
            )
        else:
            self._split_sensitivity = False
            D = step_derivative(h, Ks, Ds, Ms, dR_dv)
            self.sensitivity_matrix, dv = chain_step(
                D, h, self.sensitivity_matrix, self.velocity_sensitivity if with_v else None
            )
        if with_v:
            self.velocity_sensitivity = dv

    def dense(self, t: float) -> tuple[np.ndarray, np.ndarray]:
        """(q, q') at tau = t inside the last step, from the collocation polynomial."""
        if self.last is None:
            return self.q.copy(), self.qdot.copy()
        return self.last.dense(t)

    @property
    def t_old(self) -> float:
        return self.t if self.last is None else self.last.t_old

    def steps(self, t_end: float) -> Iterator[tuple[float, np.ndarray, np.ndarray]]:
        """Generator of fresh (tau, q, q') after every accepted step up to ``t_end`` (not the initial state)."""
        with single_blas_thread():
            while self.t < t_end - 10 * abs(np.nextafter(t_end, math.inf) - t_end):
                self.step(t_end)
                yield self.t, self.q.copy(), self.qdot.copy()


def predict_factor(h, h_old, err, err_old) -> float:
    """Step-size factor of the predictive (Gustafsson) controller: scipy's RADAU5 ``predict_factor``."""
    if err_old is None or h_old is None or err == 0:
        multiplier = 1.0
    else:
        multiplier = h / h_old * (err_old / err) ** 0.25
    with np.errstate(divide="ignore"):
        return min(1.0, multiplier) * err**-0.25 if err > 0 else MAX_FACTOR

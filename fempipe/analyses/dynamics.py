"""Motion of the pipe. Eq. (20): trajectories, unsteady flow, initial states, energy.

Radau IIA on :class:`~fempipe.model.dynamics_problem.PipeDynamics`; docs/theory/numerics.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse.linalg as spla

from fempipe.analyses.statics import solve_static
from fempipe.model.dynamics_problem import PipeDynamics, acceleration
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import IntegrationError, Radau

__all__ = [
    "PulsatingFlow",
    "Radau",
    "IntegrationError",
    "Trajectory",
    "simulate_steps",
    "simulate",
    "make_initial_state",
    "acceleration",
    "energy_rate",
    "power_terms",
]


@dataclass(frozen=True)
class PulsatingFlow:
    """Unsteady flow v(tau) = v0 (1 + sigma sin(omega tau)), v0 >= 0, 0 <= sigma <= 1, omega >= 0.

    Its derivative drives the flow-acceleration terms of Eq. (20).
    """

    v0: float
    sigma: float = 0.0
    omega: float = 0.0

    def __post_init__(self) -> None:
        for name in ("v0", "sigma", "omega"):
            val = float(getattr(self, name))
            if not math.isfinite(val):
                raise ValueError(f"{name} must be finite, got {val}")
            object.__setattr__(self, name, val)
        if self.v0 < 0:
            raise ValueError(f"v0 must be >= 0, got {self.v0}")
        if not 0.0 <= self.sigma <= 1.0:
            raise ValueError(f"sigma must satisfy 0 <= sigma <= 1, got {self.sigma}")
        if self.omega < 0:
            raise ValueError(f"omega must be >= 0, got {self.omega}")

    def __call__(self, tau: float) -> tuple[float, float]:
        """(v, v_dot) at tau."""
        s = self.sigma * math.sin(self.omega * tau)
        return self.v0 * (1.0 + s), self.v0 * self.sigma * self.omega * math.cos(self.omega * tau)

    def to_dict(self) -> dict:
        return {"v0": self.v0, "sigma": self.sigma, "omega": self.omega}


def power_terms(model: PipeModel, q: np.ndarray, qdot: np.ndarray, v_dot: float = 0.0) -> dict:
    """Power of each non-conservative term of Eq. (20), and ``"dE_dtau"`` = -(their sum).

    With r_dot = \\int_0^xi theta_dot n and t the tangent: ``coriolis`` v sqrt(beta)
    |r_dot(1)|^2, ``follower`` v^2 t(1) . r_dot(1), ``kelvin_voigt`` mu q'^T K q',
    ``flow_acceleration`` sqrt(beta) v_dot \\int t . r_dot, ``external_damping``
    sigma \\int |r_dot|^2 (E = T + V of :meth:`PipeModel.energy`; the balance:
    docs/theory/conventions.md).
    """
    p = model.params
    fl = model.fields(q, qdot)
    rdot = model.quad.cumulative(fl.theta_dot[:, None] * fl.normal)  # (n_q, 2)
    rdot_tip = model.quad.integrate(fl.theta_dot[:, None] * fl.normal)
    t_tip = np.array([math.cos(fl.theta_tip), math.sin(fl.theta_tip)])
    sb = math.sqrt(p.beta)
    terms = {
        "coriolis": p.v * sb * float(rdot_tip @ rdot_tip),
        "follower": p.v**2 * float(t_tip @ rdot_tip),
        "kelvin_voigt": p.mu * float(qdot @ (model.disc.K @ qdot)),
        "flow_acceleration": sb * v_dot * float(model.w @ np.einsum("qc,qc->q", fl.tangent, rdot)),
        "external_damping": p.external_damping * float(model.w @ np.einsum("qc,qc->q", rdot, rdot)),
    }
    terms["dE_dtau"] = -sum(terms.values())
    return terms


def energy_rate(model: PipeModel, q: np.ndarray, qdot: np.ndarray, v_dot: float = 0.0) -> float:
    """dE/dtau = -[v sqrt(beta) |r_dot(1)|^2 + v^2 t(1).r_dot(1) + mu q'^T K q'
    + sqrt(beta) v_dot \\int t.r_dot + sigma \\int |r_dot|^2]."""
    return power_terms(model, q, qdot, v_dot)["dE_dtau"]


def make_initial_state(
    model: PipeModel,
    mode: int = 1,
    amplitude: float = 0.01,
    q_static: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """The static state plus ``amplitude`` sin((2 mode - 1) pi xi / 2) in theta, at rest. Eq. (22).

    L2-projected; ``q_static`` default :func:`~fempipe.analyses.statics.solve_static`.
    Returns (q0, qdot0).
    """
    if int(mode) < 1:
        raise ValueError(f"mode must be an integer >= 1, got {mode}")
    if not math.isfinite(amplitude):
        raise ValueError(f"amplitude must be finite, got {amplitude}")
    if q_static is None:
        q_static = solve_static(model).q
    disc = model.disc
    k = (2 * int(mode) - 1) * math.pi / 2.0
    b = disc.Phi.T @ (model.w * np.sin(k * model.x))
    gram = disc.gram
    pert = spla.spsolve(gram.tocsc(), b) if disc.sparse else np.linalg.solve(gram, b)
    return np.asarray(q_static, dtype=float) + amplitude * pert, np.zeros(model.n)


def simulate_steps(
    model: PipeModel,
    q0: np.ndarray,
    qdot0: np.ndarray | None,
    t_end: float,
    *,
    t0: float = 0.0,
    **options,
) -> Iterator[tuple[float, np.ndarray, np.ndarray]]:
    """The motion as a generator of (tau, q, q'): the initial state, then every accepted step.

    Eq. (20) integrated by :class:`Radau` (``flow`` goes to :class:`PipeDynamics`, the other
    options to :class:`Radau`)."""
    problem = PipeDynamics(model, options.pop("flow", None))
    stepper = Radau(problem, q0, qdot0, t0, **options)
    yield stepper.t, stepper.q.copy(), stepper.qdot.copy()
    yield from stepper.steps(t_end)


#: The integrator's counters a :class:`Trajectory` keeps (and ``stats()`` reports, in this order).
_COUNTERS = "steps rejected_steps newton_failures n_residual n_jacobian n_lu wall_time".split()


@dataclass(frozen=True)
class Trajectory:
    """A computed trajectory: times ``t`` (m,), states ``q``, ``qdot`` (m, n), the
    integrator's counters (``n_lu``: factorization pairs), ``wall_time`` and ``flow``."""

    t: np.ndarray
    q: np.ndarray
    qdot: np.ndarray
    steps: int
    rejected_steps: int
    newton_failures: int
    n_residual: int
    n_jacobian: int
    n_lu: int
    wall_time: float
    rtol: float
    flow: dict | None = field(default=None)

    @classmethod
    def recorded(cls, t, q, qdot, stats, rtol: float, flow: dict | None = None) -> Trajectory:
        """A trajectory from recorded samples and a stepper's running statistics."""
        counts = {k: getattr(stats, k) for k in _COUNTERS}
        return cls(np.asarray(t), np.asarray(q), np.asarray(qdot), **counts, rtol=rtol, flow=flow)

    def stats(self) -> dict:
        return {k: getattr(self, k) for k in _COUNTERS}

    def to_dict(self) -> dict:
        d = self.stats()
        d.update({"rtol": self.rtol, "t_start": float(self.t[0]), "t_end": float(self.t[-1])})
        d["n_samples"] = int(self.t.size)
        if self.flow is not None:
            d["flow"] = self.flow
        return d


def simulate(
    model: PipeModel,
    q0: np.ndarray,
    qdot0: np.ndarray | None,
    t_end: float,
    *,
    t0: float = 0.0,
    n_out: int | None = None,
    rtol: float = 1e-6,
    atol: float | None = None,
    flow: Callable[[float], tuple[float, float]] | None = None,
    max_step: float = math.inf,
    h_fixed: float | None = None,
    callback: Callable[[float], None] | None = None,
) -> Trajectory:
    """Integrate the motion from tau = t0 to t_end > t0 by :class:`Radau`. Eq. (20).

    Parameters
    ----------
    model, q0, qdot0, t0, t_end
    n_out : int, optional
        Equally spaced output times (dense output); default every accepted step.
    rtol, atol, max_step, h_fixed
        See :class:`Radau`.
    flow : PulsatingFlow or callable tau -> (v, v_dot), optional
        Default the steady ``model.params.v``.
    callback : callable, optional
        ``callback(tau)`` after every step.
    """
    if not t_end > t0:
        raise ValueError(f"t_end must be > t0 = {t0}, got {t_end}")
    options = {"rtol": rtol, "atol": atol, "max_step": max_step, "h_fixed": h_fixed}
    stepper = Radau(PipeDynamics(model, flow), q0, qdot0, t0, **options)
    samples = [(stepper.t, stepper.q.copy(), stepper.qdot.copy())]
    grid = np.linspace(t0, t_end, n_out) if n_out else None
    k = 1
    for t, q, p in stepper.steps(t_end):
        if grid is None:
            samples.append((t, q, p))
        while grid is not None and k < grid.size and grid[k] <= t + 1e-14:
            samples.append((grid[k], *(stepper.dense(grid[k]) if grid[k] < t else (q, p))))
            k += 1
        if callback is not None:
            callback(t)
    ts, qs, ps = zip(*samples, strict=True)
    flow_dict = flow.to_dict() if hasattr(flow, "to_dict") else None
    return Trajectory.recorded(ts, qs, ps, stepper.stats, rtol, flow_dict)

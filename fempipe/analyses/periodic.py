"""Branches of periodic orbits of Eq. (20) by pseudo-arclength continuation in v.

A flutter event of the static branch (:mod:`fempipe.analyses.stability`) is a Hopf
point: a complex pair lambda = +-i omega of the linearisation (Eqs.
(31b)-(33)) crosses the imaginary axis at v = v_H, and a family of periodic
orbits is born there.  This module follows that family in v, stable and
unstable orbits alike, which a sweep of attractors (:mod:`fempipe.analyses.bifurcation`)
cannot see.

The periodic-orbit problem
--------------------------
With x = (q, q') the weak form of Eq. (20) is x' = F(x; v) and phi_T(x; v)
its flow over a time T (the discrete flow of :class:`fempipe.solvers.radau.Radau`).
A periodic orbit is a zero of (single shooting; Seydel, *Practical
Bifurcation and Stability Analysis*, Sec. 7.3)

    phi_T(x0; v) - x0 = 0                    (2n equations)
    <f_ref, x0 - x_ref> = 0                  (phase condition)
    <t, W (u - u_pred)> = 0  or  v = v_g     (arclength, or a fixed v)

in u = (x0, T, v): the phase condition puts x0 on the hyperplane through the
previous point's x_ref orthogonal to the flow f_ref = F(x_ref) there (a
Poincare section that the next orbit crosses; through the predicted point on
the first step, where the previous point is the equilibrium), the last row is Keller's
pseudo-arclength condition with the unit tangent t of the weighted metric W
(Keller 1977; Kuznetsov, *Elements of Applied Bifurcation Theory*, Sec.
10.2), or, where v is a good local parameter and a requested v lies ahead, the
condition v = v_g, so that every requested value is landed on exactly (a
local parametrisation in Rheinboldt's sense).  The Jacobian of the first rows
is [M - I, F(phi_T), d phi_T / dv] with M the monodromy matrix, the exact
derivative of the discrete flow accumulated step by step by the integrator
(``Radau(sensitivity=True)``, as :func:`fempipe.analyses.limit_cycle.shoot` uses it),
and d phi_T / dv accumulated in the same integration, exact for the discrete
flow too (the residual of Eq. (20) is quadratic in v, so its v-derivative at
each stage is exact from three values; :class:`fempipe.solvers.radau.Radau`,
``velocity_sensitivity``): no second integration at a shifted v.  Newton's
method reuses the monodromy matrix while the residual falls at least four
times per iteration (chord Newton), as the sweep's shooting does.

Metric.  W measures q in rad (RMS over the unknowns), q' scaled by T_H / 2 pi
(the velocity of an oscillation of that period and the same amplitude), T
relative to the Hopf period T_H and v as it is, so a step ds is about an RMS
change of theta, a relative change of the period or a change of v.

Start.  At the Hopf point (x_H, T_H = 2 pi / omega, v_H) with the critical
eigenvector z (A z = i omega z, x = (q, q')), the orbits near the Hopf point are
x_H + r Re(z e^{i omega tau}) + O(r^2) with v - v_H = O(r^2): the branch leaves
the equilibria along t_0 = (Re z, 0, 0), which is the first tangent (the first
point is the pseudo-arclength corrector of x_H + ds Re z; its v comes out of
the corrector, on whichever side of v_H the orbits lie).  Later tangents are
secants of the last two points.

Step control.  The step grows by 1.5 when the corrector needed at most four
integrations, is halved when it needed more than five, and a step is
rejected (halved) when the corrector fails or the new secant turns from the
last one by more than :data:`MAX_ANGLE`.  A corrector that stalls on the
noise of the adaptive step sequence is first retried at a tenth of the
integration tolerance.  Below ``ds_min`` the branch ends
with :class:`CycleContinuationError`, naming v and the step; the finished
points stay.

Stability and special points.  The eigenvalues of the monodromy matrix are the
Floquet multipliers; the one closest to 1 is the trivial one (the phase along
the orbit) and the orbit is stable when all others lie inside the unit circle.
They come from the Newton iterate where the matrix was last computed: on the
continuation's own steps one within 1e-3 of the orbit's amplitude
(:data:`MONODROMY_NEAR`; the multipliers are then off by about as much), at
the requested v one within 1e-6 (:data:`MONODROMY_AT_ORBIT`), whose
multipliers are those of the orbit (the trivial one within 2e-6 of 1 on
Fig. 7).  Between two consecutive points the code
reports (Kuznetsov, Ch. 4 and 5; Seydel, Sec. 7.4):

* ``fold`` -- the branch turns back in v (a multiplier passes +1, the cyclic
  fold); located at the vertex of the parabola v(s) through three points;
* ``period_doubling`` -- a real multiplier passes -1;
* ``neimark_sacker`` -- a complex pair passes the unit circle;

the last two located by the secant of the test function (|mu| - 1 of the
multiplier concerned) on the step.  The branch ends when it leaves the range of
v, returns to an equilibrium (its amplitude falls below :data:`MIN_SWING`: it
reached another Hopf point), its period exceeds :data:`MAX_PERIOD_RATIO` T_H
(an approach to a homoclinic orbit), or after ``max_steps`` steps.
"""

from __future__ import annotations

import json
import logging
import math
import os
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field, replace

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.core.parallel import run_tasks, single_blas_thread
from fempipe.io import write_text
from fempipe.model.dynamics_problem import acceleration, refuse_hysteretic
from fempipe.model.operators import PipeModel
from fempipe.solvers.radau import C as _RADAU_NODES
from fempipe.solvers.radau import IntegrationError, Radau

from .limit_cycle import TIP_KEYS, tip_coordinates

__all__ = [
    "HopfPoint",
    "CyclePoint",
    "CycleSpecialPoint",
    "CycleBranch",
    "CycleContinuationError",
    "hopf_points",
    "continue_cycles",
    "static_points",
    "cycle_diagram",
    "CycleDiagram",
]

log = logging.getLogger(__name__)

#: Largest turn of the branch (rad) between two consecutive secants before
#: the step is rejected and halved.
MAX_ANGLE = 0.5
#: A computed orbit whose tip swings (max - min of eta_tip) less than this has
#: come back to an equilibrium.
MIN_SWING = 2e-3
#: The branch stops when the period exceeds this multiple of the Hopf period.
MAX_PERIOD_RATIO = 20.0
#: Non-real multipliers this close to +1 are not counted as a complex pair.
NEAR_ONE = 0.1
#: |dv/ds| below which v is not used as the local parameter (near folds).
MIN_DV_DS = 0.2
#: The corrector's monodromy is taken within this fraction of the orbit's
#: amplitude of the converged orbit on the continuation's own steps: their
#: multipliers decide stability and locate folds, period doublings and
#: Neimark-Sacker points (refined separately), and carry an error of about
#: this size (measured: the largest non-trivial |rho| 0.158056 against
#: 0.157639 of a shot at rtol 1e-10, N = 4, alpha = 0, v = 10).
MONODROMY_NEAR = 1e-3
#: ... and within this fraction at the requested v, whose multipliers are
#: reported: the iterate predicted to be the last is integrated with the
#: sensitivity, and one more such flow follows where the iteration still
#: ended farther away.  Measured on Fig. 7 (P3:16, 36 v): the trivial
#: multiplier within 1.3e-6 of 1 at every requested v (7.7e-4 with
#: MONODROMY_NEAR).  With the landings seeded from the previous point
#: (``seed`` of the corrector) the run takes 49 flows with the sensitivity
#: and 108 without, against 55 and 70 with MONODROMY_NEAR and no seeding
#: (74 and 54 with this constant but no seeding): about the same CPU.
MONODROMY_AT_ORBIT = 1e-6
#: The orbits at the requested v are integrated this much more accurately
#: than the continuation's own steps (whose orbits only trace the branch).
#: Measured on Fig. 7 (P3:16, 36 v, against the sweep): stable cycles within
#: 4.1e-7 of the attractors found by integration, against 1.4e-6 with 1.0
#: (the chord matrix seeded from the previous point moves the last iterates,
#: and with them the integration noise), at no measurable extra CPU.
GRID_RTOL_FACTOR = 0.5


class CycleContinuationError(SolverError):
    """A branch of periodic orbits could not be continued (the corrector failed
    at the smallest step); ``branch`` holds the points finished before."""

    def __init__(self, message: str, branch: CycleBranch | None = None) -> None:
        super().__init__(message)
        self.branch = branch

    def __reduce__(self):
        return type(self), (str(self), self.branch)


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------
@dataclass(frozen=True)
class HopfPoint:
    """A Hopf point of the static branch: a flutter-type event with its eigenvector.

    Attributes
    ----------
    v, omega : float
        Flow velocity and frequency Im lambda of the critical pair.
    event_type : str
        The stability event (``flutter``, ``restabilization``, ``mode_restabilization``).
    q_static : ndarray, shape (n,)
    eigenvector : ndarray, complex, shape (2 n,)
        z = (q, i omega q) with A z = i omega z, scaled to unit RMS of its q part.
    """

    v: float
    omega: float
    event_type: str
    q_static: np.ndarray = field(repr=False)
    eigenvector: np.ndarray = field(repr=False)

    def to_dict(self, state: bool = False) -> dict:
        d = {"v": self.v, "omega": self.omega, "type": self.event_type}
        if state:
            d["q_static"] = [float(x) for x in self.q_static]
            d["eigenvector_re"] = [float(x) for x in self.eigenvector.real]
            d["eigenvector_im"] = [float(x) for x in self.eigenvector.imag]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> HopfPoint:
        z = np.asarray(d["eigenvector_re"]) + 1j * np.asarray(d["eigenvector_im"])
        return cls(d["v"], d["omega"], d["type"], np.asarray(d["q_static"], dtype=float), z)


@dataclass(frozen=True)
class CyclePoint:
    """One periodic orbit of a branch.

    Attributes
    ----------
    v, period : float
    q0, qdot0 : ndarray, shape (n,)
        The orbit's state on the phase section.
    tip : dict
        ``{"eta_tip": [min, max], "X_tip": [...], "Z_tip": [...]}`` over one period.
    multipliers : ndarray, complex
        Floquet multipliers by decreasing modulus (the trivial one included).
    stable : bool
        All non-trivial multipliers inside the unit circle.
    source : str
        ``"grid"`` (landed on a requested v) or ``"continuation"`` (a step of
        its own).
    iterations, residual : int, float
        Newton iterations (integrations) and final RMS residual.
    steps, rejected_steps : int
        Integration steps of the last period and rejected ones over the corrector.
    wall_time : float
    """

    v: float
    period: float
    q0: np.ndarray = field(repr=False)
    qdot0: np.ndarray = field(repr=False)
    tip: dict = field(default_factory=dict)
    multipliers: np.ndarray = field(default_factory=lambda: np.zeros(0, complex), repr=False)
    stable: bool = False
    source: str = "continuation"
    iterations: int = 0
    residual: float = 0.0
    steps: int = 0
    rejected_steps: int = 0
    wall_time: float = 0.0

    @property
    def max_multiplier(self) -> float:
        """Largest modulus of the non-trivial multipliers."""
        mu = _nontrivial(self.multipliers)
        return float(np.max(np.abs(mu))) if mu.size else 0.0

    def to_dict(self, state: bool = False) -> dict:
        d = {
            "v": self.v,
            "period": self.period,
            "tip": self.tip,
            "multipliers": [[float(z.real), float(z.imag)] for z in self.multipliers],
            "stable": self.stable,
            "source": self.source,
            "iterations": self.iterations,
            "residual": self.residual,
            "steps": self.steps,
            "rejected_steps": self.rejected_steps,
            "wall_time": self.wall_time,
        }
        if state:
            d["q0"] = [float(x) for x in self.q0]
            d["qdot0"] = [float(x) for x in self.qdot0]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> CyclePoint:
        mu = np.array([complex(a, b) for a, b in d["multipliers"]], dtype=complex)
        kw = {k: d[k] for k in cls.__dataclass_fields__ if k not in ("q0", "qdot0", "multipliers")}
        return cls(**kw, q0=np.asarray(d["q0"]), qdot0=np.asarray(d["qdot0"]), multipliers=mu)


@dataclass(frozen=True)
class CycleSpecialPoint:
    """A bifurcation of periodic orbits located on a branch.

    Attributes
    ----------
    v : float
    type : {"fold", "period_doubling", "neimark_sacker"}
    period : float
        Interpolated at v.
    index : int
        Index of the branch point after which it lies.
    """

    v: float
    type: str
    period: float
    index: int

    def to_dict(self) -> dict:
        return {"v": self.v, "type": self.type, "period": self.period, "index": self.index}


@dataclass(frozen=True)
class CycleBranch:
    """A branch of periodic orbits born at a Hopf point, in arclength order.

    Attributes
    ----------
    name : str
        ``"H1"``, ``"H2"``, ... by increasing v_H.
    hopf : HopfPoint
    points : tuple of CyclePoint
    special_points : tuple of CycleSpecialPoint
    end_reason : str
        Why the continuation stopped.
    steps, rejected_steps, newton_iterations : int
        Accepted continuation steps, rejected (halved) ones, and integrations
        over all correctors.
    wall_time : float
    """

    name: str
    hopf: HopfPoint
    points: tuple
    special_points: tuple
    end_reason: str
    steps: int
    rejected_steps: int
    newton_iterations: int
    wall_time: float

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "hopf": self.hopf.to_dict(),
            "special_points": [s.to_dict() for s in self.special_points],
            "end_reason": self.end_reason,
            "n_points": len(self.points),
            "steps": self.steps,
            "rejected_steps": self.rejected_steps,
            "newton_iterations": self.newton_iterations,
            "wall_time": self.wall_time,
        }


# ---------------------------------------------------------------------------
# Hopf points and equilibria
# ---------------------------------------------------------------------------
def _static_states(model: PipeModel, values: Sequence[float], v_start: float) -> dict:
    """Static states of the primary branch (the gravity-loaded state continued in v,
    as the stability analysis follows it) at ``values``, keyed by v."""
    from fempipe.analyses.statics import solve_path

    vals = sorted({float(v_start), *(float(v) for v in values)})
    sols = solve_path(model.with_params(replace(model.params, v=vals[0])), vals, "v")
    return {v: s.q for v, s in zip(vals, sols, strict=True)}


def _critical_eigenvector(
    model: PipeModel, q: np.ndarray, omega: float
) -> tuple[float, np.ndarray]:
    """(omega, z): the eigenpair of the first-order form nearest to i omega."""
    import scipy.linalg as sla

    from .stability import linearized_matrices

    K, Cd, M = (
        np.asarray(a.toarray() if hasattr(a, "toarray") else a)
        for a in linearized_matrices(model, q)
    )
    n = model.n
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-sla.solve(M, K), -sla.solve(M, Cd)]])
    lam, Z = np.linalg.eig(A)
    k = int(np.argmin(np.abs(lam - 1j * omega)))
    z = Z[:, k]
    z = z / np.sqrt(np.mean(np.abs(z[:n]) ** 2))
    return float(lam[k].imag), z


def hopf_points(
    model: PipeModel, v_min: float, v_max: float, *, ds_max: float = 0.1
) -> tuple[list[HopfPoint], float]:
    """The Hopf points of the primary static branch in [0, v_max] that matter for [v_min, v_max].

    The stability events of :func:`fempipe.analyses.stability.stability_analysis` of
    type flutter, restabilization or mode_restabilization with a non-zero
    frequency (a complex pair crossing Re lambda = 0) are Hopf points.  The
    analysis starts at ``v_min``; if the primary branch is already unstable
    there, it is repeated from v = 0 so that the Hopf points whose orbits
    reach into the range are found too.

    Returns
    -------
    hopf : list of HopfPoint, by increasing v
    v_start : float
        Start of the analysis (``v_min`` or 0).
    """
    hopf, v_start, _ = _analyse_static(model, v_min, v_max, ds_max)
    return hopf, v_start


def _analyse_static(model: PipeModel, v_min: float, v_max: float, ds_max: float = 0.1):
    """(Hopf points, start of the analysis, events of the primary branch)."""
    from .stability import stability_analysis

    res = stability_analysis(model, v_max, v_min, follow_bifurcations=False, ds_max=ds_max)
    v_start = v_min
    if v_min > 0 and any(e.at_start for e in res.events):
        v_start = 0.0
        res = stability_analysis(model, v_max, 0.0, follow_bifurcations=False, ds_max=ds_max)
    events = [
        e
        for e in res.events
        if e.branch == "primary" and not e.at_start and e.frequency > 0 and e.type != "fold"
    ]
    states = _static_states(model, [e.v for e in events], v_start) if events else {}
    out = []
    for e in events:
        m = model.with_params(replace(model.params, v=e.v))
        omega, z = _critical_eigenvector(m, states[float(e.v)], abs(e.frequency))
        out.append(HopfPoint(float(e.v), omega, e.type, states[float(e.v)], z))
    primary = [e for e in res.events if e.branch == "primary"]
    return out, v_start, primary


def _stable_between_events(events: Sequence, v: float) -> bool:
    """Linear stability of the primary branch at v from its events (stable_before/after)."""
    before = [e for e in events if e.v <= v]
    if before:
        return bool(before[-1].stable_after)
    after = [e for e in events if e.v > v]
    return bool(after[0].stable_before) if after else True


def static_points(
    model: PipeModel,
    values: Sequence[float],
    v_start: float | None = None,
    events: Sequence | None = None,
) -> list[dict]:
    """Equilibria of the primary branch at ``values`` with their linear stability.

    Each dict has the keys of a bifurcation point (``attractor`` =
    ``"equilibrium"``, ``direction`` = ``"static"``, tip [value, value], ...)
    and ``stable``: from the primary branch's stability ``events`` of
    :func:`fempipe.analyses.stability.stability_analysis` (``stable_before`` /
    ``stable_after``) when given, else :func:`fempipe.analyses.stability.linearly_stable`
    at each state (the same criterion).
    """
    from .stability import linearly_stable

    vals = sorted(float(v) for v in values)
    start = vals[0] if v_start is None else float(v_start)
    states = _static_states(model, vals, start)
    out = []
    for i, v in enumerate(vals):
        t0 = time.perf_counter()
        m = model.with_params(replace(model.params, v=v))
        q = states[v]
        stable = _stable_between_events(events, v) if events is not None else linearly_stable(m, q)
        d = _point_dict(v, "static", i, model.params.alpha, "equilibrium")
        d.update(_equilibrium_tip(model, q))
        d.update(
            stable=bool(stable) if stable is not None else None,
            branch="static",
            requested=True,
            source="grid",
            floquet_multipliers=None,
            wall_time=time.perf_counter() - t0,
        )
        out.append(d)
    return out


def _equilibrium_tip(model: PipeModel, q: np.ndarray) -> dict:
    """``{"eta_tip": [y, y], "X_tip": ..., "Z_tip": ...}`` of an equilibrium, in the
    [min, max] form of the diagram's points: the static points, and the Hopf points
    where a branch of orbits starts."""
    tip = tip_coordinates(model.disc, model.params.alpha, q)
    return {k: [float(tip[k]), float(tip[k])] for k in TIP_KEYS}


def _point_dict(v, direction, index, alpha, attractor) -> dict:
    return {
        "v": float(v),
        "direction": direction,
        "index": index,
        "alpha": float(alpha),
        "attractor": attractor,
        "eta_tip": None,
        "X_tip": None,
        "Z_tip": None,
        "period": None,
        "period_n": None,
        "max_multiplier": None,
        "steps": 0,
        "rejected_steps": 0,
        "wall_time": 0.0,
    }


# ---------------------------------------------------------------------------
# The flow map and its derivatives
# ---------------------------------------------------------------------------
def _nontrivial(mu: np.ndarray) -> np.ndarray:
    if mu.size < 2:
        return mu[:0]
    return np.delete(mu, int(np.argmin(np.abs(mu - 1.0))))


@dataclass
class _Flow:
    xT: np.ndarray
    fT: np.ndarray
    monodromy: np.ndarray | None
    dv: np.ndarray | None  # d phi_T(x) / dv at fixed x and T
    steps: int
    rejected: int
    record: list


def _flow(model: PipeModel, x: np.ndarray, T: float, rtol: float, sensitivity: bool) -> _Flow:
    """phi_T(x) with the step data (for the tip extrema) and, if asked, the monodromy."""
    n = model.n
    st = Radau(
        model, x[:n], x[n:], 0.0, rtol=rtol, sensitivity=sensitivity, velocity_sensitivity=True
    )
    record = []
    for _ in st.steps(T):
        t_old, h, q_old, p_old, Q, P, _acc = st.last
        record.append((t_old, h, q_old, Q))
    return _Flow(
        xT=np.r_[st.q, st.qdot],
        fT=np.r_[st.qdot, st.qddot],
        monodromy=st.sensitivity_matrix if sensitivity else None,
        dv=st.velocity_sensitivity if sensitivity else None,
        steps=st.stats.steps,
        rejected=st.stats.rejected_steps,
        record=record,
    )


# Weights of the cubic through (0, q_old), (c_i, Q_i): the integrator's
# collocation polynomial, evaluated at s = (t - t_old) / h.
_NODES = np.r_[0.0, _RADAU_NODES]


def _lagrange(s: np.ndarray) -> np.ndarray:
    s = np.atleast_1d(s)[:, None]
    L = np.ones((s.shape[0], 4))
    for j in range(4):
        for m in range(4):
            if m != j:
                L[:, j] *= (s[:, 0] - _NODES[m]) / (_NODES[j] - _NODES[m])
    return L


def _tip_extrema(model: PipeModel, record: list, per_step: int = 8) -> dict:
    """[min, max] of the tip coordinates over one period, from the collocation
    polynomials: sampled ``per_step`` times per step, each extremum refined by a
    bounded scalar minimisation on the polynomial of its step and the neighbours."""
    from scipy.optimize import minimize_scalar

    disc, alpha = model.disc, model.params.alpha
    s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
    L = _lagrange(s)  # (per_step, 4)
    nodes = np.stack([np.vstack([q_old[None, :], Q]) for _, _, q_old, Q in record])  # (m, 4, n)
    qs = np.einsum("sj,mjn->msn", L, nodes).reshape(-1, model.n)
    tips = tip_coordinates(disc, alpha, qs)
    ts = np.array([t0 + h * s for t0, h, _, _ in record]).ravel()
    t_end = record[-1][0] + record[-1][1]
    starts = np.array([r[0] for r in record])

    def state_at(t: float) -> np.ndarray:
        k = int(np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(record) - 1))
        t0, h, q_old, Q = record[k]
        w = _lagrange(np.array([(t - t0) / h]))[0]
        return w @ np.vstack([q_old[None, :], Q])

    out = {}
    for key in TIP_KEYS:
        y = np.asarray(tips[key])
        ext = []
        for sign in (1.0, -1.0):  # min, then max
            k = int(np.argmin(sign * y))
            a = ts[k - 1] if k > 0 else ts[k]
            b = ts[k + 1] if k + 1 < ts.size else t_end
            r = minimize_scalar(
                lambda t, key=key, sign=sign: sign * tip_coordinates(disc, alpha, state_at(t))[key],
                bounds=(a, b),
                method="bounded",
                options={"xatol": 1e-10 * max(1.0, t_end)},
            )
            ext.append(min(sign * y[k], float(r.fun)) * sign)
        out[key] = [float(min(ext)), float(max(ext))]
    return out


# ---------------------------------------------------------------------------
# Continuation
# ---------------------------------------------------------------------------
class _CorrectorError(Exception):
    """The corrector did not converge (the step is halved)."""


class _Continuer:
    """Newton correctors and the stepping of one branch (see the module docstring)."""

    def __init__(
        self, model: PipeModel, hopf: HopfPoint, rtol: float, tol: float, xtol: float, max_iter: int
    ):
        self.model = model
        self.xtol = xtol
        self.n = model.n
        self.hopf = hopf
        self.rtol, self.tol, self.max_iter = rtol, tol, max_iter
        self.T_H = 2 * math.pi / hopf.omega
        n = self.n
        s = self.T_H / (2 * math.pi)
        # u -> z = S u: the metric of the arclength (module docstring).
        self.S = np.r_[
            np.full(n, 1 / math.sqrt(n)), np.full(n, s / math.sqrt(n)), 1 / self.T_H, 1.0
        ]
        self.integrations = 0
        self.rejected_integration_steps = 0

    def at(self, v: float) -> PipeModel:
        return self.model.with_params(self.model.params.with_flow(float(v)))

    def residual_norm(self, r: np.ndarray, T: float) -> float:
        n = self.n
        s = T / (2 * math.pi)
        return float(np.sqrt(np.mean(r[:n] ** 2) + np.mean((r[n:] * s) ** 2)))

    def rtol_after(self, previous: CyclePoint | None) -> float:
        """Integration tolerance for the next point: ``rtol`` times the distance
        of the previous orbit's nearest non-trivial multiplier from 1 (at least
        a tenth).  An error e of the flow map moves the fixed point by about
        e / |1 - mu|, so near the Hopf point and near folds (mu -> 1) the flow
        is integrated more accurately (measured at P3:16, alpha = 0, v = 6.4,
        mu = 0.87: tip error 1.4e-6 at rtol = 1e-5, 2e-7 at 1e-6)."""
        if previous is None:
            return 0.1 * self.rtol
        mu = _nontrivial(previous.multipliers)
        d = float(np.min(np.abs(1.0 - mu))) if mu.size else 1.0
        return self.rtol * min(1.0, max(0.1, d))

    def correct(
        self,
        u_pred: np.ndarray,
        tangent: np.ndarray | None,
        u_ref: np.ndarray | None = None,
        rtol: float | None = None,
        monodromy_at: float = MONODROMY_NEAR,
        seed: _Flow | None = None,
    ) -> tuple:
        """Newton on the extended system from ``u_pred``: pseudo-arclength with the
        (z-space) ``tangent``, or at the fixed v of ``u_pred`` if ``tangent`` is None.

        The monodromy returned (and so the Floquet multipliers) is taken at an
        iterate within ``monodromy_at`` times the orbit's amplitude of the
        converged orbit (the chord iteration reuses an older one; for
        :data:`MONODROMY_AT_ORBIT` the iterate predicted to be the last takes
        the sensitivity, and where the converged orbit is still farther, one
        more flow with the sensitivity is integrated at it):
        :data:`MONODROMY_NEAR` on the continuation's own steps,
        :data:`MONODROMY_AT_ORBIT` at the requested v, whose multipliers are
        reported.

        ``seed``, a flow with the sensitivity at a nearby orbit (the previous
        point's last flow), gives the chord matrix of the first iteration, so
        that it needs no sensitivity of its own; if the residual then falls
        less than four times, the matrix is computed afresh as usual.

        The phase section passes through the state of ``u_ref`` (the last point of
        the branch; the predictor when None), orthogonal to the flow there: the
        new x0 does not drift along the orbit from one point to the next, so
        that secants measure the change of the orbit, not of its phase.

        Returns (u, flow of the last iterate, monodromy, iterations, rejected steps).
        """
        n2 = 2 * self.n
        rtol = self.rtol if rtol is None else rtol
        u = u_pred.copy()
        u_ref = u_pred if u_ref is None else u_ref
        x_ref = u_ref[:n2]
        m_ref = self.at(u_ref[-1])
        f_ref = np.r_[x_ref[n2 // 2 :], acceleration(m_ref, x_ref[: n2 // 2], x_ref[n2 // 2 :])]
        # Orthogonal in the metric: on a near-Hopf orbit, an ellipse in the
        # plane of Re z, Im z, a section through a principal axis stays there.
        f_ref = self.S[:n2] ** 2 * f_ref
        f_ref = f_ref / np.linalg.norm(f_ref)
        fixed_v = tangent is None
        J = None
        res_prev = res_exact = math.inf
        stale = False
        rejected = 0
        monodromy = u_mono = None

        def chord(fl: _Flow) -> np.ndarray:
            k = n2 + (1 if fixed_v else 2)
            J = np.zeros((k, k))
            J[:n2, :n2] = fl.monodromy - np.eye(n2)
            J[:n2, n2] = fl.fT
            J[n2, :n2] = f_ref
            if not fixed_v:
                J[:n2, -1] = fl.dv
                J[-1] = tangent * self.S
            return J

        if seed is not None and seed.monodromy is not None and seed.dv is not None:
            J, monodromy = chord(seed), seed.monodromy
        # Where the multipliers are wanted at the orbit, the iterate predicted
        # to be the last (the residual and the correction times the chord's
        # contraction rate within tol and xtol) gets the sensitivity, once: it
        # is then within about xtol of the converged orbit and no extra flow
        # is needed after convergence.
        at_orbit = monodromy_at < MONODROMY_NEAR
        last_next = asked = False
        for it in range(1, self.max_iter + 1):
            x, T, v = u[:n2], u[n2], u[-1]
            need = J is None or stale or last_next
            last_next = False
            m = self.at(v)
            try:
                fl = _flow(m, x, T, rtol, sensitivity=need)
            except IntegrationError as exc:
                raise _CorrectorError(str(exc)) from None
            self.integrations += 1
            rejected += fl.rejected
            r = fl.xT - x
            g = float(f_ref @ (x - x_ref))
            c = 0.0 if fixed_v else float(tangent @ (self.S * (u - u_pred)))
            res = self.residual_norm(r, T)
            log.debug("corrector it %d need %s res %.3e g %.2e c %.2e", it, need, res, g, c)
            if need:
                if res > 0.5 * res_exact:
                    # An exact Newton step that did not halve the residual: the
                    # integration noise, not the linearisation, limits it.
                    raise _CorrectorError(f"Newton stalled at the residual {res:.1e}")
                res_exact = res
                monodromy = fl.monodromy
                u_mono = u.copy()
                J = chord(fl)
            stale = not need and res > res_prev / 4
            rate = min(1.0, res / res_prev) if math.isfinite(res_prev) else 0.1
            res_prev = res
            rhs = -np.r_[r, g] if fixed_v else -np.r_[r, g, c]
            try:
                du = np.linalg.solve(J, rhs)
            except np.linalg.LinAlgError:
                raise _CorrectorError("singular Jacobian") from None
            if not np.all(np.isfinite(du)):
                raise _CorrectorError("non-finite Newton step")
            # Converged when the residual is small and so is the correction it
            # asks for: the error of this iterate (the residual alone hides it
            # where a multiplier is near 1, e.g. close to the Hopf point).
            correction = max(
                self.residual_norm(du[:n2], T), abs(du[n2]) / T, 0.0 if fixed_v else abs(du[-1])
            )
            if (
                res < self.tol
                and abs(g) < self.tol
                and abs(c) < self.tol
                and correction < self.xtol
            ):
                amplitude = self.residual_norm(fl.fT * T / (2 * math.pi), T)
                if (
                    u_mono is None
                    or self.residual_norm(u[:n2] - u_mono[:n2], T) > monodromy_at * amplitude
                ):
                    # The multipliers of a matrix taken this far from the orbit
                    # (small orbits near the Hopf point) would be off by as much
                    # (measured: the trivial one at 1.03): once more at the orbit.
                    fl = _flow(m, x, T, rtol, sensitivity=True)
                    self.integrations += 1
                    rejected += fl.rejected
                    monodromy = fl.monodromy
                    it += 1
                return u, fl, monodromy, it, rejected
            if at_orbit and not need and not asked:
                last_next = rate * res < self.tol and rate * correction < self.xtol
                asked = last_next
            size = float(np.linalg.norm(self.S[:n2] * du[:n2]) * math.sqrt(2))
            lam = min(1.0, 0.3 / size) if size > 0 else 1.0
            if fixed_v:
                u[: n2 + 1] += lam * du
            else:
                u += lam * du
            if not u[n2] > 0:
                raise _CorrectorError("the period became negative")
        raise _CorrectorError(f"no convergence in {self.max_iter} Newton iterations")

    def point(self, u, fl, monodromy, it, rejected, source, t0) -> CyclePoint:
        n = self.n
        mu = np.linalg.eigvals(monodromy)
        mu = mu[np.argsort(-np.abs(mu))]
        nt = _nontrivial(mu)
        return CyclePoint(
            v=float(u[-1]),
            period=float(u[2 * n]),
            q0=u[:n].copy(),
            qdot0=u[n : 2 * n].copy(),
            tip=_tip_extrema(self.at(u[-1]), fl.record),
            multipliers=mu,
            stable=bool(np.all(np.abs(nt) < 1.0)),
            source=source,
            iterations=it,
            residual=self.residual_norm(fl.xT - u[: 2 * n], u[2 * n]),
            steps=fl.steps,
            rejected_steps=rejected,
            wall_time=time.perf_counter() - t0,
        )


def _u_of(pt: CyclePoint) -> np.ndarray:
    return np.r_[pt.q0, pt.qdot0, pt.period, pt.v]


def _swing(pt: CyclePoint) -> float:
    lo, hi = pt.tip["eta_tip"]
    return hi - lo


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
    """Follow the periodic orbits born at a Hopf point by pseudo-arclength continuation.

    Solves the periodic-orbit problem of Eq. (20) in (x0, T, v) (module
    docstring: single shooting with the exact monodromy of the discrete flow,
    a Poincare phase condition, Keller's pseudo-arclength condition or a fixed
    v on the requested values).

    Parameters
    ----------
    model : PipeModel
        alpha, beta, gamma, mu from ``model.params`` (its v is ignored).
    hopf : HopfPoint
        Where the branch starts (:func:`hopf_points`).
    v_range : (float, float)
        The branch ends once it leaves this range of v.
    values : sequence of float
        Requested v: each is landed on exactly (fixed-v corrector) every time
        the branch passes it (``source="grid"``).
    name : str
        Branch name.
    rtol : float
        Integration tolerance of :class:`fempipe.solvers.radau.Radau`, scaled down by
        the distance of the nearest non-trivial Floquet multiplier from 1 (down
        to rtol / 10; see ``_Continuer.rtol_after``); the orbits at the
        requested v at :data:`GRID_RTOL_FACTOR` times that.  At the default
        1e-5 the periods and tip extrema of P3:16 orbits at alpha = 0,
        v = 6.4 ... 12 lie within 4.7e-8 and 4.1e-7 of orbits shot at
        rtol = 1e-10 (measured at the 29 requested v of Fig. 7; the error is
        that of the integrated flow and moves with the step sequences), with
        55-60 % of the steps of rtol = 1e-6.
    tol : float
        Newton tolerance on the RMS of phi_T(x0) - x0 (q' scaled by T / 2 pi),
        on the phase and on the arclength conditions.
    xtol : float
        ... and on the Newton correction that residual asks for (the error of
        the iterate: q in rad, q' scaled by T / 2 pi, T relative, v), which
        the residual alone underestimates by 1 / (1 - mu) where a multiplier
        mu is near 1 (near the Hopf point, near folds).
    ds, ds_min, ds_max : float
        First, smallest and largest arclength step (metric of the module docstring).
    max_steps : int
        Steps before the branch ends.
    max_iter : int
        Newton iterations per corrector.
    resume : dict, optional
        The state written to ``on_point`` by an interrupted run with the same
        arguments: the branch continues from there.
    on_point : callable, optional
        Called after every accepted point with a plain-JSON dict of the whole
        branch state (points with their states, step size), which ``resume``
        accepts.

    Returns
    -------
    CycleBranch

    Raises
    ------
    CycleContinuationError
        If the corrector fails at the smallest step; names v and the step, and
        carries the finished part of the branch.
    ValueError
        For bad arguments or hysteretic damping (no time-domain meaning).
    """
    refuse_hysteretic(model.params, "continue_cycles")
    v_lo, v_hi = (float(a) for a in v_range)
    if not v_lo < v_hi:
        raise ValueError(f"v_range must have v_min < v_max, got {v_range}")
    if not 0 < ds_min <= ds <= ds_max:
        raise ValueError(f"need 0 < ds_min <= ds <= ds_max, got {ds_min}, {ds}, {ds_max}")
    if not 0 < tol < 1 or not 0 < rtol < 1:
        raise ValueError(f"tol and rtol must lie in (0, 1), got {tol}, {rtol}")
    t_start = time.perf_counter()
    grid = np.array(sorted(float(v) for v in values if v_lo <= v <= v_hi))
    cont = _Continuer(model, hopf, rtol, tol, xtol, max_iter)
    n = model.n
    u_H = np.r_[hopf.q_static, np.zeros(n), cont.T_H, hopf.v]
    points: list[CyclePoint] = []
    seed = None  # the last flow with the sensitivity of the previous point, if any
    steps = rejected = 0
    wall_before = 0.0
    integ_before = 0
    if resume is not None:
        points = [CyclePoint.from_dict(d) for d in resume["points"]]
        ds = float(resume["ds"])
        steps, rejected = int(resume["steps"]), int(resume["rejected_steps"])
        integ_before = int(resume["newton_iterations"])
        wall_before = float(resume["wall_time"])
        if resume.get("end_reason") is not None:
            return _branch(
                name, hopf, points, resume["end_reason"], steps, rejected, integ_before, wall_before
            )

    def state(end_reason=None, error=None) -> dict:
        return {
            "name": name,
            "hopf": hopf.to_dict(),
            "points": [p.to_dict(state=True) for p in points],
            "ds": ds,
            "steps": steps,
            "rejected_steps": rejected,
            "newton_iterations": integ_before + cont.integrations,
            "wall_time": wall_before + time.perf_counter() - t_start,
            "end_reason": end_reason,
            "error": error,
        }

    def finish(reason: str) -> CycleBranch:
        st = state(end_reason=reason)
        if on_point is not None:
            on_point(st)
        return _branch(
            name, hopf, points, reason, steps, rejected, st["newton_iterations"], st["wall_time"]
        )

    us = [u_H] + [_u_of(p) for p in points]
    # Rotate z so that Re z is the major axis of the ellipse Re(z e^{i omega tau})
    # in the metric: the first orbit starts on it and later ones stay there
    # (the phase section through a principal axis is orthogonal to the flow).
    w = cont.S[: 2 * n]
    a, b = w * hopf.eigenvector.real, w * hopf.eigenvector.imag
    psi = 0.5 * math.atan2(-2.0 * float(a @ b), float(a @ a - b @ b))
    z_hopf_dir = cont.S * np.r_[(hopf.eigenvector * np.exp(1j * psi)).real, 0.0, 0.0]
    z_hopf_dir /= np.linalg.norm(z_hopf_dir)
    with single_blas_thread():
        while True:
            if steps >= max_steps:
                return finish(f"max_steps ({max_steps}) reached")
            u_k = us[-1]
            if len(us) == 1:
                tangent = z_hopf_dir
            else:
                d = cont.S * (us[-1] - us[-2])
                tangent = d / np.linalg.norm(d)
            t_v = tangent[-1]  # dv/ds (v weight 1)
            v_k = u_k[-1]
            if len(us) > 1 and abs(t_v) >= MIN_DV_DS:
                if (t_v > 0 and v_k >= v_hi - 1e-12) or (t_v < 0 and v_k <= v_lo + 1e-12):
                    return finish("reached the end of the v range")
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
                u_pred = _predict(cont.S, us, tangent, h)
                u_pred[-1] = target
                use_tangent = None
                source = "grid"
                near = MONODROMY_AT_ORBIT
            else:
                h = ds
                u_pred = _predict(cont.S, us, tangent, h)
                use_tangent = tangent
                source = "continuation"
                near = MONODROMY_NEAR
            try:
                rtol_k = cont.rtol_after(points[-1] if points else None)
                if source == "grid":
                    rtol_k *= GRID_RTOL_FACTOR
                try:
                    u, fl, mono, it, rej = cont.correct(
                        u_pred,
                        use_tangent,
                        u_k if len(us) > 1 else None,
                        rtol_k,
                        near,
                        seed if source == "grid" else None,
                    )
                except _CorrectorError as first:
                    # Newton can stall on the jumps of the adaptive step sequence
                    # (measured: a residual floor of 3e-6 at rtol = 1e-5, P3:16,
                    # alpha = pi/2, v = 9.2): the same step once more, ten times
                    # more accurately, before the step is halved.
                    log.info("%s: %s at v = %.6g; rtol %.1e", name, first, u_pred[-1], rtol_k / 10)
                    rejected += 1
                    u, fl, mono, it, rej = cont.correct(
                        u_pred, use_tangent, u_k if len(us) > 1 else None, rtol_k / 10, near
                    )
                d_new = cont.S * (u - u_k)
                # (From the equilibrium to the first orbit is no secant of the family.)
                if len(us) > 2:
                    cosang = float(d_new @ tangent) / max(np.linalg.norm(d_new), 1e-300)
                    turn = math.acos(max(-1.0, min(1.0, cosang)))
                    if turn > MAX_ANGLE:
                        raise _CorrectorError(f"the branch turned by {turn:.2f} rad in one step")
            except _CorrectorError as exc:
                rejected += 1
                ds = 0.5 * min(ds, abs(h))
                log.info(
                    "%s: corrector failed at v = %.6g (%s); step %.3g", name, u_pred[-1], exc, ds
                )
                if ds < ds_min:
                    msg = (
                        f"branch {name} of periodic orbits (from the Hopf point v = {hopf.v:.6g}) "
                        f"cannot be continued beyond v = {v_k:.6g}: the corrector failed at "
                        f"v = {u_pred[-1]:.6g} with the smallest step ds = {ds_min:g} "
                        f"(step {steps + 1}; {exc})"
                    )
                    st = state(end_reason="failed", error=msg)
                    if on_point is not None:
                        on_point(st)
                    raise CycleContinuationError(
                        msg,
                        _branch(
                            name,
                            hopf,
                            points,
                            "failed",
                            steps,
                            rejected,
                            st["newton_iterations"],
                            st["wall_time"],
                        ),
                    ) from None
                continue
            if source == "continuation" and grid.size:
                # Requested v passed by this step (near the Hopf point or a fold,
                # where v is no local parameter): landed on at fixed v from the
                # secant between the two orbits around them.
                lo_, hi_ = sorted((v_k, u[-1]))
                crossed = grid[(grid > lo_ + 1e-9) & (grid < hi_ - 1e-9)]
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
                    except _CorrectorError as exc:
                        log.warning(
                            "%s: requested v = %.6g passed but not landed on (%s)", name, vg, exc
                        )
                        continue
                    gpt = cont.point(*got, "grid", t1)
                    if _swing(gpt) < MIN_SWING:
                        log.warning("%s: v = %.6g converged to the equilibrium", name, vg)
                        continue
                    points.append(gpt)
                    us.append(got[0])
            pt = cont.point(u, fl, mono, it, rej, source, t0)
            points.append(pt)
            us.append(u)
            # A last flow with the sensitivity (at a requested v) seeds the
            # chord matrix of the next landing on a requested v.
            seed = fl if fl.monodromy is not None else None
            steps += 1
            if it <= 4:
                ds = min(ds_max, 1.5 * max(ds, abs(h)))
            elif it > 5:
                ds = max(ds_min, 0.5 * ds)
            if on_point is not None:
                on_point(state())
            log.info(
                "%s v=%.6g T=%.6g eta [%.4g, %.4g] %s %s (%d its)",
                name,
                pt.v,
                pt.period,
                *pt.tip["eta_tip"],
                "stable" if pt.stable else "unstable",
                source,
                it,
            )
            if _swing(pt) < MIN_SWING and len(points) > 2:
                return finish(f"returned to an equilibrium near v = {pt.v:.6g} (a Hopf point)")
            if pt.period > MAX_PERIOD_RATIO * cont.T_H:
                return finish(f"period above {MAX_PERIOD_RATIO:g} T_H (homoclinic approach)")
            if not v_lo - 1e-12 <= pt.v <= v_hi + 1e-12 and len(points) > 1:
                inside = v_lo <= hopf.v <= v_hi
                prev_v = points[-2].v
                # Outside the range: stop once moving away from it.
                if inside or (pt.v - prev_v) * (pt.v - 0.5 * (v_lo + v_hi)) > 0:
                    return finish("left the v range")


def _predict(S: np.ndarray, us: list, tangent: np.ndarray, h: float) -> np.ndarray:
    """The point at arclength h ahead of the last one: on the polynomial through the
    last four (or three) points, parametrised by chord length in the metric, when
    they are about evenly spaced and h is not much longer than their spacing (as
    on a run of requested v); else on the tangent."""
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


def _branch(name, hopf, points, reason, steps, rejected, its, wall) -> CycleBranch:
    return CycleBranch(
        name=name,
        hopf=hopf,
        points=tuple(points),
        special_points=tuple(_special_points(points)),
        end_reason=reason,
        steps=steps,
        rejected_steps=rejected,
        newton_iterations=its,
        wall_time=wall,
    )


def _is_real(z: np.ndarray) -> np.ndarray:
    return np.abs(z.imag) <= 1e-10 * np.maximum(1.0, np.abs(z))


def _tests(pt: CyclePoint) -> tuple[int, int, float, float]:
    """(real multipliers below -1, complex ones outside the unit circle,
    the most negative real multiplier + 1, the largest complex modulus - 1)."""
    mu = _nontrivial(pt.multipliers)
    real = _is_real(mu)
    neg = mu[real & (mu.real < 0)].real
    # A "complex pair" within NEAR_ONE of +1 is two real multipliers near 1 (the
    # trivial one and the one through +1 near a Hopf point or a fold) that the
    # eigensolver splits into a pair: no Neimark-Sacker point.
    cplx = np.abs(mu[~real & (np.abs(mu - 1.0) > NEAR_ONE)])
    return (
        int(np.sum(neg < -1.0)),
        int(np.sum(cplx > 1.0)),
        float(neg.min() + 1.0) if neg.size else math.nan,
        float(cplx.max() - 1.0) if cplx.size else math.nan,
    )


def _special_points(points: Sequence[CyclePoint]) -> list[CycleSpecialPoint]:
    out = []
    for k in range(1, len(points)):
        a, b = points[k - 1], points[k]
        if k >= 2:
            p0 = points[k - 2]
            if (a.v - p0.v) * (b.v - a.v) < 0:
                out.append(_fold(p0, a, b, k - 1))
        ta, tb = _tests(a), _tests(b)
        for count, value, kind in ((0, 2, "period_doubling"), (1, 3, "neimark_sacker")):
            if ta[count] != tb[count]:
                fa, fb = ta[value], tb[value]
                if kind == "period_doubling":
                    fa, fb = -fa, -fb  # > 0 outside
                w = fa / (fa - fb) if math.isfinite(fa) and math.isfinite(fb) and fa != fb else 0.5
                w = min(1.0, max(0.0, w))
                out.append(
                    CycleSpecialPoint(
                        v=float(a.v + w * (b.v - a.v)),
                        type=kind,
                        period=float(a.period + w * (b.period - a.period)),
                        index=k - 1,
                    )
                )
    return out


def _fold(p0: CyclePoint, a: CyclePoint, b: CyclePoint, index: int) -> CycleSpecialPoint:
    """Vertex of the parabola v(s) through three points (s: chord length in (v, T, swing))."""

    def dist(p, q):
        return math.hypot(p.v - q.v, p.period - q.period, _swing(p) - _swing(q))

    s = np.array([0.0, dist(p0, a), dist(p0, a) + dist(a, b)])
    vs = np.array([p0.v, a.v, b.v])
    Ts = np.array([p0.period, a.period, b.period])
    c = np.polyfit(s, vs, 2)
    if c[0] == 0:
        return CycleSpecialPoint(float(a.v), "fold", float(a.period), index)
    s_star = float(np.clip(-c[1] / (2 * c[0]), s[0], s[-1]))
    return CycleSpecialPoint(
        v=float(np.polyval(c, s_star)),
        type="fold",
        period=float(np.polyval(np.polyfit(s, Ts, 2), s_star)),
        index=index,
    )


# ---------------------------------------------------------------------------
# Diagrams: the static branch and every branch of periodic orbits, resumable
# ---------------------------------------------------------------------------
#: Floquet multipliers listed per point in the JSON (largest moduli).
N_MULTIPLIERS = 8


def cycle_point_dict(pt: CyclePoint, branch: str, index: int, alpha: float) -> dict:
    """A cycle as a point of ``fempipe bifurcation --json`` (the sweep's keys plus
    ``stable``, ``branch``, ``requested``, ``source``, ``floquet_multipliers``)."""
    d = _point_dict(pt.v, "continuation", index, alpha, "periodic")
    d.update({k: list(pt.tip[k]) for k in TIP_KEYS})
    d.update(
        period=pt.period,
        period_n=1,
        max_multiplier=pt.max_multiplier,
        steps=pt.steps,
        rejected_steps=pt.rejected_steps,
        wall_time=pt.wall_time,
        stable=pt.stable,
        branch=branch,
        requested=pt.source == "grid",
        source=pt.source,
        floquet_multipliers=[
            [float(z.real), float(z.imag)] for z in pt.multipliers[:N_MULTIPLIERS]
        ],
        newton_iterations=pt.iterations,
        residual=pt.residual,
    )
    return d


@dataclass(frozen=True)
class CycleDiagram:
    """A bifurcation diagram by continuation: equilibria and periodic orbits.

    Attributes
    ----------
    points : list of dict
        Equilibria (``direction="static"``) at the requested v, then the points
        of every branch of periodic orbits (``direction="continuation"``) in
        arclength order; by alpha.
    branches : list of dict
        :meth:`CycleBranch.to_dict` of every branch, with ``alpha``.
    special_points : list of dict
        Folds, period doublings, Neimark-Sacker points with ``alpha`` and ``branch``.
    hopf_points : list of dict
    errors : list of str
        Branches that could not be continued (their finished points are kept).
    wall_time : float
    manifest : dict
    """

    points: list
    branches: list
    special_points: list
    hopf_points: list
    errors: list
    wall_time: float
    manifest: dict

    def to_dict(self) -> dict:
        return {
            "points": list(self.points),
            "branches": list(self.branches),
            "special_points": list(self.special_points),
            "hopf_points": list(self.hopf_points),
            "errors": list(self.errors),
            "wall_time": self.wall_time,
            "discretization": self.manifest["discretization"],
            "params": self.manifest["params"],
        }


def _alpha_task(
    model: PipeModel,
    values: list,
    alpha_index: int,
    store_dir: str,
    manifest: dict,
    options: dict,
    on_point: Callable[[], None] | None = None,
) -> dict:
    """Static branch, Hopf points and all branches of periodic orbits at one alpha."""
    from .bifurcation import PointStore

    store = PointStore(store_dir, manifest)
    alpha = float(model.params.alpha)
    v_lo, v_hi = min(values), max(values)
    static_path = store.directory / f"a{alpha_index:02d}-static.json"
    if static_path.exists():
        st = json.loads(static_path.read_text())
        hopf = [HopfPoint.from_dict(h) for h in st["hopf"]]
        eq_points = st["points"]
    else:
        hopf, v_start, events = _analyse_static(model, v_lo, v_hi)
        eq_points = static_points(model, values, v_start, events)
        saved = {
            "hopf": [h.to_dict(state=True) for h in hopf],
            "v_start": v_start,
            "points": eq_points,
        }
        write_text(static_path, json.dumps(saved))
    if on_point is not None:
        on_point()
    out = {
        "points": list(eq_points),
        "branches": [],
        "special_points": [],
        "errors": [],
        "hopf_points": [
            dict(h.to_dict(), alpha=alpha, branch=f"H{k}", **_equilibrium_tip(model, h.q_static))
            for k, h in enumerate(hopf, start=1)
        ],
    }
    covered: list[tuple[float, float]] = []
    for k, h in enumerate(hopf, start=1):
        name = f"H{k}"
        if any(abs(h.v - a) < 1e-6 or abs(h.v - b) < 1e-6 for a, b in covered):
            # The branch of an earlier Hopf point ended here: the same orbits.
            continue
        path = store.directory / f"a{alpha_index:02d}-{name}.json"
        resume = json.loads(path.read_text()) if path.exists() else None

        def save(state: dict, path=path) -> None:
            write_text(path, json.dumps(state))
            if on_point is not None:
                on_point()

        try:
            if resume is not None and resume.get("end_reason") == "failed":
                raise CycleContinuationError(
                    resume["error"],
                    _branch(
                        name,
                        h,
                        [CyclePoint.from_dict(d) for d in resume["points"]],
                        "failed",
                        resume["steps"],
                        resume["rejected_steps"],
                        resume["newton_iterations"],
                        resume["wall_time"],
                    ),
                )
            br = continue_cycles(
                model,
                h,
                (v_lo, v_hi),
                values,
                name=name,
                resume=resume,
                on_point=save,
                **options,
            )
        except CycleContinuationError as exc:
            br = exc.branch
            out["errors"].append(f"alpha = {alpha:.6g}: {exc}")
        if br is None:
            continue
        if br.points and br.end_reason.startswith("returned to an equilibrium"):
            covered.append((h.v, br.points[-1].v))
            # The other end: the next Hopf point nearest to where the branch ended.
            ends = [g.v for g in hopf if g is not h]
            if ends:
                near = min(ends, key=lambda x: abs(x - br.points[-1].v))
                covered.append((near, near))
        out["points"].extend(cycle_point_dict(p, name, i, alpha) for i, p in enumerate(br.points))
        out["branches"].append(dict(br.to_dict(), alpha=alpha))
        out["special_points"].extend(
            dict(s.to_dict(), alpha=alpha, branch=name) for s in br.special_points
        )
    return out


def _manifest(model: PipeModel, values, alphas, options) -> dict:
    p = model.params.to_dict()
    p.pop("v")
    p.pop("alpha")
    return {
        "method": "continuation",
        "discretization": model.disc.to_dict(),
        "params": p,
        "alphas": [float(a) for a in alphas],
        "values": sorted(float(v) for v in values),
        "options": {k: options[k] for k in sorted(options)},
    }


def cycle_diagram(
    model: PipeModel,
    values: Sequence[float],
    *,
    alphas: Sequence[float] | None = None,
    store_dir: str | os.PathLike | None = None,
    executor: Executor | None = None,
    workers: int | None = None,
    progress: Callable[[], None] | None = None,
    **options,
) -> CycleDiagram:
    """Bifurcation diagram by continuation (Figs. 7-10): equilibria and periodic orbits.

    For each alpha: the stability events of the primary static branch
    (:func:`fempipe.analyses.stability.stability_analysis`), its equilibria at the
    requested v with their linear stability, and the branch of periodic
    orbits of Eq. (20) born at every Hopf point, by :func:`continue_cycles`.
    A branch that ends at another Hopf point (a family joining flutter and
    restabilisation) is not followed a second time from there.

    Parameters
    ----------
    model : PipeModel
    values : sequence of float
        Requested flow velocities (the diagram's range is their min to max).
    alphas : sequence of float, optional
        Inclinations; default ``[model.params.alpha]``.
    store_dir : path, optional
        Resumable store: ``run.json`` (the run's manifest; a store of another
        run is refused with ValueError), the static part and every branch's
        state after each accepted point.  A rerun resumes where it stopped.
    executor, workers
        Run the alphas in parallel (as :func:`fempipe.analyses.bifurcation.bifurcation_diagram`).
    progress : callable, optional
        Called (in this process) whenever a point is finished.
    **options
        Passed to :func:`continue_cycles` (``rtol``, ``tol``, ``ds``, ``ds_max`` ...).

    Returns
    -------
    CycleDiagram
        Failed branches are listed in ``errors`` with their finished points kept.
    """
    import tempfile

    refuse_hysteretic(model.params, "cycle_diagram")
    t0 = time.perf_counter()
    values = sorted(float(v) for v in values)
    if len(values) < 2 or values[0] == values[-1]:
        raise ValueError("values must span a range of v (at least two different values)")
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    alphas = [model.params.alpha] if alphas is None else [float(a) for a in alphas]
    manifest = _manifest(model, values, alphas, options)
    tmp = None
    if store_dir is None:
        tmp = tempfile.TemporaryDirectory(prefix="fempipe-cycles-")
        store_dir = tmp.name
    try:
        from .bifurcation import PointStore

        PointStore(store_dir, manifest)  # refuses a store of another run
        in_process = executor is None and (workers is None or int(workers) == 1 or len(alphas) == 1)
        tasks = [
            (
                model.with_params(replace(model.params, alpha=a)),
                values,
                ia,
                str(store_dir),
                manifest,
                dict(options),
                progress if in_process else None,
            )
            for ia, a in enumerate(alphas)
        ]
        results = run_tasks(
            _alpha_task, tasks, workers=None if in_process else workers, executor=executor
        )
    finally:
        if tmp is not None:
            tmp.cleanup()
    for r in results:
        if isinstance(r, BaseException):
            raise r
    return CycleDiagram(
        points=[p for r in results for p in r["points"]],
        branches=[b for r in results for b in r["branches"]],
        special_points=[s for r in results for s in r["special_points"]],
        hopf_points=[h for r in results for h in r["hopf_points"]],
        errors=[e for r in results for e in r["errors"]],
        wall_time=time.perf_counter() - t0,
        manifest=manifest,
    )

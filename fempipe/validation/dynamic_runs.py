"""Shared computations of the nonlinear-oscillation cases (Figs. 7-12).

Each discretisation (the converged FE mesh and the paper's N = 3, N = 4)
gets the same treatment: sweeps in v with :func:`fempipe.bifurcation.sweep`
(each point starts from the previous attractor), limit cycles with
:func:`fempipe.limit_cycle.find_attractor` and one period of the cycle
resampled with :func:`fempipe.dynamics.simulate` for time traces, phase
portraits and oscillating shapes.

The linear onset used to check the sweeps is located here independently of
:mod:`fempipe.stability`: bisection on the sign of the largest real part of
the linearised spectrum (:func:`fempipe.limit_cycle.static_growth_rate`) along
the static branch.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np

from ..discretization import Modal, parse_discretization
from ..kinematics import shape
from ..operators import PipeModel
from ..params import Params
from .static_shapes import PAPER_MODES

__all__ = [
    "DYN_FE",
    "DYN_FE_QUICK",
    "PAPER_PARAMS",
    "Orbit",
    "attractor",
    "dyn_discretizations",
    "linear_onset",
    "orbit",
    "sweep_up",
]

#: FE mesh for the dynamics: the limit-cycle amplitude at alpha = 0, v = 10 of
#: P3:8 agrees with P3:16 to ~1e-6 (convergence case); quick runs use P3:4 (~2e-4).
DYN_FE = "P3:8"
DYN_FE_QUICK = "P3:4"
#: The paper's Section 5 parameters (Paidoussis & Semler's silicone-rubber pipe).
PAPER_PARAMS = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3}


def dyn_discretizations(quick: bool) -> dict:
    """``{"FE P3:8": ..., "N = 3": Modal(3), "N = 4": Modal(4)}``."""
    fe = DYN_FE_QUICK if quick else DYN_FE
    out = {f"FE {fe}": parse_discretization(fe=fe)}
    for n in PAPER_MODES:
        out[f"N = {n}"] = Modal(n)
    return out


def model_for(disc, alpha: float, v: float) -> PipeModel:
    return PipeModel(disc, Params(alpha=alpha, v=v, **PAPER_PARAMS))


def sweep_up(disc, alpha: float, values, perturbation: float = 0.01) -> list:
    """Bifurcation points for increasing v (the paper's diagrams are swept up)."""
    from ..bifurcation import sweep

    m = model_for(disc, alpha, float(min(values)))
    return sweep(m, sorted(float(v) for v in values), "up", perturbation=perturbation)


@functools.lru_cache(maxsize=64)
def _attractor_cached(spec: str, alpha: float, v: float):
    from ..limit_cycle import find_attractor

    disc = _disc_from_spec(spec)
    return find_attractor(model_for(disc, alpha, v))


def _disc_from_spec(spec: str):
    if spec.startswith("N = "):
        return Modal(int(spec[4:]))
    return parse_discretization(fe=spec.removeprefix("FE "))


def attractor(label: str, alpha: float, v: float):
    """The attractor reached from the static state + 0.01 rad in mode 1 (cached per process)."""
    return _attractor_cached(label, float(alpha), float(v))


@dataclass(frozen=True)
class Orbit:
    """One period of a limit cycle, resampled.

    ``t`` (m,), ``tip`` dict of (m,) arrays (eta_tip, X_tip, Z_tip),
    ``tip_rate`` dict of (m,) arrays (their tau-derivatives), ``shapes`` a
    list of (Z_g, X_g) centrelines at ``n_shapes`` phases.
    """

    label: str
    alpha: float
    v: float
    period: float
    t: np.ndarray
    tip: dict
    tip_rate: dict
    shapes: list


def orbit(
    label: str,
    disc,
    alpha: float,
    v: float,
    q,
    qdot,
    period: float | None,
    periods: float = 1.0,
    n_out: int = 400,
    n_shapes: int = 12,
) -> Orbit:
    """Resample ``periods`` periods from a state on the attractor (or the static shape)."""
    from ..dynamics import simulate
    from ..kinematics import tip_velocity
    from ..limit_cycle import tip_coordinates

    m = model_for(disc, alpha, v)
    if period is None:  # an equilibrium: a single shape
        s = shape(disc, q, alpha)
        tip = {k: np.array([val]) for k, val in tip_coordinates(disc, alpha, q).items()}
        return Orbit(
            label,
            alpha,
            v,
            float("nan"),
            np.zeros(1),
            tip,
            {k: np.zeros(1) for k in tip},
            [(s.Z_g, s.X_g)],
        )
    traj = simulate(m, q, qdot, periods * period, n_out=n_out, rtol=1e-8)
    tip = tip_coordinates(disc, alpha, traj.q)
    rates = [tip_velocity(disc, qq, pp, alpha) for qq, pp in zip(traj.q, traj.qdot, strict=True)]
    tip_rate = {k: np.array([r[k] for r in rates]) for k in ("eta_tip", "X_tip", "Z_tip")}
    idx = np.linspace(0, np.searchsorted(traj.t, traj.t[0] + period) - 1, n_shapes).astype(int)
    shapes = []
    for i in idx:
        s = shape(disc, traj.q[i], alpha)
        shapes.append((s.Z_g, s.X_g))
    return Orbit(label, alpha, v, period, traj.t - traj.t[0], tip, tip_rate, shapes)


def linear_onset(disc, alpha: float, v_lo: float, v_hi: float, tol: float = 1e-4) -> float:
    """First v in [v_lo, v_hi] where the static state loses linear stability.

    Follows the sagged static branch (continuation in gamma, then v) and
    bisects the sign of the largest real part of the spectrum.  Returns NaN
    if the state is unstable at ``v_lo`` or stable at ``v_hi``.
    """
    from ..limit_cycle import static_growth_rate
    from .static_shapes import static_shapes

    def growth(v: float) -> float:
        st = static_shapes(
            disc,
            alpha,
            PAPER_PARAMS["gamma"],
            [v],
            beta=PAPER_PARAMS["beta"],
            mu=PAPER_PARAMS["mu"],
            n_points=3,
        )
        return static_growth_rate(model_for(disc, alpha, v), st.q[0])

    g_lo, g_hi = growth(v_lo), growth(v_hi)
    if not (g_lo < 0 < g_hi):
        return float("nan")
    while v_hi - v_lo > tol:
        mid = 0.5 * (v_lo + v_hi)
        if growth(mid) < 0:
            v_lo = mid
        else:
            v_hi = mid
    return 0.5 * (v_lo + v_hi)

"""Computations of the 3-D cases on the paper's case: the out-of-plane Hopf point and the
cycles born there (for ``space_onset`` and ``space_convergence``).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.limit_cycle import LimitCycle, find_attractor, shoot
from fempipe.analyses.stability import PLANES, find_critical_velocity
from fempipe.analyses.stability.hopf import HopfNormalForm
from fempipe.analyses.statics import solve_sagged
from fempipe.analyses.three_d.onset import hopf_normal_form_3d
from fempipe.model.discretization import FiniteElement
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.projection import project
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D

#: Default integration and Newton tolerances of the shot cycles: the tip extrema and
#: periods to ~1e-9, far below the differences the cases measure (>= 1e-8).
RTOL, TOL = 1e-9, 1e-8


@dataclass(frozen=True)
class Onset:
    """The out-of-plane Hopf point on one mesh."""

    elements: int
    planar: PipeModel
    normal_form: HopfNormalForm


def planar_model(elements: int, alpha: float, v: float = 0.0) -> PipeModel:
    """The paper's pipe on P3 with ``elements`` elements at (alpha, v)."""
    return PipeModel(FiniteElement(elements, 3), Params(alpha=alpha, v=v, **PAPER_CASE))


def onset(elements: int, alpha: float, v_max: float = 7.0) -> Onset:
    """The normal form of the first out-of-plane Hopf point on P3:``elements``, started from the
    out-of-plane v_cr and the sagged state there.
    """
    pm = planar_model(elements, alpha)
    vo = find_critical_velocity(pm, v_max=v_max, planes=PLANES).out_of_plane.v_cr
    if vo is None:
        raise ValueError(f"no out-of-plane loss of stability below v = {v_max} at alpha = {alpha}")
    q = solve_sagged(pm.with_params(replace(pm.params, v=vo))).q
    return Onset(elements, pm, hopf_normal_form_3d(pm, q, vo, v_out_of_plane=vo))


def amplitude(cycle: LimitCycle, key: str = "Y_tip") -> float:
    """(max - min) / 2 of a tip coordinate over the cycle."""
    lo, hi = cycle.tip[key]
    return 0.5 * (hi - lo)


def space_cycle_near_onset(on: Onset, delta: float) -> LimitCycle:
    """The non-planar cycle at v_cr + delta, shot from the normal form's prediction."""
    nf = on.normal_form
    v = nf.v + delta
    model = PipeModel3D(on.planar.disc, replace(on.planar.params, v=v))
    U0, Ud0, T = nf.initial_state(v)
    return shoot(PipeDynamics3D(model), U0, Ud0, T, rtol=RTOL, tol=TOL)


def _project3(src, U: np.ndarray, dst) -> np.ndarray:
    """The three fields (theta, a, b) of a 3-D state projected field by field."""
    return project(src, U.reshape(3, src.n).T, dst).T.ravel()


def space_cycles(
    elements: list[int], alpha: float, v: float, rtol: float = RTOL
) -> dict[int, LimitCycle]:
    """The non-planar cycle at (alpha, v) on each P3 mesh, coarse to fine: the first from the
    normal form, each next from the previous one projected (Newton to 10 ``rtol``).
    """
    out: dict[int, LimitCycle] = {}
    prev = None
    for ne in elements:
        if prev is None:
            on = onset(ne, alpha)
            U0, Ud0, T = on.normal_form.initial_state(v)
            pm = on.planar
        else:
            pm = planar_model(ne, alpha)
            (src, c) = prev
            U0 = _project3(src, c.q0, pm.disc)
            Ud0 = _project3(src, c.qdot0, pm.disc)
            T = c.period
        model = PipeModel3D(pm.disc, replace(pm.params, v=v))
        cyc = shoot(PipeDynamics3D(model), U0, Ud0, T, rtol=rtol, tol=10.0 * rtol)
        out[ne] = cyc
        prev = (pm.disc, cyc)
    return out


def planar_cycles(
    elements: list[int], alpha: float, v: float, rtol: float = RTOL
) -> dict[int, LimitCycle]:
    """The planar cycle at (alpha, v) on each P3 mesh, as :func:`space_cycles` (first by integration)."""
    out: dict[int, LimitCycle] = {}
    prev = None
    for ne in elements:
        m = planar_model(ne, alpha, v)
        if prev is None:
            att = find_attractor(m)
            if att.kind != "periodic":
                raise ValueError(f"the planar attractor at v = {v} is {att.kind}, not periodic")
            c = att.cycle
            q0, p0, T = c.q0, c.qdot0, c.period
        else:
            src, c = prev
            q0, p0, T = project(src, c.q0, m.disc), project(src, c.qdot0, m.disc), c.period
        cyc = shoot(PipeDynamics(m), q0, p0, T, rtol=rtol, tol=10.0 * rtol)
        out[ne] = cyc
        prev = (m.disc, cyc)
    return out


def fit_slope(deltas: np.ndarray, ratios: np.ndarray, degree: int = 2) -> tuple[float, float]:
    """(r0, k): the fit ratios = r0 (1 + k delta + ...) of degree ``degree`` in delta."""
    coef = np.polyfit(np.asarray(deltas), np.asarray(ratios), degree)
    r0 = float(coef[-1])
    return r0, float(coef[-2] / r0)

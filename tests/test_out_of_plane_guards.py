"""The out-of-plane multipliers of a moving planar state against Liouville's identity.

For the linear equation M psi_ddot + C(tau) psi_dot + K(tau) psi = 0 about any planar
motion (:class:`fempipe.model.out_of_plane.motion.OutOfPlaneMotion`), the first-order
form has the trace -tr(M^-1 C(tau)), so the monodromy over [0, T] has the determinant

    prod rho_k = exp(-\\int_0^T tr(M^-1 C(tau)) dtau)      (Liouville).

The left side comes from the integrator's sensitivity of the variational problem
(:func:`fempipe.analyses.three_d.floquet.compute_out_of_plane_floquet`); the right side is a
quadrature of the damping matrices along the same planar motion, integrated again here.
Liouville's identity holds for every motion, not only a cycle, so a short transient of
large amplitude serves.  The sine modes keep every multiplier well above the round-off
of the monodromy (finite elements have modes whose multipliers underflow).
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from fempipe.analyses.three_d.floquet import compute_out_of_plane_floquet
from fempipe.model.discretization import Modal
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.out_of_plane.motion import OutOfPlaneMotion
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.radau import Radau
from fempipe.solvers.radau.tableau import A

RTOL = 1e-9


def _damping_integral(model: PipeModel, q0, qdot0, T: float) -> float:
    """\\int_0^T tr(M^-1 C) along the planar motion from (q0, qdot0), by the Radau weights on
    every step's stages (order 5, like the integrator)."""
    motion = OutOfPlaneMotion(model)
    stepper = Radau(PipeDynamics(model), q0, qdot0, rtol=RTOL)
    total = 0.0
    for _ in stepper.steps(T):
        rec = stepper.last
        traces = []
        for q, p, a in zip(rec.Q, rec.P, rec.A, strict=True):
            _, C, M = motion.matrices(q, p, a)
            traces.append(np.trace(np.linalg.solve(M, C)))
        total += rec.h * float(np.dot(A[-1], traces))
    return total


@pytest.mark.parametrize(
    "disc, params",
    [
        (Modal(3), Params(alpha=math.pi / 2, v=10.0, mu=0.005, beta=0.142, gamma=18.9)),
        (Modal(3), Params(alpha=0.7, v=6.0, mu=0.003, end_mass=0.2, external_damping=0.3)),
    ],
)
def test_liouville_identity_of_the_out_of_plane_monodromy(disc, params):
    """log prod |rho_k| = -\\int tr(M^-1 C) over tau in [0, 0.25] from a bent, moving state
    (the paper's pipe at alpha = pi/2, v = 10; a pipe with an end mass and external
    damping).  Measured: the two sides agree to 7e-13 and 1.1e-11 relative at rtol 1e-9
    (6e-14 on the paper's pipe's own cycle at rtol 1e-10); the limit 1e-8 is the
    integration tolerance's size, with room for another machine's round-off.
    """
    model = PipeModel(disc, params)
    rng = np.random.default_rng(7)
    q0 = rng.normal(scale=0.3, size=model.n)
    qdot0 = rng.normal(scale=1.0, size=model.n)
    T = 0.25
    motion = SimpleNamespace(q0=q0, qdot0=qdot0, period=T)
    rho = compute_out_of_plane_floquet(model, motion, rtol=RTOL).multipliers
    assert rho.size == 2 * model.n
    assert np.abs(rho).min() > 1e-8  # every multiplier resolved
    lhs = float(np.sum(np.log(np.abs(rho))))
    rhs = -_damping_integral(model, q0, qdot0, T)
    assert abs(rhs) > 0.5  # the damping acts
    assert lhs == pytest.approx(rhs, rel=1e-8), (lhs, rhs)


def test_small_cycle_multipliers_tend_to_the_strong_form_spectrum():
    """Near its Hopf point the planar cycle shrinks to the static state, and its out-of-plane
    multipliers tend to exp(lambda T), lambda the out-of-plane roots about the static state
    from the strong-form solver (:mod:`fempipe.validation.lateral`: C^1 spectral elements on
    solve_bvp's static state, no code shared with the FE model), T the cycle's period.

    The paper's pipe at alpha = pi/2 on P3:6, cycles shot at v_cr + delta from the Hopf
    normal form (supercritical), delta = 0.01 and 0.005: the deviation rho - exp(lambda T)
    is linear in delta (the cycle's amplitude squared), so its Richardson limit
    2 d(delta / 2) - d(delta) is the part that does not vanish with the cycle.  Measured:
    1.5e-4 against 2.6e-2 (0.6 %) for the leading pair (|rho| = 1.9: the static state is
    unstable out of the plane above v = 5.82), 7.3e-7 against 5.1e-5 (1.4 %) for the next;
    the limit is 5 % of the smaller deviation, and 1e-3 |rho|."""
    from dataclasses import replace

    from fempipe.analyses.limit_cycle import shoot
    from fempipe.analyses.stability import find_critical_velocity
    from fempipe.analyses.stability.hopf.normal_form import first_lyapunov_coefficient
    from fempipe.analyses.statics import solve_sagged
    from fempipe.model.discretization import FiniteElement
    from fempipe.validation import lateral

    base = Params(alpha=math.pi / 2, beta=0.142, gamma=18.9, mu=0.005)
    planar = PipeModel(FiniteElement(6, 3), base)
    onset = find_critical_velocity(planar, v_max=8.0)
    at_onset = planar.with_params(replace(base, v=onset.v_cr))
    nf = first_lyapunov_coefficient(
        at_onset, solve_sagged(at_onset).q, omega=onset.events[0].frequency
    )
    assert nf.side == "above"
    strong = lateral.LateralProblem(base, lateral.HermiteSpectral(24))
    dev = {}
    for delta in (0.01, 0.005):
        v = onset.v_cr + delta
        model = planar.with_params(replace(base, v=v))
        cycle = shoot(PipeDynamics(model), *nf.initial_state(v), rtol=1e-10, tol=1e-9)
        rho = compute_out_of_plane_floquet(model, cycle, rtol=1e-10).multipliers[:4]
        ref = np.exp(strong.eigenvalues(v) * cycle.period)
        dev[delta] = np.array([r - ref[np.argmin(np.abs(ref - r))] for r in rho])
    limit = 2.0 * dev[0.005] - dev[0.01]
    assert np.all(np.abs(limit) < 0.05 * np.abs(dev[0.005])), (limit, dev)
    assert np.all(np.abs(limit) < 1e-3 * np.abs(rho)), (limit, rho)

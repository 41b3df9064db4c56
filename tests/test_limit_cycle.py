"""Limit cycles: onset at the linear v_cr, shooting vs long integration, Floquet multipliers."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.limit_cycle import ShootingError, find_attractor, recurrence, shoot
from fempipe.analyses.stability import compute_spectrum, growth_rate, linearly_stable
from fempipe.analyses.statics import solve_static
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.kinematics import compute_tip

# P3 on 4 elements: v_cr within 1e-4 of the converged value (the stability
# tests) and cheap enough for the default run.
DISC = FiniteElement(4, 3)


def _v_cr(alpha: float = 0.0) -> float:
    """Linear critical velocity from the quadratic eigenproblem (fempipe.analyses.stability)."""
    from fempipe.analyses.stability import find_critical_velocity

    return find_critical_velocity(PipeModel(DISC, Params(alpha=alpha)), v_max=8.0).v_cr


@pytest.fixture(scope="module")
def onset():
    v_cr = _v_cr()
    cycles = {}
    for d in (0.05, 0.1):
        m = PipeModel(DISC, Params(alpha=0.0, v=v_cr + d))
        cycles[d] = (m, find_attractor(m))
    return v_cr, cycles


def test_onset_amplitude_vanishes_at_linear_v_cr(onset):
    """Supercritical Hopf: A^2 is linear in v - v0; v0 must equal the linear v_cr.

    Two cycles at v_cr + 0.05 and v_cr + 0.1 (alpha = 0), A = max eta(1); the
    straight-line extrapolation of A^2 to zero gives v0.  Measured
    |v0 - v_cr| = 1.8e-3 (the cubic normal form's O(dv^2) correction); we
    allow 0.01.
    """
    v_cr, cycles = onset
    (v1, a1), (v2, a2) = [(m.params.v, att.tip["eta_tip"][1]) for m, att in cycles.values()]
    for _, att in cycles.values():
        assert att.kind == "periodic" and att.period_n == 1
    v0 = v1 - a1**2 * (v2 - v1) / (a2**2 - a1**2)
    assert abs(v0 - v_cr) < 0.01, (v0, v_cr)


def test_floquet_multiplier_near_onset_matches_linear_growth(onset):
    """Normal form r' = sigma r - c r^3: the cycle's radial multiplier is exp(-2 sigma T).

    sigma is the growth rate of the static state (linear eigenvalues), an
    independent computation.  The relation holds to O(v - v_cr): measured
    ln(mu_2) / (-2 sigma T) = 0.99 at v_cr + 0.05; we allow 15 %.
    """
    _, cycles = onset
    m, att = cycles[0.05]
    sigma = growth_rate(m, solve_static(m).q)
    assert sigma > 0
    mu2 = att.cycle.max_nontrivial_multiplier
    ratio = math.log(mu2) / (-2 * sigma * att.period)
    assert abs(ratio - 1) < 0.15, ratio
    # The trivial multiplier (phase along the orbit) is 1 to the integration accuracy.
    mu = att.cycle.floquet_multipliers
    assert np.min(np.abs(mu - 1)) < 1e-5


def test_equilibrium_below_v_cr():
    v = _v_cr() - 0.3
    m = PipeModel(DISC, Params(alpha=0.0, v=v))
    att = find_attractor(m)
    assert att.kind == "equilibrium"
    q = solve_static(m).q
    tip = compute_tip(DISC, q, 0.0)
    assert att.tip["X_tip"] == [pytest.approx(tip["X_tip"])] * 2


def test_equilibrium_decision_is_the_stability_criterion():
    """v = mu = 0, alpha = 0: a conservative system whose hanging straight pipe is
    the minimum of the potential energy (positive definite static Jacobian,
    checked here), hence stable (Lagrange-Dirichlet), as the resolved-mode
    criterion of stability.compute_spectrum and critical says.  Round-off gives the
    unfiltered spectrum of M^-1 K Re lambda = +2e-15 (measured), which once
    made the attractor finder refuse the equilibrium, integrate to t_max and
    report "non-periodic".  It must decide as stability does."""
    m = PipeModel(Modal(2), Params(alpha=0.0, mu=0.0, v=0.0))
    q = solve_static(m).q
    K = np.asarray(m.static_jacobian(q))
    assert np.linalg.eigvalsh(0.5 * (K + K.T)).min() > 0
    assert compute_spectrum(m, q).stable and linearly_stable(m, q)
    att = find_attractor(m, t_max=5.0)
    assert att.kind == "equilibrium"


def test_solver_failures_share_one_base_and_survive_pickling():
    """One SolverError base; a failure raised in a worker process reaches the
    parent with its message and attributes (pickle round trip)."""
    import pickle

    from fempipe.analyses.dynamics import IntegrationError
    from fempipe.analyses.statics import NewtonError
    from fempipe.core.errors import SolverError

    errors = [
        NewtonError("newton", Params(v=2.0), 3, 1e-3),
        IntegrationError("integration", 1.5, 1e-9),
        ShootingError("shooting", 4, 2e-2),
    ]
    for exc in errors:
        assert isinstance(exc, SolverError) and isinstance(exc, RuntimeError)
        back = pickle.loads(pickle.dumps(exc))
        assert type(back) is type(exc) and str(back) == str(exc)
        assert vars(back) == vars(exc)


def test_shooting_equals_long_integration():
    """alpha = pi/4, v = 8 (asymmetric cycle): shooting (rtol 1e-7) vs integration
    until successive Poincare returns agree to 1e-7 (rtol 1e-8).  Measured
    differences 4e-10 in T and 3e-9 in the tip extrema; bound 1e-6."""
    m = PipeModel(DISC, Params(alpha=math.pi / 4, v=8.0))
    a = find_attractor(m)
    b = find_attractor(m, use_shooting=False, rtol=1e-8, converged_tol=1e-7)
    assert a.kind == b.kind == "periodic"
    assert a.cycle is not None and b.cycle is None
    assert a.period == pytest.approx(b.period, abs=1e-6)
    for k in ("eta_tip", "X_tip", "Z_tip"):
        np.testing.assert_allclose(a.tip[k], b.tip[k], atol=1e-6)
    # and the cycle is a cycle: integrate one period from its start
    from fempipe.analyses.dynamics import PipeDynamics, Radau

    st = Radau(PipeDynamics(m), a.cycle.q0, a.cycle.qdot0, rtol=1e-9)
    for _ in st.steps(a.period):
        pass
    assert np.sqrt(np.mean((st.q - a.cycle.q0) ** 2)) < 1e-6


def test_shoot_converges_quadratically_from_a_rough_guess():
    """Newton with the exact discrete monodromy matrix: 3-5 iterations from a 1e-2 guess."""
    m = PipeModel(DISC, Params(alpha=0.0, v=8.0))
    ref = find_attractor(m)
    c = ref.cycle
    guess_q = c.q0 * 1.02
    cyc = shoot(PipeDynamics(m), guess_q, c.qdot0 * 0.98, c.period * 1.01, level=c.level)
    assert cyc.iterations <= 5
    assert cyc.period == pytest.approx(c.period, abs=1e-7)
    assert cyc.stable


def test_alpha_zero_cycle_is_symmetric():
    """At alpha = 0 Eq. (20) is odd in theta: eta(1) swings symmetrically, Z_g = eta."""
    m = PipeModel(DISC, Params(alpha=0.0, v=10.0))
    att = find_attractor(m)
    lo, hi = att.tip["eta_tip"]
    assert lo == pytest.approx(-hi, abs=1e-6)
    np.testing.assert_allclose(att.tip["Z_tip"], att.tip["eta_tip"], atol=1e-12)
    assert att.period_n == 1


@pytest.mark.parametrize(
    "returns, expected",
    [
        ([1.0, 1.0, 1.0, 1.0], 1),
        ([1.0, 2.0, 1.0, 2.0, 1.0], 2),
        ([1.0, 2.0, 3.0, 1.0, 2.0, 3.0, 1.0], 3),
    ],
)
def test_recurrence_tells_period_n(returns, expected):
    x = [(np.array([r, 0.0]), np.zeros(2)) for r in returns]
    t = list(range(len(returns)))
    n, d = recurrence(t, x, n_max=4)
    assert n == expected and d == 0.0


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.0, math.pi / 4, math.pi / 2])
def test_limit_cycle_mesh_converged(alpha):
    """v = 10: P3:16 and P3:32 agree to 1e-6 in T and the tip extrema (measured
    3e-8 and 1.7e-7; successive differences fall 64x per refinement, h^6)."""
    res = []
    for ne in (16, 32):
        m = PipeModel(FiniteElement(ne, 3), Params(alpha=alpha, v=10.0))
        res.append(find_attractor(m, shoot_rtol=1e-8, shoot_tol=1e-7))
    a, b = res
    assert a.period == pytest.approx(b.period, abs=1e-6)
    for k in ("eta_tip", "X_tip", "Z_tip"):
        np.testing.assert_allclose(a.tip[k], b.tip[k], atol=1e-6)


def _first_return(m, q0, p0, level: float, t_end: float):
    """Independent check of a cycle: integrate from (q0, p0) at rtol 1e-9 to the
    first upward crossing of eta_tip through ``level`` after a twentieth of
    ``t_end``; return its time, the state there and the tip extrema on the way
    (16 samples per step on the integrator's dense output)."""
    from scipy.optimize import brentq

    from fempipe.analyses.dynamics import PipeDynamics, Radau
    from fempipe.analyses.limit_cycle.tips import TipTrace, eta_tip, tip_extrema

    st = Radau(PipeDynamics(m), q0, p0, rtol=1e-9)
    trace = TipTrace(m, per_step=16)
    s_old = eta_tip(m.disc, st.q) - level
    for t, q, _ in st.steps(t_end):
        trace.record(st)
        s_new = eta_tip(m.disc, q) - level
        if t > t_end / 20 and s_old < 0 <= s_new:

            def f(tt):
                return eta_tip(m.disc, st.dense(tt)[0]) - level

            t_c = brentq(f, st.t_old, st.t, xtol=1e-14)
            return (
                t_c,
                st.dense(t_c),
                tip_extrema(m, trace, per_step=16, fine=0),
            )
        s_old = s_new
    return None, (None, None), None


def test_cycle_from_the_short_transient_is_the_cycle():
    """alpha = pi/4, v = 8 (an asymmetric cycle).  The transient is integrated
    until the Poincare returns agree to 1e-3 and Newton needs one step, the
    check and the polish (the fast start); shooting from the first recurrence at 2e-2 (the old
    start, start_tol = recurrence_tol) gives the same cycle to the shooting
    tolerance, with the same Floquet multipliers.  Independently, a tight
    integration (rtol 1e-9) from the reported state comes back to the section
    for the first time after the reported period (not half or twice it), to
    the same state, through the same tip extrema (the cycle's are taken on the
    quintic interpolant of its rtol 1e-5 steps): a wrong multiple of the
    period, an unconverged orbit or wrong extrema fail here."""
    m = PipeModel(DISC, Params(alpha=math.pi / 4, v=8.0))
    fast = find_attractor(m)
    old = find_attractor(m, start_tol=2e-2)
    assert fast.kind == old.kind == "periodic" and fast.period_n == old.period_n == 1
    assert fast.t_end > old.t_end  # the fast start did integrate on
    # one Newton step, the check and perhaps the polish
    assert fast.cycle.iterations <= 3
    assert fast.period == pytest.approx(old.period, rel=1e-6)
    for k in ("eta_tip", "X_tip", "Z_tip"):
        np.testing.assert_allclose(fast.tip[k], old.tip[k], rtol=1e-6, atol=1e-7)
    np.testing.assert_allclose(
        np.abs(fast.cycle.floquet_multipliers[:4]),
        np.abs(old.cycle.floquet_multipliers[:4]),
        atol=1e-5,
    )
    c = fast.cycle
    t_ret, (q_ret, p_ret), tip = _first_return(m, c.q0, c.qdot0, c.level, 1.2 * c.period)
    assert t_ret == pytest.approx(c.period, rel=1e-6)
    scale = c.period / (2 * math.pi)
    assert np.sqrt(np.mean((q_ret - c.q0) ** 2) + np.mean(((p_ret - c.qdot0) * scale) ** 2)) < 1e-6
    for k in ("eta_tip", "X_tip", "Z_tip"):
        np.testing.assert_allclose(c.tip[k], tip[k], atol=1e-6)


def test_quintic_orbit_reproduces_quintics():
    """The interpolant through (q, q', q'') at the step ends is exact for
    polynomials of degree 5 (the basis of the tip extrema on the cycle)."""
    from fempipe.analyses.limit_cycle.tips import QuinticOrbit

    rng = np.random.default_rng(5)
    t = np.cumsum(np.r_[0.0, rng.uniform(0.05, 0.2, 7)])
    c = rng.standard_normal((6, 2))  # two components, degree 5

    def poly(x, d=0):
        P = np.polynomial.polynomial
        return np.stack([P.polyval(x, P.polyder(c[:, j], d)) for j in range(2)], axis=-1)

    orbit = QuinticOrbit(t, poly(t), poly(t, 1), poly(t, 2))
    x = np.linspace(t[0], t[-1], 101)
    np.testing.assert_allclose(orbit(x), poly(x), atol=1e-12)


def test_polish_lands_on_the_cycle():
    """Accepted at a loose tolerance (2e-4), the iterate is ~5e-5 off the cycle;
    the polishing Newton step (same monodromy, one plain period) brings the
    residual down quadratically and the alpha = 0 cycle's eta_tip extrema back
    to symmetric (a property of Eq. (20), not imposed), with the period of the
    cycle found at the default tolerance.  The multipliers are the converged
    iterate's in both."""
    m = PipeModel(DISC, Params(alpha=0.0, v=10.0))
    c = find_attractor(m).cycle
    args = (PipeDynamics(m), c.q0 * 1.01, c.qdot0 * 0.99, c.period * 1.002)
    rough = shoot(*args, level=c.level, tol=2e-4, polish=False)
    fine = shoot(*args, level=c.level, tol=2e-4)
    assert rough.residual > 1e-5 and fine.residual < 1e-3 * rough.residual
    assert fine.iterations == rough.iterations + 1
    assert abs(fine.period - c.period) < 1e-7 < abs(rough.period - c.period)
    lo, hi = fine.tip["eta_tip"]
    assert abs(hi + lo) < 1e-7 < abs(sum(rough.tip["eta_tip"]))
    # Each run's eigenvalues of the converged iterate's monodromy: equal to round-off
    # (|mu| <= 1), not bit for bit; the multipliers of the converged cycle, ~5e-5 away
    # from that iterate, differ from them by 3e-5.
    np.testing.assert_allclose(
        fine.floquet_multipliers, rough.floquet_multipliers, rtol=0, atol=1e-12
    )


def test_shooting_near_an_equilibrium_does_not_warn():
    """A sweep's attractor search that ends on an equilibrium (alpha = pi, v = 1,
    P3:8, the buckled pipe: the shooting's bordered matrix reaches rcond 2e-17
    on the way) returns the equilibrium and lets no scipy LinAlgWarning reach
    the user's terminal (it did, from ``fempipe validate``, before the
    shooting's Newton step silenced it)."""
    import warnings

    import scipy.linalg as sla

    from fempipe.validation.dynamic_runs import parse_discretization, sweep_up

    with warnings.catch_warnings():
        warnings.simplefilter("error", sla.LinAlgWarning)
        (point,) = sweep_up(parse_discretization(fe="P3:8"), np.pi, [1.0])
    assert point.attractor == "equilibrium"
    assert point.eta_tip[0] == point.eta_tip[1] and abs(point.eta_tip[0]) > 0.5

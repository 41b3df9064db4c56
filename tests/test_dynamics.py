"""Time integration of Eq. (20): energy, power balance, order, mesh independence of the steps."""

from __future__ import annotations

import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.dynamics import (
    IntegrationError,
    PulsatingFlow,
    Radau,
    acceleration,
    energy_rate,
    make_initial_state,
    power_terms,
    simulate,
    simulate_steps,
)
from fempipe.model.dynamics_problem import PipeDynamics

GL_X, GL_W = np.polynomial.legendre.leggauss(4)


# ---------------------------------------------------------------- identity --
@pytest.mark.parametrize(
    "disc", [FiniteElement(4, 2), Modal(3, n_cells=8)], ids=["P2:4", "modal:3"]
)
@pytest.mark.parametrize("v_dot", [0.0, 1.7])
def test_energy_rate_identity_at_random_states(disc, v_dot):
    """dE/dtau from the residual (q'' = -M^-1 R) equals the power formula.

    dE/dtau = grad_q E . q' + grad_q' E . q'', by Richardson-extrapolated central
    differences of model.energy along (q', q'') (error O(eps^4), eps |q''| = 1e-3,
    so ~1e-11 relative).  Each term's sign enters: flipping any of them changes
    dE/dtau by O(1).
    """
    rng = np.random.default_rng(7)
    m = PipeModel(disc, Params(alpha=0.7, v=3.0, mu=0.02, beta=0.3, gamma=5.0))
    # Smooth random states (combinations of the first three sine modes): for
    # a random FE vector q'' ~ 1e6 and no difference quotient is accurate.
    modes = np.array([make_initial_state(m, r, 1.0, q_static=np.zeros(m.n))[0] for r in (1, 2, 3)])
    for _ in range(3):
        q = 0.5 * rng.normal(size=3) @ modes
        qd = 2.0 * rng.normal(size=3) @ modes
        a = acceleration(m, q, qd, v_dot)

        def central(eps, q=q, qd=qd, a=a):
            return (m.energy(q + eps * qd, qd + eps * a) - m.energy(q - eps * qd, qd - eps * a)) / (
                2 * eps
            )

        eps = 1e-3 / max(1.0, np.abs(a).max(), np.abs(qd).max())
        fd = (4 * central(eps / 2) - central(eps)) / 3
        terms = power_terms(m, q, qd, v_dot)
        scale = sum(abs(x) for k, x in terms.items() if k != "dE_dtau")
        assert abs(fd - energy_rate(m, q, qd, v_dot)) < 1e-7 * scale
        if v_dot:
            # The flow-acceleration power is resolved: 100x the tolerance above.
            assert abs(terms["flow_acceleration"]) > 1e-5 * scale


# ---------------------------------------------------- energy conservation --
def _energy_drift(rtol: float) -> float:
    # Modal: without Kelvin-Voigt damping the FE system keeps undamped
    # h^-2 modes that an error-controlled integrator must resolve.
    m = PipeModel(Modal(3, n_cells=8), Params(alpha=0.3, v=0.0, mu=0.0))
    q0, p0 = make_initial_state(m, 1, 0.8)
    q0 = q0 + make_initial_state(m, 2, 0.3, q_static=np.zeros(m.n))[0]
    E0 = m.energy(q0, p0)
    tr = simulate(m, q0, p0, 1.0, rtol=rtol)
    return max(abs(m.energy(a, b) - E0) for a, b in zip(tr.q, tr.qdot, strict=True)) / E0


def test_energy_conserved_without_flow_and_damping():
    """v = 0, mu = 0 (large amplitude, 0.8 rad): drift bounded and shrinking with the tolerance.

    Radau IIA is not symplectic, so E drifts at the level of the local error:
    measured 9e-6 -> 1e-7 relative for rtol 1e-4 -> 1e-6; we ask for at least a
    factor 10 per factor 100 in rtol and an absolute bound of 10 rtol.
    """
    d4, d6 = _energy_drift(1e-4), _energy_drift(1e-6)
    assert d6 < 10 * 1e-6
    assert d4 < 10 * 1e-4
    assert d6 < d4 / 10


# ----------------------------------------------------------- power balance --
def _balance(flow, rtol, terms_dropped=()):
    m = PipeModel(FiniteElement(4, 2), Params(alpha=0.5, v=4.0, mu=0.02))
    q0, p0 = make_initial_state(m, 1, 0.3)
    st = Radau(PipeDynamics(m, flow), q0, p0, rtol=rtol)
    E0 = m.energy(q0, p0)
    work = work_abs = 0.0
    for _ in st.steps(0.6):
        t0, h = st.t_old, st.t - st.t_old
        for x, w in zip(GL_X, GL_W, strict=True):
            tt = t0 + 0.5 * h * (x + 1)
            qq, pp = st.dense(tt)
            mm, vd = st.problem.model_at(tt)
            terms = power_terms(mm, qq, pp, vd)
            P = terms["dE_dtau"] + sum(terms[k] for k in terms_dropped)
            work += 0.5 * h * w * P
            work_abs += 0.5 * h * w * abs(P)
    return m.energy(st.q, st.qdot) - E0, work, work_abs


@pytest.mark.parametrize("flow", [None, PulsatingFlow(4.0, 0.5, 20.0)], ids=["steady", "pulsating"])
def test_power_balance_along_trajectory(flow):
    """E(tau1) - E(tau0) = int dE/dtau along the computed trajectory (flow, damping).

    The integral uses 4-point Gauss in each step on the collocation polynomial.
    Measured mismatch 2e-10 of int |P| at rtol 1e-7; the bound 1e-7 leaves room
    for the integrator, while dropping one term (next test) misses by > 1e-2.
    """
    dE, W, W_abs = _balance(flow, 1e-7)
    assert abs(dE - W) < 1e-7 * W_abs


@pytest.mark.parametrize("term", ["coriolis", "follower", "kelvin_voigt"])
def test_power_balance_fails_without_a_term(term):
    dE, W, W_abs = _balance(None, 1e-6, terms_dropped=(term,))
    assert abs(dE - W) > 1e-3 * W_abs


def test_pulsating_flow_needs_flow_acceleration_power():
    dE, W, W_abs = _balance(PulsatingFlow(4.0, 0.5, 20.0), 1e-6, ("flow_acceleration",))
    assert abs(dE - W) > 1e-3 * W_abs


def test_pulsating_flow_with_zero_amplitude_is_steady():
    m = PipeModel(FiniteElement(4, 2), Params(alpha=0.5, v=4.0))
    q0, p0 = make_initial_state(m, 1, 0.3)
    a = simulate(m, q0, p0, 0.3, rtol=1e-7)
    b = simulate(m, q0, p0, 0.3, rtol=1e-7, flow=PulsatingFlow(4.0, 0.0, 5.0))
    # Two adaptive runs agree to their global error, not to round-off: their step
    # sequences need not coincide bit for bit (rtol 1.01e-7 moves the end by 2.5e-12,
    # the global error at rtol 1e-7 is 1.4e-10 against rtol 1e-11); an amplitude of
    # only 1e-6 moves it by 1.8e-7.
    np.testing.assert_allclose(a.q[-1], b.q[-1], rtol=0, atol=1e-9)


# ------------------------------------------------------ convergence order --
@pytest.mark.parametrize(
    "disc", [Modal(3, n_cells=8), FiniteElement(4, 2)], ids=["modal:3", "P2:4"]
)
def test_time_convergence_order(disc):
    """Fixed steps h = T/N: the global error falls as h^5 (Radau IIA, order 2s - 1 = 5).

    Reference: the same method with N = 512.  Fitted slope over N = 12..48
    (modal) / 16..64 (FE) measured 4.7-4.9; we accept [4.4, 5.6], an order 4
    or 6 method would fail.
    """
    m = PipeModel(disc, Params(alpha=0.4, v=5.0))
    q0, p0 = make_initial_state(m, 1, 0.5)
    T = 0.3

    def final(N):
        st = Radau(PipeDynamics(m), q0, p0, h_fixed=T / N, rtol=1e-10)
        for _ in st.steps(T):
            pass
        assert st.stats.steps == N
        return np.r_[st.q, st.qdot]

    ref = final(512)
    Ns = [12, 24, 48] if isinstance(disc, Modal) else [16, 32, 64]
    errs = [np.sqrt(np.mean((final(N) - ref) ** 2)) for N in Ns]
    slope = -np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert 4.4 < slope < 5.6, (errs, slope)


# --------------------------------------------------------- mesh independence --
def test_steps_do_not_grow_with_mesh_refinement():
    """Same trajectory on P2 with 4, 8, 16 elements: step counts within +-20 %.

    The stiffest rates grow like h^-4 (mu h^-4 damping), 256x from 4 to 16
    elements; an integrator that resolved them would take ~100x more steps.
    """
    steps = []
    for ne in (4, 8, 16):
        m = PipeModel(FiniteElement(ne, 2), Params(alpha=0.0, v=8.0))
        q0, p0 = make_initial_state(m, 2, 0.05)
        tr = simulate(m, q0, p0, 0.5, rtol=1e-6)
        steps.append(tr.steps)
    assert max(steps) <= 1.2 * min(steps), steps


# ---------------------------------------------------------------- API --
def test_generator_yields_initial_state_then_steps():
    m = PipeModel(Modal(2, n_cells=4), Params(v=2.0))
    q0, p0 = make_initial_state(m, 1, 0.1)
    out = list(simulate_steps(m, q0, p0, 0.1, rtol=1e-6))
    assert out[0][0] == 0.0 and np.array_equal(out[0][1], q0)
    assert out[-1][0] == pytest.approx(0.1, abs=1e-14)
    assert all(t1 > t0 for (t0, _, _), (t1, _, _) in zip(out, out[1:], strict=False))
    q0_copy = q0.copy()
    simulate(m, q0, p0, 0.05)
    assert np.array_equal(q0, q0_copy)  # the caller's arrays are not modified


def test_simulate_uniform_output_and_stats():
    m = PipeModel(Modal(2, n_cells=4), Params(v=2.0))
    q0, p0 = make_initial_state(m, 1, 0.1)
    tr = simulate(m, q0, p0, 0.2, n_out=11)
    np.testing.assert_allclose(tr.t, np.linspace(0, 0.2, 11))
    d = tr.to_dict()
    assert d["steps"] > 0 and d["rejected_steps"] >= 0 and d["wall_time"] > 0


@pytest.mark.parametrize(
    "kwargs, word",
    [
        ({"rtol": 0.0}, "rtol"),
        ({"rtol": 2.0}, "rtol"),
        ({"atol": -1.0}, "atol"),
        ({"max_step": 0.0}, "max_step"),
        ({"h_fixed": -0.1}, "h_fixed"),
    ],
)
def test_bad_options(kwargs, word):
    m = PipeModel(Modal(2, n_cells=4), Params())
    with pytest.raises(ValueError, match=word):
        Radau(PipeDynamics(m), np.zeros(2), **kwargs)


@pytest.mark.parametrize(
    "kwargs, word",
    [({"v0": -1}, "v0"), ({"v0": 1, "sigma": 1.5}, "sigma"), ({"v0": 1, "omega": -1}, "omega")],
)
def test_bad_flow(kwargs, word):
    with pytest.raises(ValueError, match=word):
        PulsatingFlow(**kwargs)


def test_fixed_step_failure_says_where():
    m = PipeModel(FiniteElement(4, 2), Params(alpha=0.4, v=5.0))
    q0, p0 = make_initial_state(m, 1, 1.5)
    st = Radau(PipeDynamics(m), q0, p0, h_fixed=0.5)
    with pytest.raises(IntegrationError, match="tau"):
        st.step()


@pytest.mark.slow
def test_steps_independent_of_mesh_p3_8_to_64():
    """The acceptance measurement: P3 with 8, 16, 32, 64 elements, tau in [0, 2],
    alpha = 0, v = 10, rtol 1e-6.  Measured 778, 709, 692, 693 steps."""
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parents[1] / "validation"))
    from dynamics_acceptance import steps

    rows = steps((8, 16, 32, 64))
    counts = [r["steps"] for r in rows if r["disc"].startswith("P3")]
    assert max(counts) <= 1.2 * min(counts), counts


# ------------------------------------------------ sensitivity to the flow --
@pytest.mark.parametrize("disc", [FiniteElement(4, 3), Modal(3, n_cells=8)], ids=str)
def test_velocity_sensitivity_of_the_flow_map(disc):
    """Radau's d phi_T(x)/dv (accumulated with the monodromy) against a central
    difference of the flow map replayed on the same steps, at v = 7 +- 1e-5."""
    params = dict(alpha=0.3, beta=0.142, gamma=18.9, mu=5e-3)
    m = PipeModel(disc, Params(v=7.0, **params))
    q0, p0 = make_initial_state(m, 1, 0.3)
    st = Radau(PipeDynamics(m), q0, p0, rtol=1e-8, sensitivity=True, velocity_sensitivity=True)
    hs = [st.last[1] for _ in st.steps(0.3)]

    def flow(v):
        s = Radau(PipeDynamics(m.with_params(Params(v=v, **params))), q0, p0, rtol=1e-8)
        t = 0.0
        for h in hs:
            s.h, s._lu = h, None
            s.step(t + h)
            t += h
        return np.r_[s.q, s.qdot]

    fd = (flow(7.0 + 1e-5) - flow(7.0 - 1e-5)) / 2e-5
    assert np.max(np.abs(st.velocity_sensitivity - fd)) < 1e-7 * np.max(np.abs(fd))
    with_flow = Radau(
        PipeDynamics(m, PulsatingFlow(7.0, 0.1, 2.0)),
        q0,
        p0,
        sensitivity=True,
        velocity_sensitivity=True,
    )
    assert with_flow.velocity_sensitivity is None  # no single v to differentiate by
    assert (
        Radau(PipeDynamics(m), q0, p0, sensitivity=True).velocity_sensitivity is None
    )  # only when asked

"""The variants of the pipe: end mass, external viscous damping, intermediate springs.

Every reference is independent of the code under test: central finite
differences of the residual and of the energy, the strong form solved by
scipy's ``solve_bvp`` (:mod:`fempipe.validation.bvp`, a multi-interval
collocation that shares no code with the weak form), the closed-form frequency
equations of the clamped-free beam with a tip mass or a tip spring, the exact
eigenvalue shift of a damping matrix sigma M, and the energy balance along
computed trajectories.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla
from clirun import run_json
from scipy.optimize import brentq

from fempipe.analyses.dynamics import Radau, acceleration, make_initial_state, power_terms, simulate
from fempipe.analyses.statics import solve_sagged, solve_static
from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.kinematics import compute_tip
from fempipe.model.params import Params, PipeSI
from fempipe.model.plane.operators import PipeModel
from fempipe.validation.bvp import solve_static_bvp

DISCS = {
    "P2:4": lambda: FiniteElement(4, 2),
    "modal:4": lambda: Modal(4),
    "modal-beam:4": lambda: Modal(4, basis="beam"),
}

BASE = Params(alpha=0.7, beta=0.3, gamma=12.0, mu=0.02, v=3.0)
#: Each variant alone, and all together.  P2:4 has nodes at 0.25, 0.5, 0.75:
#: springs at a node, inside an element and at the tip.
VARIANTS = {
    "end_mass": {"end_mass": 0.7},
    "external_damping": {"external_damping": 0.9},
    "spring_node": {"springs": ((30.0, 0.5),)},
    "spring_inside": {"springs": ((30.0, 0.37),)},
    "spring_tip": {"springs": ((15.0, 1.0),)},
    "all": {
        "end_mass": 0.7,
        "external_damping": 0.9,
        "springs": ((30.0, 0.5), (20.0, 0.37), (15.0, 1.0)),
    },
}


def random_state(n, seed, amplitude=1.5):
    rng = np.random.default_rng(seed)
    return amplitude * rng.standard_normal((3, n))


def fd_jacobian(f, x, eps=1e-6):
    return np.column_stack([(f(x + eps * e) - f(x - eps * e)) / (2 * eps) for e in np.eye(x.size)])


def dense(A):
    return A.toarray() if hasattr(A, "toarray") else np.asarray(A)


# ------------------------------------------------------------ Jacobians --
@pytest.mark.parametrize("disc_name", DISCS)
@pytest.mark.parametrize("variant", VARIANTS)
@pytest.mark.parametrize("which", ["q", "qdot", "qddot"])
def test_variant_jacobians_match_finite_differences(disc_name, variant, which):
    """The variant's own term: J(variant) - J(base) against central differences of
    R(variant) - R(base), at random states and rates (v_dot != 0)."""
    disc = DISCS[disc_name]()
    m0 = PipeModel(disc, BASE)
    m1 = m0.with_params(replace(BASE, **VARIANTS[variant]))
    q, qd, qdd = random_state(disc.n, seed=3)
    v_dot = 0.7
    idx = {"q": 0, "qdot": 1, "qddot": 2}[which]
    J = m1.jacobians(q, qd, qdd, v_dot=v_dot)[idx] - m0.jacobians(q, qd, qdd, v_dot=v_dot)[idx]

    def term(x):
        s = [q, qd, qdd]
        s[idx] = x
        return m1.residual(*s, v_dot=v_dot) - m0.residual(*s, v_dot=v_dot)

    x0 = [q, qd, qdd][idx]
    if (
        variant == "external_damping"
        and which == "qddot"
        or (variant.startswith("spring") and which != "q")
    ):
        # The term does not depend on this rate: the difference is exactly 0.
        assert np.abs(J).max() <= 1e-12 * np.abs(m1.jacobians(q, qd, qdd)[idx]).max()
        assert np.abs(fd_jacobian(term, x0)).max() < 1e-8
        return
    eps = 1e-6
    J_fd = fd_jacobian(term, x0, eps)
    scale = np.abs(J).max()
    assert scale > 1e-2  # the term is present
    tol = 1e-7 * scale + 1e-14 * np.abs(m1.residual(q, qd, qdd, v_dot)).max() / eps
    assert np.abs(J - J_fd).max() <= tol


@pytest.mark.parametrize("disc_name", DISCS)
@pytest.mark.parametrize("variant", VARIANTS)
def test_variant_static_jacobian_and_parameter_derivatives(disc_name, variant):
    disc = DISCS[disc_name]()
    p = replace(BASE, **VARIANTS[variant])
    m = PipeModel(disc, p)
    q = random_state(disc.n, seed=5)[0]
    J = dense(m.static_jacobian(q))
    assert np.abs(J - fd_jacobian(m.static_residual, q)).max() <= 1e-7 * np.abs(J).max()
    # The dynamic Jacobian at rest is the static one.
    assert np.allclose(m.jacobians(q)[0], J, rtol=0, atol=1e-12 * np.abs(J).max())
    for name in ("v", "gamma", "alpha"):
        x0, eps = getattr(p, name), 1e-6

        def R(x, name=name):
            return m.with_params(replace(p, **{name: x})).static_residual(q)

        fd = (R(x0 + eps) - R(x0 - eps)) / (2 * eps)
        d = m.static_parameter_derivative(q, name)
        assert np.abs(d - fd).max() <= 1e-7 * np.abs(d).max()


@pytest.mark.parametrize("disc_name", DISCS)
def test_static_terms_sum_to_residual_and_rate_terms(disc_name):
    disc = DISCS[disc_name]()
    m = PipeModel(disc, replace(BASE, **VARIANTS["all"]))
    q, qd, qdd = random_state(disc.n, seed=8)
    b, g, f, k = m.static_terms(q)
    assert np.array_equal(b + g + f + k, m.static_residual(q))
    assert np.abs(k).max() > 1.0 and np.abs(g - m.gravity(m.fields(q))).max() > 1.0
    # The rate part at a static state, in O(n_q), equals C^d q' + M^d q''.
    _, C, M = m.jacobians(q)
    ref = C @ qd + M @ qdd
    assert np.allclose(m.rate_terms(q, qd, qdd), ref, rtol=0, atol=1e-12 * np.abs(ref).max())


@pytest.mark.parametrize("disc_name", DISCS)
def test_mass_matrix_with_end_mass(disc_name):
    """M = M_pipe + Gamma b b^T, SPD, = dR/dq''; at theta = 0 b = (0, \\int phi_i)."""
    disc = DISCS[disc_name]()
    G = 0.8
    m0 = PipeModel(disc, BASE)
    m = m0.with_params(replace(BASE, end_mass=G))
    q, _, qdd = random_state(disc.n, seed=9)
    M = m.mass_matrix(q)
    assert np.allclose(M, M.T, rtol=0, atol=1e-15 * np.abs(M).max())
    assert np.linalg.eigvalsh(M).min() > 0
    assert np.allclose(m.residual(q, None, qdd) - m.residual(q), M @ qdd, atol=1e-12)
    phi_int = disc.Phi.T @ disc.quad.w
    M_e = m.mass_matrix(np.zeros(disc.n)) - m0.mass_matrix(np.zeros(disc.n))
    assert np.allclose(M_e, G * np.outer(phi_int, phi_int), rtol=0, atol=1e-14)


def test_spring_rule_is_exact_inside_an_element():
    """The Gauss rule on [0, xi_s] of a spring inside an element integrates the P3
    field theta^2 (degree 6) exactly: against the closed form of the polynomial."""
    disc = FiniteElement(5, 3)
    m = PipeModel(disc, Params(springs=((1.0, 0.37),)))
    q = random_state(disc.n, seed=1)[0]
    rule = m._part_rule(0.37)
    assert not rule.at_node and m._part_rule(0.4).at_node
    # theta on each element is the cubic through 4 of its points; integrate its
    # square exactly over [0, 0.2] (element 1) and [0.2, 0.37] (part of element 2).
    exact = 0.0
    for el_a, el_b, a, b in [(0.0, 0.2, 0.0, 0.2), (0.2, 0.4, 0.2, 0.37)]:
        x = np.linspace(el_a, el_b, 4)
        c = np.polyfit(x, disc.evaluate(q, x), 3)
        P = np.polyint(np.polymul(c, c))
        exact += np.polyval(P, b) - np.polyval(P, a)
    assert abs(rule.w @ (rule.Phi @ q) ** 2 - exact) < 1e-13 * max(1.0, abs(exact))
    assert abs(rule.w.sum() - 0.37) < 1e-15


# -------------------------------------------------------------- energy --
ENERGY_VARIANTS = {"end_mass": 0.6, "springs": ((40.0, 0.37), (15.0, 1.0))}


@pytest.mark.parametrize("disc_name", DISCS)
@pytest.mark.parametrize("sigma", [0.0, 1.3])
def test_power_balance_at_random_states(disc_name, sigma):
    """dE/dtau (central differences of E along (q', q'') with q'' from the residual)
    equals -(v sqrt(beta) |r_dot(1)|^2 + ... + sigma \\int |r_dot|^2): zero for
    v = mu = sigma = 0 with the end mass and springs (conservative)."""
    disc = DISCS[disc_name]()
    v, mu = (0.0, 0.0) if sigma == 0.0 else (2.5, 0.05)
    p = Params(alpha=0.9, beta=0.3, gamma=12.0, mu=mu, v=v, external_damping=sigma)
    m = PipeModel(disc, replace(p, **ENERGY_VARIANTS))
    rng = np.random.default_rng(12)
    modes = np.array([make_initial_state(m, r, 1.0, q_static=np.zeros(m.n))[0] for r in (1, 2, 3)])
    q, qd = 0.6 * rng.normal(size=3) @ modes, 2.0 * rng.normal(size=3) @ modes
    a = acceleration(m, q, qd)

    def central(eps):
        return (m.energy(q + eps * qd, qd + eps * a) - m.energy(q - eps * qd, qd - eps * a)) / (
            2 * eps
        )

    eps = 1e-3 / max(1.0, np.abs(a).max(), np.abs(qd).max())
    fd = (4 * central(eps / 2) - central(eps)) / 3
    terms = power_terms(m, q, qd)
    # The size of the largest energy flow: kinetic energy change rate.
    scale = abs(qd @ (m.mass_matrix(q) @ a)) + sum(
        abs(x) for k, x in terms.items() if k != "dE_dtau"
    )
    assert abs(fd - terms["dE_dtau"]) < 1e-7 * scale
    if sigma:
        assert terms["external_damping"] > 1e-2 * scale
        rdot = m.quad.cumulative((disc.Phi @ qd)[:, None] * m.fields(q).normal)
        assert terms["external_damping"] == pytest.approx(
            sigma * m.w @ (rdot**2).sum(axis=1), rel=1e-12
        )
    else:
        assert abs(fd) < 1e-7 * scale


def _energy_drift(rtol: float, energy_model=None) -> float:
    """Largest |E - E0| / E0 along 1 tau of large motion, v = mu = sigma = 0."""
    p = Params(alpha=0.3, v=0.0, mu=0.0, **ENERGY_VARIANTS)
    m = PipeModel(Modal(3, n_cells=8), p)
    q0, p0 = make_initial_state(m, 1, 0.8)
    q0 = q0 + make_initial_state(m, 2, 0.3, q_static=np.zeros(m.n))[0]
    em = energy_model or m
    E0 = em.energy(q0, p0)
    tr = simulate(m, q0, p0, 1.0, rtol=rtol)
    return max(abs(em.energy(a, b) - E0) for a, b in zip(tr.q, tr.qdot, strict=True)) / E0


def test_energy_conserved_with_end_mass_and_springs():
    """As tests/test_dynamics.py for the paper's pipe: the drift is at the level of the
    integrator's local error and shrinks with rtol; the energy without the end
    mass's and springs' shares is not conserved (the test can fail)."""
    d4, d6 = _energy_drift(1e-4), _energy_drift(1e-6)
    assert d6 < 10 * 1e-6
    assert d4 < 10 * 1e-4
    assert d6 < d4 / 10
    bare = PipeModel(Modal(3, n_cells=8), Params(alpha=0.3, v=0.0, mu=0.0))
    assert _energy_drift(1e-6, energy_model=bare) > 1e-2


def test_power_balance_along_trajectory_with_external_damping():
    """E(tau1) - E(tau0) = int dE/dtau along a computed trajectory with flow, Kelvin-Voigt
    and external damping, end mass and springs; dropping the external damping's
    power misses by far more."""
    p = Params(alpha=0.5, v=4.0, mu=0.02, external_damping=0.8, **ENERGY_VARIANTS)
    m = PipeModel(FiniteElement(4, 2), p)
    q0, p0 = make_initial_state(m, 1, 0.3)
    st = Radau(PipeDynamics(m), q0, p0, rtol=1e-7)
    E0 = m.energy(q0, p0)
    gx, gw = np.polynomial.legendre.leggauss(4)
    work = work_abs = damp = 0.0
    for _ in st.steps(0.6):
        t0, h = st.t_old, st.t - st.t_old
        for x, w in zip(gx, gw, strict=True):
            qq, pp = st.dense(t0 + 0.5 * h * (x + 1))
            terms = power_terms(m, qq, pp)
            work += 0.5 * h * w * terms["dE_dtau"]
            work_abs += 0.5 * h * w * abs(terms["dE_dtau"])
            damp += 0.5 * h * w * terms["external_damping"]
    dE = m.energy(st.q, st.qdot) - E0
    assert abs(dE - work) < 1e-7 * work_abs
    assert damp > 1e-2 * work_abs


# ------------------------------------------------------------- statics --
STATIC_CASES = {
    "end_mass": dict(alpha=math.pi / 2, gamma=10.0, v=2.0, end_mass=0.5),
    "end_mass_hanging_tilted": dict(alpha=0.6, gamma=6.0, v=1.0, end_mass=2.0),
    "spring_node": dict(alpha=math.pi / 2, gamma=10.0, v=2.0, springs=((50.0, 0.5),)),
    "spring_inside": dict(alpha=math.pi / 2, gamma=10.0, v=2.0, springs=((50.0, 0.37),)),
    "spring_tip": dict(alpha=1.2, gamma=15.0, v=3.0, springs=((8.0, 1.0),)),
    "all": dict(alpha=1.0, gamma=10.0, v=3.0, end_mass=0.3, springs=((20.0, 0.37), (10.0, 1.0))),
}


@pytest.mark.parametrize("case", STATIC_CASES)
def test_statics_against_strong_form_bvp(case):
    """fempipe's tip values on P3:32 against solve_bvp of the strong form
    -theta'' + gamma (1 - xi + Gamma) sin(theta + alpha) + v^2 sin(theta(1) - theta)
    + sum kappa H(xi_s - xi) n . (r(xi_s) - (xi_s, 0)) = 0 (theta'' jumps at xi_s).

    Measured: 1e-11 for the end mass and springs at nodes, 5e-8 for a spring
    inside an element (the FE error there is O(h^3), see below)."""
    c = dict(STATIC_CASES[case])
    ref = solve_static_bvp(
        c["alpha"],
        c["gamma"],
        c["v"],
        tol=1e-11,
        end_mass=c.get("end_mass", 0.0),
        springs=c.get("springs", ()),
    )
    disc = FiniteElement(32, 3)
    m = PipeModel(disc, Params(**c))
    tip = compute_tip(disc, solve_sagged(m, tol=1e-12).q, c["alpha"])
    inside = any(x not in (0.5, 1.0) for _, x in c.get("springs", ()))
    tol = 1e-6 if inside else 1e-9
    assert abs(tip["theta_tip"] - ref.theta_tip) < tol
    assert abs(tip["X_tip"] - ref.X_tip) < tol
    assert abs(tip["Z_tip"] - ref.Z_tip) < tol
    assert abs(tip["eta_tip"] - ref.eta_tip) < tol
    assert abs(tip["varsigma_tip"] - ref.varsigma_tip) < tol
    # The variant matters: the paper's pipe is far from it.
    plain = Params(alpha=c["alpha"], gamma=c["gamma"], v=c["v"])
    tip0 = compute_tip(disc, solve_sagged(PipeModel(disc, plain)).q, c["alpha"])
    assert abs(tip0["theta_tip"] - ref.theta_tip) > 1e-2


def test_spring_jump_condition_of_the_bvp():
    """The BVP's theta'' jumps at xi_s by kappa n(xi_s) . (r(xi_s) - (xi_s, 0)),
    theta and theta' are continuous, as the point force requires."""
    kappa, xs, alpha = 50.0, 0.37, math.pi / 2
    ref = solve_static_bvp(alpha, 10.0, 2.0, tol=1e-11, springs=((kappa, xs),))
    e = 1e-9
    lo, hi = ref.sol(xs - e), ref.sol(xs + e)
    assert abs(lo[0] - hi[0]) < 1e-8 and abs(lo[1] - hi[1]) < 1e-7
    # theta'' from the ODE on both sides: rebuild it from the states.
    X, Z = ref.sol(xs)[2:]
    r1 = math.cos(alpha) * X + math.sin(alpha) * Z
    r2 = -math.sin(alpha) * X + math.cos(alpha) * Z
    th = ref.sol(xs)[0]
    jump = kappa * (-math.sin(th) * (r1 - xs) + math.cos(th) * r2)
    h = 1e-4
    d2_lo = (ref.sol(xs - h)[1] - ref.sol(xs - 2 * h)[1]) / h
    d2_hi = (ref.sol(xs + 2 * h)[1] - ref.sol(xs + h)[1]) / h
    assert abs(jump) > 1.0
    assert abs((d2_lo - d2_hi) - jump) < 1e-2 * abs(jump)


@pytest.mark.parametrize("disc_name", ["P2:4", "modal:4", "modal-beam:4"])
def test_mirror_symmetry_with_every_variant(disc_name):
    """(theta, alpha) -> (-theta, -alpha) maps R to -R with every variant on, and the
    static state for -alpha is minus the one for alpha."""
    disc = DISCS[disc_name]()
    p = replace(BASE, **VARIANTS["all"])
    m1 = PipeModel(disc, p)
    m2 = m1.with_params(replace(p, alpha=-p.alpha))
    q, qd, qdd = random_state(disc.n, seed=13)
    r1 = m1.residual(q, qd, qdd, v_dot=0.4)
    assert np.allclose(m2.residual(-q, -qd, -qdd, v_dot=0.4), -r1, atol=1e-12 * np.abs(r1).max())
    s1, s2 = solve_sagged(m1).q, solve_sagged(m2).q
    assert np.abs(s1).max() > 0.1
    assert np.allclose(s2, -s1, atol=1e-9)
    assert m2.energy(-q, -qd) == pytest.approx(m1.energy(q, qd), rel=1e-13)


# ---------------------------------------------------- classical limits --
def _roots(f, n, top=40.0):
    """The n smallest roots of f in (0.5, top): sign changes on a fine grid, then Brent."""
    xs = np.linspace(0.5, top, 40000)
    fs = f(xs)
    idx = np.flatnonzero(fs[:-1] * fs[1:] < 0)[:n]
    return np.array([brentq(f, xs[i], xs[i + 1], xtol=1e-15) for i in idx])


def _frequencies(model, q=None):
    """omega_r of K x = omega^2 M x, the largest 1/omega^2 of (M, K) first (K is
    well conditioned; M of the integrated basis is not)."""
    K, _, M = model.jacobians(np.zeros(model.n) if q is None else q)
    return np.sort(1.0 / np.sqrt(sla.eigh(M, K, eigvals_only=True)))


@pytest.mark.parametrize("G", [0.5, 2.0])
def test_cantilever_with_tip_mass_frequencies(G):
    """Gravity-free, v = 0: omega = l^2 with 1 + cos l cosh l + Gamma l (cos l sinh l -
    sin l cosh l) = 0 (clamped-free beam with a tip mass, Blevins), to 1e-8."""
    disc = FiniteElement(48, 3)  # FE error of mode 4: 1e-9 (h^6)
    m = PipeModel(disc, Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0, v=0.0, end_mass=G))
    lam = _roots(
        lambda x: 1 / np.cosh(x) + np.cos(x) + G * x * (np.cos(x) * np.tanh(x) - np.sin(x)), 4
    )
    omega = _frequencies(m)[:4]
    assert np.abs(omega / lam**2 - 1).max() < 1e-8
    # Not the cantilever's own: the tip mass lowers every frequency.
    omega0 = _frequencies(PipeModel(disc, Params(alpha=0.0, gamma=0.0, mu=0.0)))[:4]
    assert np.all(omega < 0.95 * omega0)


@pytest.mark.parametrize("kappa", [10.0, 200.0])
def test_cantilever_with_tip_spring_frequencies(kappa):
    """A spring at the tip, gravity-free, v = 0: omega = l^2 with
    l^3 (1 + cos l cosh l) = kappa (cos l sinh l - sin l cosh l) (w'''(1) = kappa w(1);
    kappa -> inf gives the clamped-pinned tan l = tanh l), to 1e-8."""
    disc = FiniteElement(48, 3)  # FE error of mode 4: 1e-9 (h^6)
    m = PipeModel(disc, Params(alpha=0.0, gamma=0.0, mu=0.0, springs=((kappa, 1.0),)))
    lam = _roots(
        lambda x: (
            x**3 * (1 / np.cosh(x) + np.cos(x)) - kappa * (np.cos(x) * np.tanh(x) - np.sin(x))
        ),
        4,
    )
    omega = _frequencies(m)[:4]
    assert np.abs(omega / lam**2 - 1).max() < 1e-8
    omega0 = _frequencies(PipeModel(disc, Params(alpha=0.0, gamma=0.0, mu=0.0)))[:4]
    assert omega[0] > 1.05 * omega0[0]


@pytest.mark.parametrize("disc_name", ["P3:8", "modal:6", "modal-beam:6"])
@pytest.mark.parametrize("curved", [False, True], ids=["straight", "curved"])
def test_external_damping_shifts_every_eigenvalue_by_minus_sigma_half(disc_name, curved):
    """v = mu = 0: the damping matrix of the external damping is sigma M(q), so every
    eigenvalue of lambda^2 M + lambda sigma M + K is -sigma/2 +- i sqrt(omega^2 -
    sigma^2/4).  Also about the curved static state of a horizontal pipe with a
    spring, where only the geometrically exact damping (along r_dot, not only
    its lateral part) gives sigma M(q)."""
    disc = {
        "P3:8": lambda: FiniteElement(8, 3),
        "modal:6": lambda: Modal(6),
        "modal-beam:6": lambda: Modal(6, basis="beam"),
    }[disc_name]()
    sigma = 0.8
    p = Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0, v=0.0, external_damping=sigma)
    if curved:
        p = replace(p, alpha=math.pi / 2, gamma=10.0, springs=((20.0, 0.4),))
    m = PipeModel(disc, p)
    q = solve_sagged(m).q
    assert (np.abs(q).max() > 0.5) == curved
    K, C, M = m.jacobians(q)
    n = m.n
    Z, I = np.zeros((n, n)), np.eye(n)
    lam = sla.eig(np.block([[Z, I], [-K, -C]]), np.block([[I, Z], [Z, M]]), right=False)
    low = lam[np.argsort(np.abs(lam))][:8]
    assert np.all(np.abs(low.imag) > 1.0)
    assert np.abs(low.real + sigma / 2).max() < 1e-10
    omega2 = np.sort(1.0 / sla.eigh(M, K, eigvals_only=True))[:4]
    assert np.allclose(np.sort(np.abs(low) ** 2)[::2], omega2, rtol=1e-10)


# ------------------------------------------------- convergence orders --
def _slopes(errors, ns):
    e, n = np.asarray(errors), np.asarray(ns, dtype=float)
    return np.log(e[:-1] / e[1:]) / np.log(n[1:] / n[:-1])


def _static_tip(disc, c):
    m = PipeModel(disc, Params(**c))
    q = solve_static(m, q0=solve_sagged(m, tol=1e-10).q, tol=1e-12).q
    return compute_tip(disc, q, c["alpha"])["theta_tip"]


@pytest.mark.parametrize(
    "case, degree, ns, order",
    [
        ("end_mass", 2, (4, 8, 16), 4),
        ("end_mass", 3, (4, 8, 16), 6),
        ("spring_node", 2, (4, 8, 16), 4),
        ("spring_node", 3, (4, 8, 16), 6),
        # A spring inside an element, always at 1/3 of it: theta'' jumps inside
        # the element, the energy error is O(h^1.5) and the tip error O(h^3).
        ("spring_third", 2, (4, 16, 64), 3),
        ("spring_third", 3, (4, 16, 64), 3),
    ],
)
def test_fe_convergence_order_of_static_tip(case, degree, ns, order):
    """theta_tip against the strong-form BVP.  Measured: end mass P2 4.06, 4.00;
    P3 5.18, 5.82; spring at the node 0.5: P2 4.01, 4.00, P3 5.85, 5.96; spring at
    xi_s = 1/3 (inside an element): P2 2.67, 2.93, P3 3.02, 3.01."""
    c = dict(STATIC_CASES.get(case, {}))
    if case == "spring_third":
        c = dict(alpha=math.pi / 2, gamma=10.0, v=2.0, springs=((50.0, 1.0 / 3.0),))
    ref = solve_static_bvp(
        c["alpha"],
        c["gamma"],
        c["v"],
        tol=1e-11,
        end_mass=c.get("end_mass", 0.0),
        springs=c.get("springs", ()),
    )
    errs = [abs(_static_tip(FiniteElement(n, degree), c) - ref.theta_tip) for n in ns]
    s = _slopes(errs, ns)
    assert abs(s[-1] - order) < 0.3, (errs, s)


@pytest.mark.parametrize(
    "variant, degree, order",
    [
        ("end_mass", 2, 4),
        ("end_mass", 3, 6),
        ("spring_node", 2, 4),
        ("spring_node", 3, 6),
        ("spring_third", 2, 3),
        ("spring_third", 3, 3),
    ],
)
def test_fe_convergence_order_of_eigenvalues(variant, degree, order):
    """The three lowest frequencies of the gravity-free pipe (v = 0): against the
    tip-mass frequency equation, or for springs against P3 on 48 elements
    with a node at xi_s (error below 1e-10).  Inside an element (xi_s = 1/3,
    at 1/3 of its element on n = 4, 16, 64) the order drops to 3.  Measured: end
    mass P2 3.87, 3.97, P3 5.97, 5.98; spring at the node P2 3.67, 3.94, P3 5.99,
    5.99; inside P2 3.63, 3.29 (the h^3 term overtaking the h^4), P3 3.17, 3.01."""
    base = Params(alpha=0.0, gamma=0.0, mu=0.0)
    if variant == "end_mass":
        G = 0.5
        p = replace(base, end_mass=G)
        lam = _roots(
            lambda x: 1 / np.cosh(x) + np.cos(x) + G * x * (np.cos(x) * np.tanh(x) - np.sin(x)),
            3,
        )
        ref = lam**2
        ns = (4, 8, 16)
    else:
        xs = 0.5 if variant == "spring_node" else 1.0 / 3.0
        p = replace(base, springs=((200.0, xs),))
        ref = _frequencies(PipeModel(FiniteElement(48, 3), p))[:3]
        ns = (4, 8, 16) if variant == "spring_node" else (4, 16, 64)
    errs = [
        np.abs(_frequencies(PipeModel(FiniteElement(n, degree), p))[:3] / ref - 1).max() for n in ns
    ]
    s = _slopes(errs, ns)
    assert abs(s[-1] - order) < 0.35, (errs, s)


# ------------------------------------------------------------------ CLI --


def test_cli_static_end_mass(capsys):
    d = run_json(
        capsys,
        [
            "static",
            "--end-mass",
            "0.5",
            "--alpha",
            "pi/2",
            "--gamma",
            "10",
            "--v",
            "2",
            "--fe",
            "P3:16",
            "--json",
            "--quiet",
        ],
    )
    assert d["params"]["end_mass"] == 0.5
    tip = d["points"][0]
    ref = solve_static_bvp(math.pi / 2, 10.0, 2.0, tol=1e-11, end_mass=0.5)
    assert tip["theta_tip"] == pytest.approx(ref.theta_tip, abs=1e-8)


def test_cli_critical_with_damping_and_spring(capsys):
    argv = [
        "critical",
        "--external-damping",
        "0.1",
        "--spring",
        "50@0.5",
        "--alpha",
        "pi/2",
        "--v",
        "0,12",
        "--fe",
        "P2:6",
        "--json",
        "--quiet",
    ]
    d = run_json(capsys, argv)
    assert d["params"]["external_damping"] == 0.1
    assert d["params"]["springs"] == [[50.0, 0.5]]
    from fempipe.analyses.stability import find_critical_velocity

    p = Params(alpha=math.pi / 2, external_damping=0.1, springs=((50.0, 0.5),))
    lib = find_critical_velocity(PipeModel(FiniteElement(6, 2), p), 12.0)
    plain = find_critical_velocity(PipeModel(FiniteElement(6, 2), Params(alpha=math.pi / 2)), 12.0)
    assert d["v_cr_in_plane"] == pytest.approx(lib.v_cr, abs=1e-10)
    assert abs(lib.v_cr - plain.v_cr) > 1e-2
    # v_cr is the 3-D one: the out-of-plane problem with the same variants
    out = find_critical_velocity(PipeModel(FiniteElement(6, 2), p), 12.0, planes=("out",))
    assert d["v_cr"] == d["v_cr_out_of_plane"] == pytest.approx(out.v_cr, abs=1e-9)


def test_cli_simulate_end_mass(capsys):
    """The end mass reaches the time integration: the flutter cycle of two sine modes
    at v = 9 (0.3029 without it) is slower with the heavier tip."""
    from fempipe.analyses.limit_cycle import find_attractor

    d = run_json(
        capsys,
        ["simulate", "--end-mass", "0.2", "--modal", "2", "--v", "9", "--t-max", "60"]
        + ["--json", "--quiet"],
    )
    assert d["params"]["end_mass"] == 0.2
    assert d["attractor"] == "periodic"
    plain = find_attractor(PipeModel(Modal(2), Params(v=9.0)))
    assert d["period"] > 1.03 * plain.period


def test_cli_end_mass_kg_converts(capsys):
    """--end-mass-kg with the SI pipe: Gamma = M_e / ((m+M) L)."""
    si = ["--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058"]
    d = run_json(
        capsys,
        [
            "static",
            *si,
            "--end-mass-kg",
            "0.001",
            "--alpha",
            "pi/2",
            "--U",
            "0",
            "--modal",
            "3",
            "--json",
            "--quiet",
        ],
    )
    G = 0.001 / ((0.0159 + 0.0058) * 0.094)
    assert d["params"]["end_mass"] == pytest.approx(G, rel=1e-14)
    assert PipeSI(0.094, 1.8e-5, 0.0159, 0.0058).end_mass_ratio(0.001) == pytest.approx(G)


def test_cli_stability_map_passes_the_variants(capsys):
    argv = [
        "stability-map",
        "--modal",
        "3",
        "--alphas",
        "pi/2",
        "--v",
        "0,10",
        "--external-damping",
        "0.5",
        "--spring",
        "20@0.5",
        "--end-mass",
        "0.2",
        "--json",
        "--quiet",
    ]
    d = run_json(capsys, argv)
    assert d["end_mass"] == 0.2 and d["external_damping"] == 0.5
    assert d["springs"] == [[20.0, 0.5]]
    from fempipe.analyses.stability import find_critical_velocity

    p = Params(alpha=math.pi / 2, end_mass=0.2, external_damping=0.5, springs=((20.0, 0.5),))
    lib = find_critical_velocity(PipeModel(Modal(3), p), 10.0, ds_max=0.2)
    assert d["points"][0]["v_cr_in_plane"] == pytest.approx(lib.v_cr, abs=1e-8)
    # the map's v_cr is the first loss in 3-D: out of the plane, with the same variants
    out = find_critical_velocity(PipeModel(Modal(3), p), 10.0, ds_max=0.2, planes=("out",))
    assert d["points"][0]["v_cr"] == pytest.approx(out.v_cr, abs=1e-8)


@pytest.mark.parametrize("disc_name", DISCS)
def test_basis_values_agree_with_evaluate(disc_name):
    """disc.basis_values(x) @ q is theta(x) (the spring's part-cell rule uses it)."""
    disc = DISCS[disc_name]()
    q = random_state(disc.n, seed=2)[0]
    x = np.array([0.0, 0.1, 0.37, 0.5, 0.999, 1.0])
    assert np.allclose(dense(disc.basis_values(x)) @ q, disc.evaluate(q, x), atol=1e-13)


def test_stability_map_refuses_unknown_variants():
    from fempipe.analyses.stability import map_stability

    with pytest.raises(ValueError, match="variants are"):
        map_stability(Modal(2), [0.0], [(0.142, 18.9)], variants={"tip_mass": 1.0})


@pytest.mark.parametrize("variant", [{"external_damping": 0.5}, {"end_mass": 0.5}])
def test_sparse_stability_criterion_sees_the_variants(variant):
    """The shift-invert criterion of large FE meshes decides as the dense one.

    Horizontal pipe just above the paper's v_cr on P3:70 (210 unknowns, the
    sparse path): sigma = 0.5 stabilizes it, Gamma = 0.5 does not.  The sparse
    operator once built C x + M y from the pipe's own terms only and decided
    both the other way round.
    """
    from fempipe.analyses.stability import linearly_stable
    from fempipe.analyses.statics import solve_path

    p = Params(alpha=math.pi / 2, beta=0.142, gamma=18.9, mu=5e-3, **variant)
    model = PipeModel(FiniteElement(70, 3), p)
    q = solve_path(model, np.linspace(0.0, 6.24, 14))[-1].q
    m = model.with_params(replace(p, v=6.24))
    dense = linearly_stable(m, q, sparse=False)
    assert linearly_stable(m, q, sparse=True) == dense

"""The weak form of Eq. (20): integration operators, Jacobians, mass matrix, energy.

Every reference here is independent of the code under test: closed-form
integrals, central finite differences, a brute-force double quadrature of the
kernel G(xi, r) = 1 - max(xi, r) of the double integral (docs, "Conventions and
derivations"), and the energy/power identities.
"""

import numpy as np
import pytest

from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.quadrature import LineQuadrature

DISCS = {
    "P1:9": lambda: FiniteElement(9, 1),
    "P2:5": lambda: FiniteElement(5, 2),
    "P3:4": lambda: FiniteElement(4, 3),
    "P3:graded": lambda: FiniteElement(nodes=[0, 0.05, 0.2, 0.5, 1.0], degree=3),
    "modal:6": lambda: Modal(6),
}

PARAMS = Params(alpha=0.7, beta=0.3, gamma=12.0, mu=0.02, v=3.0)


def random_state(n, seed, amplitude=1.5):
    """States far from the straight pipe: O(1) rotations and rates."""
    rng = np.random.default_rng(seed)
    return amplitude * rng.standard_normal((3, n))


# ------------------------------------------------------------ quadrature --
@pytest.mark.parametrize("n_gauss", [1, 2, 4, 7])
def test_cumulative_exact_for_cell_polynomials(n_gauss):
    rng = np.random.default_rng(1)
    Q = LineQuadrature(np.r_[0, np.sort(rng.uniform(0, 1, 5)), 1], n_gauss)
    k = n_gauss - 1  # the interpolant through n_g points is exact to degree n_g - 1
    f = Q.x**k
    exact = Q.x ** (k + 1) / (k + 1)
    assert np.allclose(Q.cumulative(f), exact, atol=1e-14, rtol=0)
    assert np.allclose(Q.from_tip(f), 1.0 / (k + 1) - exact, atol=1e-14, rtol=0)


def test_integration_operators_are_adjoint():
    """W C^R = C^T W: the Gauss collocation identity b_p a_pq + b_q a_qp = b_p b_q."""
    Q = LineQuadrature(np.array([0, 0.1, 0.35, 0.4, 1.0]), 5)
    eye = np.eye(Q.n_q)
    C, CR = Q.cumulative(eye), Q.from_tip(eye)
    assert np.abs(Q.w[:, None] * CR - C.T * Q.w[None, :]).max() < 1e-15


def test_cumulative_converges_for_smooth_functions():
    """Local interpolation at n_g points: error O(h^(n_g + 1)) for smooth f."""
    errs = []
    for n in (4, 8, 16):
        Q = LineQuadrature.uniform(n, 3)
        errs.append(np.abs(Q.cumulative(np.cos(3 * Q.x)) - np.sin(3 * Q.x) / 3).max())
    slopes = -np.diff(np.log(errs)) / np.log(2)
    assert np.all(slopes > 3.8), slopes


# ------------------------------------------------------------ Jacobians --
def fd_jacobian(f, x, eps=1e-6):
    return np.column_stack([(f(x + eps * e) - f(x - eps * e)) / (2 * eps) for e in np.eye(x.size)])


@pytest.mark.parametrize("name", DISCS)
@pytest.mark.parametrize("which", ["q", "qdot", "qddot"])
def test_jacobians_match_finite_differences(name, which):
    disc = DISCS[name]()
    model = PipeModel(disc, PARAMS)
    q, qd, qdd = random_state(disc.n, seed=3)
    v_dot = 0.7  # exercises the unsteady-flow terms as well
    Jq, Jqd, M = model.jacobians(q, qd, qdd, v_dot=v_dot)
    args = {"q": (0, Jq), "qdot": (1, Jqd), "qddot": (2, M)}
    idx, J = args[which]

    def f(x):
        s = [q, qd, qdd]
        s[idx] = x
        return model.residual(*s, v_dot=v_dot)

    eps = 1e-6
    J_fd = fd_jacobian(f, [q, qd, qdd][idx], eps)
    # Central differences: truncation ~ eps^2 |R'''| (below 1e-7 of the
    # Jacobian's scale) plus round-off ~ 1e-16 |R| / eps, which matters where R
    # is large and the Jacobian small (the mass matrix of a fine mesh).
    tol = 1e-7 * np.abs(J).max() + 1e-14 * np.abs(f([q, qd, qdd][idx])).max() / eps
    assert np.abs(J - J_fd).max() <= tol


@pytest.mark.parametrize("name", DISCS)
def test_static_jacobian_matches_finite_differences(name):
    disc = DISCS[name]()
    model = PipeModel(disc, PARAMS)
    q = random_state(disc.n, seed=5)[0]
    J = model.static_jacobian(q)
    J = J.toarray() if hasattr(J, "toarray") else J
    J_fd = fd_jacobian(model.static_residual, q)
    assert np.abs(J - J_fd).max() <= 1e-7 * np.abs(J).max()


@pytest.mark.parametrize("parameter", ["v", "gamma", "alpha"])
def test_parameter_derivative_matches_finite_differences(parameter):
    disc = FiniteElement(6, 2)
    model = PipeModel(disc, PARAMS)
    q = random_state(disc.n, seed=6)[0]
    eps = 1e-6
    x0 = getattr(PARAMS, parameter)

    def R(x):
        from dataclasses import replace

        return model.with_params(replace(PARAMS, **{parameter: x})).static_residual(q)

    fd = (R(x0 + eps) - R(x0 - eps)) / (2 * eps)
    d = model.static_parameter_derivative(q, parameter)
    assert np.abs(d - fd).max() <= 1e-7 * np.abs(d).max()


# ---------------------------------------------------------- mass matrix --
@pytest.mark.parametrize("name", DISCS)
def test_mass_matrix_symmetric_positive_definite(name):
    disc = DISCS[name]()
    model = PipeModel(disc, PARAMS)
    q = random_state(disc.n, seed=7)[0]
    M = model.mass_matrix(q)
    assert np.allclose(M, M.T, rtol=0, atol=1e-15 * np.abs(M).max())
    assert np.linalg.eigvalsh(M).min() > 0
    # The inertia term applied in O(n) agrees with the assembled matrix.
    qdd = random_state(disc.n, seed=8)[2]
    assert np.allclose(model.residual(q, None, qdd) - model.residual(q), M @ qdd, atol=1e-12)


def test_mass_matrix_matches_double_integral_kernel():
    """docs, "The mass matrix is symmetric": M_ij = \\int\\int phi_i(xi) phi_j(r) cos(theta(xi) - theta(r)) G(xi, r),
    G = 1 - max(xi, r).  Brute-force midpoint double quadrature on a 4000^2 grid
    (error O(1/4000^2) ~ 1e-7 away from the kink, O(h) ~ 2.5e-4/4000 on it)."""
    disc = Modal(3)
    model = PipeModel(disc, PARAMS)
    q = np.array([0.8, -0.3, 0.2])
    n = 4000
    x = (np.arange(n) + 0.5) / n
    phi = np.sin(np.outer(x, disc.k))
    th = phi @ q
    G = 1.0 - np.maximum.outer(x, x)
    Kern = np.cos(th[:, None] - th[None, :]) * G / n**2
    M_ref = phi.T @ Kern @ phi
    assert np.abs(model.mass_matrix(q) - M_ref).max() < 1e-5


def test_straight_pipe_mass_matrix_closed_form():
    """At theta = 0, M_ij = \\int\\int phi_i phi_j G = \\int_0^1 Phi_i Phi_j with
    Phi_i = \\int_0^xi phi_i: for sine modes Phi_i = (1 - cos k_i xi)/k_i."""
    disc = Modal(4)
    model = PipeModel(disc, Params())
    k = disc.k
    x, w = np.polynomial.legendre.leggauss(80)
    x, w = 0.5 * (x + 1), 0.5 * w
    P = (1 - np.cos(np.outer(x, k))) / k
    assert np.allclose(model.mass_matrix(np.zeros(4)), (P.T * w) @ P, atol=1e-14)


# ------------------------------------------------------- energy / power --
def energy_rate(model, q, qd, qdd):
    """dE/dtau = q'.(K q + gravity) + q'.M q'' + dT/dq . q'.

    Only the last term, a directional derivative of the kinetic energy at
    fixed q', is taken by (4th-order central) differences; the rest is exact.
    """
    static = model.with_params(model.params.with_flow(0.0)).static_residual(q)
    h = 1e-4

    def T(s):
        return model.kinetic_energy(q + s * qd, qd)

    dT = (-T(2 * h) + 8 * T(h) - 8 * T(-h) + T(-2 * h)) / (12 * h)
    return qd @ static + qd @ (model.mass_matrix(q) @ qdd) + dT


@pytest.mark.parametrize("name", DISCS)
def test_energy_conserved_without_flow_and_damping(name):
    """v = 0, mu = 0: dE/dtau = 0 for the acceleration the residual implies."""
    disc = DISCS[name]()
    model = PipeModel(disc, Params(alpha=0.9, beta=0.3, gamma=12.0, mu=0.0, v=0.0))
    q, qd, _ = random_state(disc.n, seed=11, amplitude=1.0)
    qdd = np.linalg.solve(model.mass_matrix(q), -model.residual(q, qd, np.zeros(disc.n)))
    scale = abs(qd @ (disc.K @ q)) + abs(qd @ (model.mass_matrix(q) @ qdd))
    # The terms cancel to round-off; the FD part has truncation ~ h^4 T^(5) and
    # round-off ~ 1e-16 T / h, both ~1e-10 of the scale of the largest term.
    assert abs(energy_rate(model, q, qd, qdd)) < 1e-8 * scale


@pytest.mark.parametrize("name", DISCS)
def test_power_balance_with_flow_and_damping(name):
    """dE/dtau = -[v sqrt(beta) |r_dot(1)|^2 + v^2 t(1).r_dot(1) + mu q'^T K q']."""
    disc = DISCS[name]()
    p = Params(alpha=0.9, beta=0.3, gamma=12.0, mu=0.05, v=2.5)
    model = PipeModel(disc, p)
    q, qd, _ = random_state(disc.n, seed=12, amplitude=1.0)
    qdd = np.linalg.solve(model.mass_matrix(q), -model.residual(q, qd, np.zeros(disc.n)))
    th, thd = disc.Phi @ q, disc.Phi @ qd
    w = disc.quad.w
    rdot_tip = np.array([-(w @ (thd * np.sin(th))), w @ (thd * np.cos(th))])
    th1 = disc.tip @ q
    t_tip = np.array([np.cos(th1), np.sin(th1)])
    power = -(
        p.v * np.sqrt(p.beta) * rdot_tip @ rdot_tip
        + p.v**2 * t_tip @ rdot_tip
        + p.mu * qd @ (disc.K @ qd)
    )
    assert abs(power) > 0.1  # the identity is not trivially 0 = 0
    assert abs(energy_rate(model, q, qd, qdd) - power) < 1e-7 * abs(power)


# ------------------------------------------------------------ symmetry --
@pytest.mark.parametrize("name", ["P2:5", "modal:6"])
def test_residual_odd_under_theta_alpha_reflection(name):
    """(theta, alpha) -> (-theta, -alpha) maps Eq. (20) to minus itself."""
    from dataclasses import replace

    disc = DISCS[name]()
    q, qd, qdd = random_state(disc.n, seed=13)
    m1 = PipeModel(disc, PARAMS)
    m2 = PipeModel(disc, replace(PARAMS, alpha=-PARAMS.alpha))
    r1 = m1.residual(q, qd, qdd, v_dot=0.4)
    r2 = m2.residual(-q, -qd, -qdd, v_dot=0.4)
    assert np.allclose(r2, -r1, atol=1e-12 * np.abs(r1).max())


def test_alpha_minus_pi_flips_gravity_only():
    """docs, "The symmetry": alpha -> alpha - pi is gamma -> -gamma, not an antisymmetry
    of solutions."""
    from dataclasses import replace

    disc = FiniteElement(5, 2)
    q = random_state(disc.n, seed=14)[0]
    m1 = PipeModel(disc, PARAMS)
    m2 = PipeModel(disc, replace(PARAMS, alpha=PARAMS.alpha - np.pi))
    g1 = m1.gravity(m1.fields(q))
    assert np.allclose(m2.gravity(m2.fields(q)), -g1, atol=1e-13)
    assert np.allclose(m2.residual(q) - m2.gravity(m2.fields(q)), m1.residual(q) - g1)

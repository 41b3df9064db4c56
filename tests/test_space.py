"""The 3-D model: its chart, its exact planar reduction, its Jacobians, symmetries and energy.

References are independent of the 3-D code: the planar model (Eq. (20)) for
planar states, central finite differences for the Jacobians, the mirror
symmetry e_3 -> -e_3, the isotropy of the hanging pipe (alpha = 0) under
rotations about the vertical, and energy conservation for v = 0, mu = 0.
"""

from __future__ import annotations

import numpy as np
import pytest

from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.out_of_plane.model import build_out_of_plane_model
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.chart import _Point, fiber_direction, tangent
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D, planar_state
from fempipe.solvers.radau import Radau

VARIANTS = Params(alpha=0.7, v=3.0, mu=0.05, end_mass=0.3, external_damping=0.2)


def _chart_jacobian(u: np.ndarray, eps: float = 1e-6) -> np.ndarray:
    """dt/du by central differences at one point u = (theta, a, b)."""
    J = np.empty((3, 3))
    for c in range(3):
        d = np.zeros(3)
        d[c] = eps
        tp = tangent((u + d)[None, :, None])[0, :, 0]
        tm = tangent((u - d)[None, :, None])[0, :, 0]
        J[:, c] = (tp - tm) / (2 * eps)
    return J


def _chart_inverse(t: np.ndarray) -> np.ndarray:
    """A u with tangent(u) = t: a quaternion turning e_1 to t, twisted so that its (w, z) part
    is large, scaled to the chart (the constructive proof that every direction is reached)."""
    t = t / np.linalg.norm(t)
    axis = np.cross([1.0, 0.0, 0.0], t)
    s, c = np.linalg.norm(axis), t[0]
    if s < 1e-12:
        axis, s = np.array([0.0, 0.0, 1.0]), 0.0
    angle = np.arctan2(s, c)
    k = axis / (np.linalg.norm(axis) or 1.0)
    q0 = np.r_[np.cos(angle / 2), np.sin(angle / 2) * k]
    best = None
    for phi in np.linspace(0, 2 * np.pi, 73):  # q0 (cos(phi/2), sin(phi/2), 0, 0): same t
        cp, sp = np.cos(phi / 2), np.sin(phi / 2)
        w, x, y, z = q0
        q = np.array([w * cp - x * sp, x * cp + w * sp, y * cp + z * sp, z * cp - y * sp])
        if best is None or q[0] ** 2 + q[3] ** 2 > best[0] ** 2 + best[3] ** 2:
            best = q
    w, x, y, z = best / np.hypot(best[0], best[3])
    return np.array([2 * np.arctan2(z, w), x, y])


def test_chart_is_a_submersion_onto_the_sphere():
    rng = np.random.default_rng(1)
    # random states, and the directions where two angles or a rotation vector normal
    # to e_1 are singular: along e_3, and back along -e_1
    targets = [np.array([0.0, 0.0, 1.0]), np.array([0.0, 0.0, -1.0]), np.array([-1.0, 0, 0])]
    targets += list(rng.normal(size=(20, 3)))
    for t in targets:
        u = _chart_inverse(t)
        got = tangent(u[None, :, None])[0, :, 0]
        assert np.allclose(got, t / np.linalg.norm(t), atol=1e-12)
        sv = np.linalg.svd(_chart_jacobian(u), compute_uv=False)
        assert sv[1] > 0.05 and sv[2] < 1e-8, sv  # rank 2: the tangent space of the sphere
    for u in rng.normal(scale=3.0, size=(50, 3)):
        assert abs(np.linalg.norm(tangent(u[None, :, None])[0, :, 0]) - 1.0) < 1e-14
        sv = np.linalg.svd(_chart_jacobian(u), compute_uv=False)
        assert sv[1] > 1e-3 * sv[0], (u, sv)


def test_fiber_direction_leaves_the_tangent_unchanged():
    rng = np.random.default_rng(2)
    for u in rng.normal(scale=2.0, size=(30, 3)):
        f = fiber_direction(_Point.of(u[None, :, None]))[0, :, 0]
        assert np.linalg.norm(_chart_jacobian(u) @ f) < 1e-8 * np.linalg.norm(f)
        assert np.linalg.norm(f) > 0.1


def test_planar_tangent_is_the_planar_models():
    theta = np.linspace(-7.0, 7.0, 41)
    u = np.stack([theta, 0 * theta, 0 * theta], axis=1)[:, :, None]
    t = tangent(u)[:, :, 0]
    assert np.array_equal(t[:, 2], np.zeros_like(theta))
    assert np.allclose(t[:, :2], np.stack([np.cos(theta), np.sin(theta)], axis=1), atol=1e-15)


@pytest.mark.parametrize("disc", [FiniteElement(4, 3), Modal(4)], ids=lambda d: d.name)
def test_planar_states_give_the_planar_weak_form(disc):
    rng = np.random.default_rng(3)
    q, qd, qdd = rng.normal(size=(3, disc.n))
    planar, space = PipeModel(disc, VARIANTS), PipeModel3D(disc, VARIANTS)
    n = disc.n
    r2 = planar.residual(q, qd, qdd)
    r3 = space.residual(planar_state(q), planar_state(qd), planar_state(qdd))
    assert np.abs(r3[:n] - r2).max() < 1e-14 * np.abs(r2).max()
    assert np.array_equal(r3[n:], np.zeros(2 * n))  # a planar state stays planar
    for J2, J3 in zip(
        planar.jacobians(q, qd, qdd),
        space.jacobians(planar_state(q), planar_state(qd), planar_state(qdd)),
        strict=True,
    ):
        assert np.abs(J3[:n, :n] - J2).max() < 1e-14 * np.abs(J2).max()
        # in-plane and out-of-plane perturbations decouple (mirror symmetry)
        assert np.abs(J3[:n, n:]).max() == 0.0 and np.abs(J3[n:, :n]).max() == 0.0


@pytest.mark.parametrize("disc", [FiniteElement(3, 2), Modal(3)], ids=lambda d: d.name)
def test_jacobians_match_finite_differences(disc):
    rng = np.random.default_rng(4)
    model = PipeModel3D(disc, VARIANTS)
    U, Ud, Udd = rng.normal(scale=0.6, size=(3, model.n))
    exact = model.jacobians(U, Ud, Udd)
    for k in range(3):
        # R is quadratic in U' and affine in U'': central differences are exact there
        eps = 1e-6 if k == 0 else 1e-3
        fd = np.empty((model.n, model.n))
        for j in range(model.n):
            args = [U.copy(), Ud.copy(), Udd.copy()]
            args[k][j] += eps
            rp = model.residual(*args)
            args[k][j] -= 2 * eps
            fd[:, j] = (rp - model.residual(*args)) / (2 * eps)
        assert np.abs(fd - exact[k]).max() < 1e-6 * np.abs(fd).max(), k
    M = model.mass_matrix(U)
    assert np.array_equal(M, M.T) and np.linalg.eigvalsh(M).min() > 0
    # S states at once equal one by one
    S = rng.normal(scale=0.6, size=(3, 3, model.n))
    batch = model.residual(S[0], S[1], S[2])
    for s in range(3):
        assert np.allclose(batch[s], model.residual(S[0][s], S[1][s], S[2][s]), rtol=1e-13)


def _fit(disc, f) -> np.ndarray:
    Phi = disc.Phi.toarray() if hasattr(disc.Phi, "toarray") else disc.Phi
    return np.linalg.lstsq(Phi, f(disc.quad.x), rcond=None)[0]


def _run(model, U0, Ud0, t_end, rtol=1e-9):
    problem = PipeDynamics3D(model) if isinstance(model, PipeModel3D) else PipeDynamics(model)
    stepper = Radau(problem, U0, Ud0, rtol=rtol)
    for _ in stepper.steps(t_end):
        pass
    return stepper


def test_planar_motion_follows_the_planar_solver():
    disc = FiniteElement(4, 2)
    params = Params(alpha=np.pi / 2, v=6.0, mu=0.005)
    q0 = _fit(disc, lambda x: 0.3 * np.sin(np.pi * x / 2))
    qd0 = _fit(disc, lambda x: -0.5 * x**2)
    planar = _run(PipeModel(disc, params), q0, qd0, 0.4)
    space = _run(PipeModel3D(disc, params), planar_state(q0), planar_state(qd0), 0.4)
    n = disc.n
    assert np.array_equal(space.q[n:], np.zeros(2 * n))
    assert np.abs(space.q[:n] - planar.q).max() < 1e-7 * np.abs(planar.q).max()
    assert np.abs(space.qdot[:n] - planar.qdot).max() < 1e-6 * np.abs(planar.qdot).max()


def test_mirror_symmetry_out_of_the_plane():
    disc = FiniteElement(3, 2)
    model = PipeModel3D(disc, Params(alpha=1.1, v=5.0, mu=0.01))
    n = disc.n
    U0 = np.concatenate(
        [_fit(disc, lambda x: 0.4 * x), _fit(disc, lambda x: 0.1 * x), 0 * _fit(disc, lambda x: x)]
    )
    Ud0 = np.concatenate(
        [0 * U0[:n], _fit(disc, lambda x: 0.3 * x**2), _fit(disc, lambda x: -0.2 * x)]
    )
    mirror = np.r_[np.ones(n), -np.ones(2 * n)]
    a = _run(model, U0, Ud0, 0.3, rtol=1e-7)
    b = _run(model, mirror * U0, mirror * Ud0, 0.3, rtol=1e-7)
    assert np.abs(b.q - mirror * a.q).max() < 1e-9 * np.abs(a.q).max()


def _tangent_field(model, U) -> np.ndarray:
    return model.fields(U).t[:, :, 0]


def test_hanging_pipe_is_isotropic():
    """At alpha = 0, the motion started in a turned plane is the planar motion turned about
    the vertical e_1: to the discretization error, which falls with the mesh."""
    phi = 0.9
    errors = []
    for n_el in (2, 4):
        disc = FiniteElement(n_el, 3)
        model = PipeModel3D(disc, Params(alpha=0.0, v=4.0, mu=0.01))
        n = disc.n
        f = _fit(disc, lambda x: 0.8 * np.sin(np.pi * x / 2))
        zero = np.zeros(n)
        # at the straight pipe dt/dtheta = e_2 and dt/db = -2 e_3
        plane = _run(model, np.zeros(3 * n), np.r_[f, zero, zero], 0.3)
        turned = _run(
            model, np.zeros(3 * n), np.r_[np.cos(phi) * f, zero, -0.5 * np.sin(phi) * f], 0.3
        )
        R = np.array([[1, 0, 0], [0, np.cos(phi), -np.sin(phi)], [0, np.sin(phi), np.cos(phi)]])
        expected = _tangent_field(model, plane.q) @ R.T
        got = _tangent_field(model, turned.q)
        assert np.abs(_tangent_field(model, plane.q)[:, 2]).max() == 0.0
        errors.append(np.abs(got - expected).max())
    assert errors[1] < errors[0] / 8, errors
    assert errors[1] < 1e-4, errors


def _balance(model, U0, Ud0, t_end, rtol):
    """(max |E - E0|, max |E - E0 + work of the non-conservative terms|, E0, stepper): the work
    integrated with the Radau weights on each step's stages (order 5, as the integrator)."""
    from fempipe.solvers.radau.tableau import A

    weights = A[-1]  # Radau IIA is stiffly accurate: the last row of A are the weights

    E0 = model.energy(U0, Ud0)
    stepper = Radau(PipeDynamics3D(model), U0, Ud0, rtol=rtol)
    work, drift, balance = 0.0, 0.0, 0.0
    for _, q, p in stepper.steps(t_end):
        rec = stepper.last
        powers = [
            sum(model.power_terms(*stage).values())
            for stage in zip(rec.Q, rec.P, rec.A, strict=True)
        ]
        work += rec.h * float(np.dot(weights, powers))
        E = model.energy(q, p)
        drift = max(drift, abs(E - E0))
        balance = max(balance, abs(E - E0 + work))
    return drift, balance, E0, stepper


def test_energy_is_conserved_without_flow_and_damping():
    """v = 0, mu = 0: the energy balance closes to the integration tolerance; the energy
    itself drifts only by the gauge's work, a discretization error that falls fast with h."""
    drifts = []
    for n_el in (2, 4):
        disc = FiniteElement(n_el, 3)
        model = PipeModel3D(disc, Params(alpha=0.5, v=0.0, mu=0.0, gamma=10.0))
        n = disc.n
        s = _fit(disc, lambda x: np.sin(np.pi * x / 2))
        Ud0 = np.r_[0.5 * s, np.zeros(n), -0.2 * s]
        drift, balance, E0, stepper = _balance(model, np.zeros(3 * n), Ud0, 0.1, 1e-8)
        assert np.abs(stepper.q[n:]).max() > 1e-3  # the motion left the plane
        assert balance < 1e-9 * E0, balance / E0
        drifts.append(drift / E0)
    print("relative energy drift on P3:2 and P3:4:", drifts)
    assert drifts[1] < drifts[0] / 16, drifts  # falls at least as h^4 (measured 92x here, 38x
    # from P3:4 to P3:8 over tau = 1, where it is 6.3e-8)


def test_power_balance_with_flow_and_damping():
    disc = FiniteElement(3, 3)
    model = PipeModel3D(disc, Params(alpha=1.2, v=3.0, mu=0.02, end_mass=0.2, external_damping=0.3))
    n = disc.n
    s = _fit(disc, lambda x: np.sin(np.pi * x / 2))
    drift, balance, E0, _ = _balance(
        model, np.zeros(3 * n), np.r_[0.4 * s, 0.1 * s, -0.3 * s], 0.2, 1e-9
    )
    assert drift > 1e-3 * E0  # the flow and the damping do work
    assert balance < 1e-8 * E0, balance / E0


def test_shooting_a_planar_cycle_in_3d_gives_the_planar_cycle():
    """The shooting on the 3-D model, from a planar cycle: the same period and tips, and
    the 3-D monodromy holds the planar multipliers."""
    from fempipe.analyses.limit_cycle import find_attractor, shoot

    disc = FiniteElement(3, 3)
    planar = PipeModel(disc, Params(alpha=np.pi / 2, v=10.0))
    att = find_attractor(planar)
    cycle = shoot(PipeDynamics(planar), att.cycle.q0, att.cycle.qdot0, att.cycle.period, rtol=1e-8)
    space = shoot(
        PipeDynamics3D(PipeModel3D(disc, planar.params)),
        planar_state(cycle.q0),
        planar_state(cycle.qdot0),
        cycle.period,
        rtol=1e-8,
    )
    assert space.period == pytest.approx(cycle.period, rel=1e-9)
    for key in ("eta_tip", "X_tip", "Z_tip"):
        assert space.tip[key] == pytest.approx(cycle.tip[key], abs=1e-6)
    assert space.tip["Y_tip"] == [0.0, 0.0]
    mu3 = space.floquet_multipliers
    for mu in cycle.floquet_multipliers[:3]:
        assert np.min(np.abs(mu3 - mu)) < 1e-5 * max(1.0, abs(mu))


def _first_order_eigenvalues(K, C, M) -> np.ndarray:
    n = K.shape[0]
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-np.linalg.solve(M, K), -np.linalg.solve(M, C)]])
    return np.linalg.eigvals(A)


def test_linearization_out_of_the_plane_is_the_out_of_plane_models():
    """About a planar static state the out-of-plane block of the 3-D Jacobians has the
    spectrum of the linear out-of-plane model (an independent derivation, checked against a
    strong-form solver in the validation): stiffness, inertia, Coriolis and the objective
    damping with its spin term, to the discretization error of each."""
    from fempipe.analyses.statics import solve_static

    errors = []
    for n_el in (4, 8):
        disc = FiniteElement(n_el, 3)
        params = Params(alpha=1.2, v=4.0, mu=0.05)
        planar = PipeModel(disc, params)
        q = solve_static(planar).q
        ref = _first_order_eigenvalues(*build_out_of_plane_model(planar).linearization(q))
        ref = ref[np.argsort(np.abs(ref))][:6]
        n = disc.n
        out = np.r_[n : 3 * n]
        blocks = [J[np.ix_(out, out)] for J in PipeModel3D(disc, params).jacobians(planar_state(q))]
        lam = _first_order_eigenvalues(*blocks)
        lam = lam[np.abs(lam + 75.0) > 40.0]  # the gauge's roots, near -50 and -100
        errors.append(max(np.min(np.abs(lam - r)) / abs(r) for r in ref))
    assert errors[1] < 1e-6 and errors[1] < errors[0] / 16, errors

"""The fast paths of the 3-D model against the plain ones they replace.

Batched stage Jacobians against one state at a time, dR/dv against differences
of the residual in v (exact: R is quadratic in v), the in-plane / out-of-plane
split of the integrator's sensitivity against the full one, and the Jacobians
of the reverse accumulation (:func:`fempipe.core.dual.pullback`) against a
closed form.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from fempipe.core.dual import Dual, matvec, pullback
from fempipe.model.discretization import FiniteElement
from fempipe.model.params import Params
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D, planar_state
from fempipe.solvers.radau import Radau

PARAMS = Params(alpha=0.7, v=3.0, mu=0.05, end_mass=0.3, external_damping=0.2)


def test_batched_stage_jacobians_equal_one_by_one():
    model = PipeModel3D(FiniteElement(3, 2), PARAMS)
    rng = np.random.default_rng(7)
    Q, P, A = rng.normal(scale=0.6, size=(3, 3, model.n))
    batch = model.jacobians(Q, P, A)
    for s in range(3):
        for k, J in enumerate(model.jacobians(Q[s], P[s], A[s])):
            assert np.abs(batch[k][s] - J).max() <= 1e-13 * np.abs(J).max(), (s, k)


def test_velocity_derivative_is_the_difference_quotient_in_v():
    model = PipeModel3D(FiniteElement(3, 2), PARAMS)
    rng = np.random.default_rng(8)
    Q, P, A = rng.normal(scale=0.6, size=(3, 2, model.n))
    v, dv = PARAMS.v, 1.0
    up = model.with_params(replace(PARAMS, v=v + dv)).residual(Q, P, A)
    down = model.with_params(replace(PARAMS, v=v - dv)).residual(Q, P, A)
    # R is quadratic in v: the central difference is exact up to round-off
    fd = (up - down) / (2 * dv)
    exact = PipeDynamics3D(model).parameter_derivative(Q, P, A)
    assert np.abs(exact - fd).max() < 1e-12 * np.abs(up).max()


def _sensitivity(model, U0, Ud0, split: bool):
    problem = PipeDynamics3D(model)
    if not split:
        problem.decoupled_blocks = None
    stepper = Radau(problem, U0, Ud0, h_fixed=2e-3, sensitivity=True, velocity_sensitivity=True)
    for _ in stepper.steps(8e-3):
        pass
    return stepper


def test_split_sensitivity_at_planar_states_equals_the_full_one():
    model = PipeModel3D(FiniteElement(3, 2), PARAMS)
    nt = model.n_theta
    rng = np.random.default_rng(9)
    q, qd = rng.normal(scale=0.5, size=(2, nt))
    split = _sensitivity(model, planar_state(q), planar_state(qd), True)
    full = _sensitivity(model, planar_state(q), planar_state(qd), False)
    assert split._split_sensitivity and not full._split_sensitivity
    S, F = split.sensitivity_matrix, full.sensitivity_matrix
    assert split.stats.steps == full.stats.steps
    assert np.abs(S - F).max() < 1e-11 * np.abs(F).max()
    dv, fv = split.velocity_sensitivity, full.velocity_sensitivity
    assert np.abs(dv - fv).max() < 1e-11 * np.abs(fv).max()
    # the full computation has exact zeros between the blocks too (mirror symmetry)
    plane = np.r_[0:nt, model.n : model.n + nt]
    out = np.setdiff1d(np.arange(2 * model.n), plane)
    assert not np.any(F[np.ix_(plane, out)]) and not np.any(S[np.ix_(out, plane)])


def test_split_is_not_used_away_from_planar_states():
    model = PipeModel3D(FiniteElement(3, 2), PARAMS)
    rng = np.random.default_rng(10)
    U0, Ud0 = rng.normal(scale=0.3, size=(2, model.n))
    split = _sensitivity(model, U0, Ud0, True)
    full = _sensitivity(model, U0, Ud0, False)
    assert not split._split_sensitivity
    assert np.array_equal(split.sensitivity_matrix, full.sensitivity_matrix)


def test_pullback_through_an_integral_matches_the_closed_form():
    # y(x) = sin(u(x)) * C[u^2](x) on 5 points, C a random lower-triangular matrix,
    # u = B U with a random basis B: dy/dU = cos(u) C[u^2] B + sin(u) C diag(2u) B.
    rng = np.random.default_rng(11)
    n, k = 5, 4
    B = rng.normal(size=(n, k))
    C = np.tril(rng.normal(size=(n, n)))
    U = rng.normal(size=k)
    u = B @ U
    x = Dual(u[:, None], np.ones((n, 1, 1)))  # value (n, S = 1), d/du at the point
    integral = (x * x).nonlocal_map(lambda f: C @ f, lambda g: C.T @ g)
    y = x.sin() * integral
    seed = np.eye(n)[:, None, None, :]  # (points, S, m = 1, R = n): the rows y_r
    W, G = pullback([(y, seed)], 1)
    assert G is None
    jac = W[:, 0, 0, :].T @ B  # sum over the points of d y_r / d u(q) B[q]
    expected = np.diag(np.cos(u) * (C @ u**2)) @ B + np.diag(np.sin(u)) @ C @ np.diag(2 * u) @ B
    assert np.allclose(jac, expected, rtol=1e-13, atol=1e-13)


def test_matvec_carries_the_derivatives_of_the_broadcast_product():
    # M v with M and v Duals carrying local derivatives and one integral term each (the
    # term on both: its parts add), against the sum over the broadcast product.
    rng = np.random.default_rng(5)
    n, S, L = 4, 2, 3
    base = Dual(rng.normal(size=(n, S)), rng.normal(size=(n, S, L)))
    term = base.nonlocal_map(lambda f: np.cumsum(f, axis=0), np.triu(np.ones((n, n))))
    ((t, identity),) = term.nl.items()

    def field(shape):
        x = Dual(rng.normal(size=shape), rng.normal(size=shape + (L,)))
        return x + term[(slice(None),) + (None,) * (len(shape) - 2)] * rng.normal(size=shape)

    M, v = field((n, 3, 3, S)), field((n, 3, S))
    got, want = matvec(M, v), (M * v[:, None]).sum(axis=2)
    assert np.allclose(got.val, want.val, rtol=1e-14, atol=1e-14)
    assert np.allclose(got.loc, want.loc, rtol=1e-14, atol=1e-14)
    assert set(got.nl) == set(want.nl) == {t}
    assert np.allclose(got.nl[t], want.nl[t], rtol=1e-14, atol=1e-14)
    # a plain matrix: the derivatives of v only
    got, want = matvec(M.val, v), (v[:, None] * M.val).sum(axis=2)
    assert np.allclose(got.loc, want.loc, rtol=1e-14, atol=1e-14)
    assert np.allclose(got.nl[t], want.nl[t], rtol=1e-14, atol=1e-14)


def test_space_cycle_benchmark_is_registered():
    from fempipe.bench import available
    from fempipe.bench.three_d import bench_space_cycle, bench_space_nonplanar_cycle

    assert available()["space_cycle"] is bench_space_cycle
    assert available()["space_nonplanar_cycle"] is bench_space_nonplanar_cycle


def test_whirl_verdict_keeps_a_multiplier_near_but_not_at_one():
    """At an axisymmetric alpha the verdict leaves out the rotation's second 1 only where there
    is one: a whirl (one trivial multiplier) with another multiplier 1.04 is unstable."""
    from fempipe.analyses.limit_cycle import largest_nontrivial

    assert largest_nontrivial([1.0, 1.0 - 1e-3, 0.5], True) == 0.5  # two 1s: the rotation moves it
    assert largest_nontrivial([1.0, 1.04, 0.5], True) == pytest.approx(1.04)  # a whirl
    assert largest_nontrivial([1.0, 1.0 - 1e-3, 1.2], True) == pytest.approx(1.2)
    assert largest_nontrivial([1.0, 1.0 - 1e-3, 0.5], False) == pytest.approx(1.0 - 1e-3)

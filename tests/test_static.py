"""Static large deformation (Eq. (31a)): convergence, limits, symmetry, continuation."""

import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel, PipeSI, compute_tip
from fempipe.analyses.statics import (
    NewtonError,
    continue_static,
    solve_path,
    solve_sagged,
    solve_static,
    switch_branch,
)
from fempipe.model.discretization import DEFAULT_FE, parse_discretization

#: Texier & Dorbolo's pipe (the paper's Section 3.1, Fig. 2(b)), with the paper's g = 9.8 m/s^2.
TEXIER = PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2)
TIP_KEYS = ("theta_tip", "eta_tip", "X_tip")


def tips(disc, params, q0=None):
    model = PipeModel(disc, params)
    sol = solve_static(model, q0=q0) if q0 is not None else solve_sagged(model)
    return np.array([compute_tip(disc, sol.q, params.alpha)[k] for k in TIP_KEYS])


@pytest.fixture(scope="module")
def texier_reference():
    """P3 on 128 elements: error ~ (1/8)^6 below P3:16's 7e-10, i.e. ~3e-15."""
    p = TEXIER.params(U=2.0)
    return p, tips(FiniteElement(128, 3), p)


# --------------------------------------------------------- convergence --
# Nodal superconvergence of 1-D Galerkin FE: the tip value and the functionals
# eta(1), X_g(1) converge as h^(2k) for P_k (the adjoint problem is smooth).
MESHES = {1: [16, 32, 64, 128], 2: [4, 8, 16, 32], 3: [2, 4, 8, 16]}


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_fe_convergence_order(degree, texier_reference):
    p, ref = texier_reference
    errs = np.array([np.abs(tips(FiniteElement(n, degree), p) - ref) for n in MESHES[degree]])
    h = 1.0 / np.array(MESHES[degree])
    for j, key in enumerate(TIP_KEYS):
        slope = np.polyfit(np.log(h), np.log(errs[:, j]), 1)[0]
        assert abs(slope - 2 * degree) < 0.3, (key, slope, errs[:, j])
    # Absolute accuracy on the finest mesh of the sequence.
    assert errs[-1].max() < {1: 2e-5, 2: 1e-7, 3: 1e-9}[degree]


def test_default_discretization_accuracy():
    """The default FE choice has tip errors below 1e-7 on the Texier-Dorbolo
    range U = 0..3 m/s and the paper's case (gamma = 18.9) at several alpha and v,
    measured against a 4x refined mesh."""
    coarse = parse_discretization()
    fine = coarse.refined(4)
    assert coarse.name == DEFAULT_FE
    cases = [TEXIER.params(U) for U in (0.0, 1.0, 2.0, 3.0)]
    cases += [Params(alpha=a, v=v) for a in (np.pi / 4, np.pi / 2, 3 * np.pi / 4) for v in (0, 4)]
    for p in cases:
        err = np.abs(tips(coarse, p) - tips(fine, p)).max()
        assert err < 1e-7, (p, err)


def test_modal_converges_algebraically_to_fe(texier_reference):
    """Sine modes force theta''(0) = 0, which the solution violates
    (theta''(0) = gamma sin(alpha) + v^2 sin(theta(1))), so the modal error
    decays algebraically; measured N^-3 here.  N = 64 agrees with FE to 1e-7."""
    p, ref = texier_reference
    Ns = np.array([8, 16, 32, 64])
    errs = np.array([np.abs(tips(Modal(N), p) - ref).max() for N in Ns])
    slope = np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert -3.3 < slope < -2.7, (slope, errs)
    assert errs[-1] < 1e-7
    # theta''(0) != 0 is the cause: the FE solution's curvature at the clamp.
    disc = FiniteElement(64, 3)
    sol = solve_static(PipeModel(disc, p))
    h = 1e-3
    th = disc.evaluate(sol.q, np.array([0.0, h, 2 * h]))
    curv0 = (th[2] - 2 * th[1] + th[0]) / h**2
    expected = p.gamma * np.sin(p.alpha) + p.v**2 * np.sin(ref[0])
    assert abs(curv0 - expected) < 1e-2 * abs(expected)


# -------------------------------------------------------------- limits --
def hanging(alpha, gamma):
    """Continuation in gamma on a clamp-graded mesh (boundary layer ~ gamma^-1/2)."""
    nodes = np.unique(np.r_[np.linspace(0, 1, 33), np.geomspace(1e-4, 1, 40), 0.0])
    disc = FiniteElement(nodes=nodes, degree=3)
    model = PipeModel(disc, Params(alpha=alpha, gamma=1.0, v=0.0))
    sol = solve_path(model, np.geomspace(1.0, gamma, 25), parameter="gamma")[-1]
    return compute_tip(disc, sol.q, alpha)


@pytest.mark.parametrize("alpha", [np.pi / 2, 3 * np.pi / 4])
def test_plumb_line_limit(alpha):
    """gamma -> infinity: the pipe hangs along gravity with a clamp boundary
    layer psi'' = gamma sin(psi), psi = theta + alpha.  Its first integral
    psi' = -2 sqrt(gamma) sin(psi/2) gives Z_tip = 2 sin(alpha/2) / sqrt(gamma)
    and 1 - X_tip = 2 (1 - cos(alpha/2)) / sqrt(gamma) at leading order, with
    relative corrections O(gamma^-1/2) from the (1 - xi) weight."""
    res = {}
    for g in (1e3, 1e4):
        t = hanging(alpha, g)
        res[g] = (
            t["Z_tip"] * np.sqrt(g) / (2 * np.sin(alpha / 2)) - 1,
            (1 - t["X_tip"]) * np.sqrt(g) / (2 * (1 - np.cos(alpha / 2))) - 1,
        )
    for j in range(2):
        assert abs(res[1e4][j]) < 0.03
        # The correction shrinks like gamma^-1/2: a factor ~3.2 per decade.
        ratio = res[1e3][j] / res[1e4][j]
        assert 2.5 < ratio < 4.0, ratio


def test_straight_equilibrium_when_gravity_along_pipe():
    """alpha = 0 and alpha = pi: theta = 0 solves Eq. (31a) for every v."""
    disc = FiniteElement(8, 2)
    for alpha in (0.0, np.pi):
        model = PipeModel(disc, Params(alpha=alpha, gamma=5.0, v=2.0))
        assert np.abs(model.static_residual(np.zeros(disc.n))).max() < 1e-14


@pytest.mark.parametrize("disc", [FiniteElement(8, 3), Modal(6)], ids=["fe", "modal"])
def test_static_symmetry_alpha_to_minus_alpha(disc):
    """Eq. (20) is odd under (theta, alpha) -> (-theta, -alpha)."""
    p = Params(alpha=0.8, gamma=18.9, v=3.0)
    q1 = solve_static(PipeModel(disc, p)).q
    q2 = solve_static(PipeModel(disc, Params(alpha=-0.8, gamma=18.9, v=3.0))).q
    assert np.abs(q1).max() > 0.1
    assert np.allclose(q2, -q1, atol=1e-10)


def test_standing_column_buckles_at_greenhill_load():
    """alpha = pi, v = 0: the heavy column buckles at gamma = 7.8373 (Greenhill
    1881; the first zero of J_{-1/3}(2/3 sqrt(gamma)))."""
    from scipy.optimize import brentq
    from scipy.special import jv

    gamma_cr = brentq(lambda g: jv(-1 / 3, 2 / 3 * np.sqrt(g)), 5, 10)
    assert abs(gamma_cr - 7.8373) < 1e-4
    disc = FiniteElement(16, 3)
    model = PipeModel(disc, Params(alpha=np.pi, gamma=0.0, mu=0.0, v=0.0))
    branch = continue_static(model, "gamma", stop=12.0, ds=0.5)
    bif = branch.bifurcations
    assert len(bif) == 1 and not branch.folds
    assert abs(bif[0].value - gamma_cr) < 1e-6
    # Both buckled branches: mirror images (theta -> -theta symmetry at alpha = pi).
    b1, b2 = switch_branch(model, bif[0], "gamma", stop=12.0)
    t1 = compute_tip(disc, b1.points[-1].q, np.pi)["theta_tip"]
    t2 = compute_tip(disc, b2.points[-1].q, np.pi)["theta_tip"]
    assert b1.points[-1].value == b2.points[-1].value == 12.0
    assert abs(t1) > 0.5 and abs(t1 + t2) < 1e-8
    assert np.allclose(b1.points[-1].q, -b2.points[-1].q, atol=1e-8)


def test_buckled_branches_fold_and_reconnect_in_v():
    """alpha = pi, gamma = 18.9: the buckled states, followed in v, pass a fold,
    return to the straight state at a pitchfork and leave as their mirror image.
    Independent checks: the pitchfork v is a root of det(dR/dq) on the straight
    state (Brent), the folds of the two mirror halves coincide, and the
    Jacobian is singular at the fold."""
    from scipy.optimize import brentq

    disc = FiniteElement(16, 3)
    p = Params(alpha=np.pi, gamma=18.9, v=0.0)
    model = PipeModel(disc, p)
    n = disc.n

    def det_sign_scaled(v):
        J = model.with_params(p.with_flow(v)).static_jacobian(np.zeros(n)).toarray()
        s, logdet = np.linalg.slogdet(J)
        return s * np.exp(logdet / n)

    straight = continue_static(model, "v", stop=6.0, ds=0.2)
    assert [s.kind for s in straight.special] == ["bifurcation"]
    v_pitch = straight.special[0].value
    v_ref = brentq(det_sign_scaled, v_pitch - 0.05, v_pitch + 0.05, xtol=1e-13)
    # Located to locate_tol = 1e-10 in arclength (= v on the straight branch); the
    # reference root is good to eps ||J|| / |d sigma_min / dv| ~ 1e-14.  Measured
    # 3.7e-14 on the Haswell, Sandybridge and Prescott kernels (1.9e-6 when the
    # locator stopped at the corrector's failure near the singular point).
    assert abs(v_pitch - v_ref) < 2e-10

    column = continue_static(model.with_params(Params(alpha=np.pi, gamma=0.0)), "gamma", stop=18.9)
    up, _ = switch_branch(model, column.bifurcations[0], "gamma", stop=18.9)
    buckled = up.points[-1]
    assert abs(compute_tip(disc, buckled.q, np.pi)["theta_tip"]) > 1.0
    branch = continue_static(model, "v", stop=6.0, q0=buckled.q, ds=0.2)
    assert branch.end_reason == "returned to v = 0"
    assert np.allclose(branch.points[-1].q, -buckled.q, atol=1e-7)
    folds = [s for s in branch.folds if abs(s.value - v_ref) > 1e-4]
    assert len(folds) == 2
    assert abs(folds[0].value - folds[1].value) < 1e-7
    assert folds[0].value > v_ref
    fold = folds[0]
    J = model.with_params(p.with_flow(fold.value)).static_jacobian(fold.q).toarray()
    sv = np.linalg.svd(J, compute_uv=False)
    assert sv[-1] < 1e-6 * sv[0]


def test_newton_failure_names_the_parameters():
    model = PipeModel(FiniteElement(4, 2), Params(alpha=np.pi / 2, gamma=18.9, v=2.0))
    with pytest.raises(NewtonError) as err:
        solve_static(model, max_iter=1)
    msg = str(err.value)
    assert "v=2" in msg and "gamma=18.9" in msg and "iterations" in msg
    assert err.value.iterations == 1 and err.value.residual > 0


def test_converged_state_balances_every_load_even_at_huge_v():
    """v = 1e100, alpha = pi/2: on the straight pipe the follower term vanishes
    and gravity, ||R|| ~ gamma, is wholly unbalanced.  Measured against the
    load coefficients 1 + gamma + v^2 = 1e200 that residual is round-off; a
    converged state must balance the gravity force it carries."""
    model = PipeModel(FiniteElement(16, 3), Params(alpha=np.pi / 2, gamma=18.9, v=1e100))
    straight = np.zeros(model.n)
    gravity = np.linalg.norm(model.gravity(model.fields(straight)))
    assert np.linalg.norm(model.static_residual(straight)) == pytest.approx(gravity)
    sol = solve_static(model)
    assert np.any(sol.q != 0.0)
    load = np.linalg.norm(model.gravity(model.fields(sol.q)))
    assert np.linalg.norm(model.static_residual(sol.q)) <= 1e-10 * load


@pytest.mark.parametrize("v", [1e160, 1e300])
def test_loads_beyond_floating_point_range_raise_newton_error(v):
    """v^2 overflows: a NewtonError naming v, not an OverflowError or a NaN state."""
    model = PipeModel(FiniteElement(4, 2), Params(alpha=np.pi / 2, v=v))
    with pytest.raises(NewtonError, match="not finite") as err:
        solve_static(model)
    assert f"v={v:.6g}" in str(err.value)
    with pytest.raises(NewtonError, match="not finite"):
        solve_path(model, [v])


def test_newton_error_is_a_solver_error():
    from fempipe.core.errors import SolverError

    assert issubclass(NewtonError, SolverError) and issubclass(NewtonError, RuntimeError)


def test_solve_path_matches_pointwise_solves():
    disc = FiniteElement(8, 2)
    model = PipeModel(disc, Params(alpha=np.pi / 3, gamma=10.0))
    vs = np.linspace(0, 6, 7)
    path = solve_path(model, vs)
    for v, sol in zip(vs, path, strict=True):
        direct = solve_static(model.with_params(model.params.with_flow(v)), q0=sol.q * 0.9)
        assert np.allclose(sol.q, direct.q, atol=1e-10)
        assert sol.params.v == v


def test_sagged_state_is_the_energy_minimum_near_vertical():
    """alpha = 160 deg, gamma = 18.9, v = 0: Newton from the straight pipe finds a
    nearly straight equilibrium (theta_tip ~ +0.93) that is a saddle of the
    potential energy; the gravity-loaded state leans over (theta_tip ~ -2.25)
    and is a minimum: lower energy and a positive definite Hessian."""
    disc = FiniteElement(16, 3)
    model = PipeModel(disc, Params(alpha=np.radians(160), gamma=18.9, v=0.0))
    loaded = solve_sagged(model)
    straightish = solve_static(model)
    assert loaded.q @ disc.tip < -2.0 and straightish.q @ disc.tip > 0.5
    assert model.potential_energy(loaded.q) < model.potential_energy(straightish.q) - 1.0
    H = model.static_jacobian(loaded.q).toarray()
    assert np.linalg.eigvalsh(0.5 * (H + H.T)).min() > 0
    H2 = model.static_jacobian(straightish.q).toarray()
    assert np.linalg.eigvalsh(0.5 * (H2 + H2.T)).min() < 0


def test_gravity_loading_iterations_are_reported_apart():
    """The Newton work of the gravity loading is counted on its own.

    The loaded state at gamma = 18.9 is reached by continuation in gamma
    (tens of Newton iterations); polishing it and solving a neighbouring state
    from it take a few.  Both counts must be visible separately.
    """
    model = PipeModel(FiniteElement(3, 8), Params(alpha=np.pi / 2, v=0.0))
    loaded = solve_sagged(model)
    assert loaded.loading_iterations > 5
    assert 0 <= loaded.iterations - loaded.loading_iterations <= 5
    d = loaded.to_dict()
    assert d["gravity_loading_iterations"] == loaded.loading_iterations
    assert d["newton_iterations"] == loaded.iterations
    near = solve_static(model.with_params(Params(alpha=np.pi / 2, v=0.5)), q0=loaded.q)
    assert near.loading_iterations == 0 and 0 < near.iterations <= 6

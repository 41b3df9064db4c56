"""Linear stability (Eqs. (31b)-(33)): matrices, spectra, critical velocities, events.

Every reference number comes from outside fempipe.analyses.stability: finite
differences of the residual, closed-form integrals of the sine modes, the
Euler-Bernoulli cantilever, Beck's and Greenhill's columns, Gregory &
Paidoussis' pipe, refined meshes, the other discretization, a brute-force
scan, an extended (Moore-Spence) fold system, symmetry.
"""

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import jv

from fempipe import FiniteElement, Modal, Params, PipeModel, solve_static
from fempipe.analyses.stability import (
    STABILITY_TOL,
    analyse_stability,
    cantilever_frequencies,
    compute_spectrum,
    find_critical_velocity,
    linearized_matrices,
    linearly_stable,
    map_stability,
    mode_shape,
    resolution,
    trace_root_locus,
)
from fempipe.analyses.statics import solve_sagged
from fempipe.model.kinematics import compute_shape

PAPER = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3}
P3_16 = FiniteElement(16, 3)


def upper(spec, mode):
    """The eigenvalue of ``mode`` with Im >= 0 (the paper's Re Omega >= 0)."""
    k = np.flatnonzero((spec.mode == mode) & (spec.lam.imag >= 0))
    return spec.lam[k[np.argmax(spec.lam[k].imag)]]


# ------------------------------------------------------------ matrices --
@pytest.mark.parametrize("disc", [FiniteElement(6, 2), Modal(5)], ids=["fe", "modal"])
def test_matrices_are_finite_differences_of_the_residual(disc):
    """K, C, M are dR/dq, dR/dq', dR/dq'' at a strongly deformed static state.

    Central differences with step 1e-6 have truncation error ~1e-12 times the
    third derivative and round-off ~1e-16/1e-6 times |R| ~ 30: 1e-7 relative
    to the matrix norm is two orders above both.
    """
    p = Params(alpha=np.pi / 3, v=4.0, **PAPER)
    model = PipeModel(disc, p)
    q = solve_sagged(model).q
    assert np.abs(q).max() > 0.5  # a large deformation, not the straight pipe
    K, C, M = linearized_matrices(model, q)
    n, h = disc.n, 1e-6
    z = np.zeros(n)
    fd = [np.empty((n, n)) for _ in range(3)]
    for j in range(n):
        e = np.zeros(n)
        e[j] = h
        fd[0][:, j] = (model.residual(q + e, z, z) - model.residual(q - e, z, z)) / (2 * h)
        fd[1][:, j] = (model.residual(q, e, z) - model.residual(q, -e, z)) / (2 * h)
        fd[2][:, j] = (model.residual(q, z, e) - model.residual(q, z, -e)) / (2 * h)
    for A, B in zip((K, C, M), fd, strict=True):
        assert np.abs(A - B).max() < 1e-7 * np.abs(B).max()


def test_matrices_match_closed_forms_at_the_straight_state():
    """Eqs. (33a)-(33c) at theta_s = 0 for the sine modes phi_r = sin(k_r xi), integrals by hand.

    M_ij = int_0^1 Phi_i Phi_j (Phi_r = int_0^s phi_r = (1 - cos k_r s)/k_r, since
    G(xi, r) = 1 - max(xi, r) = int 1[s > xi] 1[s > r] ds);
    C_ij = 2 v sqrt(beta) int phi_i (cos k_j xi - cos k_j)/k_j + mu k_i^2/2 delta_ij;
    K_ij = k_i^2/2 delta_ij + gamma cos(alpha) int (1 - xi) phi_i phi_j
           + v^2 (phi_j(1) int phi_i - int phi_i phi_j).
    All smooth integrals: 200-point Gauss-Legendre, exact to round-off, and
    independent of fempipe's quadrature and integration operators.
    """
    N = 4
    disc = Modal(N)
    p = Params(alpha=0.0, beta=0.3, gamma=7.0, mu=0.01, v=2.5)
    K, C, M = linearized_matrices(PipeModel(disc, p), np.zeros(N))
    x, w = np.polynomial.legendre.leggauss(200)
    x, w = 0.5 * (x + 1), 0.5 * w
    k = (2 * np.arange(1, N + 1) - 1) * np.pi / 2
    phi = np.sin(np.outer(x, k))
    Phi = (1 - np.cos(np.outer(x, k))) / k
    tail = (np.cos(np.outer(x, k)) - np.cos(k)) / k
    Mx = (Phi * w[:, None]).T @ Phi
    Cx = 2 * p.v * np.sqrt(p.beta) * (phi * w[:, None]).T @ tail + p.mu * np.diag(k**2 / 2)
    pp = (phi * w[:, None]).T @ phi
    Kx = (
        np.diag(k**2 / 2)
        + p.gamma * np.cos(p.alpha) * (phi * (w * (1 - x))[:, None]).T @ phi
        + p.v**2 * (np.outer(w @ phi, np.sin(k)) - pp)
    )
    for A, B in ((K, Kx), (C, Cx), (M, Mx)):
        assert np.abs(A - B).max() < 1e-12 * np.abs(B).max()


def test_fe_matrices_match_closed_forms_at_the_straight_state():
    """The same closed forms for P2 elements, integrated independently: the basis
    is sampled with scikit-fem's probes on 4 sub-cells per element with 6 Gauss
    points each (exact for the piecewise polynomials involved, degree <= 6), and
    Phi_i(s) = int_0^s phi_i is integrated exactly with a 6-point Gauss rule
    mapped onto [cell start, s].  Bending is scikit-fem's assembled K."""
    disc = FiniteElement(5, 2)
    n = disc.n
    p = Params(alpha=0.0, beta=0.3, gamma=7.0, mu=0.01, v=2.5)
    K, C, M = linearized_matrices(PipeModel(disc, p), np.zeros(n))
    g, gw = np.polynomial.legendre.leggauss(6)
    g, gw = 0.5 * (g + 1), 0.5 * gw
    edges = np.linspace(0, 1, 5 * 4 + 1)
    a, h = edges[:-1, None], np.diff(edges)[:, None]
    x, w = (a + h * g).ravel(), (h * gw).ravel()
    I = np.eye(n)
    phi = disc.evaluate(I, x)
    cell_int = (disc.evaluate(I, (a + h * g).ravel()) * w[:, None]).reshape(-1, 6, n).sum(axis=1)
    start = np.vstack([np.zeros(n), np.cumsum(cell_int, axis=0)])  # int_0^{edge}
    cell = np.repeat(np.arange(edges.size - 1), 6)
    part = np.array(
        [
            gw @ disc.evaluate(I, edges[c] + (s - edges[c]) * g) * (s - edges[c])
            for s, c in zip(x, cell, strict=True)
        ]
    )
    Phi = start[cell] + part
    total = start[-1]
    Kb = disc.K.toarray()
    Mx = (Phi * w[:, None]).T @ Phi
    Cx = 2 * p.v * np.sqrt(p.beta) * (phi * w[:, None]).T @ (total[None, :] - Phi) + p.mu * Kb
    pp = (phi * w[:, None]).T @ phi
    Kx = (
        Kb
        + p.gamma * np.cos(p.alpha) * (phi * (w * (1 - x))[:, None]).T @ phi
        + p.v**2 * (np.outer(w @ phi, disc.tip) - pp)
    )
    for A, B in ((K, Kx), (C, Cx), (M, Mx)):
        assert np.abs(A - B).max() < 1e-12 * np.abs(B).max()


# ------------------------------------------------------ classical limits --
def test_cantilever_frequency_equation():
    """beta_r of cos(beta) cosh(beta) = -1 (e.g. Blevins, Formulas for natural
    frequency and mode shape, Table 8-1: 1.87510407, 4.69409113, 7.85475744)."""
    beta = np.sqrt(cantilever_frequencies(3))
    assert np.allclose(beta, [1.87510407, 4.69409113, 7.85475744], atol=1e-8)


def test_clamped_free_beam_frequencies():
    """v = gamma = mu = 0: the Euler-Bernoulli cantilever, Im lambda = beta_r^2 =
    3.5160, 22.034, 61.697, Re lambda = 0.  P3:16 errors measured 1e-11, 5e-9,
    9e-8 (order h^6); the bound 1e-6 is ten times the largest of them."""
    spec = compute_spectrum(PipeModel(P3_16, Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0)))
    got = np.array([upper(spec, r).imag for r in (1, 2, 3)])
    exact = np.array([1.87510407, 4.69409113, 7.85475744]) ** 2
    assert np.abs(got / exact - 1).max() < 1e-6
    assert np.abs(spec.lam.real).max() < 1e-8 * np.abs(spec.lam).max()
    assert spec.stable


def test_beck_column_flutters_at_20_05():
    """beta = gamma = mu = 0 leaves the follower force v^2 alone: Beck's column
    (Beck 1952) flutters at v^2 = P L^2/EI = 20.05.  The literature gives four
    digits, so the bound is half a unit of the last one (2.5e-4 relative)."""
    res = find_critical_velocity(
        PipeModel(P3_16, Params(alpha=0.0, beta=0.0, gamma=0.0, mu=0.0)), 6.0
    )
    assert res.critical.type == "flutter"
    assert abs(res.v_cr**2 / 20.05 - 1) < 2.5e-4


def test_standing_column_buckles_at_greenhill_load():
    """alpha = pi, v = 0 (the straight column is static for every gamma): a real
    eigenvalue crosses zero at gamma = 7.8373, the first zero of
    J_{-1/3}(2/3 sqrt(gamma)) (Greenhill 1881).  Brent on the largest real part;
    P3:16 resolves the buckling mode to ~1e-9."""
    exact = brentq(lambda g: jv(-1.0 / 3.0, 2.0 / 3.0 * np.sqrt(g)), 5.0, 10.0, xtol=1e-14)
    q0 = np.zeros(P3_16.n)

    def max_real(gamma):
        p = Params(alpha=np.pi, beta=0.142, gamma=gamma, mu=5e-3, v=0.0)
        return compute_spectrum(PipeModel(P3_16, p), q0).max_real

    assert max_real(7.5) < 0 < max_real(8.2)
    gamma_cr = brentq(max_real, 7.5, 8.2, xtol=1e-12)
    assert abs(gamma_cr - exact) < 1e-7 * exact
    assert abs(exact - 7.8373) < 1e-4


def test_gregory_paidoussis_cantilever():
    """beta = 0.2, gamma = mu = 0: the horizontal (gravity-free) cantilever
    conveying fluid flutters in its second mode at v_cr ~ 5.6 (Gregory &
    Paidoussis 1966; Paidoussis, Fluid-Structure Interactions vol. 1, Fig. 3.10).
    The value is read off a figure: +-0.15 (about 3 %)."""
    res = find_critical_velocity(
        PipeModel(P3_16, Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0)), 8.0
    )
    assert res.critical.type == "flutter" and res.critical.mode == 2
    assert abs(res.v_cr - 5.6) < 0.15


# --------------------------------------------------------- convergence --
LOADED = Params(alpha=np.pi / 2, v=3.0, **PAPER)


@pytest.fixture(scope="module")
def reference_mode2():
    """Mode 2 at a sagged state (alpha = pi/2, v = 3) on P3:64 (error ~1e-11)."""
    return upper(compute_spectrum(PipeModel(FiniteElement(64, 3), LOADED)), 2)


MESHES = {1: [16, 32, 64, 128], 2: [4, 8, 16, 32], 3: [4, 8, 16, 32]}


@pytest.mark.parametrize("degree", [1, 2, 3])
def test_eigenvalue_convergence_order(degree, reference_mode2):
    """Eigenvalues (with the static state they linearize about) converge as
    h^(2k) for P_k.  Measured slopes 2.00, 3.97, 5.8 (P3 pre-asymptotic on the
    coarse meshes); bound +-0.35."""
    errs = [
        abs(
            upper(compute_spectrum(PipeModel(FiniteElement(n, degree), LOADED)), 2)
            - reference_mode2
        )
        for n in MESHES[degree]
    ]
    slope = np.polyfit(np.log(1.0 / np.array(MESHES[degree])), np.log(errs), 1)[0]
    assert abs(slope - 2 * degree) < 0.35, (slope, errs)


def test_modal_converges_to_fe(reference_mode2):
    """Sine modes converge algebraically (measured N^-3, the theta''(0) = 0
    defect); Richardson extrapolation of N = 32, 64 with that order agrees with
    the FE reference to 2e-6 relative (N = 64 alone: 2.5e-6)."""
    Ns = np.array([16, 32, 64])
    lams = np.array([upper(compute_spectrum(PipeModel(Modal(N), LOADED)), 2) for N in Ns])
    errs = np.abs(lams - reference_mode2)
    slope = np.polyfit(np.log(Ns), np.log(errs), 1)[0]
    assert -3.3 < slope < -2.7, (slope, errs)
    extrapolated = lams[-1] + (lams[-1] - lams[-2]) / 7.0
    assert abs(extrapolated - reference_mode2) < 2e-6 * abs(reference_mode2)


def test_default_discretization_vcr_accuracy():
    """The default P3:16 gives v_cr within 1e-6 (relative) of P3:32; measured
    2.5e-9 (P3: 8, 16, 32, 64 differ by 1e-6, 1.6e-8, 2.5e-10: order 6)."""
    p = Params(alpha=np.pi / 2, **PAPER)
    coarse = find_critical_velocity(PipeModel(P3_16, p), 10.0).v_cr
    fine = find_critical_velocity(PipeModel(FiniteElement(32, 3), p), 10.0).v_cr
    assert abs(coarse / fine - 1) < 1e-6


# ------------------------------------------------------------ symmetry --
@pytest.mark.parametrize("disc", [P3_16, Modal(4)], ids=["fe", "modal"])
def test_spectrum_symmetric_under_alpha_to_minus_alpha(disc):
    """(theta, alpha) -> (-theta, -alpha) maps states to states and leaves
    K, C, M unchanged (they depend on cos of the state): identical spectra."""
    a = compute_spectrum(PipeModel(disc, Params(alpha=1.0, v=4.0, **PAPER)))
    b = compute_spectrum(PipeModel(disc, Params(alpha=-1.0, v=4.0, **PAPER)))
    assert np.allclose(a.q, -b.q, atol=1e-10)
    assert np.array_equal(a.mode, b.mode)
    assert np.abs(a.lam - b.lam).max() < 1e-9 * np.abs(a.lam).max()


# ------------------------------------------------- resolved modes, filter --
def test_resolution_rule():
    """Modal N reproduces the cantilever within 5 % for N - 1 modes (the N-th
    is 8-9 % off); finite elements resolve more modes as the mesh is refined."""
    for N in (3, 4, 8):
        assert resolution(Modal(N)).n_resolved == N - 1
    n16, n32 = resolution(P3_16).n_resolved, resolution(FiniteElement(32, 3)).n_resolved
    assert 20 <= n16 < n32


@pytest.mark.parametrize(
    "n_elements, n_resolved",
    [(128, 150), pytest.param(256, 300, marks=pytest.mark.slow)],
    ids=["n=384", "n=768"],
)
def test_no_false_instability_fine_p3_at_rest(n_elements, n_resolved):
    """128 (256, slow) P3 elements, v = mu = 0: the exactly conservative spectrum
    (n = 384, 768; dense shift-invert) must come out stable.  The discarded top of
    the spectrum has Re lambda up to 5e-3 to 1.2e-2 (n = 384; ~0.5 at n = 768,
    |lambda| ~ 1e7) from round-off alone: that is what the resolution rule
    removes."""
    p = Params(alpha=np.pi / 2, beta=0.142, gamma=18.9, mu=0.0, v=0.0)
    spec = compute_spectrum(PipeModel(FiniteElement(n_elements, 3), p))
    assert spec.method == "shift-invert"
    assert spec.stable and spec.max_real_unresolved > 0.0
    assert spec.n_resolved_modes > n_resolved


@pytest.mark.parametrize(
    ("params", "v_cr"),
    [
        (Params(alpha=np.pi / 2, **PAPER), 6.2100952),
        (Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0), 5.5914044),
    ],
    ids=["paper-pi/2", "undamped-beta0.2"],
)
def test_fine_mesh_stable_below_unstable_above_vcr(params, v_cr):
    """128 P3 elements (n = 384) at 0.95 v_cr is stable and at 1.05 v_cr is not:
    the filter neither invents an instability nor hides the real one.  v_cr from
    P3:16 (test_default_discretization_vcr_accuracy, the G&P test).  The dense
    criterion of compute_spectrum() (linearly_stable(sparse=False), the same decision
    without the mode numbers' path back to v = 0) about the static state of P3:16
    projected onto the fine mesh and corrected by Newton there (continuing the
    fine mesh from v = 0 took 11-14 s of the test's 28)."""
    from fempipe.model.projection import project

    disc = FiniteElement(128, 3)
    for f, stable in ((0.95, True), (1.05, False)):
        p = params.with_flow(f * v_cr)
        q16 = solve_sagged(PipeModel(P3_16, p)).q
        model = PipeModel(disc, p)
        q = solve_static(model, q0=project(P3_16, q16, disc), tol=1e-12).q
        assert linearly_stable(model, q, sparse=False) is stable, f


# ------------------------------------------------------- v_cr, events --
def brute_force_vcr(model, v_max, dv=0.05):
    """Spectral abscissa on a grid, then bisection: a second, simple implementation."""
    q = solve_sagged(model.with_params(model.params.with_flow(0.0))).q

    def state(v, q0):
        return solve_static(model.with_params(model.params.with_flow(v)), q0=q0).q

    def unstable(v, q):
        return compute_spectrum(model.with_params(model.params.with_flow(v)), q).max_real > 0

    v = 0.0
    while v < v_max:
        q_next = state(v + dv, q)
        if unstable(v + dv, q_next):
            lo, hi, qlo = v, v + dv, q
            while hi - lo > 1e-11:
                mid = 0.5 * (lo + hi)
                qm = state(mid, qlo)
                lo, hi, qlo = (mid, hi, qm) if not unstable(mid, qm) else (lo, mid, qlo)
            return 0.5 * (lo + hi)
        v, q = v + dv, q_next
    return None


@pytest.mark.parametrize("alpha", [0.0, 3 * np.pi / 4])
def test_vcr_equals_brute_force(alpha):
    """v_cr located by tracking + Brent equals bisection on the sign of the
    largest real part (independent of tracking) to 1e-8."""
    model = PipeModel(P3_16, Params(alpha=alpha, **PAPER))
    res = find_critical_velocity(model, 10.0)
    assert res.critical.type == "flutter" and res.critical.mode == 2
    assert abs(res.v_cr - brute_force_vcr(model, 10.0)) < 1e-8


def moore_spence_fold(model, q, v, phi):
    """Solve R(q, v) = 0, J(q, v) phi = 0, l.phi = 1 by Newton with a
    finite-difference Jacobian: the fold as a regular root (independent of the
    continuation's bisection)."""
    n = q.size
    l = phi / (phi @ phi)

    def F(y):
        m = model.with_params(model.params.with_flow(y[n]))
        J = m.static_jacobian(y[:n])
        J = J.toarray() if hasattr(J, "toarray") else J
        return np.concatenate([m.static_residual(y[:n]), J @ y[n + 1 :], [l @ y[n + 1 :] - 1]])

    y = np.concatenate([q, [v], phi / (l @ phi)])
    for _ in range(6):
        r = F(y)
        D = np.empty((y.size, y.size))
        for k in range(y.size):
            e = np.zeros(y.size)
            e[k] = 1e-7
            D[:, k] = (F(y + e) - F(y - e)) / 2e-7
        y = y - np.linalg.solve(D, r)
    assert np.linalg.norm(F(y)) < 1e-10
    return y[n]


def test_alpha_pi_events_on_every_branch():
    """alpha = pi, gamma = 18.9 > 7.837: the straight column is unstable at
    v = 0 (divergence, mode 1), restabilizes at a subcritical pitchfork, then
    flutters in mode 2 (paper Sec. 4, Fig. 5(d)); the two buckled branches are
    mirror images with a fold.  Independent checks: the pitchfork is where
    det K^d = 0 on the straight state (Brent on det K^d); the fold solves the Moore-Spence system."""
    model = PipeModel(P3_16, Params(alpha=np.pi, **PAPER))
    res = analyse_stability(model, v_max=6.0)
    prim = next(b for b in res.branches if b.name == "primary")
    assert [(e.type, e.mode) for e in prim.events] == [
        ("divergence", 1),
        ("restabilization", 1),
        ("flutter", 2),
    ]
    assert prim.events[0].v == 0.0 and prim.events[0].at_start
    assert res.v_cr == 0.0 and res.v_flutter == prim.events[2].v

    def smallest(v):
        J = model.with_params(model.params.with_flow(v)).static_jacobian(np.zeros(P3_16.n))
        sign, logdet = np.linalg.slogdet(J.toarray())
        return sign * np.exp(logdet / P3_16.n)  # continuous, zero where K^d is singular

    v_pf = brentq(smallest, 2.5, 3.5, xtol=1e-13)
    assert abs(prim.events[1].v - v_pf) < 1e-9

    kids = [b for b in res.branches if b.parent == "primary"]
    assert len(kids) == 2
    for b in kids:
        assert abs(b.born_at - v_pf) < 1e-9
        assert [e.type for e in b.events] == ["fold"]
        assert b.events[0].stable_before != b.events[0].stable_after
    assert kids[0].events[0].v == pytest.approx(kids[1].events[0].v, abs=1e-10)
    assert np.allclose(kids[0].theta_tip, -kids[1].theta_tip, atol=1e-8)
    # The fold, independently.
    from fempipe.analyses.statics import continue_static, switch_branch

    br = continue_static(model, "v", stop=6.0, ds_max=0.1)
    b1, _ = switch_branch(
        model.with_params(model.params.with_flow(3.0)), br.bifurcations[0], "v", 6.0
    )
    f = b1.folds[0]
    J = model.with_params(model.params.with_flow(f.value)).static_jacobian(f.q).toarray()
    w, V = np.linalg.eig(J)
    v_fold = moore_spence_fold(model, f.q, f.value, V[:, np.argmin(np.abs(w))].real)
    assert abs(kids[0].events[0].v - v_fold) < 1e-9


def test_event_types_and_directions_along_a_folded_branch():
    """alpha = 179 deg: the favoured lean folds back (S-shaped branch, two folds)
    before the near-straight part flutters; v_cr is the first fold, where the
    loaded state stops existing."""
    model = PipeModel(P3_16, Params(alpha=np.radians(179.0), **PAPER))
    res = analyse_stability(model, v_max=6.0, follow_bifurcations=False)
    types = [e.type for e in res.branches[0].events]
    assert types.count("fold") == 2 and "flutter" in types
    assert res.critical.type == "fold"
    assert res.v_cr == max(res.branches[0].folds)
    assert res.v_flutter > res.v_cr


# --------------------------------------------------------- root loci --
def test_root_locus_tracks_modes_by_continuity():
    """Mode numbers follow their branch: on a coarse v grid (tracking inserts
    points where needed) they agree with a fine grid, and the mode crossing the
    axis is mode 2 near v_cr = 6.3337 (alpha = 0)."""
    model = PipeModel(P3_16, Params(alpha=0.0, **PAPER))
    coarse = trace_root_locus(model, np.linspace(0, 8, 9), n_modes=4)
    fine = trace_root_locus(model, np.linspace(0, 8, 81), n_modes=4)
    assert np.array_equal(coarse.modes, fine.modes)
    # Same eigenvalues under the same mode numbers (the two members of one
    # mode, a conjugate pair or two real roots, may come in either order).
    for m in set(fine.modes):
        cols = fine.modes == m
        a = np.sort_complex(fine.lam[::10][:, cols])
        b = np.sort_complex(coarse.lam[:, cols])
        assert np.abs(a - b).max() < 1e-8, m
    # Continuity on the fine grid: every step is small against the distance to
    # the nearest eigenvalue of another mode (so no two modes were swapped).
    lam, modes = fine.lam, fine.modes
    other = modes[:, None] != modes[None, :]
    gaps = np.where(other, np.abs(lam[:, :, None] - lam[:, None, :]), np.inf).min(axis=2)
    assert (np.abs(np.diff(lam, axis=0)) < 0.5 * gaps[:-1]).all()
    crossing = np.flatnonzero(np.diff(np.sign(fine.lam.real), axis=0).any(axis=0))
    assert set(fine.modes[crossing]) == {2}
    assert fine.stable[fine.v < 6.33].all() and not fine.stable[fine.v > 6.34].any()


def test_mode_shape_global_frame_is_the_derivative_of_the_centerline():
    """The global-frame mode shape equals a finite difference of
    kinematics.compute_shape along the mode (step 1e-6: error ~1e-12 + 1e-10)."""
    model = PipeModel(P3_16, Params(alpha=np.pi / 4, v=3.0, **PAPER))
    spec = compute_spectrum(model)
    k = int(np.flatnonzero(spec.mode == 2)[0])
    ms = mode_shape(P3_16, spec, k)
    assert abs(np.abs(ms.theta).max() - 1) < 1e-12
    j = int(np.argmax(np.abs(ms.theta)))
    assert abs(ms.theta[j].imag) < 1e-12 and ms.theta[j].real > 0
    x = spec.vectors[:, k] * (ms.theta[j] / P3_16.evaluate(spec.vectors[:, k], ms.xi)[j])
    h = 1e-6
    for part, d in (("real", x.real), ("imag", x.imag)):
        plus = compute_shape(P3_16, spec.q + h * d, np.pi / 4)
        minus = compute_shape(P3_16, spec.q - h * d, np.pi / 4)
        dX = (plus.X_g - minus.X_g) / (2 * h)
        dZ = (plus.Z_g - minus.Z_g) / (2 * h)
        assert np.allclose(getattr(ms.X_g, part), dX, atol=1e-8)
        assert np.allclose(getattr(ms.Z_g, part), dZ, atol=1e-8)


# -------------------------------------------------------------- sweeps --
def test_stability_map_serial_parallel_and_executor_agree():
    """The same points serially, on 2 processes and on a thread executor."""
    disc = Modal(4)
    kw = {"mu": 5e-3, "v_max": 10.0}
    alphas, curves = [0.0, np.pi / 2], [(0.142, 18.9), (0.3, 18.9)]
    serial = map_stability(disc, alphas, curves, **kw)
    par = map_stability(disc, alphas, curves, workers=2, **kw)
    seen = []
    with ThreadPoolExecutor(2) as ex:
        thr = map_stability(
            disc, alphas, curves, executor=ex, callback=lambda d, n, r: seen.append(d), **kw
        )
    assert sorted(seen) == [1, 2, 3, 4]
    # Each v_cr is Brent's to EVENT_XTOL = 1e-10: runs whose BLAS calls round
    # differently (thread count, buffer alignment) may stop anywhere within it;
    # a point computed for the wrong (alpha, beta) is off by > 0.1.
    for other in (par, thr):
        np.testing.assert_allclose(other.array(), serial.array(), rtol=0, atol=1e-9)
    assert serial.array()[1, 0] > serial.array()[0, 0]  # beta up, v_cr up (alpha = 0)


# ------------------------------------------------------------ bad input --
def test_bad_input_names_the_parameter():
    model = PipeModel(P3_16, Params(**PAPER))
    with pytest.raises(ValueError, match="v_min"):
        analyse_stability(model, v_max=1.0, v_min=2.0)
    with pytest.raises(ValueError, match="n_modes"):
        trace_root_locus(model, [0.0, 1.0], n_modes=0)
    with pytest.raises(ValueError, match="tolerance"):
        resolution(P3_16, tolerance=2.0)
    with pytest.raises(ValueError, match="resolves no mode"):
        compute_spectrum(PipeModel(FiniteElement(1, 1), Params(**PAPER)))
    assert STABILITY_TOL < 1e-6


def test_alpha_a_hair_below_pi_gives_the_events_of_pi(caplog):
    """alpha = 3.14159265 (pi - 3.6e-9, as typed): the near-straight branch steps over
    the imperfect pitchfork at the restabilization, where Brent finds no static state
    in the last ~1e-6 of its bracket.  The event is still reported, within that
    bracket of the perfect case's (v = 3.00372, Eq. (31b)), with a warning instead
    of a failure; the other events are those of alpha = pi."""
    import logging

    from fempipe.model.params import PAPER_CASE

    def events(alpha):
        m = PipeModel(FiniteElement(8, 3), Params(alpha=alpha, **PAPER_CASE))
        res = analyse_stability(m, 6.0, follow_bifurcations=False)
        return [(e.type, e.v) for e in res.events if e.branch == "primary"]

    exact = events(np.pi)
    with caplog.at_level(logging.WARNING, logger="fempipe.analyses.stability.branch_analysis"):
        hair = events(3.14159265)
    assert [t for t, _ in hair] == [t for t, _ in exact]
    assert "restabilization" in [t for t, _ in exact]
    for (t, v_hair), (_, v_exact) in zip(hair, exact, strict=True):
        assert abs(v_hair - v_exact) < (1e-5 if t == "restabilization" else 1e-6), t
    assert "imperfect bifurcation" in caplog.text

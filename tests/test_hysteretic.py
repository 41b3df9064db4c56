"""Hysteretic (structural) damping: EI -> EI (1 + i mu_h sgn(omega)) in the linear stability problem.

The references come from outside fempipe.analyses.stability: the undamped frequencies
of the same discretization and the exact clamped-free beam frequencies (at
rest the hysteretic roots are known in closed form), a beam-mode Galerkin
solution of the textbook lateral-displacement equation of the straight pipe
written below, Paidoussis' published theory for hanging cantilevers conveying
air, the dense criterion for the sparse one, the problem without mu_h for
what mu_h must not change (real roots, divergence, folds).
"""

import math
from dataclasses import replace

import numpy as np
import pytest
import scipy.linalg as sla
from clirun import run_json
from scipy.optimize import brentq

from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.stability import (
    analyse_stability,
    cantilever_frequencies,
    compute_spectrum,
    find_critical_velocity,
    growth_rate,
    linearly_stable,
    resolution,
)
from fempipe.analyses.statics import solve_sagged
from fempipe.cli import main

P3_16 = FiniteElement(16, 3)
PAPER = {"beta": 0.142, "gamma": 18.9}


# ----------------------------------------------------------------------------
# An independent reference: Paidoussis' beam-mode Galerkin of the straight pipe
# ----------------------------------------------------------------------------
def _beam_roots(n):
    """lambda_r of cos(lambda) cosh(lambda) = -1 (cos + sech = 0: no overflow)."""
    out = []
    for r in range(1, n + 1):
        c = (r - 0.5) * np.pi
        f = lambda x: np.cos(x) + 1.0 / np.cosh(x)  # noqa: E731
        out.append(brentq(f, c - 0.4, c + 0.4, xtol=1e-15) if c < 40 else c)
    return np.array(out)


def _beam_modes(lam, x):
    """phi_r, phi_r', phi_r'' of the clamped-free beam modes (rows) at the points x.

    phi = cosh(l x) - cos(l x) - s (sinh(l x) - sin(l x)), s = (cosh l + cos l)/(sinh l + sin l),
    written as ((1 - s) e^{l x} + (1 + s) e^{-l x})/2 - cos(l x) + s sin(l x) with
    (1 - s) e^{l x}/2 = (sin l - cos l - e^{-l}) e^{l (x - 1)} / (1 - e^{-2l} + 2 sin(l) e^{-l}),
    in which no exponential exceeds 1.
    """
    L, X = lam[:, None], x[None, :]
    em = np.exp(-L)
    den = 1.0 - em**2 + 2.0 * np.sin(L) * em
    s = 1.0 - 2.0 * em * (np.sin(L) - np.cos(L) - em) / den
    a = (np.sin(L) - np.cos(L) - em) * np.exp(L * (X - 1.0)) / den
    b = 0.5 * (1.0 + s) * np.exp(-L * X)
    phi = a + b - np.cos(L * X) + s * np.sin(L * X)
    d1 = L * (a - b + np.sin(L * X) + s * np.cos(L * X))
    d2 = L**2 * (a + b + np.cos(L * X) - s * np.sin(L * X))
    return phi, d1, d2


class BeamModeGalerkin:
    """The straight pipe's lateral motion eta(xi, tau) on N clamped-free beam modes.

    The textbook equation (Paidoussis, gravity along the pipe, hanging, with
    Kelvin-Voigt mu and the hysteretic loss factor for harmonic motion):

        (1 + mu d/dtau + i mu_h sgn(omega)) eta'''' + v^2 eta''
            - gamma [(1 - xi) eta']' + 2 sqrt(beta) v eta_dot' + eta_ddot = 0,

    eta(0) = eta'(0) = 0, eta''(1) = eta'''(1) = 0.  With eta = sum q_j phi_j
    and the Galerkin projection on phi_i: q'' + C q' + K q = 0 with
    K = (1 + i mu_h) diag(l^4) + v^2 B + gamma G, C = 2 sqrt(beta) v D + mu diag(l^4),
    B_ij = int phi_i phi_j'', D_ij = int phi_i phi_j', G_ij = int (1 - xi) phi_i' phi_j'
    (the gravity term integrated by parts; the boundary terms vanish), for the
    roots with Im lambda > 0; the others are their conjugates.  Integrals by
    composite Gauss-Legendre quadrature (400 cells of 12 points).
    """

    def __init__(self, n_modes: int) -> None:
        self.lam = _beam_roots(n_modes)
        g, w = np.polynomial.legendre.leggauss(12)
        e = np.linspace(0.0, 1.0, 401)
        h = 0.5 * (e[1:] - e[:-1])[:, None]
        x = (0.5 * (e[1:] + e[:-1])[:, None] + h * g).ravel()
        wx = (h * w).ravel()
        phi, d1, d2 = _beam_modes(self.lam, x)
        self.gram = (phi * wx) @ phi.T
        self.B = (phi * wx) @ d2.T
        self.D = (phi * wx) @ d1.T
        self.G = (d1 * wx * (1.0 - x)) @ d1.T

    def positive_roots(self, v, beta, gamma, mu, mu_h):
        """Roots with Im lambda > 0 of the positive-frequency problem.

        First-order form in the scaled state (S q, q'), S = diag(l^2): the
        pencil [[0, S], [-K S^-1, -C]] - lambda [[I, 0], [0, gram]] has norm
        ~ l_N^2 ~ 3.5e4 (not l_N^4 ~ 1.2e9 as with the state (q, q')), so QZ's
        absolute error eps ||pencil|| is 1e-11 on the lowest roots, not 2e-7.
        """
        n = self.lam.size
        L4 = np.diag(self.lam**4)
        S = self.lam**2
        K = (1.0 + 1j * mu_h) * L4 + v**2 * self.B + gamma * self.G
        C = 2.0 * math.sqrt(beta) * v * self.D + mu * L4
        Z, eye = np.zeros((n, n)), np.eye(n)
        A = np.block([[Z, np.diag(S)], [-K / S[None, :], -C]])
        lam = sla.eigvals(A, np.block([[eye, Z], [Z, self.gram]]))
        return lam[lam.imag > 0]

    def critical_velocity(self, beta, gamma, mu, mu_h, v_lo=4.0, v_hi=8.0):
        """The first v at which a root with Im lambda > 0 crosses to Re lambda > 0."""

        def f(v):
            return self.positive_roots(v, beta, gamma, mu, mu_h).real.max()

        vs = np.linspace(v_lo, v_hi, 17)
        fs = [f(v) for v in vs]
        k = next(i for i in range(1, vs.size) if fs[i - 1] < 0 < fs[i])
        return brentq(f, vs[k - 1], vs[k], xtol=1e-13)


@pytest.fixture(scope="module")
def galerkin():
    return BeamModeGalerkin(60)


def test_beam_mode_reference_is_the_classical_cantilever(galerkin):
    """The helper itself: orthonormal modes, and at v = gamma = mu = 0 the roots
    i l_r^2 sqrt(1 + i mu_h) of the hysteretic beam.  QZ round-off: eps times the
    scaled pencil's norm l_60^2 ~ 3.5e4 over |lambda_1| = 3.5, 2e-12 (measured
    0.6-1.2e-13 on the Haswell, Sandybridge, Prescott kernels; 1.3e-11 to 1.1e-7
    with the unscaled pencil of norm l_60^4 ~ 1e9)."""
    assert np.abs(galerkin.gram - np.eye(galerkin.lam.size)).max() < 1e-12
    roots = galerkin.positive_roots(0.0, 0.2, 0.0, 0.0, 0.03)
    roots = roots[np.argsort(roots.imag)][:5]
    exact = 1j * galerkin.lam[:5] ** 2 * np.sqrt(1 + 0.03j)
    assert np.abs(roots / exact - 1).max() < 1e-9


# ----------------------------------------------------------------------------
# At rest: closed forms
# ----------------------------------------------------------------------------
def _at_rest(disc, mu_h, mu=0.0):
    model = PipeModel(disc, Params(alpha=0.0, beta=0.2, gamma=0.0, mu=mu, hysteretic_damping=mu_h))
    return compute_spectrum(model, np.zeros(disc.n))


@pytest.mark.parametrize(
    "disc", [FiniteElement(32, 3), Modal(8), Modal(10, basis="beam")], ids=lambda d: d.name
)
def test_cantilever_at_rest_roots_are_the_undamped_ones_times_one_plus_i_mu_h(disc):
    """v = gamma = mu = 0: K^d is the bending matrix alone, so every resolved root
    obeys lambda^2 = -omega_r^2 (1 + i mu_h sgn(Im lambda)), omega_r the undamped
    frequencies of the same discretization (the roots i omega_r without mu_h).
    Measured 3.7e-10 relative at most (QZ round-off of the top resolved modes of
    P3:32; the symmetric eigensolver's omega_1 of the canonical modes is itself
    1.8e-8 off there, eps ||K|| / omega_1^2, so it is not the reference)."""
    mu_h = 0.03
    spec = _at_rest(disc, mu_h)
    plain = _at_rest(disc, 0.0)
    assert np.array_equal(spec.mode, plain.mode)
    assert np.abs(plain.lam.real).max() < 1e-8 * np.abs(plain.lam).max()
    omega = np.abs(plain.lam)
    sgn = np.sign(spec.lam.imag)
    assert np.all(sgn != 0) and spec.lam.size == 2 * resolution(disc).n_resolved
    expected = -(omega**2) * (1 + 1j * mu_h * sgn)
    assert np.abs(spec.lam**2 / expected - 1).max() < 1e-8
    assert np.all(spec.lam.real < 0)  # damped: Re lambda = -mu_h omega / 2 to first order
    # the negative-frequency half is the conjugate of the positive one, mode by mode
    # (exactly: hysteretic_roots conjugates the continued half, it does not recompute it)
    up, lo = spec.lam[sgn > 0], spec.lam[sgn < 0]
    assert np.array_equal(spec.mode[sgn > 0], spec.mode[sgn < 0])
    assert np.array_equal(lo, up.conj())


@pytest.mark.parametrize("disc", [FiniteElement(64, 3), Modal(12, basis="beam")], ids=str)
def test_cantilever_at_rest_against_the_exact_beam_frequencies(disc):
    """Converged discretizations: lambda^2 = -beta_r^4 (1 + i mu_h) with beta_r the
    exact clamped-free roots (cos beta cosh beta = -1), to 1e-8 for the modes
    converged to that level (P3:64: modes 1-4; the beam basis: all twelve)."""
    mu_h = 0.05
    spec = _at_rest(disc, mu_h)
    upper = spec.lam.imag > 0
    lam, mode = spec.lam[upper], spec.mode[upper]
    keep = mode <= (4 if isinstance(disc, FiniteElement) else 12)
    exact = cantilever_frequencies(12)[mode[keep] - 1]
    assert keep.sum() == (4 if isinstance(disc, FiniteElement) else 12)
    assert np.abs(lam[keep] ** 2 / (-(exact**2) * (1 + 1j * mu_h)) - 1).max() < 1e-8


def test_kelvin_voigt_and_hysteretic_at_rest():
    """mu = 5e-3 as well: C^d = mu K, so each canonical mode has
    lambda^2 + mu omega^2 lambda + omega^2 (1 + i mu_h) = 0 while it oscillates
    (the root with Im > 0, and its conjugate); modes 7 and up are overdamped
    (mu omega > 2): real roots, which mu_h leaves exactly as they are."""
    mu, mu_h = 5e-3, 0.02
    spec = _at_rest(P3_16, mu_h, mu)
    plain = _at_rest(P3_16, 0.0, mu)
    omega = resolution(P3_16).frequencies[spec.mode - 1]
    osc = mu * omega < 2.0
    assert osc.sum() == 12 and (~osc).sum() > 20
    w = omega[osc]
    disc = np.sqrt((mu * w**2) ** 2 - 4 * w**2 * (1 + 1j * mu_h) + 0j)
    roots = np.stack([(-mu * w**2 + disc) / 2, (-mu * w**2 - disc) / 2])
    upper = roots[np.argmax(roots.imag, axis=0), np.arange(w.size)]
    lam = spec.lam[osc]
    expected = np.where(lam.imag > 0, upper, upper.conj())
    assert np.abs(lam / expected - 1).max() < 1e-8
    real = spec.lam[~osc]
    assert np.all(real.imag == 0)
    # Kept, not continued: the roots of the real problem, from a second QZ run on
    # the same matrices (equal to its round-off, eps ||pencil||; continuing them
    # through the complex problem would move them by ~mu_h |lambda|).
    np.testing.assert_allclose(
        np.sort(real.real),
        np.sort(plain.lam[plain.lam.imag == 0].real),
        rtol=0,
        atol=1e-12 * np.abs(plain.lam).max(),
    )


# ----------------------------------------------------------------------------
# With flow: the straight pipe against the classical computation
# ----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("beta", "gamma", "mu"),
    [(0.2, 0.0, 0.0), (0.142, 18.9, 0.0), (0.142, 18.9, 5e-3)],
    ids=["gravity-free", "hanging", "hanging-kelvin-voigt"],
)
def test_vcr_of_the_straight_pipe_against_the_beam_mode_galerkin(galerkin, beta, gamma, mu):
    """v_cr with mu_h = 0.01 (alpha = 0: the straight state, gravity along the
    pipe) on P3:16 against the 60-mode Galerkin of the lateral-displacement
    equation: 1e-6 relative (measured 1.7e-8 to 3.0e-8, the Galerkin's own
    N^-4 truncation).  Applying mu_h to the gravity stiffness too would move the
    hanging v_cr by 1.3e-2; without mu_h it is 3e-2 lower."""
    mu_h = 0.01
    ref = galerkin.critical_velocity(beta, gamma, mu, mu_h)
    res = find_critical_velocity(
        PipeModel(P3_16, Params(alpha=0.0, beta=beta, gamma=gamma, mu=mu, hysteretic_damping=mu_h)),
        10.0,
    )
    assert res.critical.type == "flutter" and res.critical.mode == 2
    assert abs(res.v_cr / ref - 1) < 1e-6, (res.v_cr, ref)
    # the located crossing is a root of the reference at Re lambda = 0
    roots = galerkin.positive_roots(res.v_cr, beta, gamma, mu, mu_h)
    k = np.argmax(roots.real)
    assert abs(roots[k].imag / res.critical.frequency - 1) < 1e-6


@pytest.mark.parametrize(
    ("beta", "gamma", "mu_h", "u_cf", "omega_cf"),
    [(2.03e-3, 42.4, 0.0, 5.62, 19.5), (2.03e-3, 42.4, 0.02, 5.79, 18.1)],
)
def test_paidoussis_hanging_cantilevers_conveying_air(beta, gamma, mu_h, u_cf, omega_cf):
    """Paidoussis, Fluid-Structure Interactions vol. 1 (1998), Table 3.4, p. 143
    (theory of Paidoussis 1970, hanging cantilevers conveying air, mu the
    hysteretic loss factor): u_cf and omega_cf within half a unit of the printed
    digit.  The table's other row (beta = 0.23e-3, gamma = 61.1) is not
    reproduced by fempipe either (u_cf 6.1447 and 6.3931, omega_cf 21.29 and
    18.43 for mu = 0 and 0.02, against 6.15, 6.33, 21.3, 19.7 printed); the
    classical solver of fempipe.validation.classical finds the same."""
    p = Params(alpha=0.0, beta=beta, gamma=gamma, mu=0.0, hysteretic_damping=mu_h)
    res = find_critical_velocity(PipeModel(P3_16, p), 10.0)
    assert res.critical.type == "flutter"
    assert abs(res.v_cr - u_cf) <= 0.005, res.v_cr
    assert abs(res.critical.frequency - omega_cf) <= 0.05, res.critical.frequency


# ----------------------------------------------------------------------------
# What mu_h must not change; events
# ----------------------------------------------------------------------------
def test_real_roots_and_mode_numbers_are_those_without_mu_h():
    """The standing column (alpha = pi, gamma = 18.9 > 7.84) diverges at v = 0: its
    real roots (sgn 0) are the same with mu_h; the complex pairs are damped and
    conjugate-symmetric; mode numbers (canonical at v = 0) are the same."""
    q = np.zeros(P3_16.n)
    a = compute_spectrum(PipeModel(P3_16, Params(alpha=np.pi, **PAPER)), q)
    b = compute_spectrum(PipeModel(P3_16, Params(alpha=np.pi, hysteretic_damping=0.05, **PAPER)), q)
    assert np.array_equal(a.mode, b.mode)
    real = a.lam.imag == 0
    assert real.sum() >= 2 and a.max_real > 4
    # the real roots of the problem without mu_h, kept (a second QZ run: its round-off)
    np.testing.assert_allclose(b.lam[real], a.lam[real], rtol=0, atol=1e-12 * np.abs(a.lam).max())
    assert np.all(b.lam[~real].real < a.lam[~real].real)
    up = b.lam.imag > 0  # the lower half is the upper one conjugated (not recomputed): exact
    assert np.array_equal(np.sort_complex(b.lam[up].conj()), np.sort_complex(b.lam[b.lam.imag < 0]))


def test_every_positive_frequency_root_solves_its_problem():
    """A deformed, flowing state with Kelvin-Voigt damping (alpha = pi/2, v = 3,
    mu = 5e-3, mu_h = 0.01).  Each reported root with Im lambda > 0 is a root of
    the positive-frequency problem, det(lambda^2 M + lambda C + K + i mu_h K_b) = 0,
    or, if kept as it is, of the problem without mu_h: smallest over largest
    singular value below 1e-12 (measured 1e-15).  The kept ones are the nearly
    real Kelvin-Voigt roots near -1/mu = -200 that the Coriolis force pairs up
    (|Im lambda| < 0.05): the loss would move them by -i mu_h / mu = -0.02 i,
    across the real axis; the oscillating modes 1-6 all solve the first problem."""
    from fempipe.analyses.stability import linearized_matrices

    mu_h = 0.01
    model = PipeModel(
        P3_16, Params(alpha=np.pi / 2, mu=5e-3, v=3.0, hysteretic_damping=mu_h, **PAPER)
    )
    q = solve_sagged(model).q
    spec = compute_spectrum(model, q)
    K, C, M = linearized_matrices(model, q)
    Kb = P3_16.K.toarray()

    def residual(lam, stiffness):
        sv = sla.svdvals(lam**2 * M + lam * C + stiffness)
        return sv[-1] / sv[0]

    kept = []
    for lam, mode in zip(spec.lam, spec.mode, strict=True):
        if lam.imag <= 0:
            continue
        r_plus, r_0 = residual(lam, K + 1j * mu_h * Kb), residual(lam, K)
        assert min(r_plus, r_0) < 1e-12, (mode, lam, r_plus, r_0)
        if r_0 < r_plus:
            kept.append(lam)
        else:
            assert mode <= 6 or lam.real < -0.5 * abs(lam)
    assert set(range(1, 7)) <= set(spec.mode[spec.lam.imag > 0].tolist())
    assert len(kept) >= 5
    assert all(abs(x + 200) < 1 and x.imag < 0.05 for x in kept)


def test_events_divergence_and_folds_stay_flutter_moves():
    """alpha = pi, v <= 6: the divergence at v = 0, the restabilization and the folds
    of the buckled branches are real-root events (to 1e-9 the same with mu_h =
    0.05); the flutter of mode 2 is located as usual (Re lambda of the tracked
    root through 0) and moves; just below and above it the spectrum says stable
    and unstable."""
    base = Params(alpha=np.pi, **PAPER)
    a = analyse_stability(PipeModel(P3_16, base), 6.0)
    hyst = replace(base, hysteretic_damping=0.05)
    b = analyse_stability(PipeModel(P3_16, hyst), 6.0)
    key = [(e.branch, e.type, e.mode) for e in a.events]
    assert key == [(e.branch, e.type, e.mode) for e in b.events]
    for ea, eb in zip(a.events, b.events, strict=True):
        if ea.type == "flutter":
            assert eb.v - ea.v > 0.05
            flutter = eb
        else:
            assert abs(ea.v - eb.v) < 1e-9
    model = PipeModel(P3_16, replace(hyst, v=flutter.v - 1e-6))
    below = compute_spectrum(model, solve_sagged(model).q)
    model = PipeModel(P3_16, replace(hyst, v=flutter.v + 1e-6))
    above = compute_spectrum(model, solve_sagged(model).q)
    assert below.stable and not above.stable
    assert above.mode[above.unstable].tolist() == [2, 2]


# ----------------------------------------------------------------------------
# The stability criterion: dense and sparse
# ----------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("params", "mu_h", "stable_without", "stable_with"),
    [
        # stabilizing: the hanging paper pipe between v_cr = 6.3337 and 6.4446
        (Params(alpha=0.0, mu=5e-3, v=6.4, **PAPER), 0.05, False, True),
        # destabilizing: beta = 0.65, where damping is known to destabilize
        (Params(alpha=0.0, beta=0.65, gamma=10.0, mu=0.0, v=12.0), 0.1, True, False),
        (Params(alpha=np.pi / 2, mu=5e-3, v=3.0, **PAPER), 0.05, True, True),
        (Params(alpha=np.pi, mu=5e-3, v=1.0, **PAPER), 0.05, False, False),
    ],
    ids=["stabilized", "destabilized", "deformed", "diverging"],
)
def test_sparse_criterion_decides_as_the_dense_one(params, mu_h, stable_without, stable_with):
    """P3:80 (n = 240, above the dense limit): the sparse shift-invert path with
    mu_h decides by itself (no fallback) and as the dense criterion, and mu_h
    changes the decision where it should."""
    from fempipe.analyses.stability.criterion import _DENSE, _sparse_stable

    disc = FiniteElement(80, 3)
    model = PipeModel(disc, params)
    q = solve_sagged(model).q
    assert linearly_stable(model, q, sparse=False) is stable_without
    hyst = model.with_params(replace(params, hysteretic_damping=mu_h))
    dense = linearly_stable(hyst, q, sparse=False)
    cheap = _sparse_stable(hyst, q, 0.05)
    assert cheap is not _DENSE
    assert cheap is dense is stable_with
    assert linearly_stable(hyst, q) is stable_with  # the default path for this n


@pytest.mark.parametrize("disc", [P3_16, Modal(6, basis="beam")], ids=lambda d: d.name)
def test_linearly_stable_and_growth_rate_are_the_spectrum_criterion(disc):
    """The criterion of fempipe static's flag and of the attractor finder's equilibrium
    test, with mu_h: the decision and the growth rate of spectrum."""
    for v, stable in ((6.4, True), (7.0, False)):
        model = PipeModel(disc, Params(alpha=0.0, mu=5e-3, v=v, hysteretic_damping=0.05, **PAPER))
        q = solve_sagged(model).q
        spec = compute_spectrum(model, q)
        assert spec.stable is stable
        assert linearly_stable(model, q) is stable
        assert growth_rate(model, q) == pytest.approx(spec.max_real, rel=1e-9, abs=1e-12)


# ----------------------------------------------------------------------------
# Time domain: refused
# ----------------------------------------------------------------------------
def test_time_domain_refuses_hysteretic_damping():
    from fempipe.analyses.bifurcation import compute_bifurcation_diagram, sweep
    from fempipe.analyses.dynamics import simulate
    from fempipe.analyses.limit_cycle import find_attractor, shoot
    from fempipe.model.dynamics_problem import PipeDynamics

    disc = Modal(4)
    model = PipeModel(disc, Params(v=8.0, hysteretic_damping=0.1))
    q = np.zeros(disc.n)
    calls = [
        lambda: simulate(model, q, None, 1.0),
        lambda: PipeDynamics(model),
        lambda: shoot(PipeDynamics(model), q, q, 1.0),
        lambda: find_attractor(model),
        lambda: sweep(model, [8.0]),
        lambda: compute_bifurcation_diagram(model, [8.0]),
    ]
    for call in calls:
        with pytest.raises(ValueError, match="hysteretic damping .* no time-domain meaning"):
            call()


# ----------------------------------------------------------------------------
# Command line
# ----------------------------------------------------------------------------


def test_cli_critical(capsys):
    argv = ["critical", "--alpha", "pi/2", "--v", "0,9", "--modal", "4", "--json", "--quiet"]
    d = run_json(capsys, [*argv, "--hysteretic-damping", "0.01"])
    plain = run_json(capsys, argv)
    assert d["params"]["hysteretic_damping"] == 0.01
    lib = find_critical_velocity(
        PipeModel(Modal(4), Params(alpha=np.pi / 2, hysteretic_damping=0.01, **PAPER)), 9.0
    )
    assert d["v_cr_in_plane"] == pytest.approx(lib.v_cr, abs=1e-12)
    assert d["v_cr_in_plane"] - plain["v_cr_in_plane"] > 1e-3
    # the loss acts on the out-of-plane bending too
    assert d["v_cr_out_of_plane"] - plain["v_cr_out_of_plane"] > 1e-3


def test_cli_spectrum(capsys):
    argv = ["spectrum", "--v", "0,3", "--fe", "P2:4", "--json", "--quiet"]
    d = run_json(capsys, [*argv, "--hysteretic-damping", "0.05"])
    assert d["params"]["hysteretic_damping"] == 0.05
    model = PipeModel(FiniteElement(4, 2), Params(alpha=0.0, v=3.0, hysteretic_damping=0.05))
    spec = compute_spectrum(model, solve_sagged(model).q)
    got = [complex(e["re"], e["im"]) for e in d["points"][1]["eigenvalues"]]
    ref = spec.lam[np.isin(spec.mode, d["modes"])]
    assert np.abs(np.sort_complex(np.array(got)) - np.sort_complex(ref)).max() < 1e-9
    plain = run_json(capsys, argv)
    assert d["points"][1]["max_real"] < plain["points"][1]["max_real"]


def test_cli_stability_map(capsys):
    argv = ["stability-map", "--alphas", "0,pi/2", "--v", "0,9", "--modal", "4", "--json"]
    d = run_json(capsys, [*argv, "--quiet", "--hysteretic-damping", "0.01"])
    assert d["hysteretic_damping"] == 0.01
    lib = find_critical_velocity(
        PipeModel(Modal(4), Params(alpha=0.0, hysteretic_damping=0.01, **PAPER)), 9.0, ds_max=0.2
    )
    assert d["points"][0]["v_cr"] == pytest.approx(lib.v_cr, abs=1e-9)


def test_cli_static_stable_flag(capsys):
    """fempipe static's stable flag decides with mu_h: the hanging paper pipe at
    v = 6.4 flutters without it and is stable with mu_h = 0.05."""
    argv = ["static", "--alpha", "0", "--v", "6.4", "--json", "--quiet"]
    assert run_json(capsys, argv)["points"][0]["stable"] is False
    d = run_json(capsys, [*argv, "--hysteretic-damping", "0.05"])
    assert d["points"][0]["stable"] is True and d["params"]["hysteretic_damping"] == 0.05


@pytest.mark.parametrize("command", ["simulate", "bifurcation"])
def test_cli_time_domain_refuses_the_option(capsys, command):
    argv = [command, "--v", "8", "--modal", "4", "--hysteretic-damping", "0.1", "--quiet"]
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--hysteretic-damping" in err[0]

"""The classical linear solver of fempipe.validation.classical checks itself.

Every reference here is printed in the literature or a closed form solved
independently of the solver (Bessel functions, transcendental frequency
equations, the roots of a scalar quadratic): the beam functions and
Paidoussis' integrals, Beck's column, Gregory & Paidoussis' cantilever,
Blevins' tip-mass cantilever, Greenhill's column and its version with a top
load, Chen's tip-spring divergence, Plaut & Infante's externally damped Beck
column, the hysteretic beam, and Paidoussis' hanging cantilevers conveying
air.  The two discretizations (Paidoussis' beam-mode Galerkin and the
Legendre spectral elements) check each other where no closed form exists.
"""

import numpy as np
import pytest
from scipy.optimize import brentq

from fempipe.model.params import Params
from fempipe.validation.classical import (
    BeamGalerkin,
    StraightPipe,
    beam_mode_values,
    cantilever_roots,
    critical_velocity,
    eigenvalues,
    heavy_column_buckling,
    large_damping_limit,
    spectral_abscissa,
    stiffness_roots,
    tip_mass_frequencies,
    tip_spring_divergence,
)
from fempipe.validation.classical_galerkin import beam_mode_coefficients

LEG = {"method": "legendre", "n": 16}


def upper(lam, k):
    """The k-th eigenvalue (0-based) with Im > 0, by frequency."""
    up = lam[lam.imag > 1e-9]
    return up[np.argsort(up.imag)][k]


# --------------------------------------------------------------- beam modes --
def test_cantilever_roots():
    """cos l cosh l = -1: 1.87510407, 4.69409113, 7.85475744, 10.99554073
    (Blevins 1979, Table 8-1); lambda_r -> (2r - 1) pi / 2 to 1e-15 from r = 12."""
    lam = cantilever_roots(40)
    assert np.allclose(lam[:4], [1.87510407, 4.69409113, 7.85475744, 10.99554073], atol=5e-9)
    r = np.arange(12, 41)
    assert np.abs(lam[11:] - (2 * r - 1) * np.pi / 2).max() < 1e-12


def test_beam_modes_are_the_textbook_functions():
    """The overflow-free form equals cosh - cos - s (sinh - sin) (and its second
    derivative) where the textbook form is still accurate (lambda < 17), they
    are orthonormal and |phi_r(1)| = 2 (Paidoussis 1998, App. B)."""
    n, x = 5, np.linspace(0, 1, 11)[:, None]
    lam = cantilever_roots(n)
    s = (np.cosh(lam) + np.cos(lam)) / (np.sinh(lam) + np.sin(lam))
    phi = np.cosh(lam * x) - np.cos(lam * x) - s * (np.sinh(lam * x) - np.sin(lam * x))
    d2 = lam**2 * (np.cosh(lam * x) + np.cos(lam * x) - s * (np.sinh(lam * x) + np.sin(lam * x)))
    assert np.abs(beam_mode_values(n, x[:, 0]) - phi).max() < 1e-9
    assert np.abs(beam_mode_values(n, x[:, 0], 2) - d2).max() < 1e-8
    g = BeamGalerkin(40)
    assert np.abs(g.gram - np.eye(40)).max() < 1e-12
    assert np.allclose(g.tip, 2.0 * (-1.0) ** np.arange(40), atol=1e-12)
    # phi_r'''' = lambda^4 phi_r, also at lambda = 124 (round-off: eps lambda^4 |phi|)
    x = np.linspace(0, 1, 7)
    err = np.abs(beam_mode_values(40, x, 4) - g.lam4 * beam_mode_values(40, x))
    assert np.all(err < 1e-11 * g.lam4)


def test_paidoussis_integrals():
    """b_sr = int phi_s phi_r' and c_sr = int phi_s phi_r'' by quadrature equal the
    closed forms of Paidoussis (1998), Table 3.1 and App. B (b_rr = 2, Eq. (B.4);
    c_rr = lambda_r s_r (2 - lambda_r s_r), Eq. (B.8))."""
    n = 12
    g = BeamGalerkin(n)
    lam = cantilever_roots(n)
    s = beam_mode_coefficients(lam)[2]
    S, R = np.meshgrid(np.arange(n), np.arange(n), indexing="ij")
    sgn = (-1.0) ** (S + R)
    ls, lr = lam[S], lam[R]
    off = S != R
    b = np.full((n, n), 2.0)
    b[off] = (4.0 / ((ls / lr) ** 2 + sgn))[off]
    c = lr * s[R] * (2.0 - lr * s[R])
    with np.errstate(invalid="ignore"):  # 0/0 on the diagonal, replaced below
        c[off] = (4.0 * (lr * s[R] - ls * s[S]) / (sgn - (ls / lr) ** 2))[off]
    assert np.abs(g.b - b).max() < 1e-12
    assert np.abs(g.c - c).max() < 1e-12 * np.abs(c).max()


# ----------------------------------------------------------- classical pipes --
def test_cantilever_frequencies_both_discretizations():
    """v = gamma = 0: omega_r = lambda_r^2 exactly for the beam modes (they are the
    modes), and to 1e-11 for the Legendre elements (p = 16, degree 18)."""
    exact = cantilever_roots(4) ** 2
    for method, n, tol in (("galerkin", 6, 1e-12), ("legendre", 16, 1e-11)):
        lam = eigenvalues(StraightPipe(), 0.0, method, n)
        got = np.array([upper(lam, k).imag for k in range(4)])
        assert np.abs(got / exact - 1).max() < tol
        assert np.abs(lam.real).max() < 1e-9 * np.abs(lam).max()


def test_beck_column():
    """beta = gamma = 0: Beck's column flutters at v^2 = P L^2/EI = 20.05 (Beck 1952;
    Paidoussis 1998, Sec. 3.4; four digits printed: half a unit of the last).
    The Legendre value is converged: p = 12 and 24 agree to 1e-10; the beam modes
    converge to it (N = 10, 20, 40 errors measured 4.1e-4, 4.2e-5, 3.2e-6 in v^2)."""
    ref = critical_velocity(StraightPipe(), 6.0, **LEG)
    assert ref.kind == "flutter"
    assert abs(ref.v_cr**2 - 20.05) < 0.005
    other = critical_velocity(StraightPipe(), 6.0, method="legendre", n=24)
    assert abs(other.v_cr - ref.v_cr) < 1e-10
    errs = [
        abs(critical_velocity(StraightPipe(), 6.0, method="galerkin", n=n).v_cr ** 2 - ref.v_cr**2)
        for n in (10, 20, 40)
    ]
    assert errs[0] > errs[1] > errs[2] and errs[2] < 5e-6


def test_gregory_paidoussis_cantilever():
    """gamma = mu = 0: the horizontal cantilever flutters in its second mode at
    u_cf ~ 5.6 for beta = 0.2 (Gregory & Paidoussis 1966a; Paidoussis 1998,
    p. 112, Fig. 3.27: a value read off a figure, +-0.15 as in
    tests/test_stability.py).  (The same page gives ~7.0 for beta = 0.295, on
    the steep part of the S-shaped v_cr(beta) curve: 7.2605 here and with
    fempipe's FE, so that reading is not used.)  Refining: beam modes N = 10, 20, 40 and
    Legendre p = 10, 20, 40 all within 2e-6 of p = 40, the Legendre ones within 1e-10."""
    ref = critical_velocity(StraightPipe(beta=0.2), 8.0, method="legendre", n=40)
    assert ref.kind == "flutter" and abs(ref.v_cr - 5.6) < 0.15
    for n in (10, 20):
        assert (
            abs(
                critical_velocity(StraightPipe(beta=0.2), 8.0, method="legendre", n=n).v_cr
                - ref.v_cr
            )
            < 1e-10
        )
    gal = [
        critical_velocity(StraightPipe(beta=0.2), 8.0, method="galerkin", n=n).v_cr
        for n in (10, 20, 40)
    ]
    assert abs(gal[0] - ref.v_cr) > abs(gal[1] - ref.v_cr) > abs(gal[2] - ref.v_cr)
    assert abs(gal[2] - ref.v_cr) < 2e-6


def test_paper_case_hanging_pipe_matches_fempipe_readme():
    """alpha = 0, beta = 0.142, gamma = 18.9, mu = 5e-3: fempipe's converged FE v_cr
    is 6.3336872532 (docs, Convergence of the two modal bases: P3:64).  A
    different equation (eta, not theta) and method; the FE reference carries
    its own 1e-10."""
    o = critical_velocity(StraightPipe(beta=0.142, gamma=18.9, mu=5e-3), 10.0, **LEG)
    assert abs(o.v_cr - 6.3336872532) < 1e-9


def test_from_params():
    """Straight pipes only; standing for alpha = pi."""
    p = StraightPipe.from_params(Params(alpha=np.pi, beta=0.1, gamma=3.0, end_mass=0.2))
    assert p.standing and p.gamma == 3.0 and p.end_mass == 0.2
    assert not StraightPipe.from_params(Params(alpha=0.7, gamma=0.0)).standing
    with pytest.raises(ValueError, match="straight"):
        StraightPipe.from_params(Params(alpha=np.pi / 2))


# ---------------------------------------------------------------- variants --
@pytest.mark.parametrize("end_mass", [0.2, 1.0, 5.0])
def test_tip_mass_cantilever_frequencies(end_mass):
    """gamma = v = 0: 1 + cos l cosh l + Gamma l (cos l sinh l - sin l cosh l) = 0,
    omega = l^2 (Blevins 1979).  Legendre to 1e-11; the beam modes, which all
    have eta'''(1) = 0 while the tip mass makes it nonzero, converge as N^-3
    (N = 10, 20, 40: errors fall by 7.9-8.0 per doubling, measured)."""
    exact = tip_mass_frequencies(end_mass, 3)
    pipe = StraightPipe(end_mass=end_mass)
    lam = eigenvalues(pipe, 0.0, **LEG)
    assert np.abs(np.array([upper(lam, k).imag for k in range(3)]) / exact - 1).max() < 1e-11
    errs = []
    for n in (10, 20, 40):
        lam = eigenvalues(pipe, 0.0, "galerkin", n)
        errs.append(np.abs(np.array([upper(lam, k).imag for k in range(3)]) / exact - 1).max())
    ratios = np.array(errs[:-1]) / np.array(errs[1:])
    assert np.all((ratios > 7.0) & (ratios < 9.0))


def test_greenhill_column():
    """alpha = pi, v = 0: the standing column buckles at gamma = 7.837 (Greenhill
    1881; Paidoussis 1998, Sec. 3.5.3: the first zero of J_(-1/3)); a real
    eigenvalue through zero, located by Brent on the stability margin."""
    exact = heavy_column_buckling(0.0)
    assert abs(exact - 7.837) < 5e-4

    def margin(g):
        return spectral_abscissa(StraightPipe(beta=0.2, gamma=g, standing=True), 0.0, **LEG)[0]

    assert abs(brentq(margin, 5.0, 9.0, xtol=1e-13) - exact) < 1e-10


@pytest.mark.parametrize("end_mass", [0.1, 0.5, 2.0])
def test_heavy_column_with_end_weight(end_mass):
    """The standing column with an end mass: its weight Gamma gamma loads the top.
    The Bessel-function solution (heavy_column_buckling) against the eigenvalue
    through zero: the end mass's tension term s_g gamma Gamma in both the field
    and the tip condition."""
    exact = heavy_column_buckling(end_mass)
    assert exact < heavy_column_buckling(0.0)

    def margin(g):
        pipe = StraightPipe(beta=0.2, gamma=g, standing=True, end_mass=end_mass)
        return spectral_abscissa(pipe, 0.0, **LEG)[0]

    assert abs(brentq(margin, 0.2 * exact, 1.5 * exact, xtol=1e-13) - exact) < 1e-9 * exact


def test_heavy_column_with_large_end_mass_tends_to_euler():
    """Gamma -> infinity: the top load Gamma gamma dominates, Euler's cantilever
    load pi^2/4 (the self-weight adds O(1/Gamma))."""
    assert abs(100.0 * heavy_column_buckling(100.0) - np.pi**2 / 4) < 0.01


@pytest.mark.parametrize("kappa", [100.0, 1000.0])
def test_tip_spring_divergence(kappa):
    """gamma = 0, a spring kappa at xi = 1: divergence at the root of
    u^3 + kappa (sin u - u cos u) = 0 (Chen 1971a; Paidoussis 1998, p. 158,
    Eq. (3.119)), whatever beta; the Legendre solver finds a real eigenvalue
    through zero there, to 1e-9."""
    exact = tip_spring_divergence(kappa)
    for beta in (0.1, 0.5):
        o = critical_velocity(StraightPipe(beta=beta, springs=((kappa, 1.0),)), 8.0, **LEG)
        assert o.kind == "divergence" and abs(o.v_cr - exact) < 1e-9


def test_tip_spring_limit_is_clamped_pinned():
    """kappa -> infinity: tan u = u, u = 4.4934 (the clamped-pinned pipe, Paidoussis
    1998, Sec. 3.4)."""
    assert abs(tip_spring_divergence(1e9) - 4.4934) < 1e-4


def test_interior_spring_two_discretizations():
    """A spring inside the pipe (kappa = 50 at xi = 0.6, beta = 0.2, hanging
    gamma = 10): the Legendre elements cut at the spring converge (p = 12 and 24
    agree to 1e-10); the beam modes, smooth across the spring while eta''' jumps,
    converge to the same v_cr towards N^-3 (errors measured 2.3e-3, 4.2e-4,
    6.0e-5, 8.0e-6 for N = 10, 20, 40, 80: ratios 5.6, 6.9, 7.5)."""
    pipe = StraightPipe(beta=0.2, gamma=10.0, springs=((50.0, 0.6),))
    ref = critical_velocity(pipe, 12.0, method="legendre", n=24)
    assert abs(critical_velocity(pipe, 12.0, method="legendre", n=12).v_cr - ref.v_cr) < 1e-10
    errs = [
        abs(critical_velocity(pipe, 12.0, method="galerkin", n=n).v_cr - ref.v_cr)
        for n in (10, 20, 40)
    ]
    assert errs[0] / errs[1] > 5 and errs[1] / errs[2] > 6 and errs[2] < 1e-4


def _undamped_nu(v):
    """The roots nu of K x = nu M x of Beck's column (beta = gamma = 0, no damping)."""
    return stiffness_roots(StraightPipe(), v, nu_max=1000.0)


@pytest.mark.parametrize("sigma", [2.0, 10.0, 50.0])
def test_beck_column_external_damping_from_undamped_roots(sigma):
    """With C = sigma M (beta = 0, no end mass), each undamped root nu = a + ib of
    K x = nu M x gives lambda^2 + sigma lambda + nu = 0, whose roots are stable iff
    b^2 < sigma^2 a (Routh-Hurwitz for a complex quadratic).  The v_cr of that
    scalar criterion equals the damped eigenproblem's."""

    def crit(v):
        nu = _undamped_nu(v)
        return np.max(nu.imag**2 - sigma**2 * nu.real)

    vs = np.arange(4.0, 6.2, 0.02)
    k = next(i for i, v in enumerate(vs) if crit(v) > 0)
    v_scalar = brentq(crit, vs[k - 1], vs[k], xtol=1e-13)
    o = critical_velocity(StraightPipe(sigma=sigma), 8.0, **LEG)
    assert abs(o.v_cr - v_scalar) < 1e-9


def test_beck_column_external_damping_plaut_infante():
    """External damping raises Beck's load from 20.05 to 37.7 EI/L^2 for large
    damping (Plaut & Infante 1970, Int. J. Solids Struct. 6, 491-496, abstract;
    printed to 0.1: +-0.05).  The limit solves Re nu = 0 for the complex undamped
    pair (the criterion above as sigma -> infinity); sigma = 3000 is within 1e-3 of it."""
    v_inf = brentq(lambda v: np.min(_undamped_nu(v).real), 5.0, 6.5, xtol=1e-13)
    assert abs(v_inf**2 - 37.7) < 0.05
    assert abs(large_damping_limit(StraightPipe(), 8.0) - v_inf) < 1e-9  # Re nu to round-off
    o = critical_velocity(StraightPipe(sigma=3000.0), 7.0, lam_max=1e7, **LEG)
    assert 0 < v_inf**2 - o.v_cr**2 < 1e-3
    small = critical_velocity(StraightPipe(sigma=0.1), 7.0, **LEG)
    assert abs(small.v_cr**2 - 20.05) < 0.005


def test_hysteretic_beam():
    """v = gamma = 0: (1 + i mu_h) lambda_r^4 + lambda^2 = 0, so the consistent
    root is lambda = i lambda_r^2 (1 + i mu_h)^(1/2) (Im > 0) and its conjugate."""
    mu_h = 0.05
    lam = eigenvalues(StraightPipe(mu_h=mu_h), 0.0, **LEG)
    exact = 1j * cantilever_roots(3) ** 2 * np.sqrt(1 + 1j * mu_h)
    got = np.array([upper(lam, k) for k in range(3)])
    assert np.abs(got / exact - 1).max() < 1e-11
    low = lam[lam.imag < 0].conj()
    assert np.allclose(low[np.argsort(low.imag)][:3], got, rtol=1e-12)


def test_hysteretic_onset_equals_kelvin_voigt_at_its_frequency():
    """At a flutter onset lambda = i omega, E (1 + i mu_h) is E (1 + mu lambda) with
    mu = mu_h / omega: the Kelvin-Voigt pipe with that mu has the same critical
    eigenvalue at the same v (a check of the hysteretic root selection)."""
    pipe = StraightPipe(beta=2.03e-3, gamma=42.4, mu_h=0.02)
    h = critical_velocity(pipe, 10.0, **LEG)
    kv = StraightPipe(beta=2.03e-3, gamma=42.4, mu=0.02 / h.frequency)
    lam = eigenvalues(kv, h.v_cr, **LEG)
    k = np.argmin(np.abs(lam - 1j * h.frequency))
    assert abs(lam[k] - 1j * h.frequency) < 1e-8


@pytest.mark.parametrize(
    ("beta3", "gamma", "mu_h", "u_cf", "omega_cf"),
    [(2.03, 42.4, 0.0, 5.62, 19.5), (2.03, 42.4, 0.02, 5.79, 18.1), (0.23, 61.1, 0.0, None, 21.3)],
)
def test_paidoussis_hanging_cantilevers(beta3, gamma, mu_h, u_cf, omega_cf):
    """Paidoussis (1998), Table 3.4, p. 143 (Paidoussis 1970), theory columns for
    hanging cantilevers conveying air, mu the hysteretic loss factor: reproduced to
    half a unit of the printed digit.  Not here, because not reproduced (the
    validation case 'hysteretic' reports them with the numbers): beta = 0.23e-3,
    u_cf(mu = 0) printed 6.15, computed 6.1447; u_cf, omega_cf(mu = 0.02)
    printed 6.33, 19.7, computed 6.3931, 18.43."""
    o = critical_velocity(
        StraightPipe(beta=beta3 * 1e-3, gamma=gamma, mu_h=mu_h), 10.0, step=0.05, **LEG
    )
    assert o.kind == "flutter"
    if u_cf is not None:
        assert abs(o.v_cr - u_cf) <= 0.005
    assert abs(o.frequency - omega_cf) <= 0.05


def test_external_damping_does_not_act_on_the_end_mass():
    """The beam-mode damping matrix is sigma I (the distributed mass), the mass
    matrix I + Gamma phi(1) phi(1)^T; the Legendre elements, formed separately,
    agree with it at v = 0 (eigenvalues to the beam modes' N^-3 error at N = 40)."""
    pipe = StraightPipe(sigma=2.0, end_mass=0.5)
    g = BeamGalerkin(40)
    _, _, C0, _, M = g.pencil(pipe)
    assert np.abs(C0 - 2.0 * np.eye(40)).max() < 1e-12
    assert np.abs(M - np.eye(40) - 0.5 * np.outer(g.tip, g.tip)).max() < 1e-12
    a = eigenvalues(pipe, 0.0, **LEG)
    b = eigenvalues(pipe, 0.0, "galerkin", 40)
    a, b = a[a.imag > 0][:3], b[b.imag > 0][:3]
    assert np.abs(a / b - 1).max() < 2e-5
    # and it is not sigma (M with the tip mass): that gives lambda^2 + sigma lambda + omega^2 = 0
    w2 = tip_mass_frequencies(0.5, 3)
    wrong = -1.0 + 1j * np.sqrt(w2 - 1.0)
    assert np.abs(a - wrong).min() > 1e-2


def test_divergence_with_kelvin_voigt_converges_in_p():
    """A divergence (a real eigenvalue through zero) with Kelvin-Voigt damping, whose
    overdamped stiff modes (lambda ~ -mu omega^2, up to 1e12 here) would swamp the
    round-off of a direct companion form: the hanging pipe with a spring
    kappa = 300 at xi_s = 0.75.  p = 12 ... 40 agree to 1e-10: the eigensolver's
    shifted companion (quadratic_eigenvalues) has a norm of the order of the low
    modes', not of 1e12, so its round-off moves v_cr by ~eps, and each v_cr is
    Brent's to xtol = 1e-12 (measured 1.8e-14 to 2.0e-14 on the Haswell,
    Sandybridge and Prescott kernels)."""
    pipe = StraightPipe(beta=0.142, gamma=18.9, mu=5e-3, springs=((300.0, 0.75),))
    v = [critical_velocity(pipe, 12.0, method="legendre", n=p) for p in (12, 24, 40)]
    assert all(o.kind == "divergence" for o in v)
    assert max(o.v_cr for o in v) - min(o.v_cr for o in v) < 1e-10


@pytest.mark.parametrize(
    "pipe",
    [
        StraightPipe(beta=0.142, gamma=18.9, mu=5e-3, end_mass=0.3),
        StraightPipe(sigma=10.0),
        StraightPipe(beta=2.03e-3, gamma=42.4, mu_h=0.02),
        StraightPipe(beta=0.2, springs=((100.0, 1.0),)),
        StraightPipe(beta=0.142, gamma=18.9, mu=5e-3, springs=((50.0, 0.5),)),
    ],
    ids=["end_mass", "external_damping", "hysteretic", "tip_spring", "interior_spring"],
)
def test_legendre_refinement_per_variant(pipe):
    """Refining p = 10, 20, 40: v_cr changes by less than 1e-9 (measured 1e-10 at most,
    p = 10 against 40), far inside the 1e-6 asked of fempipe's agreement with it."""
    v = [critical_velocity(pipe, 12.0, method="legendre", n=p).v_cr for p in (10, 20, 40)]
    assert max(v) - min(v) < 1e-9


def test_flow_acceleration_is_leipholz_column():
    """The flow-acceleration term sqrt(beta) (dv/dtau)(1 - xi) eta'' of a pipe without gravity
    or flow is Leipholz's cantilever under a uniform tangential load: flutter at q L^3/EI =
    40.05 (Leipholz 1962), for the classical term and for fempipe's K3 (FE P3:16)."""
    from fempipe.analyses.parametric import PulsationPencil
    from fempipe.model.discretization import parse_discretization
    from fempipe.model.plane.operators import PipeModel
    from fempipe.validation.classical_pulsation import flutter_load, leipholz_load

    q = leipholz_load(16)
    assert q == pytest.approx(40.05, abs=0.005)
    assert leipholz_load(12) == pytest.approx(q, rel=1e-8)
    beta = 0.36
    model = PipeModel(
        parse_discretization(fe="P3:16"), Params(alpha=0.0, beta=beta, gamma=0.0, mu=0.0)
    )
    P = PulsationPencil.of(model)
    assert np.sqrt(beta) * flutter_load(P.K0, P.K3, P.M, (1.0, 200.0)) == pytest.approx(q, rel=1e-6)
    # a decelerating flow stretches the pipe: no flutter
    assert np.isnan(flutter_load(P.K0, -P.K3, P.M, (1.0, 200.0)))


def test_classical_pulsation_at_zero_amplitude():
    """Without pulsation the DOP853 monodromy's multipliers are exp(lambda T) of the spectrum."""
    from fempipe.validation.classical_pulsation import ClassicalPulsation

    pipe = StraightPipe(beta=0.2, gamma=10.0, mu=0.005)
    omega = 30.0
    lam = eigenvalues(pipe, 6.0, **LEG)
    exact = np.exp(lam * 2 * np.pi / omega)
    rho = ClassicalPulsation(pipe, 6.0, p=6).multipliers(0.0, omega)
    exact6 = np.exp(eigenvalues(pipe, 6.0, method="legendre", n=6) * 2 * np.pi / omega)
    for r in exact6[np.argsort(-np.abs(exact6))][:4]:
        assert np.min(np.abs(rho - r)) < 1e-9
    assert np.min(np.abs(rho - exact[np.argmax(np.abs(exact))])) < 1e-4

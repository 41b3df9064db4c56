"""The clamped-free beam modes, ``Modal(N, basis="beam")``: basis, solvers, CLI.

References are independent of the code under test: the roots of
cos(l) cosh(l) = -1 from Blevins' tables, the textbook form of the modes
evaluated in 150-digit decimal arithmetic, finite differences of
``evaluate``, the exact beam frequencies (:func:`cantilever_frequencies`) and
converged finite elements (P3:16 to P3:64, whose errors are below 1e-8 here:
the validation report's convergence study).  docs, "Convergence of the two
modal bases", derives the orders N^-4 (beam) and N^-3 (sine) tested here.
"""

from __future__ import annotations

import functools
import json
import math
import pickle
from decimal import Decimal, localcontext

import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel, compute_tip, find_critical_velocity
from fempipe.analyses.statics import solve_sagged, solve_static
from fempipe.cli import main
from fempipe.model.discretization import (
    EXPECTED_ORDER,
    Discretization,
    beam_mode_slopes,
    beam_roots,
    discretization_from_name,
    parse_discretization,
)
from fempipe.model.params import PAPER_CASE
from fempipe.model.quadrature import LineQuadrature

#: Blevins, Formulas for Natural Frequency and Mode Shape, Table 8-1
#: (clamped-free beam), lambda_1..lambda_4.
BLEVINS = [1.87510407, 4.69409113, 7.85475744, 10.99554073]

#: The curved static test case: horizontal pipe, the paper's beta, gamma, v = 3.
CURVED = Params(alpha=math.pi / 2, v=3.0, **PAPER_CASE)


@pytest.fixture(autouse=True)
def _one_blas_thread():
    """The dense modal Jacobians (n_q x N products) are 50x slower with threaded
    BLAS on a loaded 2-core machine (measured at N = 32); results are unchanged."""
    from fempipe.core.parallel import single_blas_thread

    with single_blas_thread():
        yield


# ------------------------------------------------------------------ the basis --
def _dec_sin_cos(x: Decimal) -> tuple[Decimal, Decimal]:
    """sin x, cos x by their Taylor series (the context's precision covers the
    growth of the terms to e^|x| for |x| <= 200)."""
    s, c, term, n = Decimal(0), Decimal(0), Decimal(1), 0
    while True:
        if n % 4 == 0:
            c += term
        elif n % 4 == 1:
            s += term
        elif n % 4 == 2:
            c -= term
        else:
            s -= term
        n += 1
        term = term * x / n
        if n > 10 and abs(term) < Decimal(10) ** -70:
            return s, c


def _textbook(lam: float, xi: float, derivative: int) -> float:
    """psi^(k)(xi) from the textbook form, in 150-digit decimals.

    psi = phi'/lambda with phi = cosh - cos - s (sinh - sin), so
    psi = sinh + sin - s (cosh - cos), psi' = lambda (cosh + cos - s (sinh + sin)),
    psi'' = lambda^2 (sinh - sin - s (cosh + cos)), psi''' = lambda^3 phi.
    """
    with localcontext() as ctx:
        ctx.prec = 150
        L = Decimal(lam)  # the float root, exactly
        x = L * Decimal(xi)
        sL, cL = _dec_sin_cos(L)
        sx, cx = _dec_sin_cos(x)
        eL, ex = L.exp(), x.exp()
        chL, shL = (eL + 1 / eL) / 2, (eL - 1 / eL) / 2
        ch, sh = (ex + 1 / ex) / 2, (ex - 1 / ex) / 2
        s = (chL + cL) / (shL + sL)
        value = [
            sh + sx - s * (ch - cx),
            ch + cx - s * (sh + sx),
            sh - sx - s * (ch + cx),
            ch - cx - s * (sh - sx),
        ][derivative]
        return float(value * L**derivative)


def test_roots_are_blevins_values_to_machine_precision():
    lam = beam_roots(64)
    np.testing.assert_allclose(lam[:4], BLEVINS, atol=6e-9)
    # cos(l) + sech(l) = 0 to the rounding of l: |f(l)| <= |f'(l)| ulp(l), f' ~ -sin(l).
    with localcontext() as ctx:
        ctx.prec = 150
        for r in (1, 2, 3, 4, 8, 16, 32, 64):
            L = Decimal(lam[r - 1])
            s, c = _dec_sin_cos(L)
            residual = abs(float(c + 2 / (L.exp() + (-L).exp())))
            assert residual <= 2 * np.spacing(lam[r - 1]), (r, residual)
    # ... and they approach (2r - 1) pi / 2 from alternating sides.
    c = (2 * np.arange(1, 65) - 1) * np.pi / 2
    assert np.all(np.sign(lam[:10] - c[:10]) == (-1.0) ** np.arange(10))
    assert abs(lam[-1] - c[-1]) < 1e-13


@pytest.mark.parametrize("r", [1, 2, 3, 4, 8, 16, 32, 64])
def test_stable_form_matches_textbook_form_in_150_digits(r):
    """The overflow-free form equals the textbook one to round-off, derivatives 0..3,
    also at lambda_64 = 199.5, where cosh(lambda) = 1e86."""
    lam = beam_roots(r)[-1:]
    xs = [0.0, 0.013, 0.1, 0.37, 0.5, 0.93, 1.0]
    for k in range(4):
        got = beam_mode_slopes(lam, xs, derivative=k)[:, 0]
        ref = np.array([_textbook(lam[0], x, k) for x in xs])
        np.testing.assert_allclose(got, ref, rtol=0, atol=2e-14 * lam[0] ** (k + 1))


def _one_sided(f, x0: float, h: float, order: int) -> float:
    """First or second derivative at x0 from 5 points on one side (h < 0: to the left)."""
    y = np.array([f(x0 + j * h) for j in range(5)])
    if order == 1:
        return float(np.dot([-25, 48, -36, 16, -3], y) / (12 * h))
    return float(np.dot([35, -104, 114, -56, 11], y) / (12 * h * h))


def test_boundary_conditions_by_finite_differences():
    """theta(0) = 0, theta'(1) = 0, theta''(1) = 0 for every basis function (finite
    differences of evaluate, independent of the derivative formulas), but
    theta''(0) != 0 -- unlike the sine modes -- and theta'''(0) = 0."""
    disc = Modal(6, basis="beam")
    for r in range(6):
        q = np.eye(6)[r]
        lam = disc.k[r]

        def f(x, q=q):
            return float(disc.evaluate(q, [x])[0])

        assert f(0.0) == 0.0
        h = 1e-3
        assert abs(_one_sided(f, 1.0, -h, 1)) < 1e-6 * lam
        assert abs(_one_sided(f, 1.0, -h, 2)) < 1e-4 * lam**2
        # psi_r''(0) = phi_r'''(0) / lambda = -2 s_r lambda^2, s_r from the textbook formula
        s_r = (math.cosh(lam) + math.cos(lam)) / (math.sinh(lam) + math.sin(lam))
        assert _one_sided(f, 0.0, h, 2) == pytest.approx(-2 * s_r * lam**2, rel=1e-4)
        assert abs(beam_mode_slopes(disc.k, [0.0], 3)[0, r]) < 1e-14 * lam**3
    # the paper's sine modes have theta''(0) = 0 instead
    sine = Modal(6)
    for r in range(6):
        second = _one_sided(lambda x, r=r: float(sine.evaluate(np.eye(6)[r], [x])[0]), 0.0, h, 2)
        assert abs(second) < 1e-4 * sine.k[r] ** 2


@pytest.mark.parametrize("n", [8, 64])
def test_stiffness_is_diag_lambda_squared(n):
    """K = diag(lambda^2) (stated) equals \\int psi_i' psi_j' summed by the quadrature;
    the basis stays bounded (|psi| <= 2.04) and the Gram matrix well conditioned."""
    disc = Modal(n, basis="beam")
    np.testing.assert_array_equal(disc.K, np.diag(disc.k**2))
    quad = LineQuadrature.uniform(4 * disc.quad.n_cells, 12)
    dpsi = beam_mode_slopes(disc.k, quad.x, 1)
    K = (dpsi.T * quad.w) @ dpsi
    np.testing.assert_allclose(K / np.outer(disc.k, disc.k), np.eye(n), rtol=0, atol=1e-13)
    xs = np.linspace(0.0, 1.0, 20001)
    assert np.abs(disc.evaluate(np.eye(n), xs)).max() < 2.04
    assert np.linalg.cond(disc.gram) < 20.0
    # the default quadrature already integrates the Gram matrix to round-off
    psi = beam_mode_slopes(disc.k, quad.x)
    np.testing.assert_allclose(disc.gram, (psi.T * quad.w) @ psi, rtol=0, atol=1e-14)
    np.testing.assert_allclose(disc.tip, disc.evaluate(np.eye(n), [1.0])[0], atol=0)


@pytest.mark.parametrize("n", [32, 64])
def test_default_quadrature_resolves_the_modes_in_the_solution(n):
    """max(32, 4N) cells of 8 Gauss points: the static tip values equal those of a
    quadrature twice as fine with 12 points per cell to 1e-12, the tolerance of the
    two Newton solves (measured 4e-16 to 1.8e-15 on the Haswell, Sandybridge and
    Prescott kernels; an under-resolved 32 x 4 or 16 x 6 misses by 5e-12, 1e-10 at
    N = 32)."""

    def tips(disc):
        m = PipeModel(disc, CURVED)
        t = compute_tip(disc, solve_static(m, q0=solve_sagged(m).q, tol=1e-12).q, CURVED.alpha)
        return np.array([t["theta_tip"], t["X_tip"]])

    default = Modal(n, basis="beam")
    fine = Modal(n, 2 * default.quad.n_cells, 12, basis="beam")
    np.testing.assert_allclose(tips(default), tips(fine), rtol=0, atol=1e-12)


def test_sine_default_is_unchanged_and_names_and_pickling():
    sine, beam = Modal(4), Modal(4, basis="beam")
    assert sine.basis == "sine" and sine.name == "modal:4" and beam.name == "modal-beam:4"
    assert sine.to_dict()["basis"] == "sine" and beam.to_dict()["basis"] == "beam"
    assert {k: v for k, v in beam.to_dict().items() if k != "basis"} == {
        "kind": "modal",
        "n_modes": 4,
        "n_dofs": 4,
        "n_cells": 32,
        "n_gauss": 8,
    }
    assert "beam" in repr(beam) and "sine" in repr(sine)
    assert isinstance(beam, Discretization)
    assert (
        (sine.expected_order, beam.expected_order) == (3.0, 4.0) == tuple(EXPECTED_ORDER.values())
    )
    back = pickle.loads(pickle.dumps(beam))
    assert back.name == "modal-beam:4"
    np.testing.assert_array_equal(back.Phi, beam.Phi)
    for d in (sine, beam, FiniteElement(5, 2)):
        assert discretization_from_name(d.name).name == d.name
    assert beam.refined(2).name == "modal-beam:8" and sine.refined(2).name == "modal:8"
    with pytest.raises(ValueError, match="basis"):
        Modal(3, basis="cosine")


def test_parse_discretization_basis():
    assert parse_discretization(modal=5, basis="beam").name == "modal-beam:5"
    assert parse_discretization(modal=5).name == "modal:5"
    with pytest.raises(ValueError, match=r"--basis.*sine, beam"):
        parse_discretization(modal=5, basis="legendre")
    with pytest.raises(ValueError, match="--basis"):
        parse_discretization(fe="P3:8", basis="beam")
    with pytest.raises(ValueError, match="--basis"):
        parse_discretization(basis="beam")


def test_code_that_refines_or_relabels_a_modal_basis_keeps_it():
    from fempipe.bench.dynamics import _disc
    from fempipe.cli.reporting import describe
    from fempipe.validation.dynamic_runs import _disc_from_spec, modal_label
    from fempipe.validation.static_shapes import refined

    beam = Modal(3, basis="beam")
    assert refined(beam).name == "modal-beam:6" and refined(Modal(3)).name == "modal:6"
    assert _disc_from_spec(modal_label(beam)).name == "modal-beam:3"
    assert modal_label(Modal(3)) == "N = 3" and _disc_from_spec("N = 3").name == "modal:3"
    assert _disc_from_spec("FE P3:8").name == "P3:8"
    assert _disc("modal-beam:4").name == "modal-beam:4" and _disc("modal:4").name == "modal:4"
    result = {"params": {"alpha": 0.0}, "discretization": beam.to_dict()}
    assert describe(result)[0] == "modal-beam:3"


def test_point_store_of_an_older_sine_run_still_resumes(tmp_path):
    """A bifurcation store written before Modal.to_dict had "basis" is a sine-mode run."""
    from fempipe.analyses.bifurcation import PointStore

    manifest = {"discretization": Modal(2).to_dict(), "values": [1.0]}
    old = json.loads(json.dumps(manifest))
    del old["discretization"]["basis"]
    (tmp_path / "run.json").write_text(json.dumps(old))
    PointStore(tmp_path, manifest)  # accepted
    beam = {"discretization": Modal(2, basis="beam").to_dict(), "values": [1.0]}
    with pytest.raises(ValueError, match="different run"):
        PointStore(tmp_path, beam)


# ------------------------------------------------------------------- solvers --
def test_linear_frequencies_at_rest_are_exact():
    """v = gamma = 0: the beam basis holds the exact modes, omega_r = lambda_r^2 for
    all N modes (the sine basis misses its N-th by 7-9 %)."""
    from fempipe.analyses.stability import compute_spectrum
    from fempipe.analyses.stability.canonical import cantilever_frequencies, resolution

    for n in (3, 6, 12):
        res = resolution(Modal(n, basis="beam"))
        assert res.n_resolved == n
        np.testing.assert_allclose(res.frequencies, cantilever_frequencies(n), rtol=1e-12)
    sine = resolution(Modal(6))
    assert sine.n_resolved == 5 and 0.05 < sine.rel_error[-1] < 0.1  # 7.6 %
    rest = Params(alpha=0.0, beta=PAPER_CASE["beta"], gamma=0.0, mu=0.0, v=0.0)
    s = compute_spectrum(PipeModel(Modal(6, basis="beam"), rest), np.zeros(6))
    up = np.sort(s.lam[s.lam.imag > 0].imag)
    np.testing.assert_allclose(up, cantilever_frequencies(6), rtol=1e-12)
    np.testing.assert_allclose(s.lam.real, 0.0, atol=1e-9)


def _curved_tips(disc) -> np.ndarray:
    m = PipeModel(disc, CURVED)
    q = solve_static(m, q0=solve_sagged(m).q, tol=1e-12).q
    t = compute_tip(disc, q, CURVED.alpha)
    return np.array([t["theta_tip"], t["X_tip"]])


def test_static_tip_converges_as_n_to_the_minus_4():
    """alpha = pi/2, v = 3: the beam modes converge to P3:64 (P3:64 and P3:128 agree to
    1e-13) as N^-expected_order = N^-4 (measured slopes 4.04, 4.16, 4.13 for
    theta_tip over N = 4..32), faster than the sine modes' N^-3."""
    ref = _curved_tips(FiniteElement(64, 3))
    Ns = np.array([8, 16, 32])
    beam = np.array([np.abs(_curved_tips(Modal(n, basis="beam")) - ref) for n in Ns])
    sine = np.array([np.abs(_curved_tips(Modal(n)) - ref) for n in Ns])
    for j in range(2):
        slope = -np.polyfit(np.log(Ns), np.log(beam[:, j]), 1)[0]
        assert abs(slope - Modal(8, basis="beam").expected_order) < 0.4, (j, slope, beam)
    # theta_tip of the sine modes (their X_tip is still pre-asymptotic here: local
    # slopes 1.9, 2.8, 3.0 from N = 8 to 64)
    slope = -np.polyfit(np.log(Ns), np.log(sine[:, 0]), 1)[0]
    assert abs(slope - Modal(8).expected_order) < 0.4, (slope, sine)
    # beam beats sine in theta_tip at every N; X_tip of the sine modes happens to be
    # small at N = 8 (2.8e-6, against 1.7e-5), so there only from N = 32 on.
    assert np.all(beam[:, 0] < sine[:, 0]) and np.all(beam[-1] < sine[-1])
    assert beam[-1].max() < 5e-8


def test_beam_coefficients_decay_like_the_derivation():
    """a_r = \\int theta' psi_r' / lambda_r^2 of the converged solution is
    2 theta'''(0) / lambda^4 + 2 theta''''(0) / lambda^5 + ..., with theta'''(0)
    and theta''''(0) from differentiating Eq. (31a) at xi = 0 (docs)."""
    p, disc = CURVED, FiniteElement(64, 3)
    m = PipeModel(disc, p)
    q = solve_static(m, q0=solve_sagged(m).q, tol=1e-12).q
    quad = LineQuadrature.uniform(512, 8)
    theta = disc.evaluate(q, quad.x)
    lam = beam_roots(40)
    # \int theta' psi' = -\int theta psi'' (theta(0) = 0, psi'(1) = 0)
    a = -(beam_mode_slopes(lam, quad.x, 2).T * quad.w) @ theta / lam**2
    h = 1e-3
    d1 = _one_sided(lambda x: float(disc.evaluate(q, [x])[0]), 0.0, h, 1)
    d2 = _one_sided(lambda x: float(disc.evaluate(q, [x])[0]), 0.0, h, 2)
    th1 = float(disc.evaluate(q, [1.0])[0])
    g, v2, al = p.gamma, p.v**2, p.alpha
    d3 = -g * math.sin(al) + (g * math.cos(al) - v2 * math.cos(th1)) * d1
    d4 = (
        -2 * g * math.cos(al) * d1
        + g * math.cos(al) * d2
        - v2 * (math.sin(th1) * d1**2 + math.cos(th1) * d2)
        - g * math.sin(al) * d1**2
    )
    assert abs(d3) > 1.0 and abs(d4) > 100.0  # theta'''(0) = -5.67, theta''''(0) = -213
    r = slice(19, 40)
    B, A = np.polyfit(1.0 / lam[r], a[r] * lam[r] ** 4 / 2, 1)
    assert A == pytest.approx(d3, rel=0.02)
    assert B == pytest.approx(d4, rel=0.05)


@functools.cache
def _converged_v_cr(alpha: float) -> float:
    """The paper case's in-plane v_cr from another discretization: quintic elements
    P5:8, converged (P4:16 and P3:32 agree with it to 3e-12).  At alpha = 0 it is
    checked against the classical straight-pipe solver (below)."""
    p = Params(alpha=alpha, **PAPER_CASE)
    return find_critical_velocity(PipeModel(FiniteElement(8, 5), p), v_max=7.0).critical.v


@pytest.mark.parametrize("alpha", [math.pi / 2, 0.0], ids=["pi/2", "0"])
def test_critical_velocity_converges_to_fe(alpha):
    """Paper case: flutter in mode 2 at v_cr; the beam modes converge to the FE value
    (P5:8, converged; P3:16 is within 1.6e-8 of it) as N^-4: errors 4e-4 / 2e-5 at
    N = 8 / 16, ratio 16-19, where the sine modes have 3.5e-3 (N = 8).  At alpha = 0
    (straight hanging pipe) the reference is also the classical linear equation's
    (fempipe.validation.classical, Legendre p = 16): 5e-12 apart."""
    from fempipe.validation.classical import StraightPipe
    from fempipe.validation.classical import critical_velocity as classical_v_cr

    p = Params(alpha=alpha, **PAPER_CASE)
    ref = _converged_v_cr(alpha)
    if alpha == 0.0:
        pipe = StraightPipe(beta=p.beta, gamma=p.gamma, mu=p.mu)
        classical = classical_v_cr(pipe, 8.0, method="legendre", n=16)
        assert classical.kind == "flutter" and abs(classical.v_cr - ref) < 1e-9
    fe = find_critical_velocity(PipeModel(FiniteElement(16, 3), p), v_max=7.0).critical
    assert abs(fe.v - ref) < 1e-7  # P3:16's discretization error
    err = []
    for n in (8, 16):
        c = find_critical_velocity(PipeModel(Modal(n, basis="beam"), p), v_max=7.0).critical
        assert (c.type, c.mode) == ("flutter", 2)
        err.append(abs(c.v - ref))
    assert err[0] < 6e-4 and err[1] < 4e-5
    assert 10.0 < err[0] / err[1] < 30.0  # 2^4 = 16
    sine = find_critical_velocity(PipeModel(Modal(8), p), v_max=7.0).critical
    assert abs(sine.v - ref) > 5 * err[0]


# ----------------------------------------------------------------------- CLI --
def _run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def test_cli_static_and_critical_on_beam_modes(capsys):
    code, out, err = _run(
        ["static", "--modal", "4", "--basis", "beam", "--alpha", "pi/2", "--v", "3", "--json"],
        capsys,
    )
    assert code == 0, err
    d = json.loads(out)
    assert d["discretization"]["basis"] == "beam" and d["discretization"]["n_modes"] == 4
    ref = _curved_tips(FiniteElement(16, 3))
    assert d["points"][0]["theta_tip"] == pytest.approx(ref[0], abs=1e-4)  # N = 4: 5e-5
    code, out, err = _run(
        ["critical", "--modal", "6", "--basis", "beam", "--alpha", "pi/2", "--v", "0,7"]
        + ["--planar", "--no-branches", "--json", "--quiet"],
        capsys,
    )
    assert code == 0, err
    d = json.loads(out)
    assert d["discretization"]["basis"] == "beam"
    # N = 6 against the converged FE value: N^-4 error ~ 1.3e-3
    assert d["v_cr"] == pytest.approx(_converged_v_cr(math.pi / 2), abs=3e-3)
    code, out, err = _run(["static", "--modal", "3", "--v", "0", "--json"], capsys)
    assert json.loads(out)["discretization"]["basis"] == "sine"


@pytest.mark.parametrize(
    "argv",
    [
        ["--basis", "beam", "--fe", "P3:8"],
        ["--basis", "beam"],
        ["--basis", "legendre", "--modal", "3"],
    ],
    ids=["with-fe", "without-modal", "unknown"],
)
def test_cli_bad_basis_exits_2_naming_basis(argv, capsys):
    code, out, err = _run(["static", *argv, "--v", "0"], capsys)
    assert code == 2 and out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and ": error: --basis" in lines[0], err


# ------------------------------------------------------------------- dynamics --
def test_limit_cycle_on_four_beam_modes():
    """The whole dynamics chain (static state, transient, shooting) runs on the beam
    basis: N = 4 finds the flutter limit cycle of alpha = 0, v = 10 (paper case)
    within 4.2e-4 of the amplitude of eta_tip (the sine modes: 6.4e-3) and 2e-4 of
    the period of the same cycle on the other discretization, FE P5:4 (7e-8 and
    3e-8 from P3:32 at shoot_rtol = 1e-10)."""
    from fempipe.analyses.limit_cycle import find_attractor

    p = Params(alpha=0.0, v=10.0, **PAPER_CASE)
    fe = find_attractor(PipeModel(FiniteElement(4, 5), p))
    att = find_attractor(PipeModel(Modal(4, basis="beam"), p))
    assert att.kind == fe.kind == "periodic"
    lo, hi = att.tip["eta_tip"]
    assert hi == pytest.approx(-lo, abs=1e-7)  # the alpha = 0 cycle is symmetric
    assert abs(hi - fe.tip["eta_tip"][1]) < 5e-4
    assert abs(att.period - fe.period) < 3e-4


@pytest.mark.slow
def test_limit_cycle_converges_on_beam_modes():
    """alpha = 0, v = 10 (paper case): the flutter limit cycle on N = 4..8 beam modes
    approaches the P3:16 amplitude eta_tip (P3:8 agrees to 4e-6)."""
    from fempipe.analyses.limit_cycle import find_attractor

    p = Params(alpha=0.0, v=10.0, **PAPER_CASE)

    def amplitude(disc):
        att = find_attractor(PipeModel(disc, p), shoot_rtol=1e-8, shoot_tol=1e-7)
        assert att.kind == "periodic"
        return att.tip["eta_tip"][1]

    ref = amplitude(FiniteElement(16, 3))
    err = np.array([abs(amplitude(Modal(n, basis="beam")) - ref) for n in (4, 6, 8)])
    assert np.all(np.diff(err) < 0) and err[0] < 1e-3 and err[-1] < 1e-4, err

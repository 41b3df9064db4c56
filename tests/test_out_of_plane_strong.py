"""The motion out of the plane: fempipe.model.out_of_plane.model against the strong form and its symmetries.

:mod:`fempipe.validation.lateral` solves the out-of-plane problem in strong
form (the deflection w on C^1 spectral elements about ``solve_bvp``'s static
state), sharing no code with fempipe's discretizations, quadrature, operators
or :mod:`fempipe.model.out_of_plane.model`.  Every reference below is an independent
computation (the strong form, the classical straight-pipe theory, the
in-plane problem) or an exact symmetry; no number is pasted.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg as sla

from fempipe.analyses import stability
from fempipe.analyses.statics import solve_static
from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.out_of_plane.model import OutOfPlaneOperators, build_out_of_plane_model
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.validation import classical, lateral

PAPER = {"beta": 0.142, "gamma": 18.9}
VARIANTS = {
    "mu": 0.005,
    "end_mass": 0.2,
    "external_damping": 0.3,
    "springs": ((50.0, 0.5),),
}


def pencil_eigenvalues(K, C, M, vectors=False):
    """All roots of (K + lambda C + lambda^2 M) x = 0 by QZ on the first-order pencil."""
    n = K.shape[0]
    dense = [A.toarray() if hasattr(A, "toarray") else np.asarray(A) for A in (K, C, M)]
    Z, I = np.zeros((n, n)), np.eye(n)
    A = np.block([[Z, I], [-dense[0], -dense[1]]])
    B = np.block([[I, Z], [Z, dense[2]]])
    if not vectors:
        return sla.eigvals(A, B)
    lam, X = sla.eig(A, B)
    return lam, X[:n]


def test_strong_form_at_alpha0_is_the_classical_hanging_pipe():
    """theta^s = 0: the strong form is Paidoussis' equation (every variant but mu_h)."""
    p = Params(alpha=0.0, **PAPER, **VARIANTS)
    cl = classical.critical_velocity(
        classical.StraightPipe.from_params(p), 6.0, v_min=4.0, method="legendre", n=24
    )
    s = lateral.critical_velocity(p, 6.0, v_min=4.0)
    assert s.kind == cl.kind == "flutter"
    assert abs(s.v_cr - cl.v_cr) < 1e-10
    assert abs(s.frequency - cl.frequency) < 1e-8


def test_strong_form_agrees_with_fe_at_one_inclination():
    """alpha = pi/4, mu = 0.005: v_cr and the flutter frequency to 1e-8 (absolute), FE P3:32."""
    p = Params(alpha=math.pi / 4, mu=0.005, **PAPER)
    lo, hi = 5.9, 6.5  # holds the onset (6.2126, found from v = 0 by the full validation case)
    s = lateral.critical_velocity(p, hi, v_min=lo)
    r = stability.find_critical_velocity(
        PipeModel(FiniteElement(32, 3), p), hi, lo, planes=("out",)
    )
    assert r.critical.type == s.kind == "flutter"
    assert abs(r.v_cr - s.v_cr) < 1e-8
    assert abs(r.critical.frequency - s.frequency) < 1e-8


def test_strong_form_converges_spectrally():
    """The eigenvalues of an inclined pipe with springs: p = 16 and p = 24 agree to 1e-10."""
    p = Params(alpha=math.pi / 3, v=3.0, **PAPER, **VARIANTS)
    st = lateral.loaded_state(p)
    lams = []
    for k in (16, 24):
        K, C, M, parts = lateral.HermiteSpectral(k).matrices(st)
        lam = lateral.eigen(K, C, M, bending=parts["bending"])
        lams.append(lam[(np.abs(lam) < 300) & (np.abs(lam + 1 / p.mu) > 10)])
    for z in lams[0]:
        assert np.min(np.abs(lams[1] - z)) < 1e-10 * abs(z)


@pytest.mark.parametrize(
    "disc", [FiniteElement(8, 3), Modal(6), Modal(6, basis="beam")], ids=["P3", "sine", "beam"]
)
@pytest.mark.parametrize("alpha, gamma", [(0.0, 18.9), (math.pi, 3.0)], ids=["hanging", "standing"])
def test_straight_pipe_out_of_plane_equals_in_plane(disc, alpha, gamma):
    """A straight round pipe has no preferred plane: same K, C, M and eigenvalues."""
    p = Params(alpha=alpha, beta=0.142, gamma=gamma, v=2.0, hysteretic_damping=0.01, **VARIANTS)
    m = PipeModel(disc, p)
    mo = build_out_of_plane_model(m)
    q = np.zeros(disc.n)
    for a, b in zip(mo.linearization(q), m.linearization(q), strict=True):
        b = b.toarray() if hasattr(b, "toarray") else np.asarray(b)
        assert np.linalg.norm(a - b) <= 1e-13 * np.linalg.norm(b)
    h_in = m.hysteretic_stiffness(q)
    h_in = h_in.toarray() if hasattr(h_in, "toarray") else h_in
    assert np.allclose(mo.hysteretic_stiffness(q), h_in, rtol=0, atol=1e-13 * np.abs(h_in).max())
    lam_in = pencil_eigenvalues(*m.linearization(q))
    lam_out = pencil_eigenvalues(*mo.linearization(q))
    # The low modes, outside the ill-conditioned cluster of Kelvin-Voigt roots at -1/mu.
    low = lam_in[(np.abs(lam_in) < 1000) & (np.abs(lam_in + 1 / p.mu) > 10)]
    assert low.size >= 8
    for z in low:
        assert np.min(np.abs(lam_out - z)) < 1e-10 * abs(z)


def _buckled(n: int = 16):
    p = Params(alpha=math.pi, beta=0.142, gamma=18.9, mu=0.005, v=1.0)
    m = PipeModel(FiniteElement(n, 3), p)
    x = m.disc.quad.x
    Phi = m.disc.Phi.toarray() if hasattr(m.disc.Phi, "toarray") else m.disc.Phi
    q0 = np.linalg.lstsq(Phi, -2.0 * x * (2.0 - x), rcond=None)[0]
    return p, m, solve_static(m, q0=q0).q


def test_buckled_standing_pipe_has_the_neutral_rotation_mode():
    """alpha = pi, buckled: lambda = 0 with the projection of sin theta^s (FE), and
    W = eta^s (strong form); the other low eigenvalues agree."""
    p, m, q = _buckled()
    ops = OutOfPlaneOperators(m)
    mats = ops.matrices(q)
    lam, X = pencil_eigenvalues(mats.K, mats.C, mats.M, vectors=True)
    i = int(np.argmin(np.abs(lam)))
    x = ops.neutral_mode(q)
    assert abs(lam[i]) < 1e-10
    assert abs(np.vdot(X[:, i], x)) / (np.linalg.norm(X[:, i]) * np.linalg.norm(x)) > 1 - 1e-10
    rest = np.delete(lam, i)
    assert rest[np.abs(rest) < 1000].real.max() < 0.0
    # The strong form about solve_bvp's buckled state: its own neutral mode.
    st = lateral.static_state(p, guess=lambda xi: -2.0 * xi * (2.0 - xi))
    assert abs(st.theta_tip - float(m.disc.tip @ q)) < 1e-7
    disc = lateral.HermiteSpectral(24)
    K, C, M, parts = disc.matrices(st)
    lam_s, W = lateral.eigen(K, C, M, bending=parts["bending"], vectors=True)
    j = int(np.argmin(np.abs(lam_s)))
    a = disc.project(p, st.eta)
    cos = abs(np.vdot(W[:, j], M @ a)) / math.sqrt(abs(np.vdot(W[:, j], M @ W[:, j])) * (a @ M @ a))
    assert abs(lam_s[j]) < 1e-10 and cos > 1 - 1e-10
    # The three lowest modes beside it: P3:16 within 1e-6 of the strong form (order 6).
    low = np.delete(lam_s, j)
    low = low[np.abs(low) < 100]
    assert low.size >= 3
    for z in low:
        assert np.min(np.abs(rest - z)) < 1e-6 * abs(z)


def test_neutral_residual_falls_under_refinement():
    """The uncorrected K on the projection of sin theta^s: the discretization error."""
    res = [
        OutOfPlaneOperators(m).matrices(q).neutral_residual for _, m, q in map(_buckled, (8, 16))
    ]
    assert res[1] < res[0] / 10


def test_quick_validation_case_passes():
    """Every numerics check of the quick case passes; the finding is reported."""
    from test_validation import quick_result

    res = quick_result("out_of_plane")
    failed = [(c.name, c.measured) for c in res.checks if c.category == "numerics" and not c.passed]
    assert not failed, failed
    paper = {c.name: c for c in res.checks if c.category == "paper"}
    assert not paper["planar_v_cr_is_first"].passed  # the out-of-plane onset comes first
    assert res.findings


@pytest.mark.slow
def test_full_validation_case_passes():
    from fempipe.validation import load_case

    res = load_case("out_of_plane").run(quick=False)
    failed = [(c.name, c.measured) for c in res.checks if c.category == "numerics" and not c.passed]
    assert not failed, failed

"""Hopf criticality of the flutter events (fempipe.analyses.stability.hopf).

The generic routine against a normal form in disguise (exact l1), the pipe's
Jacobian against differences of its vector field, the mirror symmetry
(theta, alpha) -> (-theta, -alpha), independence of the difference step,
lambda'(v) against differences of eigenvalues, the normal-form amplitude
against cycles shot near onset, refusals and the CLI keys.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from clirun import run_json

from fempipe.analyses.stability import analyse_stability
from fempipe.analyses.stability.eigensolvers import quadratic_eigen
from fempipe.analyses.stability.hopf import (
    EVENT_KEYS,
    decorate_events,
    first_lyapunov_coefficient,
    lyapunov_coefficient,
    normal_forms,
    pipe_derivatives,
    pipe_jacobian,
)
from fempipe.analyses.stability.linear import linearized_matrices
from fempipe.analyses.statics import solve_path
from fempipe.model.discretization import discretization_from_name
from fempipe.model.dynamics_problem import PipeDynamics, acceleration
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel


# ---------------------------------------------------------------- generic --
def _disguised_normal_form(a: float, b: float, w: float, seed: int = 1):
    """z' = i w z + (a + i b) |z|^2 z (z = y1 + i y2) and y3' = -2 y3, seen through the
    nonlinear change of variables y = S u + Q(S u): l1 = a / w for |q| = 1/sqrt(2)
    in y (q = (1, -i)/2 gives y = z q + zbar qbar = (Re z, Im z)).

    The change of variables has quadratic terms, so every term of Kuznetsov's
    formula is exercised, and a near-identity change leaves l1 invariant.
    The Jacobian is the complex-step derivative (exact to rounding).
    """
    rng = np.random.default_rng(seed)
    S = rng.normal(size=(3, 3)) + 3.0 * np.eye(3)
    Qc = 0.5 * rng.normal(size=(3, 3, 3))

    def f(y):
        r2 = y[0] ** 2 + y[1] ** 2
        return np.array(
            [
                -w * y[1] + (a * y[0] - b * y[1]) * r2,
                w * y[0] + (b * y[0] + a * y[1]) * r2,
                -2 * y[2],
            ]
        )

    def F(u):
        s = S @ u
        Dphi = (np.eye(3) + np.einsum("ijk,k->ij", Qc, s) + np.einsum("ijk,j->ik", Qc, s)) @ S
        return np.linalg.solve(Dphi, f(s + np.einsum("ijk,j,k->i", Qc, s, s)))

    def jac(u):
        e = 1e-30
        return np.array([F(u + 1j * e * np.eye(3)[j]).imag / e for j in range(3)]).T

    G = S.T @ np.diag([2.0, 2.0, 0.0]) @ S  # q^H G q = 1 <=> |q_y|^2 = 1/2
    return jac, G


@pytest.mark.parametrize("a", [-0.8, 0.35])
def test_generic_l1_of_a_disguised_normal_form(a):
    w = 1.7
    jac, G = _disguised_normal_form(a, 0.3, w)
    hc = lyapunov_coefficient(jac, np.zeros(3), norm=G)
    assert hc.omega == pytest.approx(w, rel=1e-12)
    assert hc.l1 == pytest.approx(a / w, rel=1e-6)
    assert hc.criticality == ("supercritical" if a < 0 else "subcritical")
    assert hc.uncertainty < 1e-6


def test_generic_degenerate_when_l1_vanishes():
    jac, G = _disguised_normal_form(0.0, 0.3, 1.7)
    hc = lyapunov_coefficient(jac, np.zeros(3), norm=G)
    assert abs(hc.l1) < 1e-6
    assert hc.criticality == "degenerate"


# ------------------------------------------------------------------- pipe --
def _hopf_state(name: str, alpha: float, v_max: float = 9.0):
    """(model, q, event) at the first flutter of the primary branch."""
    model = PipeModel(discretization_from_name(name), Params(alpha=alpha))
    res = analyse_stability(model, v_max=v_max, follow_bifurcations=False)
    ev = next(e for e in res.events if e.type == "flutter")
    q = solve_path(model, np.linspace(0.0, ev.v, 12))[-1].q
    return model.with_params(replace(model.params, v=ev.v)), q, ev, res


@pytest.fixture(scope="module")
def hopf_p34():
    return _hopf_state("P3:4", 0.6)


def test_pipe_jacobian_is_the_derivative_of_the_vector_field():
    model = PipeModel(discretization_from_name("P3:4"), Params(alpha=0.6, v=5.0, end_mass=0.2))
    rng = np.random.default_rng(0)
    n = model.n
    x = 0.3 * rng.normal(size=2 * n)

    def F(x):
        return np.concatenate([x[n:], acceleration(model, x[:n], x[n:])])

    J = pipe_jacobian(model, x)
    h = 1e-6
    for j in rng.choice(2 * n, 6, replace=False):
        e = np.zeros(2 * n)
        e[j] = h
        fd = (F(x + e) - F(x - e)) / (2 * h)
        assert np.allclose(J[:, j], fd, rtol=1e-5, atol=1e-5 * np.abs(J[:, j]).max())


def test_hopf_point_is_on_the_imaginary_axis_and_l1_is_step_independent(hopf_p34):
    m, q, ev, _ = hopf_p34
    nf = first_lyapunov_coefficient(m, q, omega=ev.frequency)
    assert abs(nf.eigenvalue.real) < 1e-8 * nf.omega
    assert nf.omega == pytest.approx(ev.frequency, rel=1e-8)
    values = [first_lyapunov_coefficient(m, q, omega=ev.frequency, step=h).l1 for h in (1e-5, 1e-3)]
    # The plateau: O(h^2) truncation and O(eps/h^2) rounding both below 1e-5.
    assert values == pytest.approx([nf.l1] * 2, rel=1e-5)
    assert nf.uncertainty < 1e-5 * abs(nf.l1)


def test_transversality_against_differences_of_the_eigenvalue(hopf_p34):
    m, q, ev, _ = hopf_p34
    nf = first_lyapunov_coefficient(m, q, omega=ev.frequency)
    dv = 1e-4
    lam = []
    for v in (ev.v - dv, ev.v + dv):
        mv = m.with_params(replace(m.params, v=v))
        qv = solve_path(m, [ev.v, v], q0=q)[-1].q
        ls, _, _ = quadratic_eigen(*linearized_matrices(mv, qv))
        lam.append(ls[np.argmin(np.abs(ls - nf.eigenvalue))])
    fd = (lam[1] - lam[0]) / (2 * dv)
    assert nf.eigenvalue_derivative == pytest.approx(fd, rel=1e-6)
    assert nf.transversality > 0  # a flutter: the pair crosses to Re > 0 as v increases


def test_mirror_symmetry_leaves_l1_unchanged(hopf_p34):
    """(theta, alpha) -> (-theta, -alpha) maps Eq. (20) onto itself."""
    m, q, ev, _ = hopf_p34
    nf = first_lyapunov_coefficient(m, q, omega=ev.frequency)
    mirror = m.with_params(replace(m.params, alpha=-m.params.alpha))
    nf_m = first_lyapunov_coefficient(mirror, -q, omega=ev.frequency)
    assert nf_m.l1 == pytest.approx(nf.l1, rel=1e-7)
    assert nf_m.transversality == pytest.approx(nf.transversality, rel=1e-7)
    assert nf_m.amplitude_coefficients["eta_tip"] == pytest.approx(
        nf.amplitude_coefficients["eta_tip"], rel=1e-7
    )


@pytest.mark.parametrize("alpha", [0.0, math.pi])
def test_straight_pipe_shortcut_equals_both_sided_differences(alpha):
    """On the straight pipe at alpha = 0, pi the Jacobian is even (mirror symmetry), so the
    normal form takes J(x0 - h u) = J(x0 + h u): the same D2J, B = 0, the same l1 as the
    two-sided differences; with J(x0 - h u) computed the first derivative vanishes too."""
    model = PipeModel(
        discretization_from_name("P3:6"), Params(alpha=alpha, gamma=10.0, beta=0.2, v=6.0)
    )
    n = model.n
    x0 = np.zeros(2 * n)
    u = np.random.default_rng(3).normal(size=2 * n)
    both = pipe_derivatives(model, x0, mirror=False)
    short = pipe_derivatives(model, x0)  # detected
    for h in (1e-4, 1e-3):
        d1, d2 = both(u, h)
        s1, s2 = short(u, h)
        scale = np.abs(d2).max()
        assert np.abs(s1).max() == 0.0 and np.abs(d1).max() <= 1e-10 * scale
        assert np.abs(s2 - d2).max() <= 1e-10 * scale
    # One Jacobian per direction instead of two.
    calls = []
    original = PipeModel.jacobians

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(PipeModel, "jacobians", counted)
        short(u, 1e-3)
        n_short = len(calls)
        both(u, 1e-3)
    assert (n_short, len(calls) - n_short) == (1, 2)
    # Off the straight pipe (alpha = 0.3) J is not even: the detection says so.
    tilted = model.with_params(replace(model.params, alpha=0.3))
    d1, _ = pipe_derivatives(tilted, x0)(u, 1e-3)
    assert np.abs(d1).max() > 1e-3


def test_amplitude_prediction_against_the_shot_cycle(hopf_p34):
    """Shot cycles at v_cr (1 + eps): the ratio to the prediction c sqrt(v - v_cr) tends to 1.

    The normal form truncates terms one order of |v - v_cr| higher
    (lambda'' and the v-dependence of l1, the fifth-order term l2 rho^2), so
    the ratio is 1 + k (v - v_cr) + ...: the deviation at 4 eps is about 4
    times that at eps, and at eps it is small.
    """
    m, q, ev, _ = _hopf_state("P2:4", 0.6)
    nf = first_lyapunov_coefficient(m, q, omega=ev.frequency)
    assert nf.criticality == "supercritical" and nf.side == "above"
    dev = _onset_deviations(m, nf, (2e-3, 8e-3), rtol=1e-8)
    # Measured: -0.0025, -0.0100 (the integration error, 1e-8, is far below).
    assert abs(dev[0]) < 0.01
    assert 3.0 < dev[1] / dev[0] < 5.0  # linear in v - v_cr


def _onset_deviations(m, nf, eps_list, rtol: float, stable: bool | None = True) -> list:
    """Shot eta_tip amplitude / prediction - 1 at v_cr (1 +- eps) on the cycles' side."""
    from fempipe.analyses.limit_cycle import shoot

    sign = 1.0 if nf.side == "above" else -1.0
    dev = []
    for eps in eps_list:
        v = nf.v * (1 + sign * eps)
        q0, qd0, T = nf.initial_state(v)
        problem = PipeDynamics(m.with_params(replace(m.params, v=v)))
        cyc = shoot(problem, q0, qd0, T, rtol=rtol, tol=10 * rtol)
        lo, hi = cyc.tip["eta_tip"]
        pred = nf.amplitude_coefficients["eta_tip"] * math.sqrt(abs(v - nf.v))
        dev.append(0.5 * (hi - lo) / pred - 1.0)
        assert cyc.period * nf.omega / (2 * math.pi) == pytest.approx(1.0, abs=0.02)
        if stable is not None:
            assert cyc.stable == stable  # supercritical: the cycle born is stable
    return dev


@pytest.mark.slow
@pytest.mark.parametrize("alpha", [0.0, math.pi / 4, math.pi / 2, 3 * math.pi / 4, math.pi])
def test_onset_cycles_of_the_paper_case(alpha):
    """The paper's case (P3:8): at the first flutter of the primary branch the shot
    amplitude over the prediction tends to 1 linearly in v - v_cr (eps = 1e-3, 4e-3,
    1.6e-2) and amplitude^2 grows like (v - v_cr)^1."""
    m, q, ev, _ = _hopf_state("P3:8", alpha, v_max=7.0)
    nf = first_lyapunov_coefficient(m, q, omega=ev.frequency)
    assert nf.criticality == "supercritical"
    eps = (1e-3, 4e-3, 1.6e-2)
    dev = _onset_deviations(m, nf, eps, rtol=1e-9)
    assert abs(dev[0]) < 0.005
    assert 3.0 < dev[1] / dev[0] < 5.0 and 3.0 < dev[2] / dev[1] < 5.0
    dv = np.array(eps) * nf.v
    amp2 = (nf.amplitude_coefficients["eta_tip"] * (1 + np.array(dev))) ** 2 * dv
    slope = np.polyfit(np.log(dv), np.log(amp2), 1)[0]
    # amp^2 = c^2 dv (1 + dev)^2 with dev ~ k dv: d log amp^2 / d log dv = 1 + 2 dev + ...,
    # so the fitted slope lies between 1 and 1 + 2 dev at the largest eps.
    assert abs(slope - 1.0) <= 2.0 * abs(dev[2]) + 1e-3


# --------------------------------------------------------- refusals, CLI --
def test_hysteretic_damping_has_no_normal_form(hopf_p34):
    m, q, ev, res = hopf_p34
    mh = m.with_params(replace(m.params, hysteretic_damping=0.05))
    with pytest.raises(ValueError, match="hysteretic_damping"):
        first_lyapunov_coefficient(mh, q)
    forms = normal_forms(mh, res)
    assert forms and all("hysteretic" in f for f in forms.values())
    d = decorate_events(res.to_dict(), mh, res)
    flutter = [e for e in d["events"] if e["type"] == "flutter"]
    assert flutter and all(e["criticality"] is None and e["hopf_note"] for e in flutter)


def test_critical_json_has_the_hopf_keys(capsys):
    d = run_json(
        capsys, ["critical", "--alpha", "0.6", "--v", "0,9", "--fe", "P3:4", "--json", "--quiet"]
    )
    assert d["critical"]["type"] == "flutter"
    for e in [d["critical"], *d["events"], *d["branches"][0]["events"]]:
        if e["type"] == "flutter" and e["plane"] == "in":
            assert set(EVENT_KEYS) <= set(e)
            assert e["criticality"] == "supercritical" and e["first_lyapunov_coefficient"] < 0
        elif e["type"] == "flutter":
            # out of the plane: the 3-D model's normal form, with the tip's swing out of it
            assert set(EVENT_KEYS) <= set(e) and e["criticality"] == "supercritical"
            assert e["hopf_note"] is None and e["Y_tip_amplitude_coefficient"] > 0
        else:
            assert "criticality" not in e
    assert d["critical"]["plane"] == "out"  # alpha = 0.6: the pipe leaves its plane first
    assert d["critical_in_plane"]["criticality"] == "supercritical"


@pytest.mark.slow
def test_subcritical_onset_with_an_end_mass():
    """beta = 0.15, end mass Gamma = 0.5 (alpha = 0): l1 > 0, and Newton shooting from the
    normal form finds the unstable cycles below v_cr (a transient would not), their
    amplitude over the prediction tending to 1 linearly in v_cr - v."""
    model = PipeModel(discretization_from_name("P3:4"), Params(alpha=0.0, beta=0.15, end_mass=0.5))
    res = analyse_stability(model, v_max=6.0, follow_bifurcations=False)
    ev = next(e for e in res.events if e.type == "flutter")
    assert ev.stable_before
    q = solve_path(model, np.linspace(0.0, ev.v, 6))[-1].q
    m = model.with_params(replace(model.params, v=ev.v))
    nf = first_lyapunov_coefficient(m, q, omega=ev.frequency)
    assert nf.criticality == "subcritical" and nf.side == "below"
    dev = _onset_deviations(m, nf, (6.25e-5, 2.5e-4), rtol=1e-9, stable=False)
    assert abs(dev[0]) < 0.01
    assert 3.0 < dev[1] / dev[0] < 5.0

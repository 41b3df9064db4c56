"""The whirl of the hanging pipe: the rotating-frame BVP (fempipe.validation.whirl_bvp) and the
periodic orbit of the 3-D model (fempipe.analyses.three_d.whirl)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fempipe.analyses.stability.eigensolvers import quadratic_eigen
from fempipe.analyses.stability.linear import linearized_matrices
from fempipe.analyses.three_d.whirl import find_whirl, whirl_state
from fempipe.model.discretization import FiniteElement
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.model import PipeModel3D
from fempipe.validation.whirl_bvp import solve_whirl_bvp


def _flutter_mode(v: float = 6.3, n_elements: int = 4):
    """The hanging pipe's flutter eigenvalue near onset and its theta on 101 points (FE)."""
    disc = FiniteElement(n_elements, 3)
    K, C, M = linearized_matrices(PipeModel(disc, Params(alpha=0.0, v=v)), np.zeros(disc.n))
    lam, X, _ = quadratic_eigen(K, C, M)
    i = int(np.argmin(np.abs(lam - 15.7j)))
    xi = np.linspace(0.0, 1.0, 101)
    Phi = disc.Phi.toarray()
    th = Phi @ X[:, i]
    x = np.r_[0.0, disc.quad.x]
    return lam[i], np.interp(xi, x, np.r_[0, th.real]) + 1j * np.interp(xi, x, np.r_[0, th.imag])


@pytest.fixture(scope="module")
def flutter():
    return _flutter_mode()


def test_bvp_whirl_is_born_at_the_planar_flutter_onset(flutter):
    """A small whirl of the continuum (tip radius 0.01, v free) sits at the Hopf point: its
    v and omega tend to the planar FE flutter onset (P3:16, computed here by
    fempipe.analyses.stability.find_critical_velocity: v_cr = 6.33369, omega_cr = 15.7355, a
    discretization error below 1e-7) as the radius^2 (the Hopf normal form: v - v_cr ~
    radius^2).  Two radii extrapolate to radius 0: measured 1e-6 and 2e-6 off."""
    from fempipe.analyses.stability import find_critical_velocity
    from fempipe.validation.whirl_bvp import _initial_guess, _result, _solve

    onset = find_critical_velocity(PipeModel(FiniteElement(16, 3), Params(alpha=0.0)), v_max=8.0)
    v_cr, omega_cr = onset.v_cr, onset.events[0].frequency

    lam, slope = flutter
    prm = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3, "alpha": 0.0, "sigma": 0.0}
    prm["end_mass"] = 0.0
    xi = np.linspace(0.0, 1.0, slope.size)
    out = []
    for R in (0.01, 0.02):
        y = _initial_guess(xi, R, 6.33, 18.9, 0.0, slope)
        res = _solve(
            xi,
            y,
            np.array([abs(lam.imag), 6.33]),
            fixed_v=None,
            R=R,
            prm=prm,
            tol=1e-9,
            max_nodes=20000,
        )
        assert res.success
        out.append(res.p)
        # the fluid's supply balances the Kelvin-Voigt and Coriolis losses
        w = _result(res, res.p[1], prm)
        assert abs(w.supply - w.dissipation) < 1e-5 * w.dissipation
    (om1, v1), (om2, v2) = out
    v0, om0 = (4 * v1 - v2) / 3, (4 * om1 - om2) / 3
    assert abs(v0 - v_cr) < 2e-5
    assert abs(om0 - omega_cr) < 2e-5
    assert v2 > v1  # supercritical in the amplitude: v grows along the branch


@pytest.mark.slow
def test_bvp_power_balance_and_rigidity(flutter):
    """At v = 7: the fluid's supply -v^2 r_dot(1) . t(1) balances the Kelvin-Voigt loss
    mu omega^2 \\int |t'|^2 (which a whirl does not escape: k = -omega t') and the Coriolis
    loss v sqrt(beta) |r_dot(1)|^2; the shape is not planar."""
    lam, slope = flutter
    w = solve_whirl_bvp(7.0, hopf=(6.33, abs(lam.imag)), slope=slope, tol=1e-9)
    assert abs(w.supply - w.dissipation) < 1e-6 * w.dissipation
    assert w.dissipation > 0
    assert 0.1 < w.radius < 0.5
    xi = np.linspace(0, 1, 201)
    assert np.max(np.abs(w.sol(xi)[2])) > 0.05 * w.radius  # r_3 != 0 inside: a twisted shape


def test_curvature_rate_of_a_turning_shape():
    """PipeModel3D.curvature_rate of a non-planar shape turning rigidly at omega about e_1 is
    k = -omega t' (the twist-free frame anchored at the clamp turns at omega (e_1 - t)), not
    zero: to the fit's error, falling with h."""
    omega = 3.0

    def shape(x):
        th, ps = 0.8 * np.sin(0.5 * np.pi * x), 0.5 * x**2
        return np.vstack([np.cos(ps) * np.cos(th), np.cos(ps) * np.sin(th), np.sin(ps)])

    errs = []
    for ne in (2, 4):
        sp = PipeModel3D(FiniteElement(ne, 3), Params(alpha=0.0, v=5.0))
        U, Ud = whirl_state(sp, shape, omega)
        fl = sp.fields(U, Ud)
        k = sp.curvature_rate(fl)[:, :, 0]
        tp = fl.t_prime[:, :, 0]
        errs.append(np.max(np.abs(k + omega * tp)) / np.max(np.abs(omega * tp)))
    assert errs[1] < 3e-3
    assert errs[1] < errs[0] / 5


def test_radius_is_a_time_average_on_unequal_steps():
    """The whirl's mean tip radius is a time average, not a mean of the step ends: on a radius
    R0 (1 + eps cos 2 omega tau) (the shape of the discrete whirl's modulation) sampled with
    steps ten times shorter where the radius is large the plain mean of the samples is 4.0e-4
    off (half the modulation's amplitude eps R0), the time average only by the trapezoidal
    rule's O(step^2) error (1.2e-7 on these coarse steps); the variation is 2 eps."""
    from fempipe.analyses.three_d.whirl import _radius_statistics

    R0, eps, omega = 0.38, 2e-3, 24.5
    T = 2 * math.pi / omega
    # fine steps where cos 2 omega tau > 0 near tau = 0 and T/2, coarse elsewhere
    edges = np.linspace(0.0, T, 9)
    ts = np.unique(
        np.concatenate(
            [
                np.linspace(a, b, 201 if k in (0, 3, 4, 7) else 21)
                for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True))
            ]
        )
    )
    rad = R0 * (1 + eps * np.cos(2 * omega * ts))
    assert abs(np.mean(rad) - R0) > 1e-4  # the samples' plain mean is biased
    mean, variation = _radius_statistics(ts, rad)
    assert abs(mean - R0) < 1e-6
    assert abs(variation - 2 * eps) < 1e-6


@pytest.mark.parametrize("alpha", [0.0, math.pi])
def test_tip_turn_is_right_handed_about_e1_at_both_axisymmetric_inclinations(alpha):
    """A bent shape turned by +phi about e_1 (from e_2 towards e_3) for phi from 0 to 2 pi:
    the tip's angle grows by 2 pi at alpha = 0 and at alpha = pi (where the files' Z_tip is
    -eta_tip, and the angle of (Z_tip, Y_tip) would fall by 2 pi), at a constant distance."""
    from fempipe.analyses.three_d.whirl import tangent_state, tip_turn

    sp = PipeModel3D(FiniteElement(3, 3), Params(alpha=alpha, v=5.0))
    th = 0.8 * np.sin(0.5 * np.pi * sp.x)
    base = np.column_stack([np.cos(th), np.sin(th), np.zeros_like(th)])
    states = []
    for phi in np.linspace(0.0, 2 * np.pi, 25):
        c, s_ = np.cos(phi), np.sin(phi)
        turn = np.array([[1.0, 0.0, 0.0], [0.0, c, -s_], [0.0, s_, c]])
        states.append(tangent_state(sp, base @ turn.T, np.zeros_like(base))[0])
    radius, angle = tip_turn(sp.tip_coordinates(np.array(states)))
    assert angle[-1] - angle[0] == pytest.approx(2 * np.pi, abs=1e-6)
    assert np.ptp(radius) < 1e-6 * radius.mean()


@pytest.mark.slow
def test_whirl_by_shooting_matches_the_bvp(flutter):
    """The whirl of the 3-D model on P3:3 at v = 10 (shot from the BVP's shape) against the
    rotating-frame BVP: omega and the tip radius to the discretization error of P3:3
    (measured 0.038 and 2.5e-4), the tip radius constant to 0.5 % along the orbit, and unstable (a
    pair of multipliers of modulus 1.40 on P3:3): the planar cycle is the attractor."""
    lam, slope = flutter
    b = solve_whirl_bvp(10.0, hopf=(6.33, abs(lam.imag)), slope=slope, tol=1e-9)
    sp = PipeModel3D(FiniteElement(3, 3), Params(alpha=0.0, v=10.0))
    U, Ud = whirl_state(sp, lambda x: b.sol(x)[3:6], b.omega)
    w = find_whirl(sp, U, Ud, b.period)
    assert abs(w.omega - b.omega) < 0.1
    assert abs(w.radius - b.radius) < 2e-3
    assert w.radius_variation < 1e-2
    assert w.rotation_defect < 1e-2
    assert not w.stable and w.max_nontrivial > 1.2
    assert math.isclose(abs(w.omega) * w.period, 2 * math.pi)


@pytest.mark.slow
def test_guess_from_a_planar_cycle_turns():
    """The standing wave plus i times its copy turned by 90 degrees a quarter period apart
    (whirl_guess_from_cycle) is a rotating wave: along the planar cycle (v = 6.5, close to
    onset, nearly harmonic) the guessed tip turns by pi/2 each quarter period, right-handed,
    at a distance from the vertical constant to the cycle's anharmonicity (1 %)."""
    from dataclasses import replace

    from fempipe.analyses.limit_cycle.attractor import find_attractor
    from fempipe.analyses.three_d.whirl import whirl_guess_from_cycle
    from fempipe.model.three_d.model import planar_state

    disc = FiniteElement(3, 3)
    params = Params(alpha=0.0, v=6.5)
    cycle = find_attractor(PipeModel(disc, params)).cycle
    lift = np.vectorize(planar_state, signature="(n)->(m)")
    cycle3 = replace(cycle, orbit_q=lift(cycle.orbit_q), orbit_qdot=lift(cycle.orbit_qdot))
    space = PipeModel3D(disc, params)
    radius, angle = [], []
    for tau in np.linspace(0.0, cycle.period, 5)[:4]:
        U, _, T = whirl_guess_from_cycle(space, cycle3, tau)
        d = space.tip_coordinates(U)
        radius.append(math.hypot(d["Z_tip"], d["Y_tip"]))
        angle.append(math.atan2(d["Y_tip"], d["Z_tip"]))
    turns = np.diff(np.unwrap(angle))
    assert np.allclose(turns, 0.5 * math.pi, atol=0.05)
    assert np.ptp(radius) < 0.02 * np.mean(radius)
    assert abs(max(radius) - cycle.tip["eta_tip"][1]) < 0.02 * max(radius)

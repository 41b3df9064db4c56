"""The period-doubled orbit inside a principal region (fempipe.analyses.parametric.response),
checked against what shares none of its code: the edge of the region from the reduced linear
problem's multipliers, the square-root law of a period-doubling bifurcation, Eq. (20)
integrated in time from a small perturbation, and the symmetry theta -> -theta."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from fempipe import FiniteElement, Params, PipeModel, PulsatingFlow
from fempipe.analyses.parametric import PulsationPencil, ReducedPulsation, floquet_multipliers
from fempipe.analyses.parametric.response import (
    continue_subharmonic,
    continue_subharmonic_in_sigma,
)
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.solvers.radau import Radau

V0, SIGMA = 6.0, 0.15
MODEL = PipeModel(
    FiniteElement(6, 3), Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.005, v=V0)
)  # Paidoussis & Issid's hanging pipe


@pytest.fixture(scope="module")
def reduced():
    return ReducedPulsation(PulsationPencil.of(MODEL), V0, 3)


def _margin(reduced, sigma, omega):
    return math.log(abs(floquet_multipliers(reduced, sigma, omega)[0]))


@pytest.fixture(scope="module")
def lower_edge(reduced):
    """The lower edge of the principal region of mode 2 at SIGMA (the linear problem)."""
    return brentq(lambda w: _margin(reduced, SIGMA, w), 24.0, 28.0, xtol=1e-12)


@pytest.fixture(scope="module")
def branch(lower_edge):
    return continue_subharmonic(MODEL, V0, SIGMA, lower_edge, ds=0.01, ds_max=0.02, max_points=5)


def _run(x, sigma, omega, periods, samples=8):
    """Eq. (20) from x over ``periods`` T (fixed steps T / 128): the end state and
    max |theta(1)| over the last 2 T from the dense output."""
    n = MODEL.n
    T = 2 * math.pi / omega
    stepper = Radau(
        PipeDynamics(MODEL, PulsatingFlow(V0, sigma, omega)), x[:n], x[n:], 0.0, h_fixed=T / 128
    )
    peak = 0.0
    for t, _, _ in stepper.steps(periods * T):
        if t > (periods - 2) * T:
            for s in np.linspace(stepper.t_old, t, samples + 1)[1:]:
                peak = max(peak, abs(MODEL.disc.tip @ stepper.dense(s)[0]))
    return np.r_[stepper.q, stepper.qdot], peak


def test_the_branch_bifurcates_supercritically_like_a_square_root(branch, lower_edge):
    """From the lower edge the orbit grows into the region, stable (supercritical), with
    amplitude ~ sqrt(omega - omega_edge): the exponent fitted is 1/2 within 0.05; every
    point is a fixed point of the 2T map to the tolerance."""
    assert branch.criticality == "supercritical" and branch.inward == 1
    assert branch.edge == lower_edge and len(branch.points) == 5
    omega = branch.values
    amp = branch.amplitudes
    assert np.all(np.diff(omega) > 0) and np.all(np.diff(amp) > 0)
    assert all(p.stable and p.residual < 1e-8 for p in branch.points[1:])
    assert abs(abs(branch.points[0].multipliers[0]) - 1) < 1e-3  # at the bifurcation: +1
    fit = slice(1, None)  # the first point sits within the edge's tolerance of omega_edge
    slope = np.polyfit(np.log(omega[fit] - lower_edge), np.log(amp[fit]), 1)[0]
    assert slope == pytest.approx(0.5, abs=0.05)
    d = branch.to_dict()
    assert d["criticality"] == "supercritical" and len(d["points"]) == 5


def test_the_mirror_of_the_orbit_is_the_orbit_shifted_by_a_period(branch):
    """theta -> -theta: the mirror image of the 2T orbit is a 2T orbit too, and it is the
    orbit half a period (T) later: the two are one branch."""
    p = branch.points[-1]
    x = np.r_[p.q0, p.qdot0]
    mirror, _ = _run(-x, SIGMA, p.omega, 2)
    assert np.linalg.norm(mirror + x) < 1e-7 * np.linalg.norm(x)
    half, _ = _run(x, SIGMA, p.omega, 1)
    assert np.linalg.norm(half + x) < 1e-7 * np.linalg.norm(x)
    assert p.x_tip[0] < p.x_tip[1] and abs(p.z_tip[0] + p.z_tip[1]) < 1e-6


def test_outside_the_region_a_small_motion_decays(reduced, lower_edge):
    """Below the lower edge the straight state is stable: a small perturbation decays."""
    omega = lower_edge - 2.0
    assert _margin(reduced, SIGMA, omega) < 0
    x = 1e-3 * np.random.default_rng(2).standard_normal(2 * MODEL.n)
    end, _ = _run(x, SIGMA, omega, 12)
    assert np.linalg.norm(end) < 0.3 * np.linalg.norm(x)


def test_the_branch_in_sigma(reduced):
    """At fixed omega = 29.5 the orbit grows from the critical sigma as sigma increases
    (into the region), stable; the edge is where the linear problem's multiplier is -1."""
    omega = 29.5
    sigma_c = brentq(lambda s: _margin(reduced, s, omega), 0.01, 0.15, xtol=1e-12)
    b = continue_subharmonic_in_sigma(MODEL, V0, omega, sigma_c, ds=0.01, max_points=3)
    assert b.parameter == "sigma" and b.inward == 1 and b.criticality == "supercritical"
    assert np.all(np.diff(b.values) > 0) and np.all(np.diff(b.amplitudes) > 0)
    assert all(p.omega == omega for p in b.points)


def test_refuses_a_start_that_is_not_an_edge():
    with pytest.raises(ValueError, match="multiplier -1"):
        continue_subharmonic(MODEL, V0, SIGMA, 20.0, max_points=1)
    with pytest.raises(ValueError, match="direction"):
        continue_subharmonic(MODEL, V0, SIGMA, 26.3, direction=0)


@pytest.mark.slow
def test_a_small_perturbation_settles_on_the_orbit(lower_edge):
    """Inside the region, on the supercritical side, Eq. (20) integrated from a small
    perturbation of the straight state settles on the computed 2T orbit: max |theta(1)| over
    the last 2T within 1e-3 relative."""
    b = continue_subharmonic(MODEL, V0, SIGMA, lower_edge, max_points=30, omega_bounds=(20, 27.0))
    p = b.points[-1]
    assert p.stable and 27.0 < p.omega < 28.0 and b.stop.startswith("omega left")
    x = 1e-3 * np.random.default_rng(5).standard_normal(2 * MODEL.n)
    _, peak = _run(x, SIGMA, p.omega, 300)
    assert peak == pytest.approx(p.amplitude, rel=1e-3)


def test_the_orbit_out_of_the_plane(branch):
    """The planar 2T orbit of the hanging pipe out of the plane (the linear out-of-plane
    equation about it, flow acceleration included): the orbit turned about the vertical is an
    orbit too, so one multiplier is 1 (to the discretization's symmetry defect, which grows from
    zero with the amplitude); the others lie inside the unit circle: the planar oscillation
    survives out of the plane."""
    from fempipe.analyses.three_d.floquet import compute_out_of_plane_floquet

    orbit = branch.points[-1]
    out = compute_out_of_plane_floquet(
        MODEL, orbit, rtol=1e-9, flow=PulsatingFlow(V0, orbit.sigma, orbit.omega)
    )
    assert out.symmetry_defect < 1e-5 and 0.1 < out.max_nontrivial < 0.5 and out.stable

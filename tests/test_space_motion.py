"""simulate_3d's classification (fempipe.analyses.three_d.motion)."""

from __future__ import annotations

import math

import numpy as np

from fempipe.analyses.three_d.motion import REST_TIME, _settled, simulate_3d, two_frequencies
from fempipe.model.discretization import FiniteElement
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.model import PipeModel3D, planar_state


def test_rest_counts_from_the_last_crossing():
    slow = np.full(6, 1e-10)
    crossed = [(2.0, None, None)]
    big = [0.1]
    assert _settled(2.0 + 1.01 * REST_TIME, slow, crossed, big, 1.0)
    assert not _settled(2.0 + 0.99 * REST_TIME, slow, crossed, big, 1.0)
    assert not _settled(2.0 + 2 * REST_TIME, np.full(6, 1e-6), crossed, big, 1.0)
    assert _settled(1.01 * REST_TIME, slow, [], [], 1.0)
    # still crossing, but with a swing that has died out
    assert _settled(2.0 + 0.5 * REST_TIME, slow, crossed, [1e-12], 1.0)


def test_a_decaying_oscillation_out_of_the_plane_is_an_equilibrium():
    """Below the out-of-plane v_cr of the horizontal pipe (5.82) the out-of-plane
    perturbation dies out about the static state, crossing the section level at every
    swing: its returns agree to the recurrence tolerance once it is small, which is not a
    periodic motion (the swings shrink by e^(Re lambda T) a return)."""
    model = PipeModel(FiniteElement(3, 3), Params(alpha=math.pi / 2, v=5.5))
    r = simulate_3d(model, t_max=60.0)
    assert r.kind == "equilibrium" and r.period is None
    assert abs(r.tip["Y_tip"][1]) < 1e-8


def test_equilibrium_after_a_crossing():
    """The standing pipe (alpha = pi, gamma = 18.9 above the column's buckling load 7.84) at
    v = 0, started below the section and moving up through it, falls to its buckled state
    on the far side and rests there: an equilibrium away from the section level, reached
    after one crossing.  The test of the section 'never crossed' ran on to t_max and called
    it non-periodic."""
    disc = FiniteElement(1, 3)
    model = PipeModel(disc, Params(alpha=math.pi, v=0.0, mu=0.3))
    Phi = disc.Phi.toarray()
    x, w = disc.quad.x, disc.quad.w
    mode = np.linalg.solve(Phi.T @ (w[:, None] * Phi), Phi.T @ (w * np.sin(0.5 * math.pi * x)))
    start = (planar_state(-0.02 * mode), planar_state(0.5 * mode))
    r = simulate_3d(model, initial=start, t_max=15.0, use_shooting=False)
    space = PipeModel3D(disc, model.params)
    eta = space.tip_coordinates(r.U)["eta_tip"]
    assert eta[0] < 0.0 < eta[-1]  # the section (eta_tip + Y_tip = 0 here) was crossed
    assert r.kind == "equilibrium"
    assert r.t_end < 15.0
    # at rest on the buckled state: the residual with zero rates vanishes there
    R = space.residual(r.U[-1])
    assert np.linalg.norm(R) < 1e-6 * np.linalg.norm(space.residual(0.5 * r.U[-1]))
    assert eta[-1] > 0.5


def test_two_incommensurate_frequencies():
    """A two-torus signal (frequencies 1 and sqrt 2, with a combination tone) is told from a
    periodic one with harmonics and a subharmonic (1, 3, 1/2): the known frequencies come
    back to the resolution of the record."""
    t = np.sort(np.random.default_rng(1).uniform(0.0, 200.0, 20000))  # uneven steps
    f2 = math.sqrt(2.0)
    quasi = [
        np.sin(2 * np.pi * t) + 0.3 * np.sin(2 * np.pi * f2 * t),
        0.1 * np.cos(2 * np.pi * (f2 - 1.0) * t),
    ]
    pair = two_frequencies(t, quasi)
    assert pair is not None and len(pair) == 2
    assert abs(pair[0] - 1.0) < 2e-3 and abs(pair[1] - f2) < 2e-3
    periodic = [np.sin(2 * np.pi * t) + 0.3 * np.sin(6 * np.pi * t) + 0.2 * np.sin(np.pi * t)]
    single = two_frequencies(t, periodic)
    assert single is not None and len(single) == 1 and abs(single[0] - 1.0) < 2e-3


def test_a_growing_out_of_plane_oscillation_needs_no_step_halving():
    """The integrator's simplified Newton iteration (mass matrix frozen at a step's start)
    converges on non-planar motion at the steps its error control asks for: the horizontal
    pipe above its out-of-plane v_cr, from the static state perturbed in and out of its plane.
    A heavy gauge (weight 1 instead of PipeModel3D.gauge_weight, model docstring) failed 103
    times in the 168 steps of this run."""
    from fempipe.analyses.statics import solve_static
    from fempipe.analyses.three_d.motion import _perturbed_static_state
    from fempipe.model.three_d.dynamics import PipeDynamics3D
    from fempipe.solvers.radau import Radau

    model = PipeModel(FiniteElement(4, 3), Params(alpha=math.pi / 2, v=10.0))
    space = PipeModel3D(model.disc, model.params)
    U0, Ud0 = _perturbed_static_state(model, space, solve_static(model).q, 1, 0.01, 0.01)
    n = model.disc.n
    stepper = Radau(PipeDynamics3D(space), U0, Ud0, rtol=1e-6)
    for _ in stepper.steps(0.3):
        pass
    assert np.abs(stepper.q[n:]).max() > 1e-3  # out of the plane
    assert stepper.stats.steps > 50
    assert stepper.stats.newton_failures == 0, stepper.stats

"""Out-of-plane perturbations of a moving planar state (the linear psi equation).

Checked against the static out-of-plane model at rest (exact), against the 3-D
model's force field (exact), and through the Floquet multipliers of a planar
cycle against the 3-D model's: two independent discretizations that must
converge to each other.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from fempipe.analyses.limit_cycle import find_attractor
from fempipe.analyses.three_d.floquet import compute_out_of_plane_floquet
from fempipe.model.discretization import FiniteElement
from fempipe.model.out_of_plane.model import OutOfPlaneOperators
from fempipe.model.out_of_plane.motion import OutOfPlaneMotion, OutOfPlaneVariation
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.model import PipeModel3D, planar_state

VARIANTS = Params(alpha=0.7, v=3.0, mu=0.05, end_mass=0.3, external_damping=0.2)


def _state(model, seed):
    rng = np.random.default_rng(seed)
    return rng.normal(scale=0.5, size=(3, model.n))


def test_at_rest_the_matrices_are_the_static_models():
    model = PipeModel(FiniteElement(5, 3), VARIANTS)
    q = _state(model, 1)[0]
    K, C, M = OutOfPlaneMotion(model).matrices(q, 0 * q, 0 * q)
    ops = OutOfPlaneOperators(model)
    st = ops.state(q)
    K0 = ops.bending(st) + ops.geometric_stiffness(st) + ops.follower()
    C0 = ops.coriolis() + VARIANTS.mu * ops.material_bending(st) + ops.external_damping()
    for got, want in ((K, K0), (C, C0), (M, ops.inertia())):
        assert np.abs(got - want).max() <= 1e-13 * np.abs(want).max()


def test_base_force_is_the_3d_models_force_field():
    """G_0 of a moving planar state: every term (inertia, Coriolis, jet, gravity, end mass,
    external damping) against :meth:`PipeModel3D.force_field` at the same planar state."""
    model = PipeModel(FiniteElement(5, 3), VARIANTS)
    q, qd, qdd = _state(model, 2)
    motion = OutOfPlaneMotion(model)
    G0 = motion.base_force(motion.base(q, qd, qdd))
    space = PipeModel3D(model.disc, VARIANTS)
    fl = space.fields(planar_state(q), planar_state(qd), planar_state(qdd))
    G = np.asarray(space.force_field(fl))[:, :, 0]
    assert np.abs(G[:, 2]).max() == 0.0
    assert np.abs(G0 - G[:, :2]).max() <= 1e-12 * np.abs(G).max()


def test_problem_rows_are_the_matrices_and_stages_batch():
    model = PipeModel(FiniteElement(4, 3), Params(alpha=1.0, v=6.0))
    problem = OutOfPlaneVariation(model)
    n = model.n
    rng = np.random.default_rng(3)
    X, Xd, Xdd = rng.normal(scale=0.4, size=(3, 3, 2 * n))
    K, C, M = problem.motion.matrices(X[0, :n], Xd[0, :n], Xdd[0, :n])
    R = problem.residual(0.0, X[0], Xd[0], Xdd[0])
    assert np.allclose(R[n:], K @ X[0, n:] + C @ Xd[0, n:] + M @ Xdd[0, n:], rtol=1e-13)
    assert np.array_equal(R[:n], model.residual(X[0, :n], Xd[0, :n], Xdd[0, :n]))
    batch = problem.stage_jacobians(X, Xd, Xdd)
    for s in range(3):
        one = problem.jacobians(0.0, X[s], Xd[s], Xdd[s])
        for k in range(3):
            assert np.abs(batch[k][s] - one[k]).max() <= 1e-12 * np.abs(one[k]).max()
            assert not batch[k][s][:n, n:].any() and not batch[k][s][n:, :n].any()
    rows = problem.stage_residuals(X, Xd, Xdd)
    for s in range(3):
        assert np.allclose(rows[s], problem.residual(0.0, X[s], Xd[s], Xdd[s]), rtol=1e-12)


def test_springs_are_refused():
    with pytest.raises(ValueError, match="springs"):
        OutOfPlaneMotion(PipeModel(FiniteElement(2, 2), Params(springs=((5.0, 0.5),))))


def test_linear_and_3d_multipliers_converge_to_each_other():
    """The linear psi equation and the 3-D model give the out-of-plane multipliers of the
    cycle at alpha = pi/2, v = 11, mu = 0.05 (a damping that is not small: without the
    Kelvin-Voigt stiffness of the moving state the linear method finds 2.09 instead of
    0.929, measured).  Measured differences 5.5e-4 (P3:3) and 1.8e-6 (P3:6)."""
    params = Params(alpha=math.pi / 2, v=11.0, mu=0.05)
    diff = {}
    for ne in (3, 6):
        model = PipeModel(FiniteElement(ne, 3), params)
        cycle = find_attractor(model).cycle
        lin = compute_out_of_plane_floquet(model, cycle)
        full = compute_out_of_plane_floquet(model, cycle, method="3d")
        assert lin.method == "linear" and full.method == "3d"
        assert lin.stable == full.stable
        diff[ne] = abs(lin.multipliers[0] - full.multipliers[0])
        # the planar blocks are the same equations: the integration tolerance apart
        assert np.abs(lin.planar_multipliers[:3] - full.planar_multipliers[:3]).max() < 1e-6
    assert diff[6] < 1e-5
    assert diff[6] < diff[3] / 2**5  # faster than h^5 (measured: h^8)

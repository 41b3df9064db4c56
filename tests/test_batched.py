"""The batched stage kernels of the pipe (fempipe.model.plane.batched) equal the plain terms.

Every public kernel of :class:`StageKernels` (residual, Jacobians, dR/dv), the
integration operators they use and the problem's choice between batched and
per-stage evaluation (:class:`PipeDynamics`), checked against
:class:`PipeModel` state by state.
"""

from __future__ import annotations

import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.dynamics import Radau, make_initial_state
from fempipe.model import dynamics_problem
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.plane import batched
from fempipe.model.plane.batched import StageKernels, integral_operators, projection_fields
from fempipe.model.quadrature import LineQuadrature
from fempipe.solvers.radau.contract import ImplicitSecondOrderProblem

DISCS = [FiniteElement(4, 2), FiniteElement(4, 3), Modal(3, n_cells=8)]


def _smooth_states(m, disc, rng):
    k = (2 * np.arange(1, 4) - 1) * np.pi / 2
    shape = np.linalg.lstsq(
        np.asarray(disc.Phi.todense() if hasattr(disc.Phi, "todense") else disc.Phi),
        np.sin(np.outer(m.x, k)),
        rcond=None,
    )[0]  # (n, 3): smooth states, as in the energy identity
    return [rng.standard_normal((3, 3)) @ shape.T for _ in range(3)]


# ------------------------------------------------- batched stage residuals --
@pytest.mark.parametrize("disc", DISCS, ids=str)
def test_batched_stage_residual_is_the_residual(disc):
    """The one-call residual of the three Radau stages equals PipeModel.residual
    stage by stage (another order of summation: round-off).  Every term
    enters: dropping any one (mu, v, gamma, beta) moves it by O(1)."""
    rng = np.random.default_rng(3)
    m = PipeModel(disc, Params(alpha=0.7, v=9.0, mu=0.02, beta=0.3, gamma=5.0))
    Q, P, A = _smooth_states(m, disc, rng)
    G = StageKernels.for_model(m).residual(Q, P, A)
    ref = np.array([m.residual(Q[i], P[i], A[i]) for i in range(3)])
    assert np.max(np.abs(G - ref)) < 1e-12 * np.max(np.abs(ref))


@pytest.mark.parametrize(
    "variant", [{"end_mass": 0.2}, {"external_damping": 0.3}, {"springs": ((5.0, 0.5),)}]
)
def test_variants_use_the_per_stage_residual(variant):
    """The kernels know the pipe without variants only: with one there are none
    and the problem offers no stage functions (Radau evaluates each stage with
    PipeModel.residual)."""
    m = PipeModel(FiniteElement(4, 2), Params(alpha=0.3, v=5.0, **variant))
    assert StageKernels.for_model(m) is None
    problem = PipeDynamics(m)
    assert problem.stage_residuals is None and problem.stage_jacobians is None
    assert not problem.prefers_batched_stage_jacobians
    assert problem.parameter_derivative is not None  # per stage
    plain = PipeModel(FiniteElement(4, 2), Params(alpha=0.3, v=5.0))
    assert PipeDynamics(plain).stage_residuals is not None
    assert PipeDynamics(plain, flow=lambda t: (5.0, 0.0)).stage_residuals is None
    assert isinstance(PipeDynamics(plain), ImplicitSecondOrderProblem)


class _PerStage(PipeDynamics):
    """The pipe's problem without its batched stage functions."""

    def __init__(self, model):
        super().__init__(model)
        self.stage_residuals = None


def test_batched_and_per_stage_integrations_agree():
    """Radau with the batched stage residual follows the per-stage one (the same
    steps, states to round-off amplified by the Newton iterations)."""
    m = PipeModel(FiniteElement(4, 3), Params(alpha=0.0, v=10.0))
    q0, p0 = make_initial_state(m, 1, 0.3)
    runs = []
    for problem in (PipeDynamics(m), _PerStage(m)):
        st = Radau(problem, q0, p0, rtol=1e-6)
        for _ in st.steps(0.3):
            pass
        runs.append((st.stats.steps, st.q))
    assert runs[0][0] == runs[1][0]
    np.testing.assert_allclose(runs[0][1], runs[1][1], atol=1e-10)


# ------------------------------------------------ batched stage Jacobians --
@pytest.mark.parametrize("integrals", ["dense", "cells"])
@pytest.mark.parametrize("disc", DISCS, ids=str)
def test_batched_jacobians_are_the_model_jacobians(disc, integrals, monkeypatch):
    """The batched Jacobians (projections moved onto the test side, states
    stacked) equal PipeModel.jacobians at each state, (dR/dq, dR/dq', M), to
    round-off, with the integration operators as dense matrices and cell by
    cell (the path of meshes beyond DENSE_INTEGRALS_MAX points)."""
    if integrals == "cells":
        monkeypatch.setattr(batched, "DENSE_INTEGRALS_MAX", 0)
    rng = np.random.default_rng(4)
    m = PipeModel(disc, Params(alpha=0.7, v=9.0, mu=0.02, beta=0.3, gamma=5.0))
    Q, P, A = (0.5 * rng.standard_normal((3, m.n)) for _ in range(3))
    J = StageKernels.for_model(m).jacobians(Q, P, A)
    for i in range(3):
        ref_i = m.jacobians(Q[i], P[i], A[i])
        for got, ref in zip((J[0][i], J[1][i], J[2][i]), ref_i, strict=True):
            assert np.max(np.abs(got - ref)) < 1e-13 * np.max(np.abs(ref))
    assert StageKernels.for_model(PipeModel(disc, Params(v=9.0, end_mass=0.1))) is None


@pytest.mark.parametrize("integrals", ["dense", "cells"])
def test_integral_operators_are_the_quadratures(integrals, monkeypatch):
    """C and C^R of the kernels (dense or cell by cell) equal LineQuadrature's
    cumulative and from_tip, and so do its cell-wise forms."""
    if integrals == "cells":
        monkeypatch.setattr(batched, "DENSE_INTEGRALS_MAX", 0)
    quad = LineQuadrature(np.array([0.0, 0.1, 0.35, 0.5, 0.8, 1.0]), 4)
    f = np.random.default_rng(6).standard_normal((quad.n_q, 2, 3))
    cumulative, from_tip = integral_operators(quad)
    np.testing.assert_allclose(cumulative(f), quad.cumulative(f), atol=1e-14)
    np.testing.assert_allclose(from_tip(f), quad.from_tip(f), atol=1e-14)
    np.testing.assert_allclose(quad.cumulative_cells(f), quad.cumulative(f), atol=1e-14)
    np.testing.assert_allclose(quad.from_tip_cells(f), quad.from_tip(f), atol=1e-14)


@pytest.mark.parametrize("integrals", ["dense", "cells"])
def test_projection_fields_are_the_adjoint_integrals(integrals, monkeypatch):
    """(V, U) = ((C^R)^T (w g), C^T V), dense or cell by cell."""
    if integrals == "cells":
        monkeypatch.setattr(batched, "DENSE_INTEGRALS_MAX", 0)
    quad = LineQuadrature(np.array([0.0, 0.2, 0.45, 1.0]), 3)
    g = np.random.default_rng(8).standard_normal((quad.n_q, 5))
    eye = np.eye(quad.n_q)
    Cm, Rm = quad.cumulative(eye), quad.from_tip(eye)
    V, U = projection_fields(quad)(g)
    np.testing.assert_allclose(V, Rm.T @ (quad.w[:, None] * g), atol=1e-14)
    np.testing.assert_allclose(U, Cm.T @ (Rm.T @ (quad.w[:, None] * g)), atol=1e-14)


def test_cumulative_adjoint_is_the_transpose_of_the_cumulative_integral():
    """The cell-by-cell C^T g of the Jacobians equals the transpose of the dense
    cumulative-integral matrix, on unequal cells (each cell's length enters)."""
    quad = LineQuadrature(np.array([0.0, 0.1, 0.35, 0.5, 0.8, 1.0]), 4)
    g = np.random.default_rng(5).standard_normal((quad.n_q, 7))
    Cm = quad.cumulative(np.eye(quad.n_q))
    np.testing.assert_allclose(quad.cumulative_adjoint(g), Cm.T @ g, atol=1e-14)


# ------------------------------------------------ sensitivity to the flow --
class _Subclassed(PipeModel):
    """A PipeModel subclass: its velocity derivative takes the per-stage path."""


@pytest.mark.parametrize("disc", DISCS, ids=str)
@pytest.mark.parametrize(
    "extra, cls",
    [({}, PipeModel), ({"end_mass": 0.2, "springs": ((5.0, 0.5),)}, PipeModel), ({}, _Subclassed)],
    ids=["batched", "variants", "subclass"],
)
def test_velocity_derivative_of_the_stage_residuals(disc, extra, cls):
    """dR/dv of the three stages (used for d phi_T/dv) against a central difference
    of PipeModel.residual in v (exact for R quadratic in v, up to its rounding).
    Every v-dependent term enters: Coriolis (beta) and follower (its v^2)."""
    rng = np.random.default_rng(5)
    base = dict(alpha=0.7, mu=0.02, beta=0.3, gamma=5.0, **extra)
    m = cls(disc, Params(v=9.0, **base))
    Q, P, A = (0.5 * rng.standard_normal((3, m.n)) for _ in range(3))
    got = PipeDynamics(m).parameter_derivative(Q, P, A)
    dv = 0.5  # R is quadratic in v: the central difference is exact for any dv
    hi, lo = (cls(disc, Params(v=9.0 + s * dv, **base)) for s in (1.0, -1.0))
    ref = np.array(
        [(hi.residual(*z) - lo.residual(*z)) / (2 * dv) for z in zip(Q, P, A, strict=True)]
    )
    assert np.max(np.abs(got - ref)) < 1e-12 * np.max(np.abs(ref))
    assert PipeDynamics(m, flow=lambda t: (9.0, 0.0)).parameter_derivative is None


@pytest.mark.parametrize("disc", [FiniteElement(4, 3), Modal(3, n_cells=8)], ids=str)
def test_batched_stage_jacobians_give_the_same_sensitivities(disc, monkeypatch):
    """The three stage Jacobians of the sensitivity in one batched call (small
    discretizations) or three: the same monodromy and d phi/dv to round-off."""
    m = PipeModel(disc, Params(v=7.0, alpha=0.3, beta=0.142, gamma=18.9, mu=5e-3))
    q0, p0 = make_initial_state(m, 1, 0.3)

    def run():
        problem = PipeDynamics(m)
        st = Radau(problem, q0, p0, rtol=1e-8, sensitivity=True, velocity_sensitivity=True)
        for _ in st.steps(0.3):
            pass
        return problem, st

    problem, batched_run = run()
    assert problem.prefers_batched_stage_jacobians
    monkeypatch.setattr(dynamics_problem, "BATCHED_STAGES_MAX", 0)
    problem, single = run()
    assert not problem.prefers_batched_stage_jacobians
    assert batched_run.stats.steps == single.stats.steps
    S, S1 = batched_run.sensitivity_matrix, single.sensitivity_matrix
    assert np.max(np.abs(S - S1)) < 1e-12 * np.max(np.abs(S1))
    dv, dv1 = batched_run.velocity_sensitivity, single.velocity_sensitivity
    assert np.max(np.abs(dv - dv1)) < 1e-12 * np.max(np.abs(dv1))

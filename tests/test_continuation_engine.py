"""The pseudo-arclength engine on toy curves, through its public protocol only."""

import numpy as np
import pytest

from fempipe.solvers.continuation import (
    BorderedSolution,
    ContinuationError,
    ContinuationProblem,
    CurvePoint,
    KellerPolicy,
    continue_curve,
    solve_with_determinant,
    tangent,
)


class Curve:
    """F(x, lambda) = 0 for one scalar equation in one state: the Euclidean
    inner product, dense bordered solves."""

    def __init__(self, f, f_x, f_lambda):
        self.f, self.f_x, self.f_lambda = f, f_x, f_lambda

    def residual(self, y):
        return np.array([self.f(*y)])

    def derivatives(self, y):
        return np.array([[self.f_x(*y)]]), np.array([self.f_lambda(*y)])

    def solve_bordered(self, lin, row, rhs, *, determinant=False):
        Fx, Fl = lin
        A = Fx if row is None else np.block([[Fx, Fl[:, None]], [row[None, :]]])
        if determinant:
            return BorderedSolution(*solve_with_determinant(A, rhs))
        return BorderedSolution(np.linalg.solve(A, rhs))

    def inner(self, a, b):
        return float(a @ b)

    def dual(self, t):
        return t


def circle():
    """x^2 + lambda^2 = 1: folds in lambda at lambda = +-1 (x = 0)."""
    return Curve(
        lambda x, lam: x * x + lam * lam - 1.0, lambda x, lam: 2 * x, lambda x, lam: 2 * lam
    )


def parabola():
    """x^2 = lambda: one fold at lambda = 0."""
    return Curve(lambda x, lam: x * x - lam, lambda x, lam: 2 * x, lambda x, lam: -1.0)


def run(problem, y0, direction, **options):
    t, sign, _ = tangent(problem, np.asarray(y0, float), np.asarray(direction, float))
    first = CurvePoint(np.array([y0[0]]), y0[1], t, 0, 0.0, sign)
    return continue_curve(KellerPolicy(problem, first, **options), 0.1)


def test_toy_and_package_problems_satisfy_the_protocol():
    from fempipe.analyses.periodic import OrbitProblem
    from fempipe.analyses.statics import StaticFamily
    from fempipe.model.discretization import parse_discretization
    from fempipe.model.params import Params
    from fempipe.model.plane.operators import PipeModel

    assert isinstance(circle(), ContinuationProblem)
    model = PipeModel(parse_discretization("P2:4"), Params(v=1.0))
    assert isinstance(StaticFamily(model, "v"), ContinuationProblem)
    names = ("residual", "derivatives", "solve_bordered", "inner", "dual")
    assert all(callable(getattr(OrbitProblem, name, None)) for name in names)


def test_circle_is_followed_around_both_folds():
    res = run(circle(), (1.0, 0.0), (0.0, 1.0), ds_max=0.2, max_steps=40)
    assert res.end_reason == "max_steps" and res.rejected_steps == 0
    y = np.array([[p.q[0], p.value] for p in res.points])
    np.testing.assert_allclose(np.hypot(y[:, 0], y[:, 1]), 1.0, atol=1e-12)
    # Steps of 0.15 (Newton takes 4 iterations to 1e-10: the step stays), so
    # 40 steps end between arclength 3 pi / 2 and 2 pi: past lambda = 1 and -1.
    folds = [(e.kind, e.value, e.q[0]) for e in res.events]
    assert [k for k, _, _ in folds] == ["fold", "fold"]
    np.testing.assert_allclose([v for _, v, _ in folds], [1.0, -1.0], atol=1e-12)
    np.testing.assert_allclose([x for _, _, x in folds], [0.0, 0.0], atol=1e-9)
    # The tangent's parameter component changes sign exactly across each fold.
    for e in res.events:
        a, b = res.points[e.index], res.points[e.index + 1]
        assert a.tangent[1] * b.tangent[1] < 0


def test_parabola_fold_is_located_where_lambda_turns_back():
    res = run(parabola(), (1.0, 1.0), (0.0, -1.0), ds_max=0.25, max_steps=20)
    (fold,) = res.events
    assert fold.kind == "fold" and abs(fold.value) < 1e-12 and abs(fold.q[0]) < 1e-6
    assert min(p.value for p in res.points) >= 0.0 and res.points[-1].q[0] < -1.0


def test_a_curve_without_solutions_stalls_with_a_continuation_error():
    # x^2 + lambda^2 = -1 has no real points: the corrector fails at every step.
    problem = Curve(
        lambda x, lam: x * x + lam * lam + 1.0, lambda x, lam: 2 * x, lambda x, lam: 2 * lam
    )
    first = CurvePoint(np.array([1.0]), 0.0, np.array([0.0, 1.0]), 0, 0.0, 1)
    with pytest.raises(ContinuationError, match="fell below"):
        continue_curve(KellerPolicy(problem, first, ds_min=1e-3), 0.1)

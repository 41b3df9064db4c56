"""The integrator's contract (fempipe.solvers.radau.contract) with a problem that is not the pipe."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from fempipe.solvers.radau import ImplicitSecondOrderProblem, IntegrationError, Radau


class DampedOscillators:
    """M q'' + D q' + K q = 0 with diagonal M, D, K: the contract's rules 1-5 only."""

    autonomous = True
    stage_residuals = None
    stage_jacobians = None
    prefers_batched_stage_jacobians = False
    parameter_derivative = None

    def __init__(self, m, d, k):
        self.M, self.D, self.K = (np.diag(np.asarray(a, dtype=float)) for a in (m, d, k))
        self.n = len(m)

    def residual(self, t, q, qdot, qddot):
        return self.M @ qddot + self.D @ qdot + self.K @ q

    def jacobians(self, t, q, qdot, qddot):
        return self.K.copy(), self.D.copy(), self.M.copy()

    def acceleration(self, t, q, qdot):
        return -np.linalg.solve(self.M, self.D @ qdot + self.K @ q)

    def describe(self):
        return "oscillators"


def test_a_problem_of_the_contract_is_integrated():
    """Two damped oscillators: the end state, the dense output and the monodromy
    against the exact solution."""
    prob = DampedOscillators([1.0, 2.0], [0.1, 0.0], [4.0, 8.0])
    assert isinstance(prob, ImplicitSecondOrderProblem)
    st = Radau(prob, [1.0, 0.5], [0.0, 0.0], rtol=1e-10, sensitivity=True)
    for _ in st.steps(1.0):
        pass

    def exact(t):
        # q1'' + 0.1 q1' + 4 q1 = 0, q1(0) = 1; q2'' + 4 q2 = 0, q2(0) = 0.5
        z, w = 0.05, np.sqrt(4.0 - 0.05**2)
        q1 = np.exp(-z * t) * (np.cos(w * t) + z / w * np.sin(w * t))
        return np.array([q1, 0.5 * np.cos(2.0 * t)])

    np.testing.assert_allclose(st.q, exact(1.0), atol=1e-8)
    t_mid = 0.5 * (st.t_old + st.t)
    np.testing.assert_allclose(st.dense(t_mid)[0], exact(t_mid), atol=1e-7)
    t_old, h, *_ = st.last
    assert st.last.t_old == t_old and st.t == pytest.approx(t_old + h)
    # undamped oscillator: its block of the monodromy is a rotation of det 1
    S = st.sensitivity_matrix[np.ix_([1, 3], [1, 3])]
    assert abs(np.linalg.det(S) - 1.0) < 1e-7
    assert st.velocity_sensitivity is None


def test_a_model_is_not_a_problem():
    """Rule 10: the integrator takes a problem of the contract; a model (or anything
    without the contract's members) is refused, naming what it lacks and how to build one."""
    from fempipe import FiniteElement, Params, PipeModel

    model = PipeModel(FiniteElement(2, 2), Params())
    with pytest.raises(TypeError, match=r"dynamics problem.*PipeDynamics\(model\)") as err:
        Radau(model, np.zeros(model.n))
    assert "PipeModel has no autonomous" in str(err.value)

    prob = DampedOscillators([1.0], [0.0], [1.0])
    members = ("n", "autonomous", "stage_residuals", "stage_jacobians", "residual")
    without = SimpleNamespace(**{m: getattr(prob, m) for m in members})
    with pytest.raises(TypeError, match="SimpleNamespace has no prefers_batched_stage_jacobians, "):
        Radau(without, [1.0])


def test_failure_names_the_problem():
    """A step below round-off raises IntegrationError naming the problem (rule 14)."""

    class Blowup(DampedOscillators):
        def residual(self, t, q, qdot, qddot):
            return np.full(self.n, np.nan)

    st = Radau(Blowup([1.0], [0.0], [1.0]), [1.0], rtol=1e-6)
    with pytest.raises(IntegrationError, match="oscillators"):
        for _ in st.steps(1.0):
            pass


def test_the_integrator_imports_no_model():
    """Rule 10: nothing in fempipe/solvers/radau/ imports fempipe.model (nor a
    private name of another module)."""
    import ast
    from pathlib import Path

    import fempipe.solvers.radau as pkg

    for path in Path(pkg.__file__).parent.glob("*.py"):
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.ImportFrom):
                module = node.module or ""
                assert "model" not in module.split("."), (path.name, module)
                assert not any(a.name.startswith("_") for a in node.names), (path.name, module)
            elif isinstance(node, ast.Import):
                assert not any("fempipe.model" in a.name for a in node.names), path.name

"""The first-order (companion) form of lambda^2 M + lambda C + K (fempipe.core.companion).

Checked against what the form must be, not against an earlier copy of its code: the pencil's
eigenpairs solve the quadratic problem, the standard form's action on z = (x, y) is
(y, -M^-1 (K x + C y)) by an independent solve, its eigenvalues are the pencil's (QZ, another
algorithm), and the pipe's first-order Jacobian is the finite-difference derivative of the
first-order vector field of Eq. (20).
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from fempipe.core.companion import first_order_matrix, first_order_pencil
from fempipe.model.discretization import FiniteElement
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel


def _matrices(n: int = 7, seed: int = 3):
    """K (nonsymmetric), C, M (SPD) of size n."""
    rng = np.random.default_rng(seed)
    K = rng.standard_normal((n, n))
    C = rng.standard_normal((n, n))
    B = rng.standard_normal((n, n))
    M = B @ B.T + n * np.eye(n)
    return K, C, M


@pytest.mark.parametrize("hysteretic", [False, True])
def test_pencil_is_the_block_form(hysteretic):
    """A = [[0, I], [-K, -C]], B = [[I, 0], [0, M]]: the arrays the QZ branch of the
    eigensolver built with np.block (also for a complex K, hysteretic damping)."""
    K, C, M = _matrices()
    if hysteretic:
        K = K + 1j * 0.05 * M
    n = K.shape[0]
    Z, I = np.zeros((n, n)), np.eye(n)
    A, B = first_order_pencil(K, C, M)
    A0, B0 = np.block([[Z, I], [-K, -C]]), np.block([[I, Z], [Z, M]])
    assert A.dtype == A0.dtype and B.dtype == B0.dtype
    assert np.array_equal(A, A0) and np.array_equal(B, B0)
    # (lambda^2 M + lambda C + K) x = 0 for every eigenpair of the pencil.
    lam, V = sla.eig(A, B)
    for k in range(lam.size):
        x = V[:n, k]
        r = (lam[k] ** 2 * M + lam[k] * C + K) @ x
        assert np.linalg.norm(r) <= 1e-10 * max(1.0, abs(lam[k]) ** 2) * np.linalg.norm(x)


@pytest.mark.parametrize("factor", ["cholesky", "lu"])
def test_standard_form_acts_as_the_first_order_system(factor):
    """A z = (y, -M^-1 (K x + C y)) for z = (x, y), M^-1 applied by an independent solver
    (numpy's LU on M alone), with or without the caller's Cholesky factor; its eigenvalues
    are those of the pencil (QZ)."""
    K, C, M = _matrices(9, seed=11)
    n = K.shape[0]
    rng = np.random.default_rng(2)
    z = rng.standard_normal((2 * n, 3))
    x, y = z[:n], z[n:]
    want = np.vstack([y, -np.linalg.solve(M, K @ x + C @ y)])
    variants = [first_order_matrix(K, C, M, factor=factor)]
    if factor == "cholesky":
        variants.append(first_order_matrix(K, C, M, mass_factor=sla.cho_factor(M)))
    A, B = first_order_pencil(K, C, M)
    lam = sla.eigvals(A, B)
    for J in variants:
        assert J.shape == (2 * n, 2 * n)
        np.testing.assert_allclose(J @ z, want, rtol=0, atol=1e-12 * np.abs(want).max())
        mu = np.linalg.eigvals(J)
        assert np.abs(lam[:, None] - mu[None, :]).min(axis=1).max() <= 1e-10 * np.abs(lam).max()


def test_first_order_matrix_refuses_what_it_cannot_do():
    K, C, M = _matrices()
    with pytest.raises(ValueError, match="factor"):
        first_order_matrix(K, C, M, factor="qr")
    with pytest.raises(ValueError, match="mass_factor"):
        first_order_matrix(K, C, M, factor="lu", mass_factor=sla.cho_factor(M))


def test_the_critical_eigenvector_of_periodic_solves_the_quadratic_problem():
    """The Hopf start of the cycle branches (fempipe.analyses.periodic.hopf) takes its
    eigenpair from first_order_matrix(K, C, M, factor='lu'): z = (x, lambda x) with
    (lambda^2 M + lambda C + K) x = 0 to round-off, and lambda the eigenvalue of the
    pencil (QZ, another algorithm) nearest to i omega."""
    from fempipe.analyses.periodic.hopf import critical_eigenvector
    from fempipe.analyses.stability import linearized_matrices
    from fempipe.analyses.statics import solve_sagged

    model = PipeModel(FiniteElement(4, 3), Params(alpha=0.0, beta=0.142, gamma=18.9, v=8.4))
    q = solve_sagged(model).q
    omega = 10.0
    K, C, M = (np.asarray(a) for a in linearized_matrices(model, q))
    w, z = critical_eigenvector(model, q, omega)
    n = model.n
    x, lx = z[:n], z[n:]
    lam = lx @ np.conj(x) / (x @ np.conj(x))
    assert lam.imag == pytest.approx(w, rel=1e-10)
    scale = np.linalg.norm(K) + abs(lam) * np.linalg.norm(C) + abs(lam) ** 2 * np.linalg.norm(M)
    residual = (lam**2 * M + lam * C + K) @ x
    assert np.linalg.norm(residual) <= 1e-11 * scale * np.linalg.norm(x)
    A, B = first_order_pencil(K, C, M)
    mu = sla.eigvals(A, B)
    assert w == pytest.approx(mu[np.argmin(np.abs(mu - 1j * omega))].imag, rel=1e-10)


@pytest.mark.parametrize("alpha", [0.3, np.pi])
def test_pipe_jacobian_is_the_derivative_of_the_first_order_field(alpha):
    """hopf.pipe_jacobian at a moving, deformed state against central differences of
    F(q, q') = (q', -M(q)^-1 R(q, q', 0)), the first-order form of Eq. (20) (so the
    derivative of the mass matrix times the acceleration is in it)."""
    from fempipe.analyses.stability.hopf import pipe_jacobian

    params = Params(alpha=alpha, beta=0.142, gamma=18.9, v=6.0, mu=0.005)
    model = PipeModel(FiniteElement(4, 3), params)
    n = model.n
    x = 0.3 * np.random.default_rng(5).standard_normal(2 * n)

    def field(x):
        q, qd = x[:n], x[n:]
        return np.concatenate(
            [qd, -np.linalg.solve(model.mass_matrix(q), model.residual(q, qd, None))]
        )

    h = 1e-6
    fd = np.column_stack([(field(x + h * e) - field(x - h * e)) / (2 * h) for e in np.eye(2 * n)])
    J = pipe_jacobian(model, x)
    assert np.abs(J - fd).max() <= 1e-6 * np.abs(fd).max()
    assert np.abs(J[n:, :n]).max() > 1.0  # the stiffness block is there, not two zeros

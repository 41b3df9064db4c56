"""The first-order (companion) form of lambda^2 M + lambda C + K (fempipe.core.companion).

Each builder must reproduce, bit for bit, the matrices its callers formed
themselves before: the QZ pencil of the stability eigensolver, the Cholesky
form of the Hopf normal form's Jacobian and the LU form of the periodic
orbits' critical eigenvector.
"""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg as sla

from fempipe.core.companion import first_order_matrix, first_order_pencil
from fempipe.model.discretization import FiniteElement
from fempipe.model.operators import PipeModel
from fempipe.model.params import Params


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


def test_cholesky_matrix_is_the_normal_forms_jacobian():
    """factor='cholesky': one cho_factor, both blocks in one cho_solve, written into a
    zero matrix (the former pipe_jacobian), with or without the caller's factor."""
    K, C, M = _matrices()
    n = K.shape[0]
    cf = sla.cho_factor(M)
    want = np.zeros((2 * n, 2 * n))
    want[:n, n:] = np.eye(n)
    want[n:] = -sla.cho_solve(cf, np.hstack([K, C]))
    assert np.array_equal(first_order_matrix(K, C, M), want)
    assert np.array_equal(first_order_matrix(K, C, M, mass_factor=cf), want)
    # The standard form of the pencil: the same eigenvalues.
    A, B = first_order_pencil(K, C, M)
    lam, mu = sla.eigvals(A, B), np.linalg.eigvals(want)
    assert lam.size == mu.size == 2 * n
    assert np.abs(lam[:, None] - mu[None, :]).min(axis=1).max() <= 1e-10 * np.abs(lam).max()


def test_lu_matrix_is_the_periodic_orbits_matrix():
    """factor='lu': two LU solves and np.block, the expression of
    fempipe.analyses.periodic's critical eigenvector, bit for bit."""
    K, C, M = _matrices(9, seed=11)
    n = K.shape[0]
    want = np.block([[np.zeros((n, n)), np.eye(n)], [-sla.solve(M, K), -sla.solve(M, C)]])
    assert np.array_equal(first_order_matrix(K, C, M, factor="lu"), want)
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
    from fempipe.analyses.statics import sagged_state

    model = PipeModel(FiniteElement(4, 3), Params(alpha=0.0, beta=0.142, gamma=18.9, v=8.4))
    q = sagged_state(model).q
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


def test_pipe_jacobian_keeps_its_operations():
    """hopf.pipe_jacobian through first_order_matrix: the arrays of its former inline code."""
    from fempipe.analyses.stability.hopf import pipe_jacobian

    model = PipeModel(FiniteElement(4, 3), Params(alpha=0.3, beta=0.142, gamma=18.9, v=6.0))
    n = model.n
    rng = np.random.default_rng(5)
    x = 0.1 * rng.standard_normal(2 * n)
    q, qd = x[:n], x[n:]
    M = model.mass_matrix(q)
    cf = sla.cho_factor(M)
    a = -sla.cho_solve(cf, model.residual(q, qd, None))
    Jq, Jqd, _ = model.jacobians(q, qd, a)
    want = np.zeros((2 * n, 2 * n))
    want[:n, n:] = np.eye(n)
    want[n:] = -sla.cho_solve(cf, np.hstack([Jq, Jqd]))
    assert np.array_equal(pipe_jacobian(model, x), want)

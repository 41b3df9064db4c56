"""``fempipe.core.dual``, operation by operation, against central finite differences.

Every 3-D Jacobian of fempipe is built by these operations, so each is checked on its own:
a small expression using it is evaluated twice, on plain arrays (the values, differenced in
the unknowns) and on :class:`~fempipe.core.dual.Dual` numbers (the exact derivatives, pulled
back to the unknowns by :func:`~fempipe.core.dual.pullback`).  The unknowns ``u`` (K per state,
S states) reach the points through random "bases" ``B`` (L local quantities at n points), as
the finite-element fields do.
"""

from __future__ import annotations

import numpy as np
import pytest

from fempipe.core import dual as D  # noqa: N812  (the module read as one letter, like np)

N, S, K, L = 7, 2, 5, 4
RNG = np.random.default_rng(20261207)
BASES = RNG.normal(size=(L, N, K)) * 0.7
A = np.tril(RNG.normal(size=(N, N)))  # an integral-like (lower-triangular) operator
A2 = np.triu(RNG.normal(size=(N, N)))
TIP = np.zeros((N, 1))
TIP[-1, 0] = 1.0
C = RNG.normal(size=K)  # a linear functional of the unknowns (a tip value)
U0 = RNG.normal(size=(K, S)) * 0.8


def _fields(u: np.ndarray, as_dual: bool) -> list:
    """The L local quantities at the N points, each state's from its own unknowns."""
    values = np.einsum("lqk,ks->lqs", BASES, u)
    if not as_dual:
        return list(values)
    out = []
    for k in range(L):
        loc = np.zeros((N, S, L))
        loc[:, :, k] = 1.0
        out.append(D.Dual(values[k], loc))
    return out


def _map(x, matrix: np.ndarray, adjoint):
    op = lambda y: np.tensordot(matrix, y, axes=1)  # noqa: E731
    return x.nonlocal_map(op, adjoint) if isinstance(x, D.Dual) else op(x)


def _functional(u: np.ndarray, as_dual: bool):
    val = (C @ u)[None]  # shape (1, S)
    return D.linear_functional(val, C[None, None, :]) if as_dual else val


def _vector(a, b, c):
    return D.stack([a, b, c], axis=1)


EXPRESSIONS = {
    "add": lambda f, u, d: f[0] + f[1] + 2.0,
    "radd, rsub, neg": lambda f, u, d: 3.0 + f[0] - (-f[1]) - (1.5 - f[2]),
    "sub": lambda f, u, d: f[0] - f[1] - f[2] * f[3],
    "mul": lambda f, u, d: f[0] * f[1] * f[1] + 0.5 * f[2] + f[3] * np.linspace(1, 2, N)[:, None],
    "truediv": lambda f, u, d: f[0] / (2.0 + f[1] * f[1]) + f[2] / 3.0,
    "rtruediv": lambda f, u, d: 1.5 / (2.0 + D.cos(f[0])) + f[1] / np.linspace(1, 2, N)[:, None],
    "reciprocal": lambda f, u, d: (
        (f[0] * f[0] + 1.0).reciprocal() if d else 1.0 / (f[0] * f[0] + 1.0)
    ),
    "sin, cos": lambda f, u, d: D.sin(f[0] * f[1]) + D.cos(f[2]) * f[3],
    "getitem": lambda f, u, d: _vector(f[0], f[1] * f[2], D.sin(f[3]))[:, 1] * f[0],
    "sum": lambda f, u, d: _vector(f[0] * f[1], f[2], f[3] * f[3]).sum(axis=1),
    "stack": lambda f, u, d: _vector(f[0], 2.0 * np.ones((N, S)), f[1] * f[3]),
    "dot": lambda f, u, d: D.dot(_vector(f[0], f[1], f[2]), _vector(f[3], f[0] * f[1], 1.0 + f[2])),
    "dot, array first": lambda f, u, d: D.dot(
        RNG_FIXED_VECTOR, _vector(f[0], f[1] * f[1], D.sin(f[2]))
    ),
    "cross": lambda f, u, d: D.cross(_vector(f[0], f[1], f[2]), _vector(f[3], D.sin(f[0]), f[1])),
    "matvec": lambda f, u, d: D.matvec(
        D.stack(
            [
                _vector(f[0], f[1], f[2]),
                _vector(f[3], f[0] * f[1], f[2] * f[2]),
                _vector(D.cos(f[3]), f[1], 1.0 + 0 * f[0]),
            ],
            axis=1,
        ),
        _vector(f[2], D.sin(f[3]), f[0] * f[3]),
    ),
    "integral, matrix adjoint": lambda f, u, d: _map(f[0] * D.sin(f[1]), A, A.T) * f[2],
    "integral, callable adjoint": lambda f, u, d: _map(f[0] * f[3], A, lambda y: A.T @ y) * f[1],
    "integral of an integral": lambda f, u, d: _map(_map(f[0] * f[1], A, A.T), A2, A2.T) + f[2],
    "integral of a vector field": lambda f, u, d: D.dot(
        _map(_vector(f[0], f[1] * f[2], D.cos(f[3])), A, A.T), _vector(f[3], f[2], f[1])
    ),
    "tip value, broadcast": lambda f, u, d: D.sin(_map(f[0] * f[1], TIP.T, TIP)) * f[2] + f[3],
    "linear functional": lambda f, u, d: D.sin(_functional(u, d)) * f[0] + _functional(u, d) * f[1],
}
RNG_FIXED_VECTOR = RNG.normal(size=(N, 3, S))


def _value(name: str, u: np.ndarray) -> np.ndarray:
    return np.asarray(EXPRESSIONS[name](_fields(u, False), u, False), dtype=float)


def _jacobian_by_pullback(name: str, weights: np.ndarray) -> np.ndarray:
    """d/du of sum(weights * expression), shape (K, S), by reverse accumulation."""
    out = EXPRESSIONS[name](_fields(U0, True), U0, True)
    assert isinstance(out, D.Dual)
    n = out.shape[0]
    seed = weights.reshape(n, -1, S).transpose(0, 2, 1)[..., None]  # (n, S, m, R = 1)
    W, G = D.pullback([(out, seed)], L)
    grad = np.einsum("qsl,lqk->ks", W[..., 0], BASES)
    if G is not None:
        grad += G[:, 0, :].T
    return grad


def _jacobian_by_differences(name: str, weights: np.ndarray, h: float = 1e-6) -> np.ndarray:
    grad = np.zeros((K, S))
    for k in range(K):
        step = np.zeros((K, S))
        step[k] = h
        plus = (weights * _value(name, U0 + step)).reshape(-1, S).sum(axis=0)
        minus = (weights * _value(name, U0 - step)).reshape(-1, S).sum(axis=0)
        grad[k] = (plus - minus) / (2 * h)
    return grad


@pytest.mark.parametrize("name", list(EXPRESSIONS))
def test_each_operation_against_finite_differences(name):
    value = _value(name, U0)
    out = EXPRESSIONS[name](_fields(U0, True), U0, True)
    # the Dual's value is the plain arrays' value: the derivatives ride along, nothing else
    np.testing.assert_allclose(out.val, np.broadcast_to(value, out.shape), rtol=0, atol=1e-14)
    weights = np.random.default_rng(7).normal(size=out.shape)
    exact = _jacobian_by_pullback(name, weights)
    fd = _jacobian_by_differences(name, weights)
    scale = max(1.0, np.abs(fd).max())
    assert np.abs(exact - fd).max() <= 1e-7 * scale, (exact, fd)
    assert np.abs(exact).max() > 1e-3  # the check sees a derivative, not two zeros


def test_the_check_fails_on_a_wrong_derivative(monkeypatch):
    """The harness catches a wrong chain rule: cos with the sign of its derivative flipped."""

    def wrong_cos(self):
        s = np.sin(self.val)[..., None]
        return D.Dual(np.cos(self.val), *self._map(lambda d: s * d))

    monkeypatch.setattr(D.Dual, "cos", wrong_cos)
    weights = np.random.default_rng(7).normal(size=(N, S))
    exact = _jacobian_by_pullback("sin, cos", weights)
    fd = _jacobian_by_differences("sin, cos", weights)
    assert np.abs(exact - fd).max() > 1e-2


def test_local_derivatives_of_a_pointwise_expression():
    """Forward mode alone: ``loc`` of a pointwise expression is its partial derivatives."""
    f = _fields(U0, True)
    out = D.sin(f[0] * f[1]) / (2.0 + f[2] * f[2])
    x = [v.val for v in f]
    h = 1e-6
    for k in range(L):
        plus = [v + (h if j == k else 0.0) for j, v in enumerate(x)]
        minus = [v - (h if j == k else 0.0) for j, v in enumerate(x)]
        g = lambda y: np.sin(y[0] * y[1]) / (2.0 + y[2] * y[2])  # noqa: E731
        np.testing.assert_allclose(out.loc[..., k], (g(plus) - g(minus)) / (2 * h), atol=1e-8)

"""The Radau collocation polynomial (fempipe.solvers.radau.collocation): its three forms."""

from __future__ import annotations

import numpy as np

from fempipe.solvers.radau.collocation import (
    NODES,
    evaluate_increment,
    evaluate_lagrange,
    evaluate_product,
    increment_weights,
    lagrange_weights,
    product_weights,
)


def _cubic(s):
    # a cubic per component, shape (len(s), 3)
    s = np.asarray(s)[:, None]
    return 0.3 - 1.2 * s + 0.7 * s**2 + np.array([1.5, -2.0, 0.25]) * s**3


def test_the_forms_agree():
    """Increment, barycentric and plain-product forms of the cubic through
    (0, y_old), (c_i, Y_i) agree to 1e-15 (relative) inside a step, where the
    stage values are those of a step (Y_i - y_old small); on arbitrary node
    values to 1e-15 times the size of the Lagrange weights, also beyond the
    step (the extrapolation of Newton's starting guess)."""
    rng = np.random.default_rng(11)
    y_old = rng.standard_normal(48)
    Y = y_old + 0.01 * rng.standard_normal((3, 48))
    s = np.linspace(0.0, 1.0, 17)
    inc = np.array([evaluate_increment(x, y_old, Y) for x in s])
    lag = evaluate_lagrange(s, y_old, Y)
    prod = evaluate_product(s, y_old, Y)
    scale = np.max(np.abs(lag))
    for a, b in ((inc, lag), (prod, lag), (prod, inc)):
        assert np.max(np.abs(a - b)) < 1e-15 * scale

    Y = rng.standard_normal((3, 48))
    s = np.linspace(0.0, 2.0, 17)
    inc = np.array([evaluate_increment(x, y_old, Y) for x in s])
    lag = evaluate_lagrange(s, y_old, Y)
    prod = evaluate_product(s, y_old, Y)
    bound = np.abs(lagrange_weights(s)).sum(axis=1)[:, None] * np.max(np.abs(np.vstack([y_old, Y])))
    assert np.max(np.abs(inc - lag) / bound) < 4e-15
    assert np.max(np.abs(prod - lag) / bound) < 1e-15
    W = np.array([np.r_[1.0 - increment_weights(x).sum(), increment_weights(x)] for x in s])
    np.testing.assert_allclose(W, lagrange_weights(s), atol=1e-13, rtol=0)
    np.testing.assert_allclose(product_weights(s), lagrange_weights(s), atol=1e-13, rtol=0)


def test_a_cubic_is_reproduced():
    """The nodes' values of a cubic give back the cubic everywhere, in each form."""
    s = np.linspace(-0.5, 1.5, 11)
    vals = _cubic(NODES)
    y_old, Y = vals[0], vals[1:]
    exact = _cubic(s)
    for got in (
        np.array([evaluate_increment(x, y_old, Y) for x in s]),
        evaluate_lagrange(s, y_old, Y),
        evaluate_product(s, y_old, Y),
    ):
        assert np.max(np.abs(got - exact)) < 1e-14
    # the weights interpolate: the identity at the nodes
    np.testing.assert_allclose(lagrange_weights(NODES), np.eye(4), atol=1e-15)
    np.testing.assert_allclose(product_weights(NODES), np.eye(4), atol=1e-15)

"""Brent's method and the eigenvalue assignment against scipy's, which they stand in for.

:mod:`fempipe.core.rootfinding` and :mod:`fempipe.core.matching` exist so that
``fempipe critical`` and ``fempipe simulate`` need not import
:mod:`scipy.optimize`; the tests may.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq as scipy_brentq
from scipy.optimize import linear_sum_assignment

from fempipe.core.matching import assignment
from fempipe.core.rootfinding import brentq


def _functions(rng: np.random.Generator, n: int):
    for k in range(n):
        c, r = rng.normal(size=5), rng.uniform(-1.0, 1.0)
        if k % 2:
            yield (
                lambda x, c=c, r=r: np.polyval(c, x) * (x - r) + 0.3 * np.sin(7 * x) * (x - r) ** 2
            )
        else:
            yield lambda x, r=r: np.tanh(5 * (x - r)) + (x - r) ** 3


@pytest.mark.parametrize(
    "xtol, rtol", [(1e-12, 8.9e-16), (1e-6, 1e-3), (1e-300, 4 * np.finfo(float).eps)]
)
def test_brentq_returns_scipys_roots_bit_for_bit(xtol, rtol):
    """Same iterates, so the same float, over 400 bracketed roots of smooth and steep functions."""
    a, b, compared = -1.3, 1.2, 0
    for f in _functions(np.random.default_rng(0), 400):
        if np.sign(f(a)) == np.sign(f(b)):
            continue
        assert brentq(f, a, b, xtol=xtol, rtol=rtol) == scipy_brentq(f, a, b, xtol=xtol, rtol=rtol)
        compared += 1
    assert compared > 250


def test_brentq_errors_name_the_problem():
    with pytest.raises(ValueError, match="different signs"):
        brentq(lambda x: x * x + 1.0, -1.0, 1.0)
    with pytest.raises(ValueError, match="xtol"):
        brentq(lambda x: x, -1.0, 1.0, xtol=0.0)
    with pytest.raises(ValueError, match="rtol"):
        brentq(lambda x: x, -1.0, 1.0, rtol=1e-17)
    with pytest.raises(ValueError, match="nan"):
        brentq(lambda x: np.nan if x > 0.3 else x, -1.0, 1.0)
    with pytest.raises(RuntimeError, match="2 iterations"):
        brentq(lambda x: x - 0.1234567, -1.0, 1.0, maxiter=2)
    assert brentq(lambda x: x, 0.0, 1.0) == 0.0


def test_assignment_is_optimal_on_random_ties_and_duplicated_columns():
    """Total cost equal to linear_sum_assignment's, each column at most once.

    Integer costs make many ties; duplicated columns are the two slots per
    mode of the canonical numbering.
    """
    rng = np.random.default_rng(1)
    conflicts = 0
    for k in range(4000):
        m = int(rng.integers(1, 9))
        n = m + int(rng.integers(0, 4))
        C = rng.integers(0, 5, size=(m, n)).astype(float) if k % 3 == 0 else rng.random((m, n))
        if k % 5 == 0:
            C = np.repeat(C[:, : (n + 1) // 2], 2, axis=1)[:, :n]
            if C.shape[1] < m:
                continue
        r, c = assignment(C)
        assert np.array_equal(r, np.arange(m))
        assert np.unique(c).size == m
        r0, c0 = linear_sum_assignment(C)
        assert C[r, c].sum() == pytest.approx(C[r0, c0].sum(), abs=1e-12)
        conflicts += np.unique(C.argmin(axis=1)).size < m
    assert conflicts > 1000  # the augmenting paths were exercised, not only the argmin


def test_assignment_refuses_bad_shapes_and_values():
    with pytest.raises(ValueError, match="more rows"):
        assignment(np.zeros((3, 2)))
    with pytest.raises(ValueError, match="finite"):
        assignment(np.array([[0.0, np.nan]]))
    r, c = assignment(np.zeros((0, 3)))
    assert r.size == 0 and c.size == 0

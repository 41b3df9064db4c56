"""Newton's method with a backtracking line search, for any system R(x) = 0.

:func:`newton` knows the problem by ``balance(x) -> (R, ||R||, scale)`` (converged:
``||R|| <= tol * scale``) and ``jacobian(x)``, dense or sparse.  What R balances is the
problem's: the pipe's forces are in :mod:`fempipe.analyses.statics.equilibrium`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fempipe.core.errors import SolverError

__all__ = ["NewtonConvergenceError", "NewtonResult", "linear_solve", "newton"]

#: ``balance(x) -> (R(x), ||R(x)||, scale)``: the residual, its norm and the size of the
#: terms it balances.
Balance = Callable[[np.ndarray], tuple[np.ndarray, float, float]]


class NewtonConvergenceError(SolverError):
    """Newton's method did not converge, or met a non-finite residual or scale (``finite``
    False): ``iterations`` done and the last ``residual`` norm (nan if not finite)."""

    def __init__(self, message: str, iterations: int, residual: float, finite: bool) -> None:
        super().__init__(message)
        self.iterations = iterations
        self.residual = residual
        self.finite = finite

    def __reduce__(self):
        # Rebuilt from all the constructor's arguments (pickling across processes).
        return type(self), (str(self), self.iterations, self.residual, self.finite)


@dataclass(frozen=True)
class NewtonResult:
    """A converged iterate ``x`` after ``iterations`` steps, with ``||R(x)||``."""

    x: np.ndarray
    iterations: int
    residual_norm: float


def linear_solve(J, b: np.ndarray) -> np.ndarray:
    """Solve J x = b: ``numpy.linalg.solve`` for a dense J, SuperLU (``spsolve``)
    for a sparse one."""
    if sp.issparse(J):
        return spla.spsolve(J.tocsc(), b)
    return np.linalg.solve(J, b)


def _not_finite(iterations: int) -> NewtonConvergenceError:
    return NewtonConvergenceError("residual not finite", iterations, float("nan"), finite=False)


def newton(
    balance: Balance,
    jacobian: Callable[[np.ndarray], object],
    x0: np.ndarray,
    tol: float,
    max_iter: int,
) -> NewtonResult:
    """Solve R(x) = 0 by Newton's method from ``x0``, with a backtracking line search on ||R||.

    Parameters
    ----------
    balance : callable
        ``x -> (R, ||R||, scale)`` (:data:`Balance`).
    jacobian : callable
        ``x -> dR/dx``, dense or sparse.
    x0 : ndarray
        Initial iterate (not modified).
    tol : float
        Converged when ``||R|| <= tol * scale`` and the step is below ``1e-9 (1 + ||x||)``;
        ``x0`` itself when ``||R(x0)|| <= 1e-3 tol scale`` (the Jacobian may be singular there).
    max_iter : int

    Raises
    ------
    NewtonConvergenceError
        After ``max_iter`` iterations, a non-finite step, or a non-finite residual or scale.
    """
    x = np.asarray(x0, dtype=float)
    r, rn, scale = balance(x)
    if not (math.isfinite(rn) and math.isfinite(scale)):
        raise _not_finite(0)
    if rn <= 1e-3 * tol * scale:
        return NewtonResult(x=x, iterations=0, residual_norm=rn)
    it = 0
    for it in range(1, max_iter + 1):
        dx = linear_solve(jacobian(x), -r)
        if not np.all(np.isfinite(dx)):
            break
        lam = 1.0
        while True:
            x_new = x + lam * dx
            r_new, rn_new, scale_new = balance(x_new)
            if rn_new < (1.0 - 1e-4 * lam) * rn or lam < 1e-3 or rn < tol * scale:
                break
            lam *= 0.5
        x, r, rn, scale = x_new, r_new, rn_new, scale_new
        if not (math.isfinite(rn) and math.isfinite(scale)):
            raise _not_finite(it)
        if rn <= tol * scale and lam * np.linalg.norm(dx) <= 1e-9 * (1.0 + np.linalg.norm(x)):
            return NewtonResult(x=x, iterations=it, residual_norm=rn)
    raise NewtonConvergenceError(
        f"Newton did not converge: residual {rn:.3e} after {it} iterations", it, rn, finite=True
    )

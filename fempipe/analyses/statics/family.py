"""The static problem of Eq. (31a) along v, gamma or alpha as a continuation problem.

:class:`StaticFamily` is R(q; lambda) = 0 in the form of
:class:`fempipe.solvers.continuation.ContinuationProblem`, arclength measured in
``||(theta, lambda)||^2 = \\int_0^1 theta^2 dxi + lambda^2`` (the Gram matrix), so that
step sizes mean the same on every mesh.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.continuation import BorderedSolution, solve_with_determinant
from fempipe.solvers.newton import linear_solve

from .equilibrium import DENSE_MAX_N, force_balance

__all__ = ["CONTINUATION_PARAMETERS", "StaticFamily"]

#: The parameters a branch can be continued in.
CONTINUATION_PARAMETERS = ("v", "gamma", "alpha")


class StaticFamily:
    """The pipe models along ``parameter`` ('v', 'gamma' or 'alpha') from ``model``.

    A branch may pass through v = 0 or gamma = 0, so negative values are mapped to their
    mirror images (R depends on v^2; gamma < 0 is |gamma| with alpha + pi), dR/dlambda
    carrying the sign of the map.
    """

    def __init__(self, model: PipeModel, parameter: str) -> None:
        if parameter not in CONTINUATION_PARAMETERS:
            raise ValueError(
                f"continuation parameter must be one of {CONTINUATION_PARAMETERS}, got {parameter!r}"
            )
        self.model = model
        self.parameter = parameter
        n = model.n
        metric = model.disc.gram
        # Dense algebra up to DENSE_MAX_N unknowns (fempipe.analyses.statics.equilibrium).
        self.sparse = sp.issparse(metric) and n > DENSE_MAX_N
        self.G = metric.toarray() if sp.issparse(metric) and not self.sparse else metric
        self.n = n

    def at(self, value: float) -> PipeModel:
        """The model at parameter ``value`` (negative v, gamma mirrored)."""
        p = self.model.params
        if self.parameter == "v":
            p = replace(p, v=abs(value))
        elif self.parameter == "gamma":
            p = replace(p, gamma=abs(value), alpha=p.alpha + (np.pi if value < 0 else 0.0))
        else:
            p = replace(p, alpha=value)
        return self.model.with_params(p)

    def dR_dlambda(self, q: np.ndarray, value: float) -> np.ndarray:
        """dR/dlambda at (q, value), with the sign of the mirror map."""
        d = self.at(value).static_parameter_derivative(q, self.parameter)
        return -d if (value < 0 and self.parameter != "alpha") else d

    def balanced(self, y: np.ndarray, tol: float) -> float | None:
        """||R|| at y = (q, lambda) if the forces balance to ``tol``, else None."""
        n = self.n
        _, rn, scale = force_balance(self.at(y[n]), y[:n])
        return rn if rn <= tol * scale else None

    # -- ContinuationProblem ----------------------------------------------------
    def residual(self, y: np.ndarray) -> np.ndarray:
        """R(q; lambda) at y = (q, lambda)."""
        n = self.n
        return self.at(y[n]).static_residual(y[:n])

    def derivatives(self, y: np.ndarray) -> tuple:
        """(dR/dq, dR/dlambda) at y: dense up to DENSE_MAX_N unknowns, else sparse."""
        n = self.n
        q, value = y[:n], y[n]
        m = self.at(value)
        J = m.static_jacobian(q, dense=True) if not self.sparse else m.static_jacobian(q)
        return J, self.dR_dlambda(q, value)

    def solve_bordered(
        self, lin: tuple, row: np.ndarray | None, rhs: np.ndarray, *, determinant: bool = False
    ) -> BorderedSolution:
        """[[dR/dq, dR/dlambda], [row]] z = rhs (``row`` None: dR/dq z = rhs)."""
        J, Rl = lin
        if row is None:
            A = J
        elif self.sparse:
            A = sp.vstack([sp.hstack([J, sp.csc_matrix(Rl[:, None])]), sp.csr_matrix(row[None, :])])
            A = A.tocsc()
        else:
            A = np.block([[J, Rl[:, None]], [row[None, :]]])
        if determinant:
            return BorderedSolution(*solve_with_determinant(A, rhs))
        return BorderedSolution(linear_solve(A, rhs))

    def inner(self, a: np.ndarray, b: np.ndarray) -> float:
        """a_q^T G b_q + a_lambda b_lambda."""
        n = self.n
        return float(a[:n] @ (self.G @ b[:n]) + a[n] * b[n])

    def dual(self, t: np.ndarray) -> np.ndarray:
        """The row (G t_q, t_lambda) of the linear form <t, .>."""
        n = self.n
        return np.append(self.G @ t[:n], t[n])

"""One static equilibrium of Eq. (31a) by Newton's method, and what "converged" means.

The static residual ``R(q, 0, 0)`` is the weak form of

    -theta'' + gamma (1 - xi) sin(theta + alpha) + v^2 sin(theta(1) - theta) = 0,
    theta(0) = 0, theta'(1) = 0;

:func:`solve_static` accepts a state only when R is small compared with each of its forces
(:func:`force_balance`).  The branches of :mod:`fempipe.analyses.statics` are built on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.solvers.newton import NewtonConvergenceError, newton

__all__ = [
    "DENSE_MAX_N",
    "NewtonError",
    "StaticSolution",
    "force_balance",
    "solve_static",
]


class NewtonError(SolverError):
    """Newton's method did not converge, or met a non-finite residual (``params``,
    ``iterations``, ``residual``: the last residual norm)."""

    def __init__(self, message: str, params: Params, iterations: int, residual: float) -> None:
        super().__init__(message)
        self.params = params
        self.iterations = iterations
        self.residual = residual

    def __reduce__(self):
        # so that the error of a worker process reaches its parent intact
        return type(self), (str(self), self.params, self.iterations, self.residual)


@dataclass(frozen=True)
class StaticSolution:
    """A converged static state: ``q``, ``params``, the Newton ``iterations`` (those of the
    gravity loading of :func:`~fempipe.analyses.statics.solve_sagged` included, and counted
    apart in ``loading_iterations``) and ``residual_norm``, ||R(q, 0, 0)||."""

    q: np.ndarray
    params: Params
    iterations: int
    residual_norm: float
    loading_iterations: int = 0

    def to_dict(self) -> dict:
        return {
            "params": self.params.to_dict(),
            "newton_iterations": self.iterations,
            "gravity_loading_iterations": self.loading_iterations,
            "residual_norm": self.residual_norm,
        }


#: Largest number of unknowns for which Newton's method and the continuation use the dense
#: static Jacobian: below it the sparse constructors cost more than the dense LU.
DENSE_MAX_N = 400


def force_balance(model: PipeModel, q: np.ndarray) -> tuple[np.ndarray, float, float]:
    """R(q, 0, 0), its norm, and the size of the forces it balances.

    A state is an equilibrium when ``||R|| <= tol (||bending|| + gravity load +
    ||follower|| + ||springs||)``, each force as it acts at q; gravity is measured by its
    load (:meth:`PipeModel.gravity_load`), as sin(theta + alpha) carries an absolute
    round-off of ~1e-16 at every angle.  Scaling by the coefficients 1 + gamma + v^2
    instead would accept an unbalanced gravity load at v = 1e100.
    """
    with np.errstate(over="ignore", invalid="ignore"):  # reported as non-finite
        b, g, f, k = model.static_terms(q)
        r = b + g + f + k
    size = (
        float(np.linalg.norm(b))
        + model.gravity_load()
        + float(np.linalg.norm(f))
        + float(np.linalg.norm(k))
    )
    return r, float(np.linalg.norm(r)), size


def _not_finite(model: PipeModel, iterations: int) -> NewtonError:
    p = model.params
    return NewtonError(
        f"static residual is not finite at alpha={p.alpha:.6g}, gamma={p.gamma:.6g}, "
        f"v={p.v:.6g} (v^2 = {p.v * p.v:.3g}): the loads are outside floating-point range",
        params=p,
        iterations=iterations,
        residual=float("nan"),
    )


def solve_static(
    model: PipeModel,
    q0: np.ndarray | None = None,
    tol: float = 1e-10,
    max_iter: int = 40,
) -> StaticSolution:
    """The static state by Newton's method with a line search on ||R||. Eq. (31a).

    Parameters
    ----------
    model : PipeModel
    q0 : ndarray, shape (n,), optional
        Initial guess (default the straight pipe).
    tol, max_iter : float, int
        Relative force balance (:func:`force_balance`; last step also below 1e-9 (1 + ||q||)).

    Raises
    ------
    NewtonError
    """
    q = np.zeros(model.n) if q0 is None else np.array(q0, dtype=float)
    dense = model.n <= DENSE_MAX_N
    try:
        res = newton(
            lambda x: force_balance(model, x),
            lambda x: model.static_jacobian(x, dense=dense),
            q,
            tol,
            max_iter,
        )
    except NewtonConvergenceError as err:
        if not err.finite:
            raise _not_finite(model, err.iterations) from None
        p = model.params
        raise NewtonError(
            f"static Newton did not converge at alpha={p.alpha:.6g}, beta={p.beta:.6g}, "
            f"gamma={p.gamma:.6g}, v={p.v:.6g}: residual {err.residual:.3e} after "
            f"{err.iterations} iterations",
            params=p,
            iterations=err.iterations,
            residual=err.residual,
        ) from None
    return StaticSolution(
        q=res.x, params=model.params, iterations=res.iterations, residual_norm=res.residual_norm
    )

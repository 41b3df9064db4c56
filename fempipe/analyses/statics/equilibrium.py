"""One static equilibrium of Eq. (31a) by Newton's method, and what "converged" means.

The static residual is ``R(q, 0, 0; params)`` of :class:`~fempipe.model.operators.PipeModel`,
the weak form of

    -theta'' + gamma (1 - xi) sin(theta + alpha) + v^2 sin(theta(1) - theta) = 0,
    theta(0) = 0, theta'(1) = 0,

the sum of three forces: bending, gravity and the follower force of the jet.
:func:`solve_static` runs Newton's method (:func:`fempipe.solvers.newton.newton`) and
accepts a state only when the residual is small compared with each of them
(:func:`force_balance`), and reports loads beyond floating-point range as a
:class:`NewtonError`.  The branches and paths of :mod:`fempipe.analyses.statics`
(continued by the engine of :mod:`fempipe.solvers.continuation`) are built on it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.model.operators import PipeModel
from fempipe.model.params import Params
from fempipe.solvers.newton import NewtonConvergenceError, newton

__all__ = [
    "DENSE_MAX_N",
    "NewtonError",
    "StaticSolution",
    "force_balance",
    "solve_static",
]


class NewtonError(SolverError):
    """Newton's method did not converge, or met a non-finite residual.

    Attributes
    ----------
    params : Params
        The parameter point.
    iterations : int
    residual : float
        Last residual norm (Euclidean norm of the weak-form residual).
    """

    def __init__(self, message: str, params: Params, iterations: int, residual: float) -> None:
        super().__init__(message)
        self.params = params
        self.iterations = iterations
        self.residual = residual

    def __reduce__(self):
        # Rebuilt from all the constructor's arguments, so that the error of a
        # worker process reaches its parent intact.
        return type(self), (str(self), self.params, self.iterations, self.residual)


@dataclass(frozen=True)
class StaticSolution:
    """A converged static state.

    Attributes
    ----------
    q : ndarray, shape (n,)
    params : Params
    iterations : int
        Newton iterations used, all of them: for a state reached by gravity
        loading (:func:`fempipe.analyses.statics.solve_sagged`) those of the loading
        included.
    residual_norm : float
        Euclidean norm of R(q, 0, 0) at return.
    loading_iterations : int
        The part of ``iterations`` spent on the gravity loading (the
        continuation in gamma from 0); 0 for Newton from a neighbouring state.
    """

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


#: Largest number of unknowns for which Newton's method and the continuation
#: use the dense static Jacobian: below it scipy.sparse's constructors alone cost
#: more than the dense Jacobian and its LU (at P3:16, n = 48, many times more).
DENSE_MAX_N = 400


def force_balance(model: PipeModel, q: np.ndarray) -> tuple[np.ndarray, float, float]:
    """R(q, 0, 0), its norm, and the size of the forces it balances.

    R = bending + gravity + follower + springs.  A state is an equilibrium
    when R is small compared with each of these forces as they act at q:
    ``||R|| <= tol (||bending|| + gravity load + ||follower|| + ||springs||)``.

    * Bending, K q, the follower term, v^2 \\int phi_i sin(theta(1) - theta),
      and the springs (:meth:`PipeModel.spring`) vanish with q, also in
      floating point to round-off: they are measured as they are.
    * Gravity, gamma \\int phi_i (1 - xi + Gamma) sin(theta + alpha) (the
      pipe and its end mass), is measured by its load
      ``gamma ||\\int phi_i (1 - xi + Gamma)||`` (:meth:`PipeModel.gravity_load`)
      whatever the lever arm: sin(theta + alpha) carries an absolute
      round-off error of ~1e-16 at every angle (sin(pi) = 1.2e-16), so the
      straight column at alpha = pi is an equilibrium to that accuracy.

    Scaling by the load coefficients (1 + gamma + v^2) instead would accept an
    unbalanced load whenever another coefficient is huge: at v = 1e100 the
    straight pipe, where the follower term vanishes, would "converge" with
    the whole gravity load unbalanced.
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
    """Solve the static problem by Newton's method with the analytic Jacobian.

    The static problem is Eq. (31a), in weak form.

    Parameters
    ----------
    model : PipeModel
    q0 : ndarray, shape (n,), optional
        Initial guess (default: the straight pipe, theta = 0).
    tol : float
        Convergence when ``||R|| <= tol (||bending|| + gravity load +
        ||follower||)``, each term of R measured at the state (see
        :func:`force_balance`), and the last Newton step is below
        ``1e-9 (1 + ||q||)``.
    max_iter : int

    Returns
    -------
    StaticSolution

    Raises
    ------
    NewtonError
        Naming the parameter point, iterations and residual; also when the
        residual is not finite (loads beyond floating-point range).

    Notes
    -----
    A backtracking line search on ||R|| (:func:`fempipe.solvers.newton.newton`) keeps the
    iteration from jumping between the many equilibria of a large-deformation problem.
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

"""The state a pipe reaches when gravity is switched on (:func:`solve_sagged`), and the
states along a list of parameter values (:func:`solve_path`, what ``fempipe static``
computes): Newton bridged by continuation where it fails.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Sequence
from dataclasses import replace

import numpy as np
import scipy.sparse as sp

from fempipe.model.plane.operators import PipeModel

from .branches import continue_static
from .equilibrium import NewtonError, StaticSolution, solve_static

__all__ = ["solve_sagged", "solve_path"]

log = logging.getLogger(__name__)


def solve_sagged(model: PipeModel, tol: float = 1e-10) -> StaticSolution:
    """The static state reached by switching gravity on slowly: continuation in gamma from 0.

    The primary branch of every stability analysis (Newton from the straight pipe finds the
    unstable state for alpha >= ~150 deg); checked (theta_tip sin(alpha) < 0; at v = 0 a minimum
    of the potential energy) and repeated with smaller steps until it passes.
    """
    p = model.params
    if p.gamma == 0.0:
        return solve_static(model, tol=tol)
    start = model.with_params(replace(p, gamma=0.0))
    q = None
    for ds_max in (1.0, 0.5, 0.1, 0.02):
        branch = continue_static(start, "gamma", stop=p.gamma, tol=tol, detect=False, ds_max=ds_max)
        if branch.end_reason != "stop":
            raise NewtonError(
                f"gravity loading did not reach gamma={p.gamma:.6g} at alpha={p.alpha:.6g}, "
                f"v={p.v:.6g} ({branch.end_reason})",
                params=p,
                iterations=branch.steps,
                residual=float("nan"),
            )
        q = branch.points[-1].q
        if _loaded_plausible(model, q):
            break
        log.info("gravity loading with step %g landed on another branch; retrying", ds_max)
    sol = solve_static(model, q0=q, tol=tol)
    # Report the Newton work of the whole gravity loading, not of the last polish.
    loading = sum(pt.iterations for pt in branch.points)
    return replace(sol, iterations=sol.iterations + loading, loading_iterations=loading)


def _loaded_plausible(model: PipeModel, q: np.ndarray) -> bool:
    """theta_tip sin(alpha) < 0 and, at v = 0, a positive definite static Jacobian."""
    p = model.params
    s = math.sin(p.alpha)
    if abs(s) < 1e-12:
        return True  # alpha = 0 or pi: the straight pipe, by symmetry
    if s * float(model.disc.tip @ q) >= 0.0:
        return False
    if p.v == 0.0:
        J = model.static_jacobian(q)
        J = J.toarray() if sp.issparse(J) else np.asarray(J)
        return bool(np.linalg.eigvalsh(0.5 * (J + J.T)).min() > 0.0)
    return True


def solve_path(
    model: PipeModel,
    values: Sequence[float],
    parameter: str = "v",
    q0: np.ndarray | None = None,
    tol: float = 1e-10,
    callback: Callable[[int, StaticSolution], None] | None = None,
) -> list[StaticSolution]:
    """Static states at ``values`` of ``parameter`` along one branch, in order.

    The first from ``q0`` (default :func:`solve_sagged`), each next one by Newton from the
    extrapolation of the previous two, the gap bridged by continuation where Newton fails.
    """
    values = [float(x) for x in values]
    out: list[StaticSolution] = []
    guess = q0
    for i, value in enumerate(values):
        m = model.with_params(replace(model.params, **{parameter: value}))
        if i == 0 and q0 is None:
            sol = solve_sagged(m, tol=tol)
        else:
            if i >= 2 and values[i - 1] != values[i - 2]:
                s = (value - values[i - 1]) / (values[i - 1] - values[i - 2])
                guess = out[-1].q + s * (out[-1].q - out[-2].q)
            elif i:
                guess = out[-1].q
            try:
                sol = solve_static(m, q0=guess, tol=tol)
            except NewtonError:
                if not i:
                    raise
                start = model.with_params(replace(model.params, **{parameter: values[i - 1]}))
                br = continue_static(start, parameter, value, q0=out[-1].q, tol=tol, detect=False)
                if br.points[-1].value != value:
                    raise
                sol = solve_static(m, q0=br.points[-1].q, tol=tol)
        out.append(sol)
        if callback:
            callback(i, sol)
    return out

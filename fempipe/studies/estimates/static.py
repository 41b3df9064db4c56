"""Error estimates of static states: each state solved again on the refined discretization.

Newton starts from the coarse state transferred to the refined space (the same branch);
the floor is Newton's tolerance :data:`NEWTON_TOL`.  docs/cli/options.md, "Error estimates".
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from fempipe.analyses.statics import NewtonError, solve_static
from fempipe.model.kinematics import compute_tip
from fempipe.model.plane.operators import PipeModel
from fempipe.model.projection import project
from fempipe.studies.error_estimate import ERROR, STATIC_TIP_KEYS, describe, refine

from .shape import beside, header, pair, with_estimate

__all__ = ["NEWTON_TOL", "estimate_static_errors"]

#: Newton's tolerance of the static states: the floor of their estimates, relative to max(1, |Q|).
NEWTON_TOL = 1e-10

#: The SI values of a static point: (key, dimensionless key, factor times L).
_SI_DERIVED = (
    ("X_tip_m", "X_tip", 1.0),
    ("Z_tip_m", "Z_tip", 1.0),
    ("eta_tip_m", "eta_tip", 1.0),
    ("varsigma_tip_m", "varsigma_tip", 1.0),
    ("tip_drop_mm", "tip_drop", 1e3),
)


def estimate_static_errors(
    result: dict,
    model: PipeModel,
    solutions: Sequence,
    *,
    parameter: str = "v",
    pipe=None,
    fine=None,
    callback: Callable[[int, object], None] | None = None,
) -> dict:
    """``result`` with ``Q_error``, ``Q_refined`` beside each tip value Q of its points.

    Parameters
    ----------
    result : dict
        ``{"points": [...]}``, one point per state, with :data:`STATIC_TIP_KEYS`,
        ``tip_drop`` (and with ``pipe`` their SI values).
    model : PipeModel
    solutions : sequence of StaticSolution
    parameter : str
        The parameter along ``solutions`` (named in the notes).
    pipe, fine : PipeSI, FiniteElement or Modal, optional
        The SI pipe (its values get estimates too); ``refine(model.disc)`` if built.
    callback : callable, optional
        ``callback(i, state)`` after each refined state (None where Newton failed).
    """
    disc = model.disc
    fine = refine(disc) if fine is None else fine
    info = describe(
        disc, fine, floor=f"Newton's tolerance {NEWTON_TOL:g} max(1, |Q|)", params=model.params
    )
    fine_model = PipeModel(fine, model.params)
    notes, points = [], []
    for i, (row, sol) in enumerate(zip(result["points"], solutions, strict=True)):
        try:
            q0 = project(disc, sol.q, fine)
            state = solve_static(fine_model.with_params(sol.params), q0=q0, tol=NEWTON_TOL)
        except NewtonError as exc:
            state = None
            value = getattr(sol.params, parameter)
            notes.append(f"{parameter} = {value:.6g}: no refined state ({exc}); errors null")
        if callback is not None:
            callback(i, state)
        alpha = sol.params.alpha
        tip = None if state is None else compute_tip(fine, state.q, alpha)
        val = {k: None if tip is None else float(tip[k]) for k in STATIC_TIP_KEYS}
        val["tip_drop"] = None if tip is None else float(tip["X_tip"]) - math.cos(alpha)
        for k in (*STATIC_TIP_KEYS, "tip_drop"):
            row = with_estimate(row, k, val[k], info.order, NEWTON_TOL, ratio=info.ratio)
        if pipe is not None:
            for k, base, scale in _SI_DERIVED:
                row = beside(row, k, pair(k, row[base + ERROR], val[base], scale * pipe.L))
        points.append(row)
    result["points"] = points
    result["error_estimate"] = header(info, notes)
    return result

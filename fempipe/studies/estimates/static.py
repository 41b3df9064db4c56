"""Error estimates of static states: each state solved again on the refined discretization.

Newton starts from the coarse state transferred to the refined space, and
beside each tip value Q of a point (:data:`STATIC_TIP_KEYS`, ``tip_drop`` and
the SI values) ``Q_error`` and ``Q_refined`` are inserted; the floor is
Newton's tolerance :data:`NEWTON_TOL` (``fempipe static --error-estimate``).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from fempipe.model.kinematics import tip_values
from fempipe.model.projection import project
from fempipe.studies.error_estimate import describe, refine

from .shape import ERROR, REFINED, Refined, beside, header, with_estimate

__all__ = [
    "NEWTON_TOL",
    "STATIC_TIP_KEYS",
    "RefinedStatic",
    "refined_static_states",
    "with_static_estimates",
]

#: Newton's tolerance of the static states (:func:`fempipe.analyses.statics.solve_path`):
#: the floor of their estimates, relative to max(1, |Q|).
NEWTON_TOL = 1e-10
#: The tip values of a static state (dimensionless, Eq. (28)), in table order.
STATIC_TIP_KEYS = ("theta_tip", "eta_tip", "X_tip", "Z_tip", "varsigma_tip")


@dataclass(frozen=True)
class RefinedStatic(Refined):
    """:func:`refined_static_states`: ``states`` holds one ``StaticSolution`` per
    coarse state, None where Newton failed on the refined discretization."""

    states: tuple = ()


def refined_static_states(
    model,
    solutions: Sequence,
    parameter: str = "v",
    *,
    fine=None,
    callback: Callable[[int, object], None] | None = None,
) -> RefinedStatic:
    """Each static state solved again on the refined discretization.

    Newton starts from the coarse state transferred to the refined space
    (:func:`fempipe.model.projection.project`), so each refined state is the
    coarse one's, on the same branch, whatever the path.

    Parameters
    ----------
    model : PipeModel
        The reported model (its discretization and parameters).
    solutions : sequence of StaticSolution
        The reported states (:func:`fempipe.analyses.statics.solve_path`).
    parameter : str
        The parameter continued along ``solutions`` (named in the notes).
    fine : FiniteElement or Modal, optional
        ``refine(model.disc)`` if already built.
    callback : callable, optional
        ``callback(i, state)`` after each refined state (None where Newton failed).

    Returns
    -------
    RefinedStatic
        With a note for each state Newton could not find (its errors null).
    """
    # Imported here: the CLI loads this module at start-up (--help); these load scipy.
    from fempipe.analyses.statics import NewtonError, solve_static
    from fempipe.model.operators import PipeModel

    disc = model.disc
    fine = refine(disc) if fine is None else fine
    info = describe(
        disc, fine, floor=f"Newton's tolerance {NEWTON_TOL:g} max(1, |Q|)", params=model.params
    )
    fine_model = PipeModel(fine, model.params)
    states, notes = [], []
    for i, sol in enumerate(solutions):
        try:
            q0 = project(disc, sol.q, fine)
            states.append(solve_static(fine_model.with_params(sol.params), q0=q0, tol=NEWTON_TOL))
        except NewtonError as exc:
            states.append(None)
            value = getattr(sol.params, parameter)
            notes.append(f"{parameter} = {value:.6g}: no refined state ({exc}); errors null")
        if callback is not None:
            callback(i, states[-1])
    return RefinedStatic(fine, info, tuple(notes), tuple(states))


#: The SI values of a static point: (key, dimensionless key, factor times L).
_SI_DERIVED = (
    ("X_tip_m", "X_tip", 1.0),
    ("Z_tip_m", "Z_tip", 1.0),
    ("eta_tip_m", "eta_tip", 1.0),
    ("varsigma_tip_m", "varsigma_tip", 1.0),
    ("tip_drop_mm", "tip_drop", 1e3),
)


def _scaled(x, factor: float):
    return None if x is None else x * factor


def with_static_estimates(result: dict, solutions: Sequence, refined: RefinedStatic, pipe=None):
    """``result`` with ``Q_error``, ``Q_refined`` beside each tip value Q of its points.

    Parameters
    ----------
    result : dict
        ``{"points": [...], ...}``, one point per state of ``solutions``, with
        the tip values :data:`STATIC_TIP_KEYS` and ``tip_drop`` (and, with an
        SI pipe, ``X_tip_m``, ``Z_tip_m``, ``eta_tip_m``, ``varsigma_tip_m``,
        ``tip_drop_mm``).
    solutions : sequence of StaticSolution
        The reported states.
    refined : RefinedStatic
        :func:`refined_static_states` of ``solutions``.
    pipe : PipeSI, optional
        The SI pipe: its SI values get estimates too.

    Returns
    -------
    dict
        ``result`` (updated in place) with the new points and the top-level
        ``"error_estimate"`` (:func:`header`).

    Examples
    --------
    ``fempipe static --error-estimate`` does, for the states ``sols`` of
    :func:`fempipe.analyses.statics.solve_path` on ``model`` and their JSON-ready
    ``result = {"points": [...]}``::

        refined = refined_static_states(model, sols)
        result = with_static_estimates(result, sols, refined)
        result["points"][0]["theta_tip_error"], result["error_estimate"]["notes"]
    """
    fine, info = refined.discretization, refined.info
    out = []
    for row, sol, fine_sol in zip(result["points"], solutions, refined.states, strict=True):
        alpha = sol.params.alpha
        tip = None if fine_sol is None else tip_values(fine, fine_sol.q, alpha)
        val = {k: None if tip is None else float(tip[k]) for k in STATIC_TIP_KEYS}
        val["tip_drop"] = None if tip is None else float(tip["X_tip"]) - math.cos(alpha)
        for k in (*STATIC_TIP_KEYS, "tip_drop"):
            row = with_estimate(row, k, val[k], info.order, NEWTON_TOL, ratio=info.ratio)
        if pipe is not None:
            for k, base, scale in _SI_DERIVED:
                row = beside(
                    row,
                    k,
                    {
                        k + ERROR: _scaled(row[base + ERROR], scale * pipe.L),
                        k + REFINED: _scaled(val[base], scale * pipe.L),
                    },
                )
        out.append(row)
    result["points"] = out
    result["error_estimate"] = header(info, refined.notes)
    return result

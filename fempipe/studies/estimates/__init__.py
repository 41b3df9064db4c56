"""Error estimates attached to a result: the refined run and ``Q_error``, ``Q_refined`` beside ``Q``.

:func:`estimate_errors` computes a result again on the refined discretization of
:func:`fempipe.studies.error_estimate.refine` and inserts beside each reported number ``Q`` of
its JSON-ready dict ``Q_error`` (:func:`fempipe.studies.error_estimate.estimate`) and
``Q_refined``, with a top-level ``"error_estimate"`` entry describing the method
(:class:`~fempipe.studies.error_estimate.ErrorEstimate`) and the notes of the comparison.
What ``fempipe static``, ``critical`` and ``simulate`` report with ``--error-estimate``
(docs/cli/options.md, "Error estimates").
"""

from __future__ import annotations

from collections.abc import Sequence

from fempipe.analyses.dynamics import Trajectory
from fempipe.analyses.limit_cycle import Attractor
from fempipe.model.plane.operators import PipeModel

from .attractor import estimate_attractor_errors
from .stability import EVENT_TOL, estimate_stability_errors
from .static import NEWTON_TOL, estimate_static_errors

__all__ = ["EVENT_TOL", "NEWTON_TOL", "estimate_errors"]


def estimate_errors(result: dict, model: PipeModel, computed, **options) -> dict:
    """``result`` with the error estimates of its numbers, from a refined run of ``computed``.

    Parameters
    ----------
    result : dict
        The JSON-ready dict of the reported computation (updated and returned).
    model : PipeModel
    computed
        A sequence of ``StaticSolution`` (:func:`.static.estimate_static_errors`), a
        stability analysis (:func:`.stability.estimate_stability_errors`), an ``Attractor``
        or a pulsating flow's ``Trajectory`` (:func:`.attractor.estimate_attractor_errors`).
    **options
        Those of the function for ``computed`` (``pipe``, ``fine``, ``callback``, ...).
    """
    if isinstance(computed, Attractor | Trajectory):
        return estimate_attractor_errors(result, model, computed, **options)
    if hasattr(computed, "events"):
        return estimate_stability_errors(result, model, computed, **options)
    if isinstance(computed, Sequence):
        return estimate_static_errors(result, model, computed, **options)
    raise TypeError(f"no error estimate for a {type(computed).__name__}")

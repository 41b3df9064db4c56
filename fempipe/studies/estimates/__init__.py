"""Error estimates attached to results: the refined run and the ``Q_error`` keys beside ``Q``.

A result (the static states of a path, the stability analysis of a branch, an
attractor) is computed again on the refined discretization of
:func:`fempipe.studies.error_estimate.refine` (P_k elements halved, or twice the
modes, plus one for an odd N), and beside each reported number ``Q`` of the
result's JSON-ready dict two keys are inserted: ``Q_error``, the estimate of
:func:`fempipe.studies.error_estimate.estimate` (Roache's Grid Convergence
Index, ``max(3 |Q - Q_refined| r^p / (r^p - 1), floor)``) and ``Q_refined``,
the refined value.  The floor is the solver's tolerance on the value,
relative: ``tol * max(1, |Q|)``.  A top-level ``"error_estimate"`` entry
(:func:`header`) describes the method
(:class:`fempipe.studies.error_estimate.ErrorEstimate`) with the ``notes`` of the
comparison (an event found on one discretization only, attractors of
different kinds, a refined solve that failed).

Each kind of result has two functions: ``refined_*`` repeats the computation
on the refined discretization and returns a typed :class:`Refined` record;
``with_*_estimates`` pairs the coarse and the refined numbers and returns the
result with the estimates beside its numbers:

==========================  ===============================  ===========================
result                      refined run                      attached
==========================  ===============================  ===========================
static states of a path     :func:`refined_static_states`    :func:`with_static_estimates`
stability analysis          :func:`refined_stability`        :func:`with_stability_estimates`
attractor (``simulate``)    :func:`refined_attractor`        :func:`with_attractor_estimates`
==========================  ===============================  ===========================

These are what ``fempipe static``, ``fempipe critical`` and ``fempipe simulate``
report with ``--error-estimate``; the JSON shape is theirs (:func:`beside`,
:func:`with_estimate`: ``v_cr``, ``v_cr_error``, ``v_cr_refined``).

Examples
--------
``fempipe static --error-estimate`` does, for the states ``sols`` of
:func:`fempipe.analyses.statics.solve_path` on ``model`` and their JSON-ready
``result = {"points": [...]}``::

    refined = refined_static_states(model, sols)
    result = with_static_estimates(result, sols, refined)
    result["points"][0]["theta_tip_error"], result["error_estimate"]["notes"]
"""

from .attractor import (
    AttractorSummary,
    RefinedAttractor,
    refined_attractor,
    refined_cycle,
    with_attractor_estimates,
)
from .shape import ERROR, REFINED, Refined, beside, header, with_estimate
from .stability import EVENT_TOL, RefinedStability, refined_stability, with_stability_estimates
from .static import (
    NEWTON_TOL,
    STATIC_TIP_KEYS,
    RefinedStatic,
    refined_static_states,
    with_static_estimates,
)

__all__ = [
    "ERROR",
    "EVENT_TOL",
    "NEWTON_TOL",
    "REFINED",
    "STATIC_TIP_KEYS",
    "AttractorSummary",
    "Refined",
    "RefinedAttractor",
    "RefinedStability",
    "RefinedStatic",
    "beside",
    "header",
    "refined_attractor",
    "refined_cycle",
    "refined_stability",
    "refined_static_states",
    "with_attractor_estimates",
    "with_estimate",
    "with_stability_estimates",
    "with_static_estimates",
]

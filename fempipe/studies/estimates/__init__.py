"""Error estimates attached to results: the refined run and the ``Q_error`` keys beside ``Q``.

A result (the static states of a path, the stability analysis of a branch, an attractor) is
computed again on the refined discretization of
:func:`fempipe.studies.error_estimate.refine`, and beside each reported number ``Q`` of the
result's JSON-ready dict two keys are inserted: ``Q_error``, the estimate of
:func:`fempipe.studies.error_estimate.estimate` (the Grid Convergence Index, its floor the
solver's tolerance on the value, relative), and ``Q_refined``, the refined value.  A
top-level ``"error_estimate"`` entry (:func:`header`) describes the method with the notes of
the comparison (an event found on one discretization only, attractors of different kinds, a
refined solve that failed).

Each kind of result has two functions, ``refined_*`` (the computation repeated on the refined
discretization, a typed :class:`Refined` record) and ``with_*_estimates`` (the result with the
estimates beside its numbers): :func:`refined_static_states` and
:func:`with_static_estimates`, :func:`refined_stability` and
:func:`with_stability_estimates`, :func:`refined_attractor` and
:func:`with_attractor_estimates`.  They are what ``fempipe static``, ``critical`` and
``simulate`` report with ``--error-estimate`` (docs/cli/options.md, "Error estimates").
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

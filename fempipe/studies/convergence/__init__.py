"""Convergence studies of one quantity of the user's case: error against degrees of freedom.

A study computes one scalar :class:`Quantity` (a static tip value, the critical flow velocity
or its frequency, an eigenvalue, a limit cycle's amplitude or period) on a sequence of
discretizations of each :class:`Family` -- Lagrange elements P_k on meshes of doubling
element counts, sine or beam modes of doubling N -- and reports for each family the values,
the errors against a reference and the observed order (:func:`run_study`,
:class:`ConvergenceStudy`).  The reference is the Richardson extrapolation of the best
family's two finest values (:func:`extrapolate_richardson`), with the other families' extrapolations (and
for static tip values the collocation solution of the strong form) as independent values;
``Reference.method`` records how it was formed.  The observed order (:func:`estimate_order`)
is fitted over the asymptotic range only.

How the reference and the fit are formed: docs/cli/commands.md, "fempipe convergence"; the
theoretical orders: docs/theory/conventions.md and docs/theory/convergence.md.
"""

from .orders import estimate_order, extrapolate, extrapolate_richardson, local_orders
from .quantities import (
    CRITICAL_QUANTITIES,
    CYCLE_QUANTITIES,
    EVENT_TOL,
    PARAMETRIC_QUANTITIES,
    QUANTITIES,
    STATIC_QUANTITIES,
    STATIC_TOL,
    Family,
    Quantity,
    doubling,
    static_tip_state,
)
from .study import ConvergenceStudy, Reference, Series, run_study

__all__ = [
    "QUANTITIES",
    "STATIC_QUANTITIES",
    "CRITICAL_QUANTITIES",
    "CYCLE_QUANTITIES",
    "PARAMETRIC_QUANTITIES",
    "STATIC_TOL",
    "EVENT_TOL",
    "Quantity",
    "Family",
    "Series",
    "Reference",
    "ConvergenceStudy",
    "run_study",
    "estimate_order",
    "extrapolate_richardson",
    "local_orders",
    "extrapolate",
    "doubling",
    "static_tip_state",
]

"""Convergence studies of one quantity of the user's case: error against degrees of freedom.

:func:`run_study` computes a :class:`Quantity` on every member of each :class:`Family`
(P_k elements on doubling meshes, sine or beam modes), forms the reference by
:func:`extrapolate_richardson` of the best family and fits the observed order
(:func:`estimate_order`) over the asymptotic range.  How: docs/cli/commands.md,
"fempipe convergence"; the theoretical orders: docs/theory/convergence.md.
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

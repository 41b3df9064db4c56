"""Convergence studies of one quantity of the user's case: error against degrees of freedom.

A study computes one scalar :class:`Quantity` (a static tip value, the
critical flow velocity or its frequency, an eigenvalue, a limit cycle's
amplitude or period) on a sequence of discretizations of each
:class:`Family` -- Lagrange elements P_k on meshes of doubling element
counts, sine or beam modes of doubling N -- and reports for each family the
values, the errors against a reference and the observed order.

How the reference is formed (:func:`run_study`, recorded in
``Reference.method`` so a reader can judge it):

* for every family with at least two usable members, the Richardson
  extrapolation of its two finest values,
  ``Q* = Q_f + (Q_f - Q_c) / (r^p - 1)`` (r the ratio of the sizes, p the
  family's theoretical order in that ratio, or the observed local order of
  its last three members where no theory is known), with error estimate the
  size of the correction (at least the solver's tolerance, below which
  differences mean nothing);
* the reference is the extrapolation of the *best* family, the one with the
  smallest error estimate;
* the other families' extrapolations, and for static tip values the
  collocation solution of the strong form (scipy ``solve_bvp``, Eq. (31a)),
  are listed as independent values with their distance to the reference.

The observed order is the least-squares slope of log(error) against
log(dofs) over the asymptotic range: the finest (at most three) consecutive
members whose error is above ten times the reference's error estimate and
the solver tolerance (so that the reference's own error does not bend the
fit).  Theory (docs, "Conventions and derivations"): P_k converges as
h^(2k) in tip values, v_cr and eigenvalues (nodal superconvergence), the sine
modes as N^-3, the beam modes as given by ``Modal.expected_order``.
"""

from .orders import extrapolate, local_orders, observed_order, richardson
from .quantities import (
    CRITICAL_QUANTITIES,
    CYCLE_QUANTITIES,
    EVENT_TOL,
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
    "STATIC_TOL",
    "EVENT_TOL",
    "Quantity",
    "Family",
    "Series",
    "Reference",
    "ConvergenceStudy",
    "run_study",
    "observed_order",
    "richardson",
    "local_orders",
    "extrapolate",
    "doubling",
    "static_tip_state",
]

"""Branches of periodic orbits of Eq. (20) by pseudo-arclength continuation in v.

A flutter event of the static branch (:mod:`fempipe.analyses.stability`) is a Hopf
point: a complex pair lambda = +-i omega of the linearization (Eqs.
(31b)-(33)) crosses the imaginary axis at v = v_H, and a family of periodic
orbits is born there.  This module follows that family in v, stable and
unstable orbits alike, which a sweep of attractors (:mod:`fempipe.analyses.bifurcation`)
cannot see.

The periodic-orbit problem
--------------------------
With x = (q, q') the weak form of Eq. (20) is x' = F(x; v) and phi_T(x; v)
its flow over a time T (the discrete flow of :class:`fempipe.solvers.radau.Radau`).
A periodic orbit is a zero of (single shooting; Seydel, *Practical
Bifurcation and Stability Analysis*, Sec. 7.3)

    phi_T(x0; v) - x0 = 0                    (2n equations)
    <f_ref, x0 - x_ref> = 0                  (phase condition)
    <t, W (u - u_pred)> = 0  or  v = v_g     (arclength, or a fixed v)

in u = (x0, T, v): the phase condition puts x0 on the hyperplane through the
previous point's x_ref orthogonal to the flow f_ref = F(x_ref) there (a
Poincare section that the next orbit crosses; through the predicted point on
the first step, where the previous point is the equilibrium), the last row is Keller's
pseudo-arclength condition with the unit tangent t of the weighted metric W
(Keller 1977; Kuznetsov, *Elements of Applied Bifurcation Theory*, Sec.
10.2), or, where v is a good local parameter and a requested v lies ahead, the
condition v = v_g, so that every requested value is landed on exactly (a
local parametrization in Rheinboldt's sense).  The Jacobian of the first rows
is [M - I, F(phi_T), d phi_T / dv] with M the monodromy matrix, the exact
derivative of the discrete flow accumulated step by step by the integrator
(``Radau(sensitivity=True)``, as :func:`fempipe.analyses.limit_cycle.shoot` uses it),
and d phi_T / dv accumulated in the same integration, exact for the discrete
flow too (the residual of Eq. (20) is quadratic in v, so its v-derivative at
each stage is exact from three values; :class:`fempipe.solvers.radau.Radau`,
``velocity_sensitivity``): no second integration at a shifted v.  Newton's
method reuses the monodromy matrix while the residual falls at least four
times per iteration (chord Newton), as the sweep's shooting does.

Metric.  W measures q in rad (RMS over the unknowns), q' scaled by T_H / 2 pi
(the velocity of an oscillation of that period and the same amplitude), T
relative to the Hopf period T_H and v as it is, so a step ds is about an RMS
change of theta, a relative change of the period or a change of v.

Start.  At the Hopf point (x_H, T_H = 2 pi / omega, v_H) with the critical
eigenvector z (A z = i omega z, x = (q, q')), the orbits near the Hopf point are
x_H + r Re(z e^{i omega tau}) + O(r^2) with v - v_H = O(r^2): the branch leaves
the equilibria along t_0 = (Re z, 0, 0), which is the first tangent (the first
point is the pseudo-arclength corrector of x_H + ds Re z; its v comes out of
the corrector, on whichever side of v_H the orbits lie).  Later tangents are
secants of the last two points.

Step control.  The step grows by 1.5 when the corrector needed at most four
integrations, is halved when it needed more than five, and a step is
rejected (halved) when the corrector fails or the new secant turns from the
last one by more than :data:`MAX_ANGLE`.  A corrector that stalls on the
noise of the adaptive step sequence is first retried at a tenth of the
integration tolerance.  Below ``ds_min`` the branch ends
with :class:`CycleContinuationError`, naming v and the step; the finished
points stay.

Stability and special points.  The eigenvalues of the monodromy matrix are the
Floquet multipliers; the one closest to 1 is the trivial one (the phase along
the orbit) and the orbit is stable when all others lie inside the unit circle.
They come from the Newton iterate where the matrix was last computed: on the
continuation's own steps one within 1e-3 of the orbit's amplitude
(:data:`MONODROMY_NEAR`; the multipliers are then off by about as much), at
the requested v one within 1e-6 (:data:`MONODROMY_AT_ORBIT`), whose
multipliers are those of the orbit (the trivial one within 2e-6 of 1 on
Fig. 7).  Between two consecutive points the code
reports (Kuznetsov, Ch. 4 and 5; Seydel, Sec. 7.4):

* ``fold`` -- the branch turns back in v (a multiplier passes +1, the cyclic
  fold); located at the vertex of the parabola v(s) through three points;
* ``period_doubling`` -- a real multiplier passes -1;
* ``neimark_sacker`` -- a complex pair passes the unit circle;

the last two located by the secant of the test function (|mu| - 1 of the
multiplier concerned) on the step.  The branch ends when it leaves the range of
v, returns to an equilibrium (its amplitude falls below :data:`MIN_SWING`: it
reached another Hopf point), its period exceeds :data:`MAX_PERIOD_RATIO` T_H
(an approach to a homoclinic orbit), or after ``max_steps`` steps.

Modules: :mod:`~fempipe.analyses.periodic.results` (Hopf points, orbits,
branches), :mod:`~fempipe.analyses.periodic.hopf` (the Hopf points and the
equilibria of the static branch), :mod:`~fempipe.analyses.periodic.problem`
(the shooting problem and its corrector; the tip's extrema over a period by
:func:`fempipe.analyses.limit_cycle.tips.tip_extrema`), :mod:`~fempipe.analyses.periodic.branch`
(the continuation of one branch, by the engine of
:mod:`fempipe.solvers.continuation`), :mod:`~fempipe.analyses.periodic.special`
(folds, period doublings, Neimark-Sacker points) and
:mod:`~fempipe.analyses.periodic.diagram` (the diagram over alpha).
"""

from .branch import (
    GRID_RTOL_FACTOR,
    MAX_ANGLE,
    MAX_PERIOD_RATIO,
    MIN_DV_DS,
    CycleBranchPolicy,
    continue_cycles,
)
from .diagram import N_MULTIPLIERS, CycleDiagram, cycle_diagram, cycle_point_dict
from .hopf import hopf_points, static_points
from .problem import MONODROMY_AT_ORBIT, MONODROMY_NEAR, CycleCorrector, OrbitProblem
from .results import (
    MIN_SWING,
    CycleBranch,
    CycleContinuationError,
    CyclePoint,
    CycleSpecialPoint,
    HopfPoint,
)
from .special import NEAR_ONE, special_points

__all__ = [
    "HopfPoint",
    "CyclePoint",
    "CycleSpecialPoint",
    "CycleBranch",
    "CycleContinuationError",
    "hopf_points",
    "continue_cycles",
    "static_points",
    "cycle_diagram",
    "CycleDiagram",
    "cycle_point_dict",
    "special_points",
    "CycleCorrector",
    "CycleBranchPolicy",
    "OrbitProblem",
    "GRID_RTOL_FACTOR",
    "MAX_ANGLE",
    "MAX_PERIOD_RATIO",
    "MIN_DV_DS",
    "MIN_SWING",
    "MONODROMY_AT_ORBIT",
    "MONODROMY_NEAR",
    "N_MULTIPLIERS",
    "NEAR_ONE",
]

"""Linear stability of the static states: spectra, critical velocities, events.

Writing theta = theta^s(xi) + theta^d(xi, tau) in Eq. (20) and keeping the
terms linear in theta^d gives Eq. (31b), discretized as Eq. (32):

    M^d q_ddot + C^d q_dot + K^d q = 0,

with M^d, C^d, K^d of Eqs. (33a)-(33c) (docs, "The model").  They are the
Jacobians of the residual of Eq. (20) with respect to q'', q' and q at the
static state, so they are taken from :meth:`fempipe.model.operators.PipeModel.jacobians`
and never written a second time.  With theta^d ∝ e^{lambda tau} the quadratic
eigenproblem is solved in first-order form

    [[0, I], [-K, -C]] z = lambda [[I, 0], [0, M]] z,   z = (q, lambda q),

and every eigenvalue is reported in two conventions: lambda (Re lambda > 0
unstable) and the paper's Omega = -i lambda (theta^d ∝ e^{i Omega tau},
Im Omega < 0 unstable, Re Omega = Im lambda the frequency).

Resolved modes
--------------
A discretization with n unknowns has 2n eigenvalues, but only its lowest
modes approximate the continuum.  The rule used here (:func:`resolution`):

1. The *canonical modes* of a discretization are those of the straight,
   unloaded pipe (v = gamma = mu = 0): K phi = omega^2 M(0) phi, the
   clamped-free Euler-Bernoulli beam, whose exact frequencies beta_r^2
   (cos beta cosh beta = -1) are known.  Canonical mode r is *resolved* when
   the discretization reproduces omega_r within ``RESOLUTION_TOL`` = 5 %
   (and so are all lower ones).  P3:16 resolves 27 modes, P3:256 423,
   modal N resolves N - 1: the N-th sine mode is always 8-9 % off
   because a sine basis has theta''(0) = 0 while the clamped-free beam's
   modes do not (docs, "Conventions and derivations"); the beam basis
   (``Modal(N, basis="beam")``) is made of these modes and resolves all N.
2. An eigenvector of the actual problem (any static state, any v) is expanded
   in the canonical modes (an M(0)-orthonormal basis).  The eigenvalue is
   *resolved* when at least half of the eigenvector's squared M(0)-norm (the
   kinetic energy of the displacement it causes) lies on resolved canonical
   modes.

Only resolved eigenvalues are reported and used for stability decisions.
The unresolved ones are the top of the discrete spectrum, where |lambda| is
1e5-1e11 and the eigensolver's round-off alone gives Re lambda up to 1e-7
(QZ, P3:64) or 0.5 (shift-invert, P3:256) for an exactly conservative
problem (v = mu = 0); for mu > 0 they also include the slow Kelvin-Voigt
roots near -1/mu of modes the mesh cannot represent.

Linear stability
----------------
A static state is *linearly stable* when no resolved eigenvalue has
Re lambda > ``STABILITY_TOL`` max(1, |lambda|) = 1e-8 max(1, |lambda|)
(round-off on resolved modes was measured below 2e-10, P1:128 ... P3:64 at
v = mu = 0, an exactly conservative case).  This one criterion,
:func:`linearly_stable`, decides ``Spectrum.stable``, the ``stable`` flags of
root loci, v_cr and every event; an eigenvalue whose real part is positive
but within that round-off counts as marginal, not unstable.  Every resolved
unstable eigenvalue is listed by :func:`spectrum` and :func:`root_locus`,
whatever its mode number.

Mode numbers
------------
A mode number names one physical eigenvalue, the same whatever the range of
v asked for, the mesh or the discretization:

1. At the reference state -- v = 0 with the same alpha, beta, gamma, mu, the
   gravity-loaded pipe, conservative apart from damping -- each resolved
   eigenvalue gets the number of the canonical mode its eigenvector is made
   of (an optimal assignment, two eigenvalues per mode: a conjugate pair or
   two real roots).  Since the low canonical modes converge with the mesh,
   so do these numbers.
2. From there, numbers are carried by continuity along the static branch:
   each tracked eigenvalue is matched to the nearest eigenvalue at the next
   state (optimal assignment on the distance to a linear prediction), and
   the step is halved when the match is not clearly better than the next
   candidate.  A state at v != 0 (a single :func:`spectrum`, a root locus or
   an analysis that starts there) is first joined to v = 0 by continuing its
   branch back in v (pseudo-arclength, folds passed, steps up to
   ``REFERENCE_STEP``); a branch born at a branch point inherits the numbers
   of its parent branch there.  A branch that does not reach v = 0 going back
   is numbered where the backward continuation ends.  An eigenvalue that is
   resolved at a state but not where numbering started gets the canonical
   mode its eigenvector is made of among the free slots.

Stability events
----------------
:func:`stability_analysis` follows a static branch in v by pseudo-arclength
continuation (:func:`fempipe.analyses.statics.continuation`), computes the spectrum at
every point, and locates to 1e-10 in v (Brent's method, recomputing the
static state at every trial v) every crossing of a tracked eigenvalue through
Re lambda = 0: flutter (a complex pair to the right), divergence (a real root
through zero), restabilization (back to the left, and the state is stable
above it) or mode_restabilization (back to the left while another eigenvalue
keeps the state unstable).  Every event carries ``stable_before`` and
``stable_after``: whether the whole state is stable just below and above it.
Folds of the static branch come from the continuation (bisection to 1e-10 in
arclength; v at a fold agrees with the Moore-Spence extended system to
1e-15); a real root passes through zero there, which is reported as the fold
itself.  Branch points (pitchforks at alpha = 0, pi) are followed with
:func:`fempipe.analyses.statics.switch_branch` and the new branches analysed the same
way.  v_cr is the first velocity along the primary branch (the gravity-loaded
state continued in v) at which it is not stable.  Where the primary branch is
the straight pipe (alpha = 0 or pi) with no branch point in the range, it is
not continued: theta = 0 is exact there, K^d, C^d are fixed matrices times 1,
v and v^2 (:class:`~fempipe.analyses.stability.linear.StraightPencil`), and the
spectra are taken every ``STRAIGHT_STEP * ds_max`` in v at most (the Notes of
:func:`stability_analysis`).

Hysteretic damping
------------------
The structural loss factor mu_h (``Params.hysteretic_damping``) multiplies
the bending stiffness by 1 + i mu_h sgn(omega) (Paidoussis' convention for
harmonic motion): with theta^d ∝ e^{lambda tau} = e^{i Omega tau} the
frequency is omega = Re Omega = Im lambda, a root with Im lambda > 0 solves
Eq. (32) with K^d + i mu_h K_b, its mirror with K^d - i mu_h K_b, and a real
root (sgn 0) is not affected.  K_b is the bending matrix alone (``disc.K``):
gravity and the follower force are not the material's stiffness.  The roots
are continued in mu_h from those of the real problem at the same state
(:func:`~fempipe.analyses.stability.hysteretic.hysteretic_roots`): the reported spectrum
keeps 2n roots, conjugate symmetry and the mode numbers above; real roots,
and pairs whose continuation would reach Im lambda <= 0 (the nearly real
Kelvin-Voigt roots near -1/mu), are left as they are, so divergence, folds
and branch points do not depend on mu_h.  Every function of this package
applies it: spectra, root loci, events, v_cr, maps and the criterion
(dense and sparse).  It has no time-domain meaning, and the time integrators
refuse it (:func:`fempipe.model.dynamics_problem.refuse_hysteretic`).  docs, "Conventions
and derivations", has the derivation and the checks.

Modules
-------
``linear``          linearized matrices K^d, C^d, M^d; the straight pencil;
``eigensolvers``    the dense quadratic eigensolvers (QZ, shift-invert);
``hysteretic``      the roots with hysteretic damping, continued in mu_h;
``canonical``       canonical modes: what a discretization resolves;
``classified``      a spectrum classified by the canonical modes, mode numbers;
``criterion``       :func:`linearly_stable`, :func:`growth_rate` (dense and sparse);
``spectra``         :class:`Spectrum` at one state, mode shapes;
``tracking``        mode numbers by continuity, root loci (Fig. 5);
``events``          the results: events, branches, :class:`StabilityResult`;
``chunked_branch``  a static branch continued piece by piece (or the straight one);
``branch_analysis`` spectra, tracking and events along one branch;
``analysis``        :func:`stability_analysis`, :func:`critical_velocity`;
``spatial``         both planes: :func:`spatial_stability_analysis` (the motion out of
                    the plane of the static state, :mod:`fempipe.model.out_of_plane`;
                    :func:`spatial_root_locus` the root loci of both planes);
``maps``            v_cr against alpha (Fig. 6), several root loci, in parallel;
``hopf``            Hopf criticality of the flutter events (first Lyapunov coefficient).
"""

from fempipe.core.parallel import run_tasks

from .analysis import critical_velocity, stability_analysis
from .canonical import RESOLUTION_TOL, Resolution, cantilever_frequencies, resolution
from .classified import STABILITY_TOL
from .criterion import growth_rate, linearly_stable
from .events import BranchStability, StabilityEvent, StabilityResult
from .linear import linearized_matrices
from .maps import StabilityMap, root_loci, stability_map
from .spatial import (
    SpatialStability,
    spatial_critical_velocity,
    spatial_stability_analysis,
)
from .spectra import ModeShape, Spectrum, mode_shape, spectrum
from .tracking import RootLocus, root_locus, spatial_root_locus

__all__ = [
    "RESOLUTION_TOL",
    "STABILITY_TOL",
    "Resolution",
    "Spectrum",
    "ModeShape",
    "RootLocus",
    "StabilityEvent",
    "BranchStability",
    "StabilityResult",
    "StabilityMap",
    "SpatialStability",
    "spatial_stability_analysis",
    "spatial_critical_velocity",
    "cantilever_frequencies",
    "resolution",
    "linearized_matrices",
    "spectrum",
    "growth_rate",
    "linearly_stable",
    "mode_shape",
    "root_locus",
    "spatial_root_locus",
    "root_loci",
    "stability_analysis",
    "critical_velocity",
    "stability_map",
    "run_tasks",
]

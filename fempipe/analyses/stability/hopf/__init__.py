"""Hopf criticality of the flutter events: the first Lyapunov coefficient l1.

A flutter event of ``fempipe critical`` is a Hopf bifurcation of the static
state: one complex pair lambda(v) = mu(v) +- i omega(v) of the linearization of
Eq. (20) (Eqs. (31b)-(33)) crosses the imaginary axis at v = v_cr.  Whether the
periodic orbit born there is stable (supercritical, l1 < 0: a small limit
cycle grows like sqrt(v - v_cr) on the unstable side) or unstable
(subcritical, l1 > 0: an unstable cycle surrounds the still stable
equilibrium on the stable side, and the motion jumps to a large cycle at
v_cr) is decided by the sign of the first Lyapunov coefficient of the normal
form on the center manifold.

First-order form
----------------
With x = (q, p = q') the weak form of Eq. (20), R(q, q', q'') = 0 (linear in
q'', :class:`fempipe.model.operators.PipeModel`), is

    x' = F(x; v),   F(q, p) = (p, a(q, p)),   a = -M(q)^{-1} R(q, p, 0).

Its Jacobian is analytic: differentiating R(q, p, a(q, p)) = 0,

    D_x F = [[0, I], [-M^{-1} R_q(q, p, a), -M^{-1} R_q'(q, p, a)]],

with R_q, R_q' and M = R_q'' of :meth:`PipeModel.jacobians` evaluated at the
acceleration a (off the equilibrium the derivative of M(q) a matters).  At the
equilibrium x0 = (q0, 0) this is the first-order form of the pencil
lambda^2 M + lambda C + K of the stability code, A = D_x F(x0).

Kuznetsov's formula
-------------------
With A q = i omega q, A^T p = -i omega p, <p, q> = p^H q = 1, and the
multilinear forms B(x, y) = D^2 F(x0)[x, y], C(x, y, z) = D^3 F(x0)[x, y, z]
(Kuznetsov, Elements of Applied Bifurcation Theory, 3rd ed., Eq. (3.20) and
its n-dimensional form, Eq. (5.39)):

    c1 = 1/2 [ <p, C(q, q, qbar)> - 2 <p, B(q, A^{-1} B(q, qbar))>
               + <p, B(qbar, (2 i omega I - A)^{-1} B(q, q))> ],
    l1 = Re(c1) / omega.

On the center manifold x = x0 + z q + zbar qbar + O(|z|^2) the flow is
z' = lambda(v) z + c1 |z|^2 z + O(|z|^4), so a periodic orbit has
|z|^2 = rho^2 = -mu(v) / (omega l1), and to leading order

    rho^2 = -Re(lambda'(v_cr)) (v - v_cr) / (omega l1),
    x(tau) - x0 = 2 rho Re(q e^{i omega tau}) + O(rho^2).

It exists on the side of v_cr where Re(lambda') (v - v_cr) / l1 < 0.  (The
shorter rho^2 = -Re(lambda') (v - v_cr) / l1 measures lambda in the time
omega tau of Kuznetsov's topological normal form; here tau is the time of
Eq. (19).)

Normalization
-------------
l1 scales with |q|^2, so its value depends on how q is normalized; its sign
does not.  Here the theta-part q_theta of q has unit L2 norm,
``\\int_0^1 |theta_q(xi)|^2 dxi = 1`` (the discretization's Gram matrix), so
that l1 and rho converge with the discretization and rho is the amplitude of
the theta field: theta(xi, tau) ~ theta0 + 2 rho Re(theta_q(xi) e^{i omega tau}).
A tip quantity s(q) oscillates with (max - min)/2 = 2 rho |ds . q_theta| +
O(rho^3) (the second harmonic shifts max and min alike), which gives the
amplitude coefficients c in ``(max - min)/2 ~ c sqrt(|v - v_cr|)``.

Derivatives
-----------
B and C are differences of the analytic Jacobian J(x) = D_x F(x), never of F:

    DJ[u] = (J(x0 + h u) - J(x0 - h u)) / (2 h),
    D2J[u, u] = (J(x0 + h u) - 2 J(x0) + J(x0 - h u)) / h^2,

for u = Re q, Im q.  Since B is symmetric and bilinear,
B(q, y) = B(y, q) = (DJ[Re q] + i DJ[Im q]) y and B(qbar, y) = (DJ[Re q] -
i DJ[Im q]) y; C(q, q, qbar) = D2J[q, qbar] q = (D2J[Re q, Re q] +
D2J[Im q, Im q]) q (the mixed terms cancel).  Four Jacobians (plus A) give
every term; two on the straight pipe at alpha = 0 or pi, where the mirror
symmetry makes J even about x0 = 0, J(x0 - h u) = J(x0 + h u), and B = 0.
The errors are O(h^2) (truncation) and O(eps |J| / h^2)
(rounding of the second difference).  For the pipe the constant bending part
of J (~h_mesh^-4 after M^{-1}) is not differenced (:func:`pipe_derivatives`);
what rounding remains comes from the acceleration off the equilibrium (a sum
of O(gamma, v^2) forces that cancel at x0) and grows with the mesh.  So the
step is not fixed: l1 is computed on the ladder h = 1e-5 4^k, k = 0..4
(q of unit size), and the flattest three consecutive values are taken (the
middle one), their spread being the uncertainty, plus a rounding level 1e-10
of the size of the terms of c1.  The middle three steps are computed first,
and taken with their spread as the uncertainty when they agree to
:data:`FLAT_ENOUGH` of l1; otherwise the two ends are added.  Measured at the paper's Hopf point at
alpha = 0: l1 flat to 2e-6 relative for 1e-5 <= h <= 1e-3 on P3:4 to P3:32.
A fixed ``step`` h uses h and 2 h, the uncertainty being their difference / 3
(Richardson).  An l1 within 10 times its uncertainty of zero is called
``"degenerate"`` (a Bautin point, or a cancellation this computation cannot
resolve): neither criticality is claimed.

Transversality
--------------
lambda'(v) = <p, (dA/dv) q>, with dA/dv the derivative along the static
branch: (J(x0 + h x_v; v + h) - J(x0 - h x_v; v - h)) / (2 h), where
x_v = (q_v, 0) and q_v = -R_q^{-1} R_v the branch's tangent.

Hysteretic damping
------------------
Hysteretic damping (``Params.hysteretic_damping``) is a frequency-domain
model with no equation of motion in time, hence no normal form:
:func:`first_lyapunov_coefficient` refuses it (ValueError) and
:func:`decorate_events` reports the reason instead of a value.

Modules
-------
``lyapunov``     l1 of a generic x' = F(x): :func:`lyapunov_coefficient`;
``pipe``         the pipe's D_x F and its derivatives: :func:`pipe_jacobian`,
                 :func:`pipe_derivatives`;
``normal_form``  the pipe's normal form at one state: :func:`first_lyapunov_coefficient`;
``flutter``      the normal forms of the flutter events of a stability analysis:
                 :func:`normal_forms`, :func:`decorate_events`.
"""

from .flutter import EVENT_KEYS, decorate_events, event_states, normal_forms
from .lyapunov import (
    DEGENERATE_FACTOR,
    FLAT_ENOUGH,
    STEP_LADDER,
    HopfCoefficient,
    jacobian_differences,
    lyapunov_coefficient,
)
from .normal_form import HopfNormalForm, first_lyapunov_coefficient
from .pipe import pipe_derivatives, pipe_jacobian

__all__ = [
    "DEGENERATE_FACTOR",
    "STEP_LADDER",
    "FLAT_ENOUGH",
    "HopfCoefficient",
    "HopfNormalForm",
    "lyapunov_coefficient",
    "pipe_jacobian",
    "pipe_derivatives",
    "jacobian_differences",
    "first_lyapunov_coefficient",
    "event_states",
    "normal_forms",
    "decorate_events",
    "EVENT_KEYS",
]

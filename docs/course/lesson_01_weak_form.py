"""
Lesson 1: the weak form of an integro-differential equation
===========================================================

What you should see: how the pipe's equation (Eq. (20) of Chen, Hu, Dai & Wang, Appl. Math.
Mech. 41(9) 1381-1400, 2020) becomes a weak form in which only first derivatives appear,
why the free-end condition then needs no imposing, and how the inertia's double integrals
come out of the principle of virtual work.  A Galerkin method with three lines of algebra
reproduces a closed form, and fempipe agrees with an independent ODE solver.
"""

# %%
# 1. The model
# ------------
# A soft cantilevered pipe (length L, bending stiffness EI, mass per length m) conveys fluid
# (mass per length M, velocity U).  It is inextensible, so one function describes its shape:
# the rotation angle theta(xi, tau) of the centerline, xi = x0 / L in [0, 1].  The undeformed
# pipe makes the angle alpha with the downward vertical.  With the groups of Eq. (19)
# (v = (M/EI)^(1/2) U L, gamma = (m+M) g L^3 / EI, beta = M/(m+M)) the static equation
# (Eq. (31a)) is
#
# .. math::
#
#    -\theta'' + \gamma (1 - \xi) \sin(\theta + \alpha) + v^2 \sin(\theta(1) - \theta) = 0,
#    \qquad \theta(0) = 0, \quad \theta'(1) = 0.
#
# Bending, the moment of the weight of the pipe beyond xi, and the follower force of the jet
# leaving the free end (Eq. (14)).  The centerline follows by integration (Eq. (28)):
# X_g = int_0^xi cos(theta + alpha) (down), Z_g = int_0^xi sin(theta + alpha).
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save
from fempipe.validation.bvp import solve_static_bvp  # section 5

# Texier & Dorbolo's horizontal silicone pipe (the paper's Sec. 3.1), in SI units
pipe = fempipe.PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2)
params = pipe.params(U=2.0)
print(f"beta = {params.beta:.6f}, gamma = {params.gamma:.6f}, v = {params.v:.6f} at U = 2 m/s")

# %%
# 2. The weak form
# ----------------
# Multiply by a test function phi with phi(0) = 0 (the clamped end is prescribed, so it is
# not tested) and integrate by parts the bending term:
# int -theta'' phi = int theta' phi' - [theta' phi]_0^1 = int theta' phi', because phi(0) = 0
# and theta'(1) = 0.  The weak form: find theta, theta(0) = 0, such that for all such phi
#
# .. math::
#
#    \int_0^1 \theta' \phi' + \gamma \int_0^1 (1-\xi) \sin(\theta+\alpha) \phi
#    + v^2 \int_0^1 \sin(\theta(1) - \theta) \phi = 0.                              \qquad (W)
#
# Only first derivatives remain: theta needs a square-integrable derivative (H^1), and
# continuous piecewise polynomials (C0 Lagrange elements) are enough.  A beam written in its
# displacement w would need w'' and C1 elements; the rotation lowers the order.  The free-end
# condition theta'(1) = 0 has disappeared: it is *natural*, satisfied by the solution of (W),
# while theta(0) = 0 is *essential* and built into the space.
#
# 3. A Galerkin solution by hand
# ------------------------------
# Take the small-deflection horizontal pipe without flow: sin(theta + pi/2) ~ 1, so (W) is
# linear, int theta' phi' = -gamma int (1 - xi) phi.  Its solution is the cubic
# theta = gamma (xi^2/2 - xi^3/6 - xi/2), with theta(1) = -gamma/6 (a cantilever under its
# weight).  With the paper's sine modes phi_r = sin(k_r xi), k_r = (2r-1) pi/2 (Eq. (22)),
# the stiffness matrix int phi_r' phi_s' = delta_rs k_r^2 / 2 is diagonal and each
# coefficient is one integral: int_0^1 (1 - xi) sin(k xi) = 1/k - sin(k)/k^2.
gamma = 1.0


def galerkin_tip(n_modes: int) -> float:
    """theta(1) of the sine-mode Galerkin solution of the linear problem."""
    k = (2 * np.arange(1, n_modes + 1) - 1) * np.pi / 2
    load = -gamma * (1 / k - np.sin(k) / k**2)
    coeff = load / (k**2 / 2)
    return float(coeff @ np.sin(k))


modes = np.array([1, 2, 4, 8, 16, 32])
tip_errors = np.array([abs(galerkin_tip(n) + gamma / 6) for n in modes])
galerkin_order, _ = fempipe.estimate_order(modes, tip_errors, floor=1e-14)
for n, e in zip(modes, tip_errors, strict=True):
    print(f"N = {n:2d} sine modes: |theta_N(1) + gamma/6| = {e:.2e}")
print(f"observed order in N: {galerkin_order:.2f}")

# %%
# Every sine mode has phi''(0) = 0, the cubic has theta''(0) = gamma: the coefficients decay
# as k^-3 and the tip error as N^-3 (lesson 7 says why precisely).
#
# 4. The dynamic terms: integrals along the pipe
# ----------------------------------------------
# With the tangent t = (cos theta, sin theta) and normal n = (-sin theta, cos theta) the
# centerline is r(xi) = int_0^xi t, a virtual rotation moves it by
# delta r(xi) = int_0^xi delta theta n, and its acceleration is
# r_tt(xi) = int_0^xi (theta_tt n - theta_t^2 t).  The virtual work of the inertia forces,
# -int_0^1 r_tt . delta r dxi, becomes with the order of integration exchanged
#
# .. math::
#
#    -\int_0^1 \delta\theta(s)\, n(s) \cdot \int_s^1 \ddot r(\xi)\, d\xi\, ds,
#
# the force needed to accelerate the part of the pipe beyond s, projected on the normal: a
# double integral (Eq. (20)'s int_xi^1 int_0^s).  The equation is integro-differential and
# the mass matrix is dense; lesson 3 shows how two integration operators apply it in O(n).
#
# 5. fempipe, and an independent solver
# -------------------------------------
# :class:`fempipe.PipeModel` is the weak form of Eq. (20), written once for finite elements
# and modes.  scipy's collocation solver on the *strong* form (with theta(1) as an unknown
# parameter) shares no code with it.
model = fempipe.PipeModel(fempipe.FiniteElement(16, 2), params)
q = fempipe.solve_static(model).q
X_fe = fempipe.compute_tip(model.disc, q, params.alpha)["X_tip"]
X_bvp = solve_static_bvp(params.alpha, params.gamma, params.v, tol=1e-11).X_tip
print(f"X_g(1): fempipe P2:16 {X_fe:.10f}, solve_bvp {X_bvp:.10f}, difference {X_fe - X_bvp:.1e}")

fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
label = f"sine modes, |theta_N(1) + gamma/6| (linear): slope {-galerkin_order:.2f}"
ax.semilogy(modes, tip_errors, "o-", ms=4, label=label)
label = "fempipe P2:16 against solve_bvp, |difference of X_g(1)|"
ax.axhline(abs(X_fe - X_bvp), color="k", ls="--", lw=0.8, label=label)
ax.set_xscale("log", base=2)
ax.set_xlabel("N (sine modes)")
ax.set_ylabel("error")
ax.set_title("Against independent references: a closed form, solve_bvp", fontsize=9)
ax.legend(fontsize=7)
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("1.k", answer)`` compares an answer with a reference computed independently (a
# closed form, exact fractions, scipy's ``solve_bvp``).  Each solution runs in this lesson.
#
# 1. Derive the weak form with a test function that does *not* vanish at xi = 0: the
#    boundary term -theta'(0) phi(0) appears, the moment of the clamp (in units EI / L).
#    With phi = 1, compute theta'(0) of section 5's pipe from the P2:16 solution ``q``, and
#    compare it with the derivative of theta_h at 0.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Integrating by parts, int theta' phi' = -int theta'' phi - theta'(0) phi(0), so
#    (W) = -theta'(0) phi(0); with phi = 1 the clamp carries the moment of the weight and
#    of the follower force.  Expected: ``answer`` = -1.88628 (solve_bvp: -1.8862804) and
#    ``slope`` = -1.88784: the weak form's value (a reaction, computed from the equation)
#    is over a thousand times closer than the derivative of theta_h.
#
#    .. code-block:: python
#
#       disc = model.disc
#       theta = disc.basis_values(disc.quad.x) @ q  # at the Gauss points of the mesh
#       theta_1 = (disc.basis_values(np.array([1.0])) @ q)[0]
#       g, v, a = params.gamma, params.v, params.alpha
#       load = g * (1 - disc.quad.x) * np.sin(theta + a) + v**2 * np.sin(theta_1 - theta)
#       answer = -disc.quad.w @ load
#       slope = (disc.basis_values(np.array([1e-7])) @ q)[0] / 1e-7  # theta_h'(0)
#       print(f"theta'(0): from (W) {answer:.7f}, differentiated {slope:.7f}")
#       check("1.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Replace the sine modes by the polynomials xi, xi^2 to xi^n (they satisfy only the
#    essential condition).  Compute theta_n(1) for n = 1, 2 and theta_2(1/4), gamma = 1.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Stiffness int (xi^i)' (xi^j)' = ij / (i + j - 1), load -int (1 - xi) xi^i =
#    -1 / ((i + 1)(i + 2)).  Expected: ``tip_1`` = -0.166667 and ``tip_2`` = -0.166667,
#    already exact: the tip value's Green's function (the solution for a unit moment at the
#    tip) is xi, which both spaces contain; ``answer`` = -0.0885417, against the exact
#    -37/384 = -0.0963542 (three polynomials contain the cubic solution: exact everywhere).
#
#    .. code-block:: python
#
#       def polynomial_galerkin(n):
#           i = np.arange(1, n + 1)
#           A = np.outer(i, i) / (i[:, None] + i[None, :] - 1)
#           return np.linalg.solve(A, -1.0 / ((i + 1) * (i + 2)))
#
#       tip_1, tip_2 = (polynomial_galerkin(n).sum() for n in (1, 2))
#       answer = polynomial_galerkin(2) @ [0.25, 0.25**2]
#       print(f"theta_1(1) = {tip_1:.6f}, theta_2(1) = {tip_2:.6f}, theta_2(1/4) = {answer:.7f}")
#       check("1.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. Add an end mass Gamma (:doc:`Variants of the pipe </theory/variants>`): its weight acts
#    beyond every section, so the lever (1 - xi) becomes (1 - xi + Gamma).  Compute the
#    sine-mode tip theta_32(1) of the linear problem for gamma = 1, Gamma = 0.5.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    int_0^1 sin(k xi) = 1/k (cos k = 0), so the load gains -gamma Gamma / k.  The closed
#    form is theta(1) = -gamma (1/6 + Gamma/2).  Expected: ``answer`` = -0.416665
#    (closed form -5/12 = -0.4166667).
#
#    .. code-block:: python
#
#       k = (2 * np.arange(1, 33) - 1) * np.pi / 2
#       load = -gamma * (1 / k - np.sin(k) / k**2 + 0.5 / k)
#       answer = float((load / (k**2 / 2)) @ np.sin(k))
#       print(f"theta_32(1) with Gamma = 0.5: {answer:.7f}")
#       check("1.3", answer)
#
#    .. raw:: html
#
#       </details>

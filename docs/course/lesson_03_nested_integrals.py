"""
Lesson 3: nested integrals as lower-triangular operators
========================================================

What you should see: the double integrals of the inertia (lesson 1, section 4) applied by
two integration operators on the Gauss points of the mesh, C (from the clamp) and C^R
(from the tip); C integrates piecewise polynomials of degree n_g - 1 exactly; on Gauss
points, and only there, the two are adjoint, W C^R = C^T W; and the mass matrix is the Gram
matrix B^T W B, symmetric positive definite, equal to the paper's kernel form (Eq. (24a)).
"""

# %%
# 1. The cumulative integral on Gauss points
# ------------------------------------------
# On each cell replace f by the polynomial through its values at the n_g Gauss points and
# integrate it exactly; whole cells before contribute their Gauss sums.  As a matrix on the
# Gauss values: block lower triangular, a small dense block per cell plus the weights of all
# earlier cells.  Applying it costs O(n) (a tiny matrix per cell and a cumulative sum);
# fempipe's :class:`fempipe.model.quadrature.LineQuadrature` does that, here we build the
# dense matrix to look at it.
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.model.quadrature import lagrange_integrals
from fempipe.plotting.scripts import show_or_save


def cumulative_matrix(edges: np.ndarray, points: np.ndarray):
    """Dense C on the given reference points of each cell; also the points and weights."""
    a = lagrange_integrals(points, points)  # a[p, q] = int_0^{c_p} l_q
    b = lagrange_integrals(points, np.array([1.0]))[0]  # the weights of the rule
    h = np.diff(edges)
    k, n_c = points.size, h.size
    x = (edges[:-1, None] + h[:, None] * points[None, :]).ravel()
    w = (h[:, None] * b[None, :]).ravel()
    C = np.zeros((k * n_c, k * n_c))
    for c in range(n_c):
        rows = slice(c * k, (c + 1) * k)
        C[rows, c * k : (c + 1) * k] = h[c] * a
        C[rows, : c * k] = w[: c * k]  # all earlier cells, fully
    return C, x, w


edges = np.linspace(0.0, 1.0, 5)
gauss = 0.5 * (np.polynomial.legendre.leggauss(3)[0] + 1.0)
C, x, w = cumulative_matrix(edges, gauss)
exact_deg2 = np.max(np.abs(C @ x**2 - x**3 / 3))
inexact_deg4 = np.max(np.abs(C @ x**4 - x**5 / 5))
print(
    f"3 Gauss points, 4 cells: C x^2 - x^3/3: {exact_deg2:.1e}; C x^4 - x^5/5: {inexact_deg4:.1e}"
)

fig, ax = plt.subplots(figsize=(3.4, 3.2), layout="constrained")
ax.spy(C, markersize=3)
ax.set_title("C: 4 cells, 3 Gauss points each", fontsize=9)

# %%
# 2. Adjoint on Gauss points
# --------------------------
# Exchanging the order of integration, int_0^1 g int_xi^1 f = int_0^1 f int_0^s g: C^R is
# the L2 adjoint of C.  The discrete operators keep this, W C^R = C^T W with W = diag(w), if
# and only if the collocation matrix a and the weights b satisfy b_p a_pq + b_q a_qp = b_p b_q,
# the condition for the collocation Runge-Kutta method on those points to be symplectic
# (Hairer, Lubich & Wanner, Geometric Numerical Integration, Thm VI.4.3).  Gauss-Legendre
# points satisfy it; Lobatto and equispaced points do not.
defects = {}
for name, pts in [
    ("Gauss-Legendre", gauss),
    ("Gauss-Lobatto", np.array([0.0, 0.5, 1.0])),
    ("equispaced interior", np.array([1 / 6, 1 / 2, 5 / 6])),
]:
    Cp, xp, wp = cumulative_matrix(edges, pts)
    CR = np.outer(np.ones_like(wp), wp) - Cp  # int_x^1 = int_0^1 - int_0^x
    defects[name] = np.max(np.abs(np.diag(wp) @ CR - Cp.T @ np.diag(wp)))
    print(f"{name:20s}: max |W C^R - C^T W| = {defects[name]:.1e}")

# %%
# 3. The mass matrix is a Gram matrix
# -----------------------------------
# The centerline's velocity is r_t = C(theta_t n), the kinetic energy
# :math:`\frac12 \int |\dot r|^2`; with theta_t = sum_j phi_j qdot_j it is
# (1/2) qdot^T M qdot with M = B^T W B, B = C(Phi n): symmetric, and positive definite
# because C is injective.  It equals the paper's double integral, after one integration
# by parts
# M_ij = int int phi_i(xi) phi_j(s) cos(theta(xi) - theta(s)) (1 - max(xi, s)) ds dxi,
# dense in (i, j), yet M qdd costs O(n): two integrations.
params = fempipe.Params(alpha=np.pi / 2)
q_state = 0.7 * np.random.default_rng(0).normal(size=fempipe.FiniteElement(8, 2).n)
disc = fempipe.FiniteElement(8, 2, n_gauss=12)  # many Gauss points: this state is wild
M = fempipe.PipeModel(disc, params).mass_matrix(q_state)
asymmetry = np.max(np.abs(M - M.T))
eigs = np.linalg.eigvalsh(M)
print(
    f"mass matrix P2:8: asymmetry {asymmetry:.0e}, eigenvalues in [{eigs[0]:.2e}, {eigs[-1]:.2e}]"
)


def kernel_mass(n_cells: int) -> np.ndarray:
    """The kernel form by brute force on a tensor Gauss grid.

    The grids of 200 and 400 cells have the nodes of P2:8 among their edges, so the only
    non-smoothness left inside a cell is the kink of max(xi, s) on the diagonal: O(h^2).
    """
    e = np.linspace(0.0, 1.0, n_cells + 1)
    gx, gw = np.polynomial.legendre.leggauss(4)
    xs = (e[:-1, None] + np.diff(e)[:, None] * 0.5 * (gx + 1)).ravel()
    ws = (np.diff(e)[:, None] * 0.5 * gw).ravel()
    phis = disc.basis_values(xs).toarray()  # phi_j at xs
    th = phis @ q_state
    kern = np.cos(th[:, None] - th[None, :]) * (1.0 - np.maximum(xs[:, None], xs[None, :]))
    return (phis * ws[:, None]).T @ kern @ (phis * ws[:, None])


d1, d2 = (np.max(np.abs(kernel_mass(n) - M)) for n in (200, 400))
kernel_ratio = d1 / d2
print(
    f"kernel form - Gram form: {d1:.1e} (200 cells), {d2:.1e} (400 cells), ratio {kernel_ratio:.2f}"
)
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("3.k", answer)`` compares an answer with a reference computed independently (a
# closed form, exact fractions).  Each solution runs in this lesson.
#
# 1. C is exact for degree n_g - 1, not n_g: compute :math:`\max |C x^3 - x^4/4|` with 3 Gauss
#    points on 4 cells.  The Gauss *sum* is exact up to degree 5: why does that not help C?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Whole earlier cells contribute their Gauss sums, exact for x^3; the error is that of
#    the partial cell, whose integral runs over [x_c, x_p] only: h^3 times the node
#    polynomial (t - c_1)(t - c_2)(t - c_3) of the Gauss points integrated from 0 to c_p, a
#    part of the cell on which no quadrature rule is exact.
#    Expected: ``answer`` = 1.2207e-05 (= h^4 / 320 = 1/81920).
#
#    .. code-block:: python
#
#       answer = np.max(np.abs(C @ x**3 - x**4 / 4))
#       print(f"max |C x^3 - x^4/4| = {answer:.6e}")
#       check("3.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Prove b_p a_pq + b_q a_qp = b_p b_q for Gauss points, and compute the largest defect
#    :math:`|b_p a_{pq} + b_q a_{qp} - b_p b_q|` for the Gauss-Lobatto points (0, 1/2, 1).
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    With L_q(x) = int_0^x l_q, the product rule gives int_0^1 (l_p L_q + l_q L_p) =
#    L_p(1) L_q(1) = b_p b_q.  l_p L_q has degree 2s - 1, which s Gauss points integrate
#    exactly: int_0^1 l_p L_q = sum_r b_r l_p(c_r) L_q(c_r) = b_p a_pq.  Three Lobatto
#    points are exact to degree 3 only.  Expected: ``answer`` = 0.027778 (= 1/36; times
#    h^2 = 1/16 on section 2's cells: the 1.7e-3 printed there).
#
#    .. code-block:: python
#
#       lobatto = np.array([0.0, 0.5, 1.0])
#       a_l = lagrange_integrals(lobatto, lobatto)
#       b_l = lagrange_integrals(lobatto, np.array([1.0]))[0]
#       ba = b_l[:, None] * a_l
#       answer = np.max(np.abs(ba + ba.T - np.outer(b_l, b_l)))
#       print(f"Lobatto: max defect {answer:.6f}")
#       check("3.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. Without forming M: the bent pipe theta = xi moves with theta_t = xi.  Compute
#    :math:`2T = \int_0^1 |\dot r|^2` with r_t = C(theta_t n), two integrations on the
#    Gauss points of 8 cells (what fempipe does in O(n) for M qdd).
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    In complex notation r_t(xi) = int_0^xi s e^(is) ds = e^(i xi)(1 - i xi) - 1, so
#    2T = 7/3 - 4 sin 1 + 2 cos 1.  Expected: ``answer`` = 0.0480540 (closed form
#    0.04805401; three Gauss points per cell leave 4e-10).
#
#    .. code-block:: python
#
#       C8, x8, w8 = cumulative_matrix(np.linspace(0.0, 1.0, 9), gauss)
#       rt_x, rt_y = C8 @ (x8 * -np.sin(x8)), C8 @ (x8 * np.cos(x8))  # n = (-sin, cos)
#       answer = w8 @ (rt_x**2 + rt_y**2)
#       print(f"2T = {answer:.10f}")
#       check("3.3", answer)
#
#    .. raw:: html
#
#       </details>

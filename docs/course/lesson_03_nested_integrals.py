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
from fempipe.model.quadrature import lagrange_integrals


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

# %%
# Exercises
# ---------
# 1. Show that C is exact for degree n_g - 1 but not n_g (try x^3 above).  What degree is
#    the Gauss *sum* exact for, and why does that not help C?
# 2. Prove b_p a_pq + b_q a_qp = b_p b_q for Gauss points from the exactness of the rule.
# 3. Compute M qdd with two applications of C and C^R and compare the cost with M @ qdd for
#    n = 10 000 unknowns.

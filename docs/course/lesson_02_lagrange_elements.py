"""
Lesson 2: Lagrange elements on a MeshLine, assembled in scikit-fem
==================================================================

What you should see: scikit-fem's four pieces (mesh, element, basis, forms), the orders of
P1 to P3 on a linear model problem with a known solution (error k + 1 in L2, k in the
derivative), and a Newton solver of the pipe's weak form (W) of lesson 1 in forty lines
that agrees with fempipe to round-off and with an independent ODE solver to its
discretization error.
"""

# %%
# 1. The pieces
# -------------
# A :class:`skfem.MeshLine` of [0, 1]; a Lagrange element (``ElementLineP1``, ``P2`` or
# ``ElementLinePp(k)``); a :class:`skfem.Basis` (the element on the mesh with a quadrature
# rule); and forms, decorated Python functions evaluated at the quadrature points and
# assembled into sparse matrices and vectors.  The clamped dof is removed by ``condense``.
#
# 2. A linear model problem
# -------------------------
# -u'' = f on [0, 1], u(0) = 0, u'(1) = 0, with u = sin(3 pi xi / 2) (which satisfies both
# boundary conditions) and f = (3 pi / 2)^2 u.  Theory: the L2 error of P_k falls as
# h^(k+1), that of u' as h^k.
import matplotlib.pyplot as plt
import numpy as np
import scipy.sparse as sp
from skfem import (
    Basis,
    BilinearForm,
    ElementLineP1,
    ElementLineP2,
    ElementLinePp,
    Functional,
    LinearForm,
    MeshLine,
    condense,
    solve,
)
from skfem.helpers import dot, grad

import fempipe
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save
from fempipe.validation.bvp import solve_static_bvp  # the independent solver of section 3

K3 = 3 * np.pi / 2


def element(k: int):
    """The Lagrange element of degree k on a line."""
    return {1: ElementLineP1, 2: ElementLineP2}.get(k, lambda: ElementLinePp(k))()


@BilinearForm
def laplace(u, v, w):
    return dot(grad(u), grad(v))


@LinearForm
def load(v, w):
    return K3**2 * np.sin(K3 * w.x[0]) * v


@Functional
def l2_error(w):
    return (w["u"] - np.sin(K3 * w.x[0])) ** 2


@Functional
def h1_error(w):
    return (w["u"].grad[0] - K3 * np.cos(K3 * w.x[0])) ** 2


def model_errors(n: int, k: int) -> tuple[float, float]:
    """L2 errors of u and u' with P_k on n elements."""
    basis = Basis(MeshLine(np.linspace(0, 1, n + 1)), element(k), intorder=2 * k + 2)
    clamped = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
    u = solve(*condense(laplace.assemble(basis), load.assemble(basis), D=clamped))
    uh = basis.interpolate(u)
    return np.sqrt(l2_error.assemble(basis, u=uh)), np.sqrt(h1_error.assemble(basis, u=uh))


sizes = np.array([4, 8, 16, 32])
linear_orders = {}
fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
for k in (1, 2, 3):
    err = np.array([model_errors(int(n), k) for n in sizes])
    p_l2 = -np.polyfit(np.log(sizes[-2:]), np.log(err[-2:, 0]), 1)[0]
    p_h1 = -np.polyfit(np.log(sizes[-2:]), np.log(err[-2:, 1]), 1)[0]
    linear_orders[k] = (p_l2, p_h1)
    print(f"P{k}: L2 error of u order {p_l2:.2f} (theory {k + 1}), of u' {p_h1:.2f} (theory {k})")
    ax.loglog(1 / sizes, err[:, 0], "o-", ms=4, label=f"P{k}: u, slope {p_l2:.2f}")
ax.set_xlabel("h")
ax.set_ylabel("L2 error")
ax.set_title("-u'' = f, u = sin(3 pi xi / 2)", fontsize=9)
ax.legend(fontsize=8)

# %%
# 3. The pipe's static problem in forty lines
# -------------------------------------------
# Newton's method for (W) needs the residual r_i = (W) with phi = phi_i and the Jacobian
#
# .. math::
#
#    J_{ij} = \int \phi_j' \phi_i' + \gamma \int (1-\xi)\cos(\theta+\alpha)\phi_j\phi_i
#    + v^2 \int \cos(\theta(1)-\theta) (\phi_j(1) - \phi_j) \phi_i .
#
# The last term couples every equation to theta(1): a local mass-like matrix plus one
# dense column (rank one), so J stays sparse.  The result is checked twice: against
# fempipe (another implementation of the same discrete problem: equal to round-off) and
# against scipy's ``solve_bvp`` on the strong form, Eq. (31a) with theta(1) an unknown
# parameter, which shares no code with either (equal to P2:16's discretization error).


def static_fe(n: int, k: int, alpha: float, gamma: float, v: float, guess=None):
    """Solve (W) with P_k on n elements, Newton from theta = 0 or from ``guess(xi)``;
    (basis, dofs, Newton steps)."""
    basis = Basis(MeshLine(np.linspace(0.0, 1.0, n + 1)), element(k), intorder=4 * k - 1)
    tip = basis.probes(np.array([[1.0]])).tocsr()  # theta(1) = tip @ u
    clamped = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()

    @LinearForm
    def loads(phi, w):
        xi, th = w.x[0], w["theta"]
        return gamma * (1 - xi) * np.sin(th + alpha) * phi + v**2 * np.sin(w["tip"] - th) * phi

    @BilinearForm
    def local_jacobian(u, phi, w):
        xi, th = w.x[0], w["theta"]
        return (gamma * (1 - xi) * np.cos(th + alpha) - v**2 * np.cos(w["tip"] - th)) * u * phi

    @LinearForm
    def tip_column(phi, w):
        return v**2 * np.cos(w["tip"] - w["theta"]) * phi

    K = laplace.assemble(basis)
    # Lagrange dofs are values at the dof locations: the guess's interpolant, clamped
    u = np.zeros(basis.N) if guess is None else guess(basis.doflocs[0]) * (basis.doflocs[0] > 0)
    for it in range(1, 30):
        fields = {"theta": basis.interpolate(u), "tip": float((tip @ u)[0])}
        r = K @ u + loads.assemble(basis, **fields)
        column = sp.csr_matrix(tip_column.assemble(basis, **fields)[:, None])
        J = (K + local_jacobian.assemble(basis, **fields) + column @ tip).tocsr()
        du = solve(*condense(J, -r, D=clamped))
        u += du
        if np.linalg.norm(du) < 1e-13 * (1 + np.linalg.norm(u)):
            return basis, u, it
    raise RuntimeError("Newton did not converge")


@Functional
def x_g(w):
    return np.cos(w["theta"] + w["alpha"])


params = fempipe.PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2).params(2.0)
basis, u, its = static_fe(16, 2, params.alpha, params.gamma, params.v)
ours = x_g.assemble(basis, theta=basis.interpolate(u), alpha=params.alpha)
model = fempipe.PipeModel(fempipe.FiniteElement(16, 2), params)
theirs = fempipe.compute_tip(model.disc, fempipe.solve_static(model).q, params.alpha)["X_tip"]
X_bvp = solve_static_bvp(params.alpha, params.gamma, params.v, tol=1e-11).X_tip
print(f"X_g(1): this lesson's P2:16 {ours:.12f} after {its} Newton steps, fempipe {theirs:.12f}")
print(f"        scipy's solve_bvp on the strong form {X_bvp:.12f}: difference {ours - X_bvp:.1e}")

# %%
# The natural condition theta'(1) = 0 is satisfied only in the limit: the computed slope at
# the tip shrinks with h (for P2 as h^2).
tip_slopes = []
for n in (4, 8, 16, 32):
    b, u_n, _ = static_fe(n, 2, params.alpha, params.gamma, params.v)
    h = 1.0 / n
    # theta_h is a quadratic on the last cell: the one-sided three-point formula is exact
    p0, p1, p2 = b.probes(np.array([[1.0, 1.0 - h / 2, 1.0 - h]])) @ u_n
    tip_slopes.append(abs((3 * p0 - 4 * p1 + p2) / h))
    print(f"P2:{n:2d}: |theta_h'(1)| = {tip_slopes[-1]:.2e}")
slope_order = np.log2(tip_slopes[-2] / tip_slopes[-1])
print(f"order of theta_h'(1) -> 0: {slope_order:.2f}")
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("2.k", answer)`` compares an answer with a reference computed independently (a
# closed form, scipy's ``solve_bvp``).  Each solution runs in this lesson.
#
# 1. A load with a jump: f = 1 on [0, 0.3), 0 beyond.  The Green's function of u(1) is xi,
#    so u(1) = int_0^0.3 xi = 0.045, and in 1-D the nodal values of P_k are exact when the
#    load's integrals are.  Compute u_h(1) with P2 on 8 cells (0.3 inside a cell) and on
#    10 cells (0.3 a node).
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    A Gauss rule integrates the jump inside a cell as if it were smooth: the load vector,
#    and with it every nodal value, is off.  Put the node where the data jumps.  Expected:
#    ``off_node`` = 0.048745 and ``answer`` = 0.045000 (exact to round-off).
#
#    .. code-block:: python
#
#       @LinearForm
#       def jump_load(phi, w):
#           return (w.x[0] < 0.3) * phi
#
#       def jump_tip(n):
#           basis = Basis(MeshLine(np.linspace(0, 1, n + 1)), element(2), intorder=6)
#           clamped = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()
#           u = solve(*condense(laplace.assemble(basis), jump_load.assemble(basis), D=clamped))
#           return (basis.probes(np.array([[1.0]])) @ u)[0]
#
#       off_node, answer = jump_tip(8), jump_tip(10)
#       print(f"u_h(1): 8 cells {off_node:.7f}, 10 cells {answer:.12f}")
#       check("2.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Stand the pipe up (alpha = pi, v = 0) above Greenhill's load (lesson 4), gamma = 10.
#    ``static_fe`` from theta = 0 stays on the straight solution (R(0) = 0 there).  Start
#    Newton from the guess theta = sin(pi xi / 2) and report theta_h(1) on P2:16.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Newton converges to the solution whose basin holds the guess: here the buckled one
#    (its mirror image, from -sin, has theta(1) of the other sign).
#    Expected: ``answer`` = 1.42139 (solve_bvp: 1.4213962).
#
#    .. code-block:: python
#
#       b, u_b, its_b = static_fe(16, 2, np.pi, 10.0, 0.0, guess=lambda xi: np.sin(np.pi * xi / 2))
#       answer = (b.probes(np.array([[1.0]])) @ u_b)[0]
#       print(f"buckled standing pipe, gamma = 10: theta_h(1) = {answer:.7f} ({its_b} steps)")
#       check("2.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. How many nonzero entries has the Jacobian J of ``static_fe`` on P2:1000, against
#    (2n + 1)^2 for a dense matrix?  Predict it, then count it.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    The bending and the local term couple the 3 dofs of each cell: 9 entries per cell,
#    the n - 1 shared vertices counted twice, 8n + 1.  The rank-one term fills the tip
#    dof's column, which had 3 entries: 2n - 2 more, 10n - 1 in all.
#    Expected: ``answer`` = 9999, a fraction ``fraction`` = 0.0025 of the dense 4 004 001.
#
#    .. code-block:: python
#
#       b = Basis(MeshLine(np.linspace(0.0, 1.0, 1001)), element(2), intorder=7)
#       column = sp.csr_matrix(np.ones((b.N, 1)))  # v^2 int cos(theta(1) - theta) phi_i != 0
#       # the local term has the pattern of the bending term: both couple one cell's dofs
#       J = laplace.assemble(b) + column @ b.probes(np.array([[1.0]]))
#       answer = J.count_nonzero()
#       fraction = answer / b.N**2
#       print(f"P2:1000: {answer} nonzeros of {b.N**2} ({fraction:.2%})")
#       check("2.3", answer)
#
#    .. raw:: html
#
#       </details>

# ruff: noqa: E402
"""Finite elements for a soft pipe conveying fluid: a literate tutorial.

Read this file from top to bottom; it is a document whose examples run.
Run it with

    python validation/tutorial.py [--out DIR]

and in well under a minute it prints the checks below and writes the
convergence plot ``tutorial_convergence.png`` (into ``validation/`` by
default).  It needs only fempipe's dependencies (numpy, scipy, scikit-fem,
matplotlib).

The paper: W. Chen, Z. Hu, H. Dai & L. Wang, "Extremely large-amplitude
oscillation of soft pipes conveying fluid under gravity", Appl. Math. Mech.
41(9) 1381-1400 (2020).  Equation numbers below are the paper's.
"""

# %% 1. The model
#
# A soft cantilevered pipe (length L, bending stiffness EI, mass per length
# m) conveys fluid (mass per length M, velocity U).  It is inextensible, so
# its shape is described by one function: the rotation angle theta(xi, tau)
# of the centerline, xi = x0 / L in [0, 1] along the pipe.  The undeformed
# pipe makes the angle alpha with the downward vertical.  After scaling
# (Eq. (19): v = (M/EI)^(1/2) U L, gamma = (m+M) g L^3 / EI, beta = M/(m+M))
# the static part of the governing equation (Eq. (31a)) is
#
#     -theta'' + gamma (1 - xi) sin(theta + alpha) + v^2 sin(theta(1) - theta) = 0,
#     theta(0) = 0   (clamped),      theta'(1) = 0   (free end: no moment).
#
# The three terms are bending, the moment of the weight of the pipe beyond
# xi, and the follower force of the jet leaving the free end (Eq. (14)).
# The dynamic equation (20) adds inertia, centripetal, Coriolis and
# Kelvin-Voigt terms; the inertia terms are *double integrals* over the pipe
# (section 5 below), which is what makes this problem unusual.
#
# Positions follow from theta by integration (Eq. (28)):
#
#     X_g(xi) = int_0^xi cos(theta + alpha),   Z_g(xi) = int_0^xi sin(theta + alpha),
#
# X_g pointing down along gravity.

import argparse
import time
from pathlib import Path

import numpy as np
import scipy.sparse as sp

T_START = time.perf_counter()

# The Texier-Dorbolo pipe of the paper's Sec. 3.1 (Fig. 2(b)): a horizontal
# (alpha = pi/2) silicone pipe 94 mm long.  fempipe converts SI to the
# dimensionless groups of Eq. (19).
from fempipe import PipeSI

pipe = PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2)
params = pipe.params(U=2.0)  # 2 m/s of flow
alpha, gamma, v = params.alpha, params.gamma, params.v
print(f"beta = {params.beta:.4f}, gamma = {gamma:.4f}, v = {v:.4f}  (paper Eq. (29))")

# %% 2. The weak form, and why theta needs only C0 elements
#
# Multiply the equation by a test function phi(xi) with phi(0) = 0 (the
# clamped end is prescribed, so we do not test there) and integrate over the
# pipe.  The bending term is integrated by parts:
#
#     int_0^1 -theta'' phi = int_0^1 theta' phi' - [theta' phi]_0^1
#                          = int_0^1 theta' phi'
#
# because phi(0) = 0 and theta'(1) = 0.  So the weak form is: find theta with
# theta(0) = 0 such that for every test function phi with phi(0) = 0
#
#     int theta' phi' + gamma int (1 - xi) sin(theta + alpha) phi
#                     + v^2 int sin(theta(1) - theta) phi = 0.             (W)
#
# Two things happened.  First, only *first* derivatives of theta and phi
# appear, so (W) makes sense for any theta whose derivative is square
# integrable (the Sobolev space H^1): continuous, piecewise-polynomial
# functions -- C0 Lagrange elements -- are enough.  (A beam written in the
# transverse displacement w would need w'' and hence C1 Hermite elements;
# writing the beam in the rotation theta is what lowers the order.)
# Second, the free-end condition theta'(1) = 0 disappeared: it is *natural*,
# satisfied by the solution of (W) in the limit, not imposed on the basis.
# Only theta(0) = 0 is *essential* and must be built into the space.
#
# The paper's sine modes phi_r = sin((2r - 1) pi xi / 2) also satisfy
# theta'(1) = 0 exactly, and, as a side effect, theta''(0) = 0, which the
# true solution does not (at the clamp the equation gives theta''(0) =
# gamma sin(alpha) + v^2 sin(theta(1))).  We will see what that costs.

# %% 3. A static finite-element solver in forty lines of scikit-fem
#
# scikit-fem builds the pieces: a mesh of [0, 1], a Lagrange element, a
# basis (the element on the mesh with a quadrature rule), and forms that are
# assembled into matrices and vectors.  Newton's method needs the residual
# r_i(theta) = (W) with phi = phi_i and its Jacobian J_ij = dr_i / dtheta_j:
#
#     J_ij = int phi_j' phi_i' + gamma int (1 - xi) cos(theta + alpha) phi_j phi_i
#            + v^2 int cos(theta(1) - theta) (phi_j(1) - phi_j) phi_i .
#
# The last term couples every equation to the tip value theta(1): it is a
# local mass-like matrix plus a rank-one matrix (one dense column at the tip
# dof), which keeps J sparse.

from skfem import (
    Basis,
    BilinearForm,
    ElementLineP1,
    ElementLineP2,
    ElementLinePp,
    LinearForm,
    MeshLine,
    condense,
    solve,
)
from skfem.helpers import dot, grad

ELEMENTS = {1: ElementLineP1, 2: ElementLineP2}


def static_fe(n_elements: int, degree: int, alpha: float, gamma: float, v: float):
    """Solve (W) with P_degree elements; return (basis, theta dofs, Newton steps)."""
    mesh = MeshLine(np.linspace(0.0, 1.0, n_elements + 1))
    element = ELEMENTS[degree]() if degree in ELEMENTS else ElementLinePp(degree)
    # 2k Gauss points per element: the nonlinear terms are smooth, and a
    # rule exact to degree 4k - 1 keeps the superconvergence of section 8.
    basis = Basis(mesh, element, intorder=4 * degree - 1)
    tip = basis.probes(np.array([[1.0]])).tocsr()  # theta(1) = tip @ u
    clamped = basis.get_dofs(lambda x: np.isclose(x[0], 0.0)).all()

    @BilinearForm
    def bending(u, phi, w):
        return dot(grad(u), grad(phi))

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

    K = bending.assemble(basis)
    u = np.zeros(basis.N)
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


def tip_drop(basis, u, alpha: float) -> float:
    """X_g(1) = int_0^1 cos(theta + alpha): the drop of the tip below the clamp (units of L)."""
    from skfem import Functional

    @Functional
    def x_g(w):
        return np.cos(w["theta"] + alpha)

    return float(x_g.assemble(basis, theta=basis.interpolate(u)))


basis, u, its = static_fe(16, 2, alpha, gamma, v)
ours = tip_drop(basis, u, alpha)
print(
    f"our P2:16 solver: tip drop X_g(1) = {ours:.10f} L = {ours * pipe.L * 1e3:.4f} mm "
    f"after {its} Newton steps"
)

# %% 4. Trust, but verify: fempipe and an independent ODE solver
#
# fempipe's `PipeModel` is the same weak form, written once for both the
# finite elements and the sine modes (it does not know which it is given).
# An independent check shares no code at all: scipy's collocation BVP solver
# applied to the *strong* form, with theta(1) as an unknown parameter.

from fempipe import FiniteElement, Modal, PipeModel, solve_static, tip_values
from fempipe.validation.bvp import solve_static_bvp

model = PipeModel(FiniteElement(16, 2), params)
fem = tip_values(model.disc, solve_static(model).q, alpha)["X_tip"]
bvp = solve_static_bvp(alpha, gamma, v, tol=1e-11)
print(f"fempipe P2:16      : {fem:.10f}   (ours - fempipe = {ours - fem:.1e})")
print(f"scipy solve_bvp    : {bvp.X_tip:.10f}   (ours - BVP     = {ours - bvp.X_tip:.1e})")
# ours = fempipe to round-off (the same discrete problem); the difference from
# the BVP is the P2:16 discretization error, O(h^4) -- section 8 measures it.
assert abs(ours - bvp.X_tip) < 1e-6, "the tutorial's solver disagrees with the BVP"

# %% 5. The dynamic terms: integrals along the pipe as operators
#
# The dynamic equation (20) contains, for the inertia of the pipe and the
# fluid,
#
#     sin(theta) int_xi^1 int_0^s (theta_tt sin theta + ...) dr ds + cos(theta) ...
#
# i.e. the acceleration of the centerline, r_tt(s) = int_0^s (...), summed
# from xi to the tip: the force that the part of the pipe beyond xi needs to
# accelerate.  Two integration operators do all of it, acting on values of a
# field at the Gauss points of the mesh:
#
#     (C f)(x_q)   = int_0^{x_q} f        (cumulative, "lower triangular")
#     (C^R f)(x_q) = int_{x_q}^1 f        (from the tip).
#
# Inside a cell, f is replaced by the polynomial through its Gauss values and
# integrated exactly; whole cells contribute their Gauss sums.  So C is exact
# for piecewise polynomials of degree n_g - 1, and applying it costs O(n):
# a tiny matrix per cell plus a cumulative sum.  fempipe's LineQuadrature
# implements it; here we build it as a dense matrix to look at it.

from fempipe.model.quadrature import lagrange_integrals


def cumulative_matrix(edges: np.ndarray, points: np.ndarray):
    """Dense C on the given reference points per cell; also the points and weights."""
    a = lagrange_integrals(points, points)  # a[p, q] = int_0^{c_p} l_q
    b = lagrange_integrals(points, np.array([1.0]))[0]  # weights of the rule
    h = np.diff(edges)
    k, n_c = points.size, h.size
    x = (edges[:-1, None] + h[:, None] * points[None, :]).ravel()
    w = (h[:, None] * b[None, :]).ravel()
    C = np.zeros((k * n_c, k * n_c))
    for c in range(n_c):  # a loop is fine for a picture; fempipe vectorizes
        rows = slice(c * k, (c + 1) * k)
        C[rows, c * k : (c + 1) * k] = h[c] * a
        C[rows, : c * k] = w[: c * k]  # all earlier cells, fully
    return C, x, w


edges = np.linspace(0.0, 1.0, 5)
gauss = 0.5 * (np.polynomial.legendre.leggauss(3)[0] + 1.0)
C, x, w = cumulative_matrix(edges, gauss)
exact = x**5 / 5  # int_0^x s^4 ds: degree 4 > n_g - 1 = 2, so not exact...
print(f"C on x^4, 3 Gauss points, 4 cells: max error {np.max(np.abs(C @ x**4 - exact)):.1e}")
print(f"C on x^2 (degree <= 2, exact)     : max error {np.max(np.abs(C @ x**2 - x**3 / 3)):.1e}")

# %% 6. Why Gauss points: the two operators are adjoint
#
# In the continuum, swapping the order of integration gives
#
#     int_0^1 g(xi) int_xi^1 f ds dxi = int_0^1 f(s) int_0^s g dxi ds,
#
# i.e. C^R is the adjoint of C in L2.  The discrete operators keep this,
# W C^R = C^T W with W = diag(weights), if and only if the collocation matrix
# a and weights b of the points satisfy
#
#     b_p a_pq + b_q a_qp = b_p b_q          for all p, q,
#
# which is exactly the condition for the collocation Runge-Kutta method on
# those points to be symplectic -- and Gauss-Legendre points satisfy it
# (Sanz-Serna 1988; Hairer, Lubich & Wanner, Geometric Numerical
# Integration, Thm VI.4.3).  Other points (Lobatto, Radau, equispaced) do not.
# Why we care: the mass matrix of section 7 is built from C and C^R; with
# adjoint operators it is exactly symmetric, and the discrete system
# conserves energy exactly when it should (v = 0, mu = 0).

for name, pts in [
    ("Gauss-Legendre", gauss),
    ("Gauss-Lobatto", np.array([0.0, 0.5, 1.0])),
    ("equispaced interior", np.array([1 / 6, 1 / 2, 5 / 6])),
]:
    C, x, w = cumulative_matrix(edges, pts)
    CR = np.outer(np.ones_like(w), w) - C  # int_x^1 = int_0^1 - int_0^x
    defect = np.max(np.abs(np.diag(w) @ CR - C.T @ np.diag(w)))
    print(f"{name:20s}: max |W C^R - C^T W| = {defect:.1e}")

# %% 7. The mass matrix is a Gram matrix
#
# Write the tangent t = (cos theta, sin theta) and normal n = (-sin, cos).
# The velocity of the centerline is r_t(xi) = int_0^xi theta_t n, i.e.
# r_t = C(theta_t n), and the kinetic energy is (1/2) int |r_t|^2.  With
# theta_t = sum_j phi_j qdot_j this is (1/2) qdot^T M qdot with
#
#     M_ij = int_0^1 C(phi_i n) . C(phi_j n) dxi  =  B^T W B,   B = C(Phi n).
#
# A Gram matrix: symmetric, and positive definite because C is injective.
# It equals the paper's double integral (Eq. (24a)), which after one
# integration by parts reads
#
#     M_ij = int int phi_i(xi) phi_j(r) cos(theta(xi) - theta(r)) G(xi, r) dr dxi,
#     G(xi, r) = 1 - max(xi, r),
#
# dense in (i, j) -- yet every product M qdd costs O(n): two integrations.

disc = FiniteElement(8, 2)
q_state = 0.7 * np.random.default_rng(0).normal(size=disc.n)  # a large, arbitrary state
fempipe_M = PipeModel(disc, params).mass_matrix(q_state)
eig = np.linalg.eigvalsh(fempipe_M)
print(
    f"mass matrix P2:8 at a random state: symmetric to "
    f"{np.max(np.abs(fempipe_M - fempipe_M.T)):.0e}, eigenvalues in [{eig[0]:.2e}, {eig[-1]:.2e}]"
)


# The kernel form, brute force on a tensor Gauss grid.  The kink of
# max(xi, r) on the diagonal limits a tensor rule to O(h^2), so we check
# that the difference shrinks four-fold when the grid is halved: the two
# forms are the same matrix.  (The Gram form integrates cos(theta), sin(theta)
# through their interpolants at the n_g Gauss points of each cell, exact only
# for polynomials; for this wildly random state we take n_g = 12 so that this
# error is far below the brute-force one.)
disc = FiniteElement(8, 2, n_gauss=12)
fempipe_M = PipeModel(disc, params).mass_matrix(q_state)


def kernel_mass(n_cells: int) -> np.ndarray:
    edges_ = np.linspace(0.0, 1.0, n_cells + 1)
    gx, gw = np.polynomial.legendre.leggauss(4)
    xs = (edges_[:-1, None] + np.diff(edges_)[:, None] * 0.5 * (gx + 1)).ravel()
    ws = (np.diff(edges_)[:, None] * 0.5 * gw).ravel()
    phis = disc.basis.probes(xs[None, :]).toarray()[:, disc.free]  # phi_j at xs
    th = phis @ q_state
    kernel = np.cos(th[:, None] - th[None, :]) * (1.0 - np.maximum(xs[:, None], xs[None, :]))
    return (phis * ws[:, None]).T @ kernel @ (phis * ws[:, None])


d1, d2 = (np.max(np.abs(kernel_mass(n) - fempipe_M)) for n in (200, 400))
print(
    f"kernel form vs Gram form: max |difference| {d1:.1e} (200 cells), {d2:.1e} (400 cells), "
    f"ratio {d1 / d2:.1f} (O(h^2): 4)"
)

# %% 8. Convergence: the payoff of a finite-element formulation
#
# Now the question the paper does not ask: how accurate is a discretization?
# Refine the mesh, halve h each time, and watch the tip drop approach the
# BVP answer.  Theory for a 1-D second-order problem: the nodal values (and
# hence the tip values and integrals like X_g(1)) of P_k elements converge
# like h^(2k) -- superconvergence, twice the order of the L2 error of theta.
# The Gauss integration of section 5 is exact enough to keep it.  The sine
# modes, hampered by theta''(0) = 0, converge only algebraically in N.

reference = bvp.X_tip
results = {}
for degree, counts in {
    1: [2, 4, 8, 16, 32, 64, 128],
    2: [1, 2, 4, 8, 16, 32],
    3: [1, 2, 4, 8],
}.items():
    dofs, errs = [], []
    for n in counts:
        b_, u_, _ = static_fe(n, degree, alpha, gamma, v)
        dofs.append(b_.N - 1)  # minus the clamped dof
        errs.append(abs(tip_drop(b_, u_, alpha) - reference))
    results[f"P{degree} (this tutorial)"] = (np.array(dofs), np.array(errs))
modes = np.array([1, 2, 3, 4, 6, 8, 12, 16, 24, 32])
modal_err = []
for n in modes:
    mm = PipeModel(Modal(int(n)), params)
    modal_err.append(abs(tip_values(mm.disc, solve_static(mm).q, alpha)["X_tip"] - reference))
results["sine modes N (the paper's)"] = (modes, np.array(modal_err))

print("\nobserved orders (slope of log error vs log dofs over the last 3 points above 1e-11):")
for label, (d, e) in results.items():
    keep = np.flatnonzero(e > 1e-11)[-3:]
    p = -np.polyfit(np.log(d[keep]), np.log(e[keep]), 1)[0]
    results[label] = (d, e, p)
    print(f"  {label:28s} p = {p:.2f}")
print(
    f"  errors of the paper's N = 3 and N = 4: {modal_err[2]:.1e}, {modal_err[3]:.1e} "
    f"(= {modal_err[2] * pipe.L * 1e3:.2f} mm, {modal_err[3] * pipe.L * 1e3:.3f} mm)"
)

# %% 9. The same study for your own case, through the API
#
# Section 8 wrote the study by hand.  fempipe.studies.convergence does it for any
# quantity of any case -- `fempipe convergence` on the command line -- and
# forms its reference without knowing the answer: the Richardson
# extrapolation of the two finest members of each family,
# Q* = Q_f + (Q_f - Q_c) / (2^p - 1), the family with the smallest
# correction giving the reference, the others (and solve_bvp) as checks.
# Here it runs on the same pipe with a second modal basis, the slopes of the
# clamped-free *beam* modes (Paidoussis's classical Galerkin basis, in theta).
#
# Why the orders come out as they do:
#
# * P_k: the error of theta is O(h^(k+1)) in L2 and O(h^k) in the energy
#   norm; a tip value is a functional whose error is the product of two
#   energy-norm errors (of the problem and of its adjoint), O(h^(2k)), and
#   in 1-D the nodal values themselves are that accurate.
# * sine modes: every mode has phi''(0) = 0, but the solution has
#   theta''(0) = gamma sin(alpha) + v^2 sin(theta(1)) != 0 (Eq. (31a) at
#   xi = 0).  Integrating a mode's coefficient by parts three times leaves a
#   boundary term ~ theta''(0) / k_r^3, so the coefficients decay as r^-3,
#   the energy-norm error of the truncation as N^(-3/2) and a functional's
#   error as its square, N^-3.
# * beam modes: psi_r = phi_r' / lambda_r with phi'''' = lambda^4 phi, so
#   every mode has psi'''(0) = lambda_r^3 phi_r(0) = 0: the constraint comes
#   one derivative later than the sine modes'.  The solution's
#   theta'''(0) = -gamma sin(alpha) + (gamma cos(alpha) - v^2) theta'(0)
#   (Eq. (31a) differentiated once) is not zero either, so the coefficients
#   decay one power faster (r^-4) and functionals converge as N^-4: better
#   than the sine modes, still algebraic.

from fempipe.studies.convergence import Family, Quantity, run_study

study = run_study(
    Quantity("X_tip", params),
    [
        Family("fe", (4, 8, 16, 32, 64), degree=1),
        Family("fe", (2, 4, 8, 16), degree=2),
        Family("fe", (2, 4, 8, 16), degree=3),
        Family("modal", (2, 4, 8, 16, 32), basis="sine"),
        Family("modal", (2, 4, 8, 16, 32), basis="beam"),
    ],
    independent=[("solve_bvp", bvp.X_tip)],
)
print(f"\nfempipe.convergence: reference {study.reference.value:.12f}")
print(f"  formed by {study.reference.method}")
print(f"  solve_bvp differs by {abs(study.reference.value - bvp.X_tip):.1e}")
for s in study.series:
    print(
        f"  {s.family:11s} observed order {s.observed_order:.2f} in dofs "
        f"(theory {s.expected_order:g}; fitted on n = {[int(s.n[i]) for i in s.fit]})"
    )

# %% 10. The plot
#
# Expected: slopes 2, 4, 6 for P1, P2, P3 and about 3 for the sine modes.
# P3 reaches 1e-10 with about fifty unknowns; at slope 3 the sine modes
# would need about four hundred modes for that.  Everything above rests on
# one weak form and two integration operators; fempipe adds the dynamic
# terms, stability and time integration on the same pieces.  `fempipe validate` repeats this study for
# the critical velocities and limit cycles and compares every figure of the
# paper.

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).parent), help="directory for the PNG")
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.validation.convergence import SERIES_COLORS

    fig, ax = plt.subplots(figsize=(5.5, 4.2), layout="constrained")
    colors = list(SERIES_COLORS.values())
    for (label, (d, e, p)), style, c in zip(
        results.items(), ["o-", "s-", "^-", "d--"], colors, strict=True
    ):
        ax.loglog(d, e, style, color=c, ms=4, label=f"{label}: slope {p:.2f}")
    ax.set_xlabel("unknowns (degrees of freedom)")
    ax.set_ylabel(r"|error of tip drop $X_g(1)$| (units of $L$)")
    ax.set_title("Texier-Dorbolo pipe, U = 2 m/s: convergence", fontsize=10)
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=9)
    out = Path(args.out) / "tutorial_convergence.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=120)
    print(f"\nwrote {out} ({time.perf_counter() - T_START:.1f} s)")

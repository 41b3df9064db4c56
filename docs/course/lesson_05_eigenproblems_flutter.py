"""
Lesson 5: generalized eigenproblems and flutter
===============================================

What you should see: the linearization of Eq. (20) about a static state,
M q'' + C q' + K q = 0 (Eqs. (31b)-(33)); its first-order form, a generalized eigenproblem
A z = lambda B z; the Euler-Bernoulli cantilever's frequencies recovered with the order
2k of P_k elements; and, with flow, a non-symmetric K (the follower force) and a gyroscopic
C (Coriolis) that let a pair of eigenvalues cross into the right half plane: flutter.
"""

# %%
# 1. The linear problem and its first-order form
# ----------------------------------------------
# ``PipeModel.linearization(q)`` returns K, C, M at the static state q.  With z = (q, q')
#
# .. math::
#
#    \begin{pmatrix} 0 & I \\ -K & -C \end{pmatrix} z = \lambda
#    \begin{pmatrix} I & 0 \\ 0 & M \end{pmatrix} z ,
#
# a generalized eigenproblem solved without inverting M.  Without gravity and flow the pipe
# is an Euler-Bernoulli cantilever: lambda = +-i omega_r, omega_r = (beta_r L)^2 with
# 1 + cos(beta L) cosh(beta L) = 0, beta_1 L = 1.87510407.
import matplotlib.pyplot as plt
import numpy as np
import scipy.linalg as sla
from scipy.optimize import brentq

import fempipe


def eigenvalues(model: fempipe.PipeModel, q: np.ndarray | None = None) -> np.ndarray:
    """All eigenvalues of the pencil (finite: B is invertible)."""
    n = model.disc.n
    q = np.zeros(n) if q is None else q
    K, C, M = model.linearization(q)
    A = np.block([[np.zeros((n, n)), np.eye(n)], [-K, -C]])
    B = np.block([[np.eye(n), np.zeros((n, n))], [np.zeros((n, n)), M]])
    return sla.eig(A, B, right=False)


def oscillating(lam: np.ndarray) -> np.ndarray:
    """The eigenvalues with Im > 0 by increasing frequency (one of each conjugate pair)."""
    up = lam[lam.imag > 0]
    return up[np.argsort(up.imag)]


beta1 = brentq(lambda x: 1 + np.cos(x) * np.cosh(x), 1.0, 3.0, xtol=1e-15)
cantilever = fempipe.Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0, v=0.0)
sizes = np.array([2, 4, 8, 16])
omega_errors = []
for n in sizes:
    lam = oscillating(eigenvalues(fempipe.PipeModel(fempipe.FiniteElement(int(n), 2), cantilever)))
    omega_errors.append(abs(lam[0].imag - beta1**2))
    print(f"P2:{n:2d}: omega_1 = {lam[0].imag:.10f}, error {omega_errors[-1]:.1e}")
eigen_order = np.log2(omega_errors[-2] / omega_errors[-1])
print(f"(beta_1 L)^2 = {beta1**2:.10f}; observed order of P2 {eigen_order:.2f} (theory 2k = 4)")

# %%
# 2. Flow: non-symmetric stiffness, gyroscopic damping
# ----------------------------------------------------
# The follower force v^2 sin(theta(1) - theta) gives K a dense, non-symmetric tip column;
# the Coriolis term gives C_ij = 2 v sqrt(beta) \int phi_i \int_xi^1 phi_j on the straight
# pipe (Eq. (33b)): a skew (gyroscopic) part, and the symmetric part v sqrt(beta) b b^T,
# b_i = \int phi_i, the momentum the fluid carries out at the tip.  The eigenvalues are no
# longer on the imaginary axis; as v grows the second mode's pair crosses it: a Hopf
# (flutter) instability.  We locate it by bisection on the largest real part, then compare
# with :func:`fempipe.critical_velocity` (events tracked along the static branch).
flowing = fempipe.Params(alpha=0.0, beta=0.2, gamma=0.0, mu=1e-3)
disc = fempipe.FiniteElement(8, 3)


def growth(v: float) -> float:
    """The largest Re lambda at flow v (straight pipe: q = 0); the Kelvin-Voigt damping
    makes the high modes real and strongly negative."""
    return float(np.max(eigenvalues(fempipe.PipeModel(disc, flowing.with_flow(v))).real))


K, C, _ = fempipe.PipeModel(disc, flowing.with_flow(4.0)).linearization(np.zeros(disc.n))
print(
    f"at v = 4: max |K - K^T| = {np.max(np.abs(K - K.T)):.2f}, max |C - C^T| = "
    f"{np.max(np.abs(C - C.T)):.2f}"
)
v_bisect = brentq(growth, 4.0, 7.0, xtol=1e-10)
v_fempipe = fempipe.critical_velocity(fempipe.PipeModel(disc, flowing), v_max=8.0).v_cr
print(f"flutter: bisection v_cr = {v_bisect:.8f}, fempipe.critical_velocity {v_fempipe:.8f}")

# The eigenvalues for v = 0 ... 7, as dots coloured by v (no tracking: sorting by
# frequency would mix the modes where one becomes overdamped; fempipe's
# :func:`fempipe.root_locus` tracks them by their eigenvectors).
vs = np.linspace(0.0, 7.0, 36)
pts = []
for v in vs:
    lam = eigenvalues(fempipe.PipeModel(disc, flowing.with_flow(v)))
    lam = lam[(np.abs(lam) < 80) & (lam.imag >= 0)]
    pts += [(v, z) for z in lam]
fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
sc = ax.scatter([z.real for _, z in pts], [z.imag for _, z in pts], c=[v for v, _ in pts], s=6)
fig.colorbar(sc, ax=ax, label="v")
ax.axvline(0, color="k", lw=0.6)
ax.set_xlabel("Re lambda")
ax.set_ylabel("Im lambda")
ax.set_title(f"beta = 0.2, gamma = 0, mu = 1e-3, v = 0..7, P3:8: v_cr = {v_bisect:.4f}", fontsize=9)

# %%
# Exercises
# ---------
# 1. Show that with v = 0 and mu = 0 the pencil's eigenvalues are purely imaginary (K and M
#    symmetric, K positive definite).  Which term breaks this for v > 0?
# 2. Hang the pipe (gamma = 18.9, alpha = 0): how does gravity change omega_1 and v_cr?
# 3. Replace the bisection by a secant method on the real part of the tracked eigenvalue.
#    Why is tracking by eigenvectors safer than sorting by frequency?

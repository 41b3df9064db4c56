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
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save
from fempipe.validation.classical import StraightPipe
from fempipe.validation.classical import critical_velocity as classical_critical_velocity


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
# with :func:`fempipe.find_critical_velocity` (events tracked along the static branch: the same
# discretization, another algorithm) and with the classical linear theory of the straight
# pipe (Paidoussis' equation for the lateral displacement, solved on Legendre spectral
# elements in ``fempipe.validation.classical``): an independent reference that shares no
# code with the finite elements.
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
v_fempipe = fempipe.find_critical_velocity(fempipe.PipeModel(disc, flowing), v_max=8.0).v_cr
classical = classical_critical_velocity(
    StraightPipe(beta=0.2, gamma=0.0, mu=1e-3), v_max=8.0, method="legendre"
)
v_classical = classical.v_cr
print(f"flutter: bisection v_cr = {v_bisect:.8f}, fempipe.find_critical_velocity {v_fempipe:.8f}")
print(f"         classical theory {v_classical:.8f}: P3:8 differs by {v_bisect - v_classical:.1e}")

# The eigenvalues for v = 0 to 7, as dots coloured by v (no tracking: sorting by
# frequency would mix the modes where one becomes overdamped; fempipe's
# :func:`fempipe.trace_root_locus` tracks them by their eigenvectors).
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
ax.set_title(
    f"beta = 0.2, gamma = 0, mu = 1e-3, v = 0 to 7, P3:8: v_cr = {v_bisect:.4f}", fontsize=9
)
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("5.k", answer)`` compares an answer with a reference computed independently (a
# closed form, the classical straight-pipe theory).  Each solution runs in this lesson.
#
# 1. With v = 0 and mu = 0 the eigenvalues are purely imaginary (K, M symmetric, K
#    positive definite).  Kelvin-Voigt damping (mu = 1e-3, gamma = 0, v = 0) makes C = mu K:
#    show that lambda = -mu omega^2 / 2 +- i omega (1 - mu^2 omega^2 / 4)^(1/2) and compute
#    Re lambda_1 on P3:8.  Which terms break the symmetry for v > 0?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    On an eigenvector of K x = omega^2 M x the equation becomes
#    lambda^2 + mu omega^2 lambda + omega^2 = 0.  For v > 0 the follower force makes K
#    non-symmetric and the Coriolis term adds C.  Expected: ``answer`` = -0.0061812
#    (-mu (beta_1 L)^4 / 2 = -0.00618118).
#
#    .. code-block:: python
#
#       damped = fempipe.Params(alpha=0.0, beta=0.2, gamma=0.0, mu=1e-3, v=0.0)
#       answer = oscillating(eigenvalues(fempipe.PipeModel(disc, damped)))[0].real
#       print(f"Re lambda_1 = {answer:.9f}")
#       check("5.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Hang the pipe (gamma = 18.9, alpha = 0; beta = 0.2, mu = 1e-3): find v_cr by
#    bisection as in section 2.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Gravity puts the hanging pipe in tension, which stiffens it: v_cr rises from 5.64 to
#    7.11.  Expected: ``answer`` = 7.10614 (classical theory: 7.106154).
#
#    .. code-block:: python
#
#       hanging = fempipe.Params(alpha=0.0, beta=0.2, gamma=18.9, mu=1e-3)
#
#       def growth_hanging(v):
#           return np.max(eigenvalues(fempipe.PipeModel(disc, hanging.with_flow(v))).real)
#
#       answer = brentq(growth_hanging, 6.0, 8.0, xtol=1e-10)
#       print(f"hanging pipe: v_cr = {answer:.6f}")
#       check("5.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. At what frequency does the pipe of section 2 flutter?  Compare with the cantilever's
#    first two frequencies.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    The crossing pair's Im lambda at v_cr.  Expected: ``answer`` = 13.6002, between
#    omega_1 = 3.52 and omega_2 = 22.03 of the cantilever: the flow has coupled the modes.
#
#    .. code-block:: python
#
#       lam_cr = eigenvalues(fempipe.PipeModel(disc, flowing.with_flow(v_bisect)))
#       answer = abs(lam_cr[np.argmax(lam_cr.real)].imag)
#       print(f"flutter frequency {answer:.5f}")
#       check("5.3", answer)
#
#    .. raw:: html
#
#       </details>

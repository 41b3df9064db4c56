"""
Lesson 7: modal against finite-element truncation, and why the orders differ
============================================================================

What you should see: on one static problem, the tip error of P1, P2, P3 elements falling as
h^2, h^4, h^6 (twice the L2 order of lesson 2: superconvergence of the tip values), that of
the paper's sine modes as N^-3 and that of the clamped-free beam modes as N^-4; the reasons,
in a few lines each; and fempipe's convergence study doing the same for any quantity
without knowing the answer.  ``validation/tutorial.py`` runs this lesson and saves its plot.
"""

# %%
# 1. A study by hand
# ------------------
# The Texier-Dorbolo pipe at U = 2 m/s (lessons 1 and 2); the reference is scipy's
# ``solve_bvp`` on the strong form, to 1e-11.
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.studies.convergence import Family
from fempipe.validation.bvp import solve_static_bvp

pipe = fempipe.PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2)
params = pipe.params(U=2.0)
alpha = params.alpha
reference = solve_static_bvp(alpha, params.gamma, params.v, tol=1e-11).X_tip


def x_tip(disc: object) -> float:
    """X_g(1) of the static state on one discretization."""
    model = fempipe.PipeModel(disc, params)
    return fempipe.tip_values(disc, fempipe.solve_static(model).q, alpha)["X_tip"]


results = {}
for degree, counts in {
    1: [2, 4, 8, 16, 32, 64, 128],
    2: [1, 2, 4, 8, 16, 32],
    3: [1, 2, 4, 8],
}.items():
    discs = [fempipe.FiniteElement(n, degree) for n in counts]
    results[f"P{degree}"] = (
        np.array([d.n for d in discs]),
        np.array([abs(x_tip(d) - reference) for d in discs]),
    )
modes = np.array([1, 2, 3, 4, 6, 8, 12, 16, 24, 32])
results["sine modes N (the paper's)"] = (
    modes,
    np.array([abs(x_tip(fempipe.Modal(int(n))) - reference) for n in modes]),
)

print("observed orders (slope of log error vs log dofs over the last 3 points above 1e-11):")
hand_orders = {}
for label, (d, e) in results.items():
    keep = np.flatnonzero(e > 1e-11)[-3:]
    p = -np.polyfit(np.log(d[keep]), np.log(e[keep]), 1)[0]
    hand_orders[label] = p
    print(f"  {label:28s} p = {p:.2f}")
n3, n4 = results["sine modes N (the paper's)"][1][2:4]
print(
    f"  errors of the paper's N = 3 and N = 4: {n3:.1e}, {n4:.1e} "
    f"(= {n3 * pipe.L * 1e3:.2f} mm, {n4 * pipe.L * 1e3:.3f} mm)"
)

fig, ax = plt.subplots(figsize=(5.5, 4.2), layout="constrained")
for (label, (d, e)), style in zip(results.items(), ["o-", "s-", "^-", "d--"], strict=True):
    ax.loglog(d, e, style, ms=4, label=f"{label}: slope {hand_orders[label]:.2f}")
ax.set_xlabel("unknowns (degrees of freedom)")
ax.set_ylabel(r"|error of tip drop $X_g(1)$| (units of $L$)")
ax.set_title("Texier-Dorbolo pipe, U = 2 m/s: convergence", fontsize=10)
ax.grid(alpha=0.3, which="both")
ax.legend(fontsize=9)

# %%
# 2. Why the orders come out as they do
# -------------------------------------
# * P_k: the error of theta is O(h^(k+1)) in L2 and O(h^k) in the energy norm (lesson 2).
#   A tip value is a functional whose error is the product of two energy-norm errors (of
#   the problem and of its adjoint): O(h^(2k)); in 1-D the nodal values are that accurate.
#   The Gauss rules of lesson 3 are exact enough to keep it.
# * Sine modes: every mode has phi''(0) = 0, but the solution has
#   theta''(0) = gamma sin(alpha) + v^2 sin(theta(1)) != 0 (Eq. (31a) at xi = 0).
#   Integrating a coefficient by parts three times leaves a boundary term ~ theta''(0) / k_r^3,
#   so the coefficients decay as r^-3, the energy-norm error of the truncation as N^(-3/2)
#   and a functional's error as its square, N^-3 (lesson 1's linear problem showed it).
# * Beam modes: psi_r = phi_r' / lambda_r with phi'''' = lambda^4 phi, so every mode has
#   psi'''(0) = lambda_r^3 phi_r(0) = 0: the constraint comes one derivative later.  The
#   solution's theta'''(0) = -gamma sin(alpha) + (gamma cos(alpha) - v^2) theta'(0) is not
#   zero either: the coefficients decay as r^-4 and functionals converge as N^-4.
#
# P3 reaches 1e-10 with about fifty unknowns; at slope 3 the sine modes would need about
# four hundred.
#
# 3. The same study through the API
# ---------------------------------
# :func:`fempipe.run_study` (``fempipe convergence``) forms the reference without knowing the
# answer: the Richardson extrapolation of the two finest members of each family,
# Q* = Q_f + (Q_f - Q_c) / (2^p - 1), the family with the smallest correction giving it, the
# others (and ``solve_bvp``, given as an independent value) as checks.
study = fempipe.run_study(
    fempipe.Quantity("X_tip", params),
    [
        Family("fe", (4, 8, 16, 32, 64), degree=1),
        Family("fe", (2, 4, 8, 16), degree=2),
        Family("fe", (2, 4, 8, 16), degree=3),
        Family("modal", (2, 4, 8, 16, 32), basis="sine"),
        Family("modal", (2, 4, 8, 16, 32), basis="beam"),
    ],
    independent=[("solve_bvp", reference)],
)
print(f"\nfempipe.run_study: reference {study.reference.value:.12f}")
print(f"  formed by {study.reference.method}")
print(f"  solve_bvp differs by {abs(study.reference.value - reference):.1e}")
api_orders = {}
for s in study.series:
    api_orders[s.family] = s.observed_order
    print(
        f"  {s.family:11s} observed order {s.observed_order:.2f} in dofs "
        f"(theory {s.expected_order:g}; fitted on n = {[int(s.n[i]) for i in s.fit]})"
    )

# %%
# Exercises
# ---------
# 1. Repeat the study for the critical velocity (``Quantity("v_cr", ...)``): do the orders
#    of eigenvalues match those of the tip values?
# 2. Put an end mass (README, "Variants of the pipe") on the pipe: which basis loses an order,
#    and why (hint: theta''(1))?
# 3. Use ``fempipe.richardson`` on the P2 family by hand and compare with the study's
#    reference.

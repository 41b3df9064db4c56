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
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save
from fempipe.studies.convergence import Family
from fempipe.validation.bvp import solve_static_bvp

pipe = fempipe.PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2)
params = pipe.params(U=2.0)
alpha = params.alpha
reference = solve_static_bvp(alpha, params.gamma, params.v, tol=1e-11).X_tip


def x_tip(disc: object) -> float:
    """X_g(1) of the static state on one discretization."""
    model = fempipe.PipeModel(disc, params)
    return fempipe.compute_tip(disc, fempipe.solve_static(model).q, alpha)["X_tip"]


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
show_or_save()  # run as a script: a window, or PNG files without a display

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
# ``check("7.k", answer)`` compares an answer with a reference computed independently
# (scipy's ``solve_bvp``, the theoretical order).  Each solution runs in this lesson.
#
# 1. Repeat the study by hand for the critical velocity of the hanging pipe
#    (``fempipe.Params(alpha=0.0)``) with P2 on 4, 8, 16 cells, against the classical
#    straight-pipe theory (``fempipe.validation.classical``).  What order do the eigenvalues
#    converge with?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Like the tip values, 2k: an eigenvalue's error is, as a functional's, the product of
#    the errors of the eigenvector and of its adjoint.  Expected: ``answer`` = 3.97 (from
#    8 to 16 cells; theory 4).
#
#    .. code-block:: python
#
#       from fempipe.validation.classical import StraightPipe, critical_velocity
#
#       straight = StraightPipe(beta=0.142, gamma=18.9, mu=5e-3)
#       v_ref = critical_velocity(straight, v_max=15.0, method="legendre").v_cr
#       hang = fempipe.Params(alpha=0.0)
#       models = [fempipe.PipeModel(fempipe.FiniteElement(n, 2), hang) for n in (4, 8, 16)]
#       v_n = [fempipe.find_critical_velocity(m, v_max=15.0).v_cr for m in models]
#       err = np.abs(np.array(v_n) - v_ref)
#       answer = np.log2(err[-2] / err[-1])
#       print(f"v_cr errors {err}, order {answer:.2f}")
#       check("7.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Put an end mass Gamma = 0.5 (:doc:`Variants of the pipe </theory/variants>`) on the
#    pipe of section 1.  Compute X_g(1) on P3:8, and the orders of 16 to 32 sine and beam
#    modes against ``solve_static_bvp`` with ``end_mass=0.5``.  Which basis loses accuracy,
#    and why (hint: theta''(1))?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    The strong form at xi = 1 now gives theta''(1) = gamma Gamma sin(theta(1) + alpha),
#    no longer 0.  Every beam mode has psi_r''(1) = 0 (the beam's free end carries no
#    shear force) and cannot follow it: the beam modes drop from N^-4 to N^-2 (measured).
#    The sine modes constrain nothing at the tip beyond theta'(1) = 0 and keep N^-3.
#    Expected: ``answer`` = 0.704968 (solve_bvp: 0.7049678), ``sine_order`` = 2.99 and
#    ``beam_order`` = 2.00.
#
#    .. code-block:: python
#
#       import dataclasses
#
#       heavy = dataclasses.replace(params, end_mass=0.5)
#       ref_heavy = solve_static_bvp(alpha, heavy.gamma, heavy.v, tol=1e-10, end_mass=0.5).X_tip
#
#       def x_heavy(disc):
#           q_heavy = fempipe.solve_static(fempipe.PipeModel(disc, heavy)).q
#           return fempipe.compute_tip(disc, q_heavy, alpha)["X_tip"]
#
#       e_sine, e_beam = (
#           [abs(x_heavy(fempipe.Modal(n, basis=b)) - ref_heavy) for n in (16, 32)]
#           for b in ("sine", "beam")
#       )
#       sine_order, beam_order = np.log2(e_sine[0] / e_sine[1]), np.log2(e_beam[0] / e_beam[1])
#       answer = x_heavy(fempipe.FiniteElement(8, 3))
#       print(f"X_g(1) = {answer:.8f}; orders: sine {sine_order:.2f}, beam {beam_order:.2f}")
#       check("7.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. Extrapolate by hand (``fempipe.extrapolate_richardson``) from P2:8 and P2:16 with the order 4 and
#    compare with the reference of section 1.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    Q* = Q_16 + (Q_16 - Q_8) / (2^4 - 1) removes the leading error term: P2:16 alone is
#    off by 3.6e-7, the extrapolation by 3.4e-9.  Expected: ``answer`` = 0.527282495
#    (solve_bvp: 0.5272824985).
#
#    .. code-block:: python
#
#       x_8, x_16 = (x_tip(fempipe.FiniteElement(n, 2)) for n in (8, 16))
#       answer = float(np.real(fempipe.extrapolate_richardson(x_8, x_16, 4.0)[0]))
#       print(f"Richardson: {answer:.10f}, off by {answer - reference:.1e}")
#       check("7.3", answer)
#
#    .. raw:: html
#
#       </details>

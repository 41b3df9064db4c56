"""
Lesson 4: Newton's method and continuation
==========================================

What you should see: Newton's method on the discrete static problem R(q) = 0 doubling its
correct digits at each step; natural-parameter continuation (the previous solution as the
next guess) stopping at a fold, where the Jacobian is singular; pseudo-arclength continuation
(Keller) turning round the fold and detecting the pitchfork of the standing pipe, which
appears at Greenhill's heavy-column load.
"""

# %%
# 1. Newton by hand
# -----------------
# R(q) is the weak form (W) of lesson 1 on a discretization; ``static_residual`` and
# ``static_jacobian`` are its residual and analytic Jacobian.  Each step solves
# J(q_k) dq = -R(q_k).  Near the solution the error squares at each step (quadratic
# convergence): :math:`e_{k+1} / e_k^2` tends to a constant C.
import matplotlib.pyplot as plt
import numpy as np
from scipy.optimize import brentq
from scipy.special import jv

import fempipe
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save

model = fempipe.PipeModel(fempipe.FiniteElement(8, 3), fempipe.Params(alpha=np.pi / 2, v=3.0))
exact = fempipe.solve_static(model, tol=1e-14).q
q = np.zeros(model.disc.n)
errors = []
for k in range(8):
    errors.append(np.max(np.abs(q - exact)))
    residual = np.linalg.norm(model.static_residual(q))
    print(f"step {k}: |q - q*| = {errors[-1]:.2e}, |R| = {residual:.2e}")
    if errors[-1] < 1e-13:
        break
    q = q + np.linalg.solve(model.static_jacobian(q, dense=True), -model.static_residual(q))
e = np.array(errors)
ok = np.flatnonzero(e[1:] > 1e-12)  # steps not yet at round-off
newton_constants = e[1:][ok] / e[:-1][ok] ** 2
print("e_(k+1) / e_k^2:", ", ".join(f"{c:.3f}" for c in newton_constants))

# %%
# 2. The standing pipe: a pitchfork
# ---------------------------------
# Standing up (alpha = pi) and without flow, the straight pipe q = 0 solves R = 0 for every
# gamma.  It buckles under its own weight at Greenhill's load, the first zero of
# :math:`J_{-1/3}(\tfrac23 \sqrt\gamma)`: gamma = 7.8373.  There the Jacobian is singular and two
# mirror-image branches cross the straight one: a pitchfork.  Pseudo-arclength continuation
# solves R(q, gamma) = 0 together with a step along the tangent, (q - q_0, gamma - gamma_0)
# . t_0 = ds, whose Jacobian stays regular at folds; a change of sign of det J marks a
# bifurcation, which :func:`fempipe.continue_static` locates.
disc = fempipe.FiniteElement(8, 3)
standing = fempipe.PipeModel(disc, fempipe.Params(alpha=np.pi, gamma=0.0, v=0.0))
straight = fempipe.continue_static(standing, "gamma", stop=12.0, ds=0.5, ds_max=1.0)
pitchfork = straight.special[0]
# the independent reference: Greenhill's closed form, the first zero of J_(-1/3)
greenhill = brentq(lambda s: jv(-1.0 / 3.0, 2.0 / 3.0 * np.sqrt(s)), 5.0, 10.0, xtol=1e-14)
print(f"{pitchfork.kind} at gamma = {pitchfork.value:.8f}; Greenhill {greenhill:.8f}")
print(f"P3:8 against the closed form: {pitchfork.value - greenhill:.1e}")
right, left = fempipe.switch_branch(standing, pitchfork, "gamma", stop=12.0, ds=0.2)

# %%
# 3. A fold, and why natural continuation stops there
# ---------------------------------------------------
# Tilt the buckled pipe (gamma = 12) against its lean: continue in alpha.  The branch turns
# back at a fold, where dR/dq is singular but the extended (arclength) system is not.
tilted = fempipe.PipeModel(disc, fempipe.Params(alpha=np.pi, gamma=12.0, v=0.0))
# Which of the two branches leans which way depends on the sign of a null vector (round-off
# decides it): take the one leaning to negative theta(1), so that alpha grows against it.
lean = fempipe.compute_tip(disc, right.points[-1].q, np.pi)["theta_tip"]
leaning = left if lean > 0 else right
arc = fempipe.continue_static(
    tilted, "alpha", stop=np.pi + 0.8, q0=leaning.points[-1].q, ds=0.05, ds_max=0.1, direction=1
)
fold = next(s for s in arc.special if s.kind == "fold")
J_fold = tilted.with_params(fempipe.Params(alpha=fold.value, gamma=12.0, v=0.0))
sv = np.linalg.svd(J_fold.static_jacobian(fold.q, dense=True), compute_uv=False)
fold_singularity = sv[-1] / sv[0]
print(f"fold at alpha = {fold.value:.8f}; sigma_min / sigma_max of dR/dq: {fold_singularity:.1e}")
fold_tip = fempipe.compute_tip(disc, fold.q, fold.value)["theta_tip"]
print(f"theta(1) at the fold: {fold_tip:.4f}")
natural_failed, reached = False, np.pi
try:  # natural-parameter continuation: step alpha past the fold from the same branch
    q_prev = leaning.points[-1].q
    for a in np.linspace(np.pi, fold.value + 0.05, 25):
        q_prev = fempipe.solve_static(
            tilted.with_params(fempipe.Params(alpha=a, gamma=12.0, v=0.0)), q0=q_prev
        ).q
        reached = a
    jumped = fempipe.compute_tip(disc, q_prev, a)["theta_tip"]
    print(f"natural continuation past the fold landed on theta(1) = {jumped:.4f}: another branch")
except fempipe.NewtonError as exc:
    natural_failed = True
    print(f"natural continuation failed past the fold (last solved alpha = {reached:.5f}): {exc}")

fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
th = [fempipe.compute_tip(disc, p.q, p.value)["theta_tip"] for p in arc.points]
ax.plot([p.value for p in arc.points], th, "-")
ax.plot(fold.value, fempipe.compute_tip(disc, fold.q, fold.value)["theta_tip"], "ko")
ax.set_xlabel("alpha")
ax.set_ylabel("theta(1)")
ax.set_title(f"gamma = 12, v = 0, P3:8: fold at alpha = {fold.value:.4f}", fontsize=9)
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("4.k", answer)`` compares an answer with a reference computed independently (a
# closed form, scipy's ``solve_bvp``, linear algebra).  Each solution runs in this lesson.
#
# 1. Freeze the Jacobian at q_0 = 0 (the chord method) for alpha = pi/2, gamma = 5, v = 2
#    on P3:8.  What order do you observe, and what ratio :math:`e_{k+1} / e_k`?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    The error of the chord step is :math:`e_{k+1} = (I - J_0^{-1} J(q^*)) e_k + O(e_k^2)`:
#    linear convergence (order 1), the ratio tending to the spectral radius of
#    :math:`I - J_0^{-1} J(q^*)`.
#    Expected: ``answer`` = 0.2045 (the spectral radius: 0.20445), reaching 1e-12 in
#    ``steps`` = 17 steps.
#
#    .. code-block:: python
#
#       chord = fempipe.PipeModel(disc, fempipe.Params(alpha=np.pi / 2, gamma=5.0, v=2.0))
#       q_star = fempipe.solve_static(chord, tol=1e-14).q
#       J_0 = chord.static_jacobian(np.zeros(disc.n), dense=True)
#       q_c, e_c = np.zeros(disc.n), [np.max(np.abs(q_star))]
#       while e_c[-1] > 1e-12:
#           q_c = q_c - np.linalg.solve(J_0, chord.static_residual(q_c))
#           e_c.append(np.max(np.abs(q_c - q_star)))
#       steps, answer = len(e_c) - 1, (e_c[-1] / e_c[-6]) ** (1 / 5)
#       print(f"chord method: {steps} steps, e_(k+1) / e_k -> {answer:.4f}")
#       check("4.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Continue the straight standing pipe of section 2 to gamma = 60: where does it buckle
#    a second time?
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    At the second zero of :math:`J_{-1/3}(\tfrac23 \sqrt\gamma)`, 55.97703: a second
#    pitchfork, whose mode (one more inflexion) P3:8 resolves less well than the first.
#    Expected: ``answer`` = 55.9772.
#
#    .. code-block:: python
#
#       tall = fempipe.continue_static(standing, "gamma", stop=60.0, ds=1.0, ds_max=2.0)
#       answer = tall.special[1].value
#       print(f"bifurcations at gamma = {[round(s.value, 5) for s in tall.special]}")
#       check("4.2", answer)
#
#    .. raw:: html
#
#       </details>
#
# 3. Tilt the standing pipe by 0.05 rad (alpha = pi + 0.05) and continue in gamma from 0 to
#    12.  Does the pitchfork survive?  Report theta(1) at gamma = 12.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    No: the imperfection unfolds it; the pipe leans from the start and the branch has no
#    singular point.  Expected: ``answer`` = 1.84559 (solve_bvp: 1.845593) with
#    ``n_special`` = 0 special points.
#
#    .. code-block:: python
#
#       imperfect = fempipe.PipeModel(disc, fempipe.Params(alpha=np.pi + 0.05, gamma=0.0, v=0.0))
#       path = fempipe.continue_static(imperfect, "gamma", stop=12.0, ds=0.5, ds_max=1.0)
#       n_special = len(path.special)
#       answer = fempipe.compute_tip(disc, path.points[-1].q, np.pi + 0.05)["theta_tip"]
#       print(f"gamma = 12: theta(1) = {answer:.6f}, {n_special} special points")
#       check("4.3", answer)
#
#    .. raw:: html
#
#       </details>

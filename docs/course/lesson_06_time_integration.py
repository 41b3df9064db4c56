"""
Lesson 6: implicit time integration
===================================

What you should see: why the semi-discrete pipe is stiff (its fastest rates grow like h^-2
for the bending frequencies and like mu h^-4 for the Kelvin-Voigt damping); why an L-stable
implicit method (Radau IIA with three stages) takes steps set by the physics, not by the
mesh; its order 2s - 1 = 5 measured with fixed steps; and its energy error in a
conservative motion (v = 0, mu = 0), which shrinks with the tolerance.
"""

# %%
# 1. Stiffness
# ------------
# The eigenvalues of the linearized pipe (lesson 5) on finer meshes: the frequencies of the
# highest modes grow like h^-2, and Kelvin-Voigt damping turns them into real rates
# -mu omega^2, growing like h^-4.  An explicit method needs steps below
# :math:`1/|\lambda_{max}|`.
import matplotlib.pyplot as plt
import numpy as np
import scipy.linalg as sla

import fempipe

hanging = fempipe.Params(alpha=0.0)  # beta = 0.142, gamma = 18.9, mu = 5e-3
fastest = []
for n in (4, 8, 16):
    model = fempipe.PipeModel(fempipe.FiniteElement(n, 2), hanging)
    K, C, M = model.linearization(np.zeros(model.disc.n))
    k = model.disc.n
    A = np.block([[np.zeros((k, k)), np.eye(k)], [-K, -C]])
    B = np.block([[np.eye(k), np.zeros((k, k))], [np.zeros((k, k)), M]])
    fastest.append(np.max(np.abs(sla.eig(A, B, right=False))))
    print(f"P2:{n:2d}: max |lambda| = {fastest[-1]:.3e}")
stiffness_growth = np.log2(fastest[-1] / fastest[-2])
print(f"growth per halving of h: 2^{stiffness_growth:.2f} (Kelvin-Voigt: h^-4)")

# %%
# 2. Radau IIA and L-stability
# ----------------------------
# The 3-stage Radau IIA collocation method is implicit, of order 5 and L-stable: its
# stability function R(z) tends to 0 as z -> -infinity, so the stiff components are damped
# in one step instead of resolved.  fempipe writes its stage equations directly on the
# second-order system M(q) q'' + ... = 0 (``fempipe.solvers.radau``) and controls the error
# as Hairer and Wanner's RADAU5.  The steps needed for the same physical motion barely
# change with the mesh:
for n in (4, 8, 16):
    model = fempipe.PipeModel(fempipe.FiniteElement(n, 2), hanging.with_flow(10.0))
    q_s = fempipe.solve_static(model).q
    q0, qd0 = fempipe.initial_state(model, mode=1, amplitude=0.01, q_static=q_s)
    traj = fempipe.simulate(model, q0, qd0, 0.5, rtol=1e-6)
    print(f"P2:{n:2d}, v = 10, tau in [0, 0.5]: {traj.steps} steps")

# %%
# 3. The order, with fixed steps
# ------------------------------
# A large swing (0.5 rad in the first mode) of the hanging pipe without flow or damping, on
# three sine modes, integrated to tau = 1 with fixed steps h, h/2, ...: the differences of
# successive end states fall as h^5.
conservative = fempipe.PipeModel(fempipe.Modal(3), fempipe.Params(alpha=0.0, mu=0.0, v=0.0))
q0, qd0 = fempipe.initial_state(conservative, mode=1, amplitude=0.5)
steps = (0.02, 0.01, 0.005, 0.0025)
ends = [fempipe.simulate(conservative, q0, qd0, 1.0, h_fixed=h).q[-1] for h in steps]
diffs = np.array([np.max(np.abs(a - b)) for a, b in zip(ends[:-1], ends[1:], strict=True)])
radau_orders = np.log2(diffs[:-1] / diffs[1:])
print("successive differences:", ", ".join(f"{d:.2e}" for d in diffs))
print("observed orders:", ", ".join(f"{p:.2f}" for p in radau_orders), "(theory 2s - 1 = 5)")

# %%
# 4. Energy
# ---------
# For v = 0, mu = 0 the energy E = T + V is conserved (README, "Variants of the pipe").
# Radau IIA is not symplectic: it does not conserve E exactly, but its error follows the
# tolerance.
drifts = {}
fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
for rtol in (1e-4, 1e-6):
    traj = fempipe.simulate(conservative, q0, qd0, 2.0, rtol=rtol)
    E = np.array([conservative.energy(q, qd) for q, qd in zip(traj.q, traj.qdot, strict=True)])
    drifts[rtol] = np.max(np.abs(E - E[0])) / abs(E[0])
    print(f"rtol {rtol:.0e}: {traj.steps} steps, max |E - E(0)| / E(0) = {drifts[rtol]:.1e}")
    ax.semilogy(traj.t[1:], np.abs(E[1:] - E[0]) / abs(E[0]) + 1e-17, label=f"rtol {rtol:.0e}")
ax.set_xlabel("tau")
ax.set_ylabel("|E - E(0)| / E(0)")
ax.set_title("alpha = 0, gamma = 18.9, v = 0, mu = 0; 3 sine modes, 0.5 rad swing", fontsize=9)
ax.legend(fontsize=8)

# %%
# Exercises
# ---------
# 1. Integrate the conservative swing with the trapezoidal rule (A-stable, not L-stable) on
#    P2:16 with mu = 5e-3.  What happens to the highest modes?
# 2. Why is the order of the stage values (3) lower than that of the step (5), and when does
#    it matter (hint: dense output, events)?
# 3. Add flow (v = 3): the energy now changes by the work of the jet; check the power
#    balance with :func:`fempipe.analyses.dynamics.power_terms`.

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
from fempipe.course import check  # noqa: F401 (the exercises' solutions use it)
from fempipe.plotting.scripts import show_or_save

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
# second-order system M(q) q'' = f(q, q') (``fempipe.solvers.radau``) and controls the error
# as Hairer and Wanner's RADAU5.  The steps needed for the same physical motion barely
# change with the mesh:
for n in (4, 8, 16):
    model = fempipe.PipeModel(fempipe.FiniteElement(n, 2), hanging.with_flow(10.0))
    q_s = fempipe.solve_static(model).q
    q0, qd0 = fempipe.make_initial_state(model, mode=1, amplitude=0.01, q_static=q_s)
    traj = fempipe.simulate(model, q0, qd0, 0.5, rtol=1e-6)
    print(f"P2:{n:2d}, v = 10, tau in [0, 0.5]: {traj.steps} steps")

# %%
# 3. The order, with fixed steps
# ------------------------------
# A large swing (0.5 rad in the first mode) of the hanging pipe without flow or damping, on
# three sine modes, integrated to tau = 1 with fixed steps h, h/2, h/4, h/8: the
# differences of successive end states fall as h^5, the order the theory gives (2s - 1).
conservative = fempipe.PipeModel(fempipe.Modal(3), fempipe.Params(alpha=0.0, mu=0.0, v=0.0))
q0, qd0 = fempipe.make_initial_state(conservative, mode=1, amplitude=0.5)
steps = (0.02, 0.01, 0.005, 0.0025)
ends = [fempipe.simulate(conservative, q0, qd0, 1.0, h_fixed=h).q[-1] for h in steps]
diffs = np.array([np.max(np.abs(a - b)) for a, b in zip(ends[:-1], ends[1:], strict=True)])
radau_orders = np.log2(diffs[:-1] / diffs[1:])
print("successive differences:", ", ".join(f"{d:.2e}" for d in diffs))
print("observed orders:", ", ".join(f"{p:.2f}" for p in radau_orders), "(theory 2s - 1 = 5)")

# %%
# 4. Energy
# ---------
# For v = 0, mu = 0 the energy E = T + V is conserved (the energy paragraph of
# :doc:`Variants of the pipe </theory/variants>`): the exact conservation law is the
# independent reference here.  Radau IIA is not symplectic: it does not conserve E
# exactly, but its error follows the tolerance.
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
show_or_save()  # run as a script: a window, or PNG files without a display

# %%
# Exercises
# ---------
# ``check("6.k", answer)`` compares an answer with a reference computed independently (a
# closed form, the other side of a balance).  Each solution runs in this lesson.
#
# 1. Add flow (v = 3, mu = 5e-3; the hanging pipe on three sine modes, 0.3 rad in the first
#    mode): the energy now changes by the work of the jet, the Coriolis force and the
#    damping.  Integrate dE/dtau of :func:`fempipe.analyses.dynamics.power_terms` over
#    tau in [0, 1].
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    The power balance dE/dtau = -(sum of the non-conservative powers) holds along the
#    exact motion; Simpson's rule on 401 dense outputs integrates it.
#    Expected: ``answer`` = -0.179902 (E(1) - E(0) = -0.1799016).
#
#    .. code-block:: python
#
#       from scipy.integrate import simpson
#
#       from fempipe.analyses.dynamics import power_terms
#
#       with_flow = fempipe.PipeModel(fempipe.Modal(3), fempipe.Params(alpha=0.0, v=3.0))
#       q0_f, qd0_f = fempipe.make_initial_state(with_flow, mode=1, amplitude=0.3)
#       run = fempipe.simulate(with_flow, q0_f, qd0_f, 1.0, rtol=1e-9, n_out=401)
#       power = [power_terms(with_flow, q, qd)["dE_dtau"] for q, qd in zip(run.q, run.qdot)]
#       answer = simpson(power, x=run.t)
#       print(f"int_0^1 dE/dtau = {answer:.7f}")
#       check("6.1", answer)
#
#    .. raw:: html
#
#       </details>
#
# 2. Radau IIA is the collocation method on the Radau points c = ((4 - sqrt 6)/10,
#    (4 + sqrt 6)/10, 1): its tableau is lesson 3's a_pq and b_q on them.  Compute the
#    stability function R(z) = 1 + z b^T (I - z A)^-1 (1, 1, 1) at z = -1 and z = -1e6.
#
#    .. raw:: html
#
#       <details><summary>Solution</summary>
#
#    R is the (2, 3) Pade approximant of e^z, (1 + 2z/5 + z^2/20) / (1 - 3z/5 + 3z^2/20 -
#    z^3/60): close to e^z for small z (order 5: the local error is O(z^6)), and R(z) -> 0
#    as z -> -infinity (L-stability).  Expected: ``answer`` = 0.3679245 (e^-1 = 0.3678794)
#    and ``stiff`` = 3.0e-06 (about -3/z).
#
#    .. code-block:: python
#
#       from fempipe.model.quadrature import lagrange_integrals
#
#       radau = np.array([(4 - np.sqrt(6)) / 10, (4 + np.sqrt(6)) / 10, 1.0])
#       A_r = lagrange_integrals(radau, radau)
#       b_r = lagrange_integrals(radau, np.array([1.0]))[0]
#
#       def R(z):
#           return 1 + z * b_r @ np.linalg.solve(np.eye(3) - z * A_r, np.ones(3))
#
#       answer, stiff = R(-1.0), R(-1e6)
#       print(f"R(-1) = {answer:.8f}, R(-1e6) = {stiff:.2e}")
#       check("6.2", answer)
#
#    .. raw:: html
#
#       </details>

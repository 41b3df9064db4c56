"""
A limit cycle and its Floquet multipliers
=========================================

Above v_cr the hanging pipe (alpha = 0) flutters: the Hopf bifurcation gives birth to a
stable limit cycle.  :func:`fempipe.find_attractor` integrates from a perturbed static state
(Radau IIA), recognizes the recurrence and polishes the cycle by shooting
(:func:`fempipe.shoot`): the period and the initial state are Newton's unknowns, the
monodromy matrix comes with them and its eigenvalues are the Floquet multipliers.  One of
them is exactly 1 for every periodic orbit of an autonomous system (the direction along the
orbit); the cycle is stable when all the others lie inside the unit circle.
"""

# %%
# The attractor at v = 7 (v_cr = 6.33)
# ------------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

params = fempipe.Params(alpha=0.0, v=7.0)  # beta = 0.142, gamma = 18.9, mu = 5e-3
model = fempipe.PipeModel(fempipe.Modal(3), params)
att = fempipe.find_attractor(model, t_max=150.0)
cycle = att.cycle
mult = cycle.floquet_multipliers
print(
    f"{att.kind} attractor, period T = {cycle.period:.6f}, tip eta(1) in "
    f"[{cycle.tip['eta_tip'][0]:.5f}, {cycle.tip['eta_tip'][1]:.5f}]"
)
print("Floquet multipliers |m|:", ", ".join(f"{abs(m):.3e}" for m in mult))
trivial = mult[np.argmin(abs(mult - 1.0))]

#: the multiplier closest to 1 (exactly 1 by the orbit's time invariance), in tests/test_gallery.py
RESULT = float(abs(trivial))

# %%
# The orbit and the multipliers
# -----------------------------
tips = [fempipe.compute_tip(model.disc, q, params.alpha) for q in cycle.orbit_q]
fig, (ax1, ax2) = plt.subplots(1, 2, figsize=(6.4, 3.2), layout="constrained")
ax1.plot([t["Z_tip"] for t in tips], [-t["X_tip"] for t in tips])
ax1.set_xlabel("Z_g(1)")
ax1.set_ylabel("-X_g(1)")
ax1.set_title(f"tip orbit (axes not to scale), T = {cycle.period:.4f}", fontsize=9)
circle = np.exp(1j * np.linspace(0, 2 * np.pi, 200))
ax2.plot(circle.real, circle.imag, "k-", lw=0.6)
ax2.plot(mult.real, mult.imag, "o", ms=4)
ax2.set_aspect("equal")
ax2.set_title("Floquet multipliers", fontsize=9)
fig.suptitle(
    "alpha = 0, beta = 0.142, gamma = 18.9, mu = 5e-3, v = 7; N = 3 sine modes", fontsize=9
)
show_or_save()  # run as a script: a window, or PNG files without a display

"""
A bifurcation diagram by continuation of periodic orbits
========================================================

Instead of integrating at each flow velocity until the motion settles (the sweeps of
:func:`fempipe.compute_bifurcation_diagram`), the branch of limit cycles can be followed from its
Hopf point: :func:`fempipe.find_hopf_points` locates the flutter onsets on the static branch with
their eigenvectors, and :func:`fempipe.continue_cycles` continues the periodic orbits in v by
pseudo-arclength, on the same engine as the static branches, each orbit corrected by
shooting with its Floquet multipliers (``fempipe bifurcation --method continuation``).
Near a supercritical Hopf point the amplitude grows like sqrt(v - v_H) and the period starts
at 2 pi / omega_H.
"""

# %%
# The Hopf point and the branch (hanging pipe, alpha = 0)
# -------------------------------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

params = fempipe.Params(alpha=0.0)  # beta = 0.142, gamma = 18.9, mu = 5e-3
model = fempipe.PipeModel(fempipe.FiniteElement(4, 2), params)
hopf, _ = fempipe.find_hopf_points(model, 5.0, 7.5)
h = hopf[0]
print(
    f"Hopf point: v_H = {h.v:.6f}, omega = {h.omega:.5f}, 2 pi / omega = {2 * np.pi / h.omega:.5f}"
)
branch = fempipe.continue_cycles(model, h, (h.v, 7.2), ds_max=0.3, max_steps=20)
points = [p for p in branch.points if p.v <= 7.2]
v = np.array([p.v for p in points])
amp = np.array([0.5 * (p.tip["eta_tip"][1] - p.tip["eta_tip"][0]) for p in points])
period = np.array([p.period for p in points])
for p, a in zip(points, amp, strict=True):
    print(
        f"v = {p.v:.4f}: amplitude eta(1) = {a:.5f}, period {p.period:.5f}, "
        f"{'stable' if p.stable else 'unstable'}"
    )

#: the Hopf velocity (checked against the classical straight-pipe v_cr in tests/test_gallery.py)
RESULT = h.v

# %%
# The diagram
# -----------
# The amplitude squared is nearly linear in v near the onset (a supercritical Hopf point).
fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
ax.plot(np.r_[h.v, v], np.r_[0.0, amp], "o-", ms=3, label="stable limit cycles")
ax.plot([4.5, h.v], [0, 0], "k-", lw=1.5, label="stable equilibrium")
ax.plot([h.v, 7.2], [0, 0], "k--", lw=1, label="unstable equilibrium")
ax.set_xlabel("v")
ax.set_ylabel("amplitude of eta(1)")
ax.set_title(f"alpha = 0, beta = 0.142, gamma = 18.9, mu = 5e-3; P2:4; v_H = {h.v:.4f}", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

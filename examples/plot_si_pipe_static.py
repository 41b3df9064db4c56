"""
The static shape of a pipe given in SI units
============================================

A horizontal silicone pipe (Texier & Dorbolo's: L = 94 mm, EI = 1.8e-5 N m^2, m = 15.9 g/m,
M = 5.8 g/m) sags under its weight; the flow straightens it.  :class:`fempipe.PipeSI`
converts the SI pipe to the dimensionless groups of Eq. (19) and the flow U (m/s) to v.
The same computation on the command line is
``fempipe static --length 0.094 --EI 1.8e-5 --m 0.0159 --M 0.0058 --g 9.8 --alpha 90deg
--U 0,1,2,3``.
"""

# %%
# The pipe and its dimensionless groups
# -------------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

pipe = fempipe.PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=np.pi / 2)
params = pipe.params(U=0.0)
print(f"beta = {params.beta:.4f}, gamma = {params.gamma:.4f}, v = {pipe.v_of_U(1.0):.4f} U")

# %%
# Equilibria along the flow
# -------------------------
# :func:`fempipe.solve_path` solves Eq. (31a) by Newton's method at each flow velocity,
# starting from the previous state.  P3 elements on 8 cells are accurate to about 1e-8 here.
disc = fempipe.parse_discretization("P3:8")
model = fempipe.PipeModel(disc, params)
U = [0.0, 1.0, 2.0, 3.0]
sols = fempipe.solve_path(model, [pipe.v_of_U(u) for u in U])
drops_mm = []
for u, sol in zip(U, sols, strict=True):
    tip = fempipe.compute_tip(disc, sol.q, pipe.alpha)
    drops_mm.append(tip["X_tip"] * pipe.L * 1e3)
    print(
        f"U = {u:.0f} m/s: tip {drops_mm[-1]:6.2f} mm below the clamp, theta(1) = "
        f"{tip['theta_tip']:.4f} rad"
    )

#: the tip drop at U = 2 m/s, in units of L (checked in tests/test_gallery.py)
RESULT = drops_mm[2] / (pipe.L * 1e3)

# %%
# The shapes
# ----------
# :func:`fempipe.compute_shape` gives the centerline (X_g down, Z_g horizontal, Eq. (28)).
fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
for u, sol in zip(U, sols, strict=True):
    s = fempipe.compute_shape(disc, sol.q, pipe.alpha)
    ax.plot(s.Z_g * pipe.L * 1e3, -s.X_g * pipe.L * 1e3, label=f"U = {u:.0f} m/s")
ax.set_aspect("equal")
ax.set_xlabel("horizontal (mm)")
ax.set_ylabel("height (mm)")
ax.set_title(f"L = 94 mm, gamma = {params.gamma:.2f}, beta = {params.beta:.3f}; P3:8", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

"""
Finite elements against the paper's three sine modes
====================================================

The paper discretizes Eq. (20) with N = 3 sine modes sin((2r-1) pi xi / 2) (Eq. (22)).
Here its Fig. 2(a) case (gamma = 18.9, alpha = pi/3, v = 0, 2, 4, 6) is solved with the same
three modes (:class:`fempipe.Modal`) and with P3 elements (:class:`fempipe.FiniteElement`),
which are converged to about 1e-8; the difference is the error of the paper's truncation.
"""

# %%
# Both discretizations, one weak form
# -----------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

alpha = np.pi / 3
flows = [0.0, 2.0, 4.0, 6.0]
fe = fempipe.PipeModel(fempipe.FiniteElement(8, 3), fempipe.Params(alpha=alpha))
n3 = fempipe.PipeModel(fempipe.Modal(3), fempipe.Params(alpha=alpha))
fe_sols = fempipe.solve_path(fe, flows)
n3_sols = fempipe.solve_path(n3, flows)
x_fe, x_n3 = [], []
for v, a, b in zip(flows, fe_sols, n3_sols, strict=True):
    x_fe.append(fempipe.compute_tip(fe.disc, a.q, alpha)["X_tip"])
    x_n3.append(fempipe.compute_tip(n3.disc, b.q, alpha)["X_tip"])
    print(
        f"v = {v:.0f}: X_tip P3:8 = {x_fe[-1]:.8f}, N = 3 = {x_n3[-1]:.8f}, "
        f"N = 3 error {x_n3[-1] - x_fe[-1]:+.2e} L"
    )

#: X_g(1) at v = 4 on P3:8 (checked against scipy's solve_bvp in tests/test_gallery.py)
RESULT = x_fe[2]

# %%
# The shapes
# ----------
# On the scale of the pipe the three modes are close; the error is largest where the flow
# bends the pipe most.
fig, ax = plt.subplots(figsize=(5, 3.6), layout="constrained")
for v, a, b in zip(flows, fe_sols, n3_sols, strict=True):
    s, t = fempipe.compute_shape(fe.disc, a.q, alpha), fempipe.compute_shape(n3.disc, b.q, alpha)
    (line,) = ax.plot(s.Z_g, -s.X_g, label=f"v = {v:.0f}")
    ax.plot(t.Z_g, -t.X_g, "--", color=line.get_color())
ax.set_aspect("equal")
ax.set_xlabel("Z_g / L")
ax.set_ylabel("-X_g / L")
ax.set_title("gamma = 18.9, alpha = pi/3: P3:8 (solid), N = 3 sine modes (dashed)", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

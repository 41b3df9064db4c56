"""
Error estimates on a result
===========================

Every command takes ``--error-estimate``: fempipe recomputes the result on a refined
discretization (elements halved, or twice the modes) and reports beside each number Q an
estimate of its discretization error, ``max(3 |Q - Q_refined| 2^p / (2^p - 1), floor)`` with the
theoretical order p (2k for P_k; Roache's Grid Convergence Index).  In the library:
:func:`fempipe.estimate_errors` of the static states, a stability analysis or an
attractor.  Here the static tip positions of a coarse P2:2
model, whose errors are large enough to see, along a path in v.
"""

# %%
# A coarse result and its refinement
# ----------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

alpha = np.pi / 2
disc = fempipe.FiniteElement(2, 2)
model = fempipe.PipeModel(disc, fempipe.Params(alpha=alpha, gamma=10.0))
flows = [0.0, 1.0, 2.0, 3.0, 4.0]
sols = fempipe.solve_path(model, flows)
points = []
for sol in sols:
    tip = {k: float(x) for k, x in fempipe.compute_tip(disc, sol.q, alpha).items()}
    points.append({"v": sol.params.v, **tip, "tip_drop": tip["X_tip"] - np.cos(alpha)})
result = fempipe.estimate_errors({"points": points}, model, sols)
print(result["error_estimate"])
est = np.array([p["X_tip_error"] for p in result["points"]])
for p in result["points"]:
    print(
        f"v = {p['v']:.0f}: X_tip = {p['X_tip']:.7f} +- {p['X_tip_error']:.1e} "
        f"(refined {p['X_tip_refined']:.7f})"
    )

#: the estimated error of X_tip at v = 2 (checked against the true error in tests/test_gallery.py)
RESULT = float(est[2])

# %%
# Estimate against the true error
# -------------------------------
# The true error, against P3:32, lies below the estimate by the safety factor 3 or so.
fine = fempipe.PipeModel(fempipe.FiniteElement(32, 3), model.params)
exact = [
    fempipe.compute_tip(fine.disc, s.q, alpha)["X_tip"] for s in fempipe.solve_path(fine, flows)
]
true = np.abs(np.array([p["X_tip"] for p in points]) - exact)
print("true errors:", ", ".join(f"{e:.1e}" for e in true))
fig, ax = plt.subplots(figsize=(5, 3.2), layout="constrained")
ax.semilogy(flows, est, "o-", label="estimate (P2:2 against P2:4)")
ax.semilogy(flows, true, "s--", label="true error (against P3:32)")
ax.set_xlabel("v")
ax.set_ylabel("error of X_tip")
ax.set_title("alpha = pi/2, gamma = 10; P2:2", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

"""
A mesh-convergence study and its observed orders
================================================

How accurate is a discretization?  :func:`fempipe.run_study` refines each family (elements
halved, modes doubled), forms a reference without knowing the answer (the Richardson
extrapolation of the family with the smallest correction) and fits the observed order of
each family's error against its degrees of freedom.  For the tip values of P_k elements
theory says 2k (nodal superconvergence); the paper's sine modes give about 3.
``fempipe convergence --quantity X_tip`` is the command-line form.
"""

# %%
# The study
# ---------
# The paper's pipe (beta = 0.142, gamma = 18.9) at alpha = pi/3 and v = 4, the tip position
# X_g(1).  ``Family`` lives in :mod:`fempipe.studies.convergence`.
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save
from fempipe.studies.convergence import Family

params = fempipe.Params(alpha=np.pi / 3, v=4.0)
study = fempipe.run_study(
    fempipe.Quantity("X_tip", params),
    [
        Family("fe", (2, 4, 8, 16, 32), degree=1),
        Family("fe", (2, 4, 8, 16), degree=2),
        Family("modal", (2, 4, 8, 16), basis="sine"),
    ],
)
print(f"reference X_tip = {study.reference.value:.12f} ({study.reference.method})")
orders = {}
for s in study.series:
    orders[s.family] = s.observed_order
    print(f"{s.family:11s} observed order {s.observed_order:.2f} (theory {s.expected_order:g})")

#: the observed order of P2 (theory: 2k = 4), checked in tests/test_gallery.py
RESULT = orders["fe-P2"]

# %%
# Error against degrees of freedom
# --------------------------------
# On log-log axes each family is a line of slope -order until it reaches the solver's
# tolerance.  P2 gains four digits per decade of unknowns, the sine modes three.
fig, ax = plt.subplots(figsize=(5, 3.6), layout="constrained")
for s in study.series:
    ok = s.errors > 0
    ax.loglog(s.dofs[ok], s.errors[ok], "o-", ms=4, label=f"{s.family}: {s.observed_order:.2f}")
ax.set_xlabel("degrees of freedom")
ax.set_ylabel("|X_tip - reference|")
ax.set_title("beta = 0.142, gamma = 18.9, alpha = pi/3, v = 4", fontsize=9)
ax.grid(alpha=0.3, which="both")
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

"""
The variants: an end mass and springs
=====================================

Paidoussis' classical variants are terms of the same weak form (:doc:`Variants of the
pipe </theory/variants>`): a point mass Gamma = M_e / ((m + M) L) at the free end, springs
(kappa, xi_s) tying the centerline to its undeformed position, external viscous damping
sigma.  They are fields of :class:`fempipe.Params`, zero by default, and every analysis uses
them.  Here the frequencies of the gravity-free pipe without flow and the critical velocity
of the hanging pipe, with and without them.
"""

# %%
# Frequencies at v = 0, no gravity
# --------------------------------
# A spring at xi_s = 0.5 sits on a mesh node of 8 elements, which keeps the h^(2k) accuracy.
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

disc = fempipe.FiniteElement(8, 3)
base = dict(alpha=0.0, beta=0.142, gamma=0.0, mu=0.0, v=0.0)
cases = {
    "plain": fempipe.Params(**base),
    "end mass 0.5": fempipe.Params(**base, end_mass=0.5),
    "spring 50 at 0.5": fempipe.Params(**base, springs=((50.0, 0.5),)),
}
freqs = {}
for name, p in cases.items():
    lam = fempipe.compute_spectrum(fempipe.PipeModel(disc, p), np.zeros(disc.n)).lam
    freqs[name] = np.sort(lam.imag[lam.imag > 0])[:3]
    print(f"{name:16s}: omega_1..3 = " + ", ".join(f"{w:.6f}" for w in freqs[name]))

#: omega_1 with the end mass Gamma = 0.5 (checked against Blevins' frequency equation)
RESULT = float(freqs["end mass 0.5"][0])

# %%
# The critical velocity of the hanging pipe (gamma = 18.9, mu = 5e-3)
# -------------------------------------------------------------------
vcr = {}
for name, extra in {
    "plain": {},
    "end mass 0.5": {"end_mass": 0.5},
    "spring 50 at 0.5": {"springs": ((50.0, 0.5),)},
}.items():
    model = fempipe.PipeModel(fempipe.FiniteElement(6, 2), fempipe.Params(alpha=0.0, **extra))
    vcr[name] = fempipe.find_critical_velocity(model, v_max=15.0).v_cr
    print(f"{name:16s}: v_cr = {vcr[name]:.5f}")

fig, ax = plt.subplots(figsize=(5, 3), layout="constrained")
x = np.arange(3)
for k, (name, w) in enumerate(freqs.items()):
    ax.bar(x + 0.27 * (k - 1), w, width=0.27, label=f"{name} (v_cr = {vcr[name]:.2f})")
ax.set_yscale("log")
ax.set_xticks(x, ["omega_1", "omega_2", "omega_3"])
ax.set_title("beta = 0.142, no gravity, v = 0; P3:8 (v_cr: gamma = 18.9, P2:6)", fontsize=9)
ax.legend(fontsize=7)
show_or_save()  # run as a script: a window, or PNG files without a display

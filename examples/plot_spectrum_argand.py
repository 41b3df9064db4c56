"""
Spectra and the Argand diagram
==============================

Linearized about its static state, the pipe's motion is exp(lambda tau) times a mode
(Eqs. (31b)-(33)); :func:`fempipe.compute_spectrum` solves the generalized eigenproblem.  Without
gravity or flow the pipe is an Euler-Bernoulli cantilever and the eigenvalues are
+-i (beta_r L)^2 with 1 + cos(beta L) cosh(beta L) = 0.  :func:`fempipe.trace_root_locus` follows
the eigenvalues as the flow grows: the Argand diagram of Paidoussis' book, in which the
second mode crosses into the right half plane (flutter).
"""

# %%
# The spectrum without gravity or flow
# ------------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

params = fempipe.Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0, v=0.0)
model = fempipe.PipeModel(fempipe.FiniteElement(8, 3), params)
spec = fempipe.compute_spectrum(model, np.zeros(model.disc.n))
up = spec.lam[spec.lam.imag > 0]
lam = up[np.argsort(up.imag)][:3]
print("first three eigenvalues at v = 0:", ", ".join(f"{z:.6f}" for z in lam))

#: the first frequency Im(lambda_1) at v = 0 (checked against (beta_1 L)^2 = 1.87510407^2)
RESULT = float(lam[0].imag)

# %%
# The root locus in v
# -------------------
# beta = 0.2 and a little Kelvin-Voigt damping; the eigenvalues are tracked from one v to the
# next by matching their eigenvectors.
damped = fempipe.PipeModel(model.disc, fempipe.Params(alpha=0.0, beta=0.2, gamma=0.0, mu=1e-3))
vs = np.linspace(0.0, 8.0, 33)
locus = fempipe.trace_root_locus(damped, vs, n_modes=3)
crit = fempipe.find_critical_velocity(damped, v_max=8.0)
print(f"flutter at v_cr = {crit.v_cr:.5f}, frequency {crit.critical.frequency:.4f}")

fig, ax = plt.subplots(figsize=(5, 3.6), layout="constrained")
seen = set()
for k, mode in enumerate(locus.modes):  # a conjugate pair: two columns of one mode
    label = None if mode in seen else f"mode {mode}"
    seen.add(mode)
    ax.plot(
        locus.lam[:, k].real, locus.lam[:, k].imag, ".-", ms=3, color=f"C{mode - 1}", label=label
    )
ax.axvline(0.0, color="k", lw=0.6)
ax.set_xlabel("Re lambda")
ax.set_ylabel("Im lambda")
ax.set_title(f"beta = 0.2, gamma = 0, mu = 1e-3, v = 0 to 8: v_cr = {crit.v_cr:.3f}", fontsize=9)
ax.legend(fontsize=8)
show_or_save()  # run as a script: a window, or PNG files without a display

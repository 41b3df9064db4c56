"""
Parametric resonance under a pulsating flow
===========================================

A pump's flow pulsates, v(tau) = v0 (1 + sigma sin(omega tau)).  Well below its critical
velocity (7.1 for this pipe) the hanging pipe of Paidoussis & Issid (beta = 0.2, gamma = 10,
mu = 5e-3) is driven unstable when omega is near twice the frequency of its second mode:
:func:`fempipe.analyses.parametric.compute_parametric_chart` finds the region and where it opens,
on finite elements and on the paper's three and four sine modes.  Then Eq. (20) itself is
integrated with a pulsating flow inside and outside the region.
"""

# %%
# The charts at v0 = 6
# --------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.analyses.parametric import compute_parametric_chart
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.plotting.parametric import plot_parametric_chart
from fempipe.plotting.scripts import show_or_save
from fempipe.solvers.radau import Radau

v0 = 6.0
params = fempipe.Params(alpha=0.0, beta=0.2, gamma=10.0, mu=5e-3, v=v0)
charts = {
    disc.name: compute_parametric_chart(
        fempipe.PipeModel(disc, params), v0, (22.0, 38.0), [0.1, 0.2]
    )
    for disc in (fempipe.FiniteElement(6, 3), fempipe.Modal(3), fempipe.Modal(4))
}
for name, chart in charts.items():
    for r in chart.regions:
        print(
            f"{name}: mode {r.candidate.mode[0]} ({r.candidate.kind}) opens at sigma = "
            f"{r.sigma_threshold:.5f}, omega = {r.omega_threshold:.4f}; at sigma = 0.2 "
            f"unstable for {r.boundary[-1][1]:.3f} < omega < {r.boundary[-1][2]:.3f}"
        )
fe = charts["P3:6"]
(region,) = fe.regions

# %%
# Inside and outside the region
# -----------------------------
# A small perturbation of the straight pipe, integrated by Eq. (20) with the pulsating flow
# at sigma = 0.2: inside the region it grows, by the largest Floquet multiplier (-1.35) per
# period; outside it decays, turning with the complex pair of multipliers of modulus 0.80.
model = fempipe.PipeModel(fempipe.FiniteElement(6, 3), params)
q0 = 1e-6 * np.sin(np.linspace(0.2, 1.0, model.n))
fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(9.0, 3.6), layout="constrained")
plot_parametric_chart(fe, [charts["modal:3"], charts["modal:4"]], ax=ax0)
growth = {}
for omega, colour in (
    (region.omega_threshold, "tab:red"),
    (region.boundary[-1][2] + 3, "tab:blue"),
):
    T = 2 * np.pi / omega
    flow = fempipe.PulsatingFlow(v0, 0.2, omega)
    stepper = Radau(PipeDynamics(model, flow), q0, np.zeros(model.n), 0.0, h_fixed=T / 100)
    t, norm = [0.0], [np.linalg.norm(q0)]
    for k in range(1, 16):
        for _ in stepper.steps(k * T):
            pass
        t.append(stepper.t)
        norm.append(np.linalg.norm(np.r_[stepper.q, stepper.qdot / omega]))
    growth[omega] = norm[-1] / norm[-2]
    ax1.semilogy(t, norm, "o-", ms=3, color=colour, label=f"ω = {omega:.2f}")
    print(
        f"omega = {omega:.3f}: the state changes by {norm[-1] / norm[1]:.3g} over 14 periods, "
        f"by {growth[omega]:.4f} in the last"
    )
ax1.set_xlabel("τ")
ax1.set_ylabel("|(q, q̇/ω)| at the end of each period")
ax1.set_title("σ = 0.2: inside the region (red) and outside (blue)", fontsize=9)
ax1.legend(fontsize=8)

#: the growth per period of the small motion at the region's threshold frequency
RESULT = growth[region.omega_threshold]
show_or_save()  # run as a script: a window, or PNG files without a display

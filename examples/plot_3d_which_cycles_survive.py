"""
Which planar cycles survive in three dimensions
===============================================

The paper's model is planar: its limit cycles are motions in the plane of gravity and the clamp.
A round pipe may leave that plane.  A planar cycle is a solution of the 3-D model too
(:class:`fempipe.PipeModel3D`: its states with no out-of-plane part are the planar model's), and
:func:`fempipe.compute_out_of_plane_floquet` computes the Floquet multipliers of perturbations out of
the plane in two independent ways: by default from the linear equation of out-of-plane
perturbations about the moving planar state (one unknown, the out-of-plane rotation psi), and
with ``method="3d"`` from the 3-D model's monodromy along the cycle (its out-of-plane block).
The two are different discretizations of the same multipliers and agree to their
discretization errors; the cycle survives in 3-D when all of them lie inside the unit circle.

The hanging (alpha = 0) and the standing (alpha = pi) pipe are axisymmetric: a planar cycle
turned about the vertical is again a cycle, so one out-of-plane multiplier is exactly 1 in the
continuum (on a mesh, up to the discretization error).  It is left out of the verdict, as the
multiplier 1 of the phase is in the plane.
"""

# %%
# The cycles at v = 10, hanging and standing
# ------------------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

disc = fempipe.FiniteElement(6, 3)  # P3:6; the default mesh is P3:16
results = {}
for alpha, name in ((0.0, "hanging, alpha = 0"), (np.pi, "standing, alpha = pi")):
    model = fempipe.PipeModel(disc, fempipe.Params(alpha=alpha, v=10.0))
    cycle = fempipe.find_attractor(model, t_max=150.0).cycle
    oop = fempipe.compute_out_of_plane_floquet(model, cycle)  # the linear psi equation
    oop3 = fempipe.compute_out_of_plane_floquet(model, cycle, method="3d")  # the 3-D model
    results[name] = (cycle, oop, oop3)
    verdict = "survives" if oop.stable else "does not survive"
    print(
        f"{name}: period {cycle.period:.5f}, largest non-trivial out-of-plane multiplier "
        f"{oop.max_nontrivial:.5f} (3-D model: {oop3.max_nontrivial:.5f}) -> the planar cycle "
        f"{verdict} in 3-D"
    )

hanging, hanging3 = results["hanging, alpha = 0"][1:]
print(
    f"the rotation about the vertical: multiplier {hanging.trivial.real:.7f} "
    f"(3-D model: {hanging3.trivial.real:.7f})"
)

#: the hanging pipe's neutral out-of-plane multipliers (1 by its axisymmetry), linear and
#: 3-D, in tests/test_gallery.py
RESULT = (float(abs(hanging.trivial)), float(abs(hanging3.trivial)))

# %%
# The multipliers in the complex plane
# ------------------------------------
# In-plane multipliers (grey) and out-of-plane ones (colour: crosses from the linear psi
# equation, plus signs from the 3-D model); the neutral one of the rotation about the vertical
# is circled.
circle = np.exp(1j * np.linspace(0.0, 2.0 * np.pi, 300))
fig, axes = plt.subplots(1, 2, figsize=(7.0, 3.6), layout="constrained")
for ax, (name, (_cycle, oop, oop3)) in zip(axes, results.items(), strict=True):
    ax.plot(circle.real, circle.imag, "k-", lw=0.6)
    mu_p, mu_o = oop.planar_multipliers, oop.multipliers
    ax.plot(mu_p.real, mu_p.imag, "o", color="0.6", ms=4, label="in the plane")
    ax.plot(mu_o.real, mu_o.imag, "x", color="C3", ms=6, label="out of the plane (psi)")
    mu_3 = oop3.multipliers
    ax.plot(mu_3.real, mu_3.imag, "+", color="C0", ms=8, label="out of the plane (3-D)")
    if oop.trivial is not None:
        ax.plot(
            oop.trivial.real,
            oop.trivial.imag,
            "o",
            mfc="none",
            mec="k",
            ms=11,
            label="rotation about the vertical",
        )
    ax.set_aspect("equal")
    ax.set_xlim(-1.25, 1.25)
    ax.set_ylim(-1.25, 1.25)
    verdict = "stable" if oop.stable else "unstable"
    ax.set_title(
        f"{name}\nlargest out of plane {oop.max_nontrivial:.3f}: {verdict} in 3-D", fontsize=9
    )
    ax.set_xlabel("Re")
axes[0].set_ylabel("Im")
axes[1].legend(loc="lower left", fontsize=7)
fig.suptitle("beta = 0.142, gamma = 18.9, mu = 5e-3, v = 10; P3:6", fontsize=9)
show_or_save()  # run as a script: a window, or PNG files without a display

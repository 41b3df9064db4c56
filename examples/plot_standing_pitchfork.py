"""
The standing pipe: pitchfork and folds
======================================

A pipe standing up (alpha = pi) stays straight under its own weight until gravity reaches
Greenhill's heavy-column load; there the straight state loses stability in a pitchfork and
two buckled branches, mirror images, grow out of it.  :func:`fempipe.continue_static`
(pseudo-arclength, Keller) follows the straight branch in gamma and detects the bifurcation
by the sign of the Jacobian's determinant; :func:`fempipe.switch_branch` starts the buckled
branches.  Tilting a buckled pipe against its lean then ends the branch in a fold (a turning
point in alpha), one on each side of the vertical.
"""

# %%
# The pitchfork in gamma (v = 0)
# ------------------------------
import matplotlib.pyplot as plt
import numpy as np

import fempipe
from fempipe.plotting.scripts import show_or_save

disc = fempipe.FiniteElement(6, 2)
model = fempipe.PipeModel(disc, fempipe.Params(alpha=np.pi, gamma=0.0, v=0.0))
straight = fempipe.continue_static(model, "gamma", stop=15.0, ds=0.5, ds_max=1.0)
pitchfork = straight.special[0]
print(f"{pitchfork.kind} at gamma = {pitchfork.value:.6f}")
right, left = fempipe.switch_branch(model, pitchfork, "gamma", stop=15.0, ds=0.2)

#: the pitchfork's gamma (checked against Greenhill's J_{-1/3}(2/3 sqrt(gamma)) = 0)
RESULT = pitchfork.value

# %%
# Folds in alpha (gamma = 15)
# ---------------------------
# From the buckled state at gamma = 15, continue in alpha away from the vertical, towards the
# side opposite to the lean: the branch turns back at a fold.
tilted = fempipe.PipeModel(disc, fempipe.Params(alpha=np.pi, gamma=15.0, v=0.0))
folds = []
for branch in (right, left):
    # which branch leans which way depends on the sign of a null vector (round-off): ask
    lean = fempipe.compute_tip(disc, branch.points[-1].q, np.pi)["theta_tip"]
    direction = -1 if lean > 0 else 1
    arc = fempipe.continue_static(
        tilted,
        "alpha",
        stop=np.pi + 0.8 * direction,
        q0=branch.points[-1].q,
        ds=0.05,
        ds_max=0.1,
        direction=direction,
        max_steps=200,
    )
    folds += [s.value for s in arc.special if s.kind == "fold"]
print("folds at alpha =", ", ".join(f"{a:.6f}" for a in sorted(set(np.round(folds, 9)))))


def tip(points: list) -> tuple[np.ndarray, np.ndarray]:
    """(parameter, theta(1)) along a branch."""
    th = [fempipe.compute_tip(disc, p.q, np.pi)["theta_tip"] for p in points]
    return np.array([p.value for p in points]), np.array(th)


fig, ax = plt.subplots(figsize=(5, 3.4), layout="constrained")
for br, style in ((straight, "k-"), (right, "C0-"), (left, "C1-")):
    ax.plot(*tip(br.points), style)
ax.axvline(pitchfork.value, color="0.6", ls=":")
ax.set_xlabel("gamma")
ax.set_ylabel("theta(1)")
ax.set_title(f"alpha = pi, v = 0, P2:6: pitchfork at gamma = {pitchfork.value:.4f}", fontsize=9)
show_or_save()  # run as a script: a window, or PNG files without a display

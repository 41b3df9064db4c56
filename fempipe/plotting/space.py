"""Figures of the 3-D motion: the tip's orbit seen from above and from the side, 3-D snapshots.

One frame for every figure and file (:mod:`fempipe.io.space_trajectory`):
x = Z_g horizontal in the plane of the static state, y = -X_g up the screen
(gravity down), z = Y_g out of that plane.  The window drawn is the shot
periodic orbit, else the last period of the run (or its last tenth).
"""

from __future__ import annotations

import numpy as np

from fempipe.io.space_trajectory import space_frame_points
from fempipe.model.space import SpaceModel

__all__ = ["plot_space_snapshots", "plot_tip_orbit"]


def _caption(model: SpaceModel, motion) -> str:
    p = model.params
    # the angle in degrees, as in every other figure's caption
    head = (
        f"α = {np.degrees(p.alpha):.4g}°, β = {p.beta:.4g}, γ = {p.gamma:.4g}, μ = {p.mu:.4g}, "
        f"v = {p.v:.4g} ({model.disc.name})"
    )
    kind = f"{motion.kind}, {motion.motion}"
    if motion.period:
        kind += f", period {motion.period:.5g}"
    if motion.whirl_rate is not None:
        kind += f", whirl rate {motion.whirl_rate:.4g} rad per unit tau"
    return f"{head}\n{kind}"


def _window(motion) -> np.ndarray:
    """The states drawn: the shot orbit if any, else the last period (or tenth) of the run."""
    if motion.cycle is not None:
        return motion.cycle.orbit_q
    t = motion.t
    span = motion.period if motion.period else 0.1 * (t[-1] - t[0])
    return motion.U[t >= t[-1] - span]


def plot_tip_orbit(model: SpaceModel, motion):
    """The tip's path over the window: from above (x, z) and from the side (x, y)."""
    import matplotlib.pyplot as plt

    tip = model.tip_coordinates(np.atleast_2d(_window(motion)))
    tips = np.column_stack([tip["Z_tip"], -tip["X_tip"], tip["Y_tip"]])  # the files' frame
    fig, (top, side) = plt.subplots(1, 2, figsize=(9.0, 4.6), layout="constrained")
    top.plot(tips[:, 0], tips[:, 2], color="C0", lw=1.5)
    top.plot(0.0, 0.0, "k+", ms=10, label="clamp")
    top.set_xlabel("x = Z_g  (in the static plane)")
    top.set_ylabel("z = Y_g  (out of the plane)")
    top.set_title("tip from above")
    side.plot(tips[:, 0], tips[:, 1], color="C0", lw=1.5)
    side.plot(0.0, 0.0, "k+", ms=10, label="clamp")
    side.set_xlabel("x = Z_g")
    side.set_ylabel("y = -X_g  (gravity down)")
    side.set_title("tip from the side")
    for ax in (top, side):
        ax.set_aspect("equal", adjustable="datalim")
        ax.grid(alpha=0.3)
        ax.legend(loc="best", fontsize=8)
    fig.suptitle(_caption(model, motion), fontsize=9)
    return fig


def plot_space_snapshots(model: SpaceModel, motion, n_snapshots: int = 12):
    """The centerline at ``n_snapshots`` times of the window, in 3-D (the same frame)."""
    import matplotlib.pyplot as plt

    states = _window(motion)
    picks = np.linspace(0, len(states) - 1, n_snapshots).round().astype(int)
    fig = plt.figure(figsize=(6.4, 6.0), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    colors = plt.cm.viridis(np.linspace(0.0, 1.0, picks.size))
    for k, c in zip(picks, colors, strict=True):
        pts, _ = space_frame_points(model, states[k])
        # matplotlib's 3-D axes are z-up: draw (x, z, y) so that gravity points down
        ax.plot(pts[:, 0], pts[:, 2], pts[:, 1], color=c, lw=1.2)
    ax.set_xlabel("x = Z_g")
    ax.set_ylabel("z = Y_g")
    ax.set_zlabel("y = -X_g")
    ax.set_box_aspect((1, 1, 1))
    lim = 1.05
    ax.set_xlim(-lim, lim)
    ax.set_ylim(-lim, lim)
    ax.set_zlim(-lim, lim * 0.3)
    ax.set_title(
        _caption(model, motion) + f"\n{picks.size} snapshots over the window (dark: first)",
        fontsize=9,
    )
    return fig

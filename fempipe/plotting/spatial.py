"""The static branches and their stability in three dimensions (``fempipe critical``)."""

from __future__ import annotations

import numpy as np

from .style import EVENT_MARKERS, mask_edges, new_axes


def _out_unstable_at(branch_in, branch_out) -> np.ndarray:
    """Per in-plane sample: unstable out of the plane.

    The out-of-plane analysis samples the same branch (every third point and
    its own insertions).  Where the branch is monotone in v, the verdict at
    an in-plane sample is that after the last out-of-plane event below its v
    (events are located to 1e-10); elsewhere (a branch through a fold) it is
    that of the out-of-plane sample nearest in (v, theta(1)).
    """
    if branch_out is None or branch_out.v.size == 0:
        return np.zeros(branch_in.v.size, bool)
    v = branch_in.v
    dv = np.diff(v)
    events = [e for e in branch_out.events if e.type != "fold" and not e.at_start]
    if np.all(dv >= 0) or np.all(dv <= 0):
        rising = v[-1] >= v[0]
        order = sorted(events, key=lambda e: e.v, reverse=not rising)
        start = branch_out.n_unstable[np.argmin(np.abs(branch_out.v - v[0]))] > 0
        out = np.full(v.size, start)
        for e in order:
            past = v >= e.v if rising else v <= e.v
            out[past] = not e.stable_after
        return out
    d = np.hypot(
        v[:, None] - branch_out.v[None, :],
        branch_in.theta_tip[:, None] - branch_out.theta_tip[None, :],
    )
    return branch_out.n_unstable[np.argmin(d, axis=1)] > 0


def plot_spatial_branches(result, ax=None, title=None):
    """theta(1) of the static branches against v, stable in 3-D or not, and both planes' events.

    Solid: stable in three dimensions; dashed: unstable in the plane; dotted:
    stable in the plane, unstable out of it.  Events: open markers in the
    plane, filled out of it (○ flutter, □ divergence, △ restabilization,
    ◇ fold).

    Parameters
    ----------
    result : SpatialStability
    ax : Axes, optional

    Returns
    -------
    Axes
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    ax = new_axes(ax, size=(6.4, 5.0))
    colors = plt.cm.tab10(np.arange(10))
    outs = {b.name: b for b in result.out_of_plane.branches}
    for i, b in enumerate(result.in_plane.branches):
        c = colors[i % 10]
        bo = outs.get(b.name)
        unstable_in = b.n_unstable > 0
        unstable_out = _out_unstable_at(b, bo) & ~unstable_in
        stable = ~unstable_in & ~unstable_out
        # Each piece joined to its neighbours, so that the styles meet.
        for mask, ls, lw, label in (
            (stable, "-", 1.3, b.name),
            (unstable_in, "--", 1.3, None),
            (unstable_out, ":", 1.8, None),
        ):
            y = np.where(mask | mask_edges(mask), b.theta_tip, np.nan)
            ax.plot(b.v, y, ls, color=c, lw=lw, label=label)
        for branch, out in ((b, False), (bo, True)):
            if branch is None:
                continue
            fill = c if out else "none"
            for ev in branch.events:
                if ev.type == "fold" and out:  # the static branch's: drawn once
                    continue
                j = int(np.argmin(np.abs(b.v - ev.v)))
                ax.plot(
                    ev.v, b.theta_tip[j], EVENT_MARKERS.get(ev.type, "x"), color=c, mfc=fill, ms=7
                )
    key = [
        Line2D([], [], color="0.3", ls="-", label="stable (3-D)"),
        Line2D([], [], color="0.3", ls="--", label="unstable in the plane"),
        Line2D([], [], color="0.3", ls=":", lw=1.8, label="unstable out of the plane only"),
        Line2D([], [], color="0.3", ls="", marker="o", mfc="none", label="event in the plane"),
        Line2D([], [], color="0.3", ls="", marker="o", label="event out of the plane"),
    ]
    handles, _ = ax.get_legend_handles_labels()
    ax.legend(handles=handles + key, fontsize=9, loc="best")
    ax.set_xlabel("v")
    ax.set_ylabel(r"$\theta(1)$ of the static state (rad)")
    p = result.in_plane.params
    ax.set_title(
        title
        or rf"$\alpha$ = {np.degrees(p.alpha):.4g}°, $\beta$ = {p.beta:g}, $\gamma$ = {p.gamma:g}, "
        rf"$\mu$ = {p.mu:g}: stability in three dimensions",
        fontsize=10,
    )
    ax.grid(alpha=0.3)
    return ax

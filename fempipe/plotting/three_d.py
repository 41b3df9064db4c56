"""Figures of the 3-D motion: the tip's path in three views, 3-D snapshots of the pipe.

Frame: docs/theory/conventions.md (X_g down the page, Y_g out of the static state's plane).
Views are framed on the motion; the window drawn is the shot orbit, else the run's last period.
"""

from __future__ import annotations

import textwrap

import numpy as np

from fempipe.io.trajectory_3d import frame_points_3d
from fempipe.model.three_d.model import PipeModel3D

from .layout import shared_legend
from .static import UNSTABLE_COLOR
from .style import parameter_text

__all__ = ["plot_snapshots_3d", "plot_tip_orbit"]

#: Axis labels of the frame, as the planar figures word them.
_AXIS = {
    "X": r"$X_g$  (along gravity, $/L$)",
    "Z": r"$Z_g$  (horizontal, $/L$)",
    "Y": r"$Y_g$  (out of the plane, $/L$)",
}
#: A view's frame spans the motion plus this fraction of its extent on each side.
MARGIN = 0.08
#: The ratio of a view's height to its width is kept within these bounds (a planar
#: motion seen from above is a segment: its panel stays a readable strip).
_RATIO = (0.4, 2.5)


def _caption(model: PipeModel3D, motion, window: str, width: int = 140) -> str:
    """The parameters, then the attractor and what is drawn, wrapped to ``width`` characters."""
    head = f"{parameter_text(model.params)} ({model.disc.name})"
    kind = f"{motion.kind}, {motion.motion}"
    if motion.period:
        kind += f", period {motion.period:.5g}"
    if motion.whirl_rate is not None:
        kind += f", whirl rate {motion.whirl_rate:.4g} rad per unit τ"
    return head + "\n" + textwrap.fill(f"{kind}; {window}", width)


def _window(motion) -> tuple[np.ndarray, np.ndarray]:
    """``(tau, states)`` drawn: the shot orbit, else the last period (or tenth) of the run."""
    if motion.cycle is not None:
        return np.asarray(motion.cycle.orbit_t), np.atleast_2d(motion.cycle.orbit_q)
    t = motion.t
    span = motion.period if motion.period else 0.1 * (t[-1] - t[0])
    keep = t >= t[-1] - span
    return t[keep], motion.U[keep]


def _window_text(motion, tau: np.ndarray) -> str:
    if motion.cycle is not None:
        return "the periodic orbit (by shooting)"
    return f"τ = {tau[0]:.4g}–{tau[-1]:.4g}"


def _orbit_style(motion) -> dict:
    """Solid for an attractor, grey dashed for a shot orbit that is unstable."""
    unstable = motion.cycle is not None and motion.cycle.stable is False
    many_loops = motion.cycle is None and not motion.period  # a band of many loops
    label = "tip path"
    if motion.cycle is not None:
        verdict = {True: "stable", False: "unstable"}.get(motion.cycle.stable, "stability unknown")
        label += f" (periodic orbit, {verdict}; arrow: sense of motion)"
    return {
        "color": UNSTABLE_COLOR if unstable else "C0",
        "ls": "--" if unstable else "-",
        "lw": 0.7 if many_loops else 1.8,
        "label": label,
    }


def _sense_arrow(ax, x: np.ndarray, y: np.ndarray, color) -> None:
    """An arrowhead on a closed orbit, a quarter of the way round, pointing forward in τ."""
    k = len(x) // 4
    if len(x) < 8 or (x[k + 1], y[k + 1]) == (x[k], y[k]):
        return
    ax.annotate(
        "",
        xy=(x[k + 1], y[k + 1]),
        xytext=(x[k], y[k]),
        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 0, "mutation_scale": 16},
    )


def _view_limits(x: np.ndarray, y: np.ndarray) -> tuple[tuple, tuple]:
    """``(xlim, ylim)`` with equal scales: the data plus :data:`MARGIN`, aspect within :data:`_RATIO`."""
    cx, cy = (np.min(x) + np.max(x)) / 2, (np.min(y) + np.max(y)) / 2
    hx, hy = np.ptp(x) / 2, np.ptp(y) / 2
    # A point (an equilibrium) gets a frame of 1e-3; a swing however small fills its own.
    floor = 1e-2 * max(hx, hy) if max(hx, hy) > 0 else 1e-3
    hx, hy = max(hx, floor), max(hy, floor)
    ratio = float(np.clip(hy / hx, *_RATIO))
    hx, hy = max(hx, hy / ratio), max(hy, hx * ratio)
    hx, hy = hx * (1 + 2 * MARGIN), hy * (1 + 2 * MARGIN)
    return (cx - hx, cx + hx), (cy - hy, cy + hy)


def _static_tip(model: PipeModel3D, static, tips: dict) -> dict | None:
    """The static state's tip and verdict if within the tip path's extent of the window, else None."""
    if static is None:
        return None
    U, stable = static
    tip = {k: float(v[0]) for k, v in model.tip_coordinates(np.atleast_2d(U)).items()}
    for k in ("X_tip", "Y_tip", "Z_tip"):
        lo, hi = tips[k].min(), tips[k].max()
        reach = max(hi - lo, 1e-6)
        if not lo - reach <= tip[k] <= hi + reach:
            return None  # far from the motion: drawing it would shrink the orbit
    tip["stable"] = stable
    return tip


def _static_label(stable) -> str:
    return {True: "static state (stable)", False: "static state (unstable)"}.get(
        stable, "static state"
    )


def plot_tip_orbit(model: PipeModel3D, motion, static=None):
    """The tip's path from above, the side and the front; returns the Figure.

    ``static`` = (3-D state, stable in 3-D or None): its tip, marked when near the motion."""
    import matplotlib.pyplot as plt

    tau, states = _window(motion)
    tips = model.tip_coordinates(states)
    fixed = _static_tip(model, static, tips)
    views = (
        ("Z", "Y", r"from above (along $X_g$)"),
        ("Z", "X", r"from the side (along $Y_g$)"),
        ("Y", "X", r"from the front (along $Z_g$)"),
    )
    points = []
    for h, w, _ in views:
        x, y = tips[f"{h}_tip"], tips[f"{w}_tip"]
        if fixed is not None:
            x, y = np.append(x, fixed[f"{h}_tip"]), np.append(y, fixed[f"{w}_tip"])
        points.append(_view_limits(x, y))
    # Panels of one height, each as wide as its equal-scale view needs.
    widths = [np.ptp(xl) / np.ptp(yl) for xl, yl in points]
    # The panels' height: the largest that keeps the figure within 12.5 inches.
    height = float(np.clip(9.2 / sum(widths), 2.4, 3.6))
    fig, axes = plt.subplots(
        1,
        3,
        figsize=(height * sum(widths) + 3.3, height + 1.9),
        layout="constrained",
        width_ratios=widths,
    )
    style = _orbit_style(motion)
    for ax, (h, w, name), (xlim, ylim) in zip(axes, views, points, strict=True):
        ax.plot(tips[f"{h}_tip"], tips[f"{w}_tip"], **style)
        if motion.cycle is not None:
            _sense_arrow(ax, tips[f"{h}_tip"], tips[f"{w}_tip"], style["color"])
        if fixed is not None:
            stable = fixed["stable"] is True
            ax.plot(
                fixed[f"{h}_tip"],
                fixed[f"{w}_tip"],
                "o",
                ms=8,
                color="k" if stable else UNSTABLE_COLOR,
                mfc="k" if stable else "none",
                mew=1.6,
                label=_static_label(fixed["stable"]),
            )
        ax.set_xlim(*xlim)
        # X_g along gravity: down the page
        ax.set_ylim(*(ylim[::-1] if w == "X" else ylim))
        ax.set_aspect("equal", adjustable="box")
        ax.set_xlabel(_AXIS[h], fontsize=10)
        ax.set_ylabel(_AXIS[w], fontsize=10)
        ax.set_title(name, fontsize=11)
        ax.grid(alpha=0.3)
        ax.tick_params(labelsize=9)
    shared_legend(fig, axes, fontsize=10)
    _thin_ticks(fig, axes)
    text = f"the tip over {_window_text(motion, tau)}; the clamp at the origin, off the frame"
    # About 12 characters of 10 pt text per inch of the figure's width.
    fig.suptitle(_caption(model, motion, text, int(12 * fig.get_figwidth())), fontsize=10)
    return fig


def _thin_ticks(fig, axes) -> None:
    """Fewer x tick labels on a panel where they would touch (a narrow view), at least two."""
    from matplotlib.ticker import MaxNLocator

    for ax in axes:
        for nbins in (5, 4, 3, 2, 1):
            ax.xaxis.set_major_locator(MaxNLocator(nbins=nbins, min_n_ticks=2))
            fig.canvas.draw()
            renderer = fig.canvas.get_renderer()
            lo, hi = sorted(ax.get_xlim())
            boxes = [
                t.label1.get_window_extent(renderer).padded(5)
                for t in ax.xaxis.get_major_ticks()
                if t.label1.get_visible() and t.label1.get_text() and lo <= t.get_loc() <= hi
            ]
            if not any(a.overlaps(b) for a, b in zip(boxes, boxes[1:], strict=False)):
                break


def _snapshot_window(motion) -> tuple[np.ndarray, np.ndarray]:
    """One oscillation: the orbit or period, else one period of the strongest frequency."""
    tau, states = _window(motion)
    if motion.cycle is None and not motion.period and motion.frequencies:
        keep = tau >= tau[-1] - 1.0 / motion.frequencies[0]
        if keep.sum() >= 12:  # else the steps are too long to draw one oscillation
            return tau[keep], states[keep]
    return tau, states


def _frame_3d(ax, pts: np.ndarray) -> None:
    """Equal scales on the pipe's extent plus :data:`MARGIN`, each side at least a fifth of the longest."""
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    span = np.maximum(hi - lo, 0.2 * np.max(hi - lo)) * (1 + 2 * MARGIN)
    mid = (lo + hi) / 2
    ax.set_xlim(mid[0] - span[0] / 2, mid[0] + span[0] / 2)
    ax.set_ylim(mid[1] - span[1] / 2, mid[1] + span[1] / 2)
    # X_g along gravity, so down the page: the z axis is inverted.
    ax.set_zlim(mid[2] + span[2] / 2, mid[2] - span[2] / 2)
    # Drawn a little inside the axes' box: a 3-D axes' labels reach beyond it.
    ax.set_box_aspect(span, zoom=0.85)


def plot_snapshots_3d(model: PipeModel3D, motion, n_snapshots: int = 12, static=None):
    """The centerline at ``n_snapshots`` times over one oscillation in 3-D, colored by τ, with the
    tip's path and ``static`` as in :func:`plot_tip_orbit`; returns the Figure."""
    import matplotlib.pyplot as plt
    from matplotlib.colors import Normalize
    from matplotlib.ticker import MaxNLocator

    tau, states = _snapshot_window(motion)
    # A closed orbit ends where it starts: its last state is not drawn twice.
    closed = motion.cycle is not None or bool(motion.period)
    last = len(states) - 1
    picks = np.linspace(0, last, n_snapshots + closed)[:n_snapshots]
    picks = np.unique(picks.round().astype(int))
    fig = plt.figure(figsize=(8.0, 5.8), layout="constrained")
    ax = fig.add_subplot(projection="3d")
    norm = Normalize(tau[picks[0]], tau[picks[-1]] if picks.size > 1 else tau[picks[0]] + 1)
    cmap = plt.get_cmap("viridis")
    drawn = [np.zeros((1, 3))]  # the clamp

    def draw(U, **kw):
        _, d = frame_points_3d(model, U)
        xyz = np.column_stack([d["Z_g"], d["Y_g"], d["X_g"]])
        ax.plot(xyz[:, 0], xyz[:, 1], xyz[:, 2], **kw)
        drawn.append(xyz)

    for k in picks:
        draw(states[k], color=cmap(norm(tau[k])), lw=1.6)
    if static is not None:
        U, stable = static
        grey = stable is not True
        draw(
            U,
            color=UNSTABLE_COLOR if grey else "k",
            ls="--" if grey else "-",
            lw=1.4,
            label=_static_label(stable),
        )
    tip_tau, tip_states = _window(motion)
    tips = model.tip_coordinates(tip_states)
    # Light: over a long window the path is a band of many loops, under the snapshots.
    ax.plot(tips["Z_tip"], tips["Y_tip"], tips["X_tip"], color="0.6", lw=0.4, label="tip path")
    ax.plot([0.0], [0.0], [0.0], "ks", ms=7, label="clamp")
    _frame_3d(ax, np.vstack(drawn))
    for set_label, key in ((ax.set_xlabel, "Z"), (ax.set_ylabel, "Y"), (ax.set_zlabel, "X")):
        set_label(_AXIS[key], fontsize=10, labelpad=10)
    ax.tick_params(labelsize=9)
    spans = ax.get_box_aspect()
    for axis, span in zip((ax.xaxis, ax.yaxis, ax.zaxis), spans, strict=True):
        # Fewer ticks on a short side, where they would run into each other.
        axis.set_major_locator(MaxNLocator(nbins=max(2, round(4 * span / max(spans)))))
    # From above the plane's front side, so that the swing out of it shows.
    ax.view_init(elev=20, azim=-40)
    ax.legend(fontsize=10, loc="upper left")
    bar = fig.colorbar(plt.cm.ScalarMappable(norm, cmap), ax=ax, shrink=0.6, pad=0.08)
    bar.set_label(r"$\tau$ of the snapshot", fontsize=10)
    bar.ax.tick_params(labelsize=9)
    snaps, path = _window_text(motion, tau[picks]), _window_text(motion, tip_tau)
    if snaps == path:
        text = f"{picks.size} snapshots and the tip's path over {path}"
    else:
        text = f"{picks.size} snapshots over {snaps}, the tip's path over {path}"
    fig.suptitle(_caption(model, motion, text, width=90), fontsize=10)
    return fig

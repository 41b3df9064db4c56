"""Figures of the nonlinear oscillation (Section 5 of the paper).

:func:`plot_time_traces` (tip position against tau, Fig. 11), :func:`plot_phase_portrait`
(Fig. 12), :func:`plot_oscillating_shapes` (overlaid centerlines, insets of Figs. 7, 9),
:func:`plot_bifurcation` (extrema of a tip coordinate against v, unstable parts dashed,
Figs. 7, 9, 10) and :func:`animate` (a GIF of the moving pipe).  Every plot takes ``ax=None``
and returns the Axes.
"""

from __future__ import annotations

import math
import os
import textwrap
from collections.abc import Sequence

import numpy as np

from fempipe.model.discretization import Discretization
from fempipe.model.params import PAPER_CASE, VARIANT_FIELDS
from fempipe.plotting.style import finish_axes, new_axes, runs

__all__ = [
    "plot_time_traces",
    "plot_phase_portrait",
    "plot_oscillating_shapes",
    "plot_bifurcation",
    "diagram_figure",
    "diagram_figure_3d",
    "paper_panel",
    "animate",
    "animation_figure",
    "render_frames",
]

_LABEL = {"eta_tip": r"$\eta(1)$", "X_tip": r"$X_{g}(1)$", "Z_tip": r"$Z_{g}(1)$"}


def _tip_series(disc: Discretization, q: np.ndarray, qdot: np.ndarray | None, alpha: float) -> dict:
    """Tip coordinates (and their rates X_dot, Z_dot) of the states q, shape (m, n)."""
    from fempipe.model.kinematics import compute_tip, tip_velocity

    out = compute_tip(disc, np.atleast_2d(q), alpha)
    if qdot is not None:
        rates = tip_velocity(disc, np.atleast_2d(q), np.atleast_2d(qdot), alpha)
        out["Z_dot"] = rates["Z_tip"]
        out["X_dot"] = rates["X_tip"]
    return out


def plot_time_traces(disc: Discretization, t, q, alpha: float, ax=None, title: str | None = None):
    """Tip position in the global frame against time ``t`` of the states ``q`` (m, n), Fig. 11."""
    ax = new_axes(ax, (7, 3.5))
    tip = _tip_series(disc, q, None, alpha)
    ax.plot(t, tip["X_tip"], label=_LABEL["X_tip"] + " (along gravity)")
    ax.plot(t, tip["Z_tip"], label=_LABEL["Z_tip"] + " (horizontal)")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)
    finish_axes(ax, r"$\tau$", r"tip position ($/L$)", title)
    return ax


def plot_phase_portrait(
    disc: Discretization,
    q,
    qdot,
    alpha: float,
    ax=None,
    coordinate: str = "Z_tip",
    label=None,
    title=None,
):
    """Phase trajectory of a tip coordinate (Z_g(1) by default), Fig. 12."""
    if coordinate not in ("Z_tip", "X_tip"):
        raise ValueError(f"coordinate must be 'Z_tip' or 'X_tip', got {coordinate!r}")
    ax = new_axes(ax, (4.5, 4))
    tip = _tip_series(disc, q, qdot, alpha)
    dot = tip["Z_dot"] if coordinate == "Z_tip" else tip["X_dot"]
    ax.plot(tip[coordinate], dot, lw=1.0, label=label)
    finish_axes(ax, _LABEL[coordinate], r"$d$" + _LABEL[coordinate] + r"$/d\tau$", title)
    if label:
        ax.legend(fontsize="small")
    return ax


def plot_oscillating_shapes(
    disc: Discretization, q, alpha: float, ax=None, n_shapes: int = 12, title=None
):
    """Overlaid centerlines in the global frame: Z_g across, X_g (gravity) down the page.

    ``q`` (shape (m, n)) holds states over about one period; ``n_shapes`` of them are drawn.
    """
    import matplotlib.pyplot as plt

    from fempipe.model.kinematics import compute_shape

    ax = new_axes(ax, (4.5, 5))
    q = np.atleast_2d(q)
    idx = np.linspace(0, q.shape[0] - 1, min(n_shapes, q.shape[0])).round().astype(int)
    cmap = plt.get_cmap("viridis")
    for j, k in enumerate(idx):
        s = compute_shape(disc, q[k], alpha)
        ax.plot(
            s.Z_g,
            s.X_g,
            color=cmap(j / max(len(idx) - 1, 1)),
            lw=1.2,
            label="shapes over the shown time\n(color: early to late)" if j == 0 else None,
        )
    _global_frame(ax, alpha)
    ax.legend(fontsize=9, loc="best", framealpha=0.9)
    if title:
        ax.set_title(title)
    return ax


def _global_frame(ax, alpha: float) -> None:
    """The undeformed pipe, the clamp and the frame of the centerlines: gravity down the page."""
    ax.plot([0, np.sin(alpha)], [0, np.cos(alpha)], "k--", lw=0.8, label="undeformed")
    ax.plot([0], [0], "ks", ms=6, label="clamp")
    ax.set_aspect("equal")
    ax.set_xlabel(r"$Z_g$ ($/L$)")
    ax.set_ylabel(r"$X_g$ ($/L$, gravity $\downarrow$)")
    ax.set_xlim(-1.1, 1.1)
    ax.set_ylim(1.1, -1.1)  # X_g points along gravity: down the page
    ax.grid(alpha=0.3)


def plot_bifurcation(
    points: Sequence[dict],
    key: str = "eta_tip",
    ax=None,
    label=None,
    title=None,
    special_points: Sequence[dict] = (),
    caption: str | None = None,
    hopf_points: Sequence[dict] = (),
):
    """Extrema of a tip coordinate against v (Figs. 7, 9, 10).

    Parameters
    ----------
    points : sequence of dict
        Sweep points (``direction`` "up"/"down", :func:`fempipe.analyses.bifurcation.compute_bifurcation_diagram`),
        drawn as markers, and/or continuation points (:func:`fempipe.analyses.periodic.compute_cycle_diagram`:
        "static" equilibria, "continuation" orbits by ``branch``), drawn as lines, dashed where unstable.
    key : {"eta_tip", "X_tip", "Z_tip"}
    special_points : sequence of dict
        ``{"v", "type", "branch"}`` of cycle bifurcations: vertical marks.
    caption : str, optional
        Parameters, written small in the axes' corner.
    hopf_points : sequence of dict
        ``{"v", "branch"}`` (and the equilibrium's ``key`` where known): each branch of orbits
        starts at its marked Hopf point.
    """
    if key not in _LABEL:
        raise ValueError(f"key must be one of {sorted(_LABEL)}, got {key!r}")
    ax = new_axes(ax, (6, 4))
    style = {"up": ("o", "C0", "sweep up"), "down": ("x", "C3", "sweep down")}
    for direction, (marker, color, text) in style.items():
        pts = [p for p in points if p["direction"] == direction]
        if not pts:
            continue
        v = np.array([p["v"] for p in pts])
        lo = np.array([p[key][0] for p in pts], dtype=float)
        hi = np.array([p[key][1] for p in pts], dtype=float)
        lab = f"{label}: {text}" if label else text
        ax.plot(v, hi, marker, color=color, ms=5, mfc="none", label=lab)
        ax.plot(v, lo, marker, color=color, ms=5, mfc="none")
    _plot_continuation(ax, points, key, label, hopf_points)
    for k, sp in enumerate(special_points):
        ax.axvline(
            sp["v"], color="C2", lw=0.8, ls=":", label="cycle bifurcation" if k == 0 else None
        )
        ax.annotate(
            sp["type"].replace("_", " "),
            (sp["v"], 1.0),
            xycoords=("data", "axes fraction"),
            rotation=90,
            va="top",
            ha="right",
            fontsize=9,
            color="C2",
        )
    finish_axes(ax, r"$v$", _LABEL[key] + " extrema", title)
    ax.legend(fontsize="small")
    if caption:
        # Inside the axes, bottom left: kept by any layout engine.
        ax.text(0.01, 0.01, caption, transform=ax.transAxes, fontsize=6, va="bottom", wrap=True)
    return ax


def _plot_continuation(ax, points: Sequence[dict], key: str, label, hopf=()) -> None:
    """Equilibria and orbit branches, solid stable, dashed unstable, from their Hopf points."""
    static = sorted((p for p in points if p["direction"] == "static"), key=lambda p: p["v"])
    start = {}
    sv = np.array([p["v"] for p in static])
    sy = np.array([p[key][0] for p in static], dtype=float)
    for h in hopf:
        if key in h:  # the equilibrium at the Hopf point, also outside the requested v
            y = float(h[key][0])
        elif static and sv[0] <= h["v"] <= sv[-1]:
            y = float(np.interp(h["v"], sv, sy))
        else:
            continue
        ax.plot([h["v"]], [y], "D", color="k", ms=4, label=None if start else "Hopf point")
        start[h.get("branch")] = (h["v"], y)
    groups = {}
    for p in points:
        if p["direction"] == "static":
            groups.setdefault(("static", "static"), []).append(p)
        elif p["direction"] == "continuation":
            groups.setdefault(("cycle", p.get("branch", "")), []).append(p)
    shown = set()
    for k, ((kind, name), pts) in enumerate(sorted(groups.items())):
        if kind == "static":
            pts = sorted(pts, key=lambda p: p["v"])
            # The stability changes at a Hopf point between two equilibria, not at the
            # next requested v: the Hopf point joins the line with the later state's flag.
            for hv, hy in start.values():
                k = int(np.searchsorted([p["v"] for p in pts], hv))
                if 0 < k < len(pts) and pts[k - 1].get("stable") != pts[k].get("stable"):
                    pts.insert(k, {**pts[k], "v": hv, key: [hy, hy], "requested": False})
        color = "k" if kind == "static" else f"C{(k % 8) + 1}"
        v = np.array([p["v"] for p in pts])
        lo = np.array([p[key][0] for p in pts], dtype=float)
        hi = np.array([p[key][1] for p in pts], dtype=float)
        flags = [bool(p.get("stable")) for p in pts]
        if kind == "cycle" and name in start:
            # From the Hopf point (amplitude 0) with the first orbit's stability.
            hv, hy = start[name]
            v, lo, hi = np.r_[hv, v], np.r_[hy, lo], np.r_[hy, hi]
            flags = [flags[0], *flags]
            pts = [pts[0], *pts]
        for stable, sl in runs(flags):
            ls = "-" if stable else "--"
            what = "equilibria" if kind == "static" else f"orbits {name}"
            text = f"{what}, {'stable' if stable else 'unstable'}"
            if label:
                text = f"{label}: {text}"
            lab = None if text in shown else text
            shown.add(text)
            ax.plot(v[sl], hi[sl], ls, color=color, lw=1.3, label=lab)
            if kind == "cycle":
                ax.plot(v[sl], lo[sl], ls, color=color, lw=1.3)
        req = np.array([bool(p.get("requested", True)) for p in pts])
        if kind == "cycle" and name in start:
            req[0] = False
        if kind == "cycle" and req.any():
            ax.plot(v[req], hi[req], ".", color=color, ms=3)
            ax.plot(v[req], lo[req], ".", color=color, ms=3)


def _closed(q: np.ndarray) -> bool:
    """Whether the last state repeats the first (a closed periodic orbit)."""
    scale = max(float(np.max(np.abs(q))), 1e-300)
    return q.shape[0] > 2 and float(np.max(np.abs(q[-1] - q[0]))) <= 1e-6 * scale


def animation_figure(disc: Discretization, t, q, alpha: float, title: str | None = None):
    """``(fig, draw, n_frames)`` of :func:`animate`; ``draw(k)`` returns the changed artists.

    A closed orbit loses its last frame, so the looping GIF shows no state twice.
    """
    import matplotlib.pyplot as plt

    from fempipe.io.trajectory import CenterlineSampler

    q = np.atleast_2d(q)
    t = np.asarray(t, dtype=float)
    sampler = CenterlineSampler(disc, alpha, points_per_cell=2)
    period = None
    if _closed(q):
        period = float(t[-1] - t[0])
        q, t = q[:-1], t[:-1]
    fig, ax = plt.subplots(figsize=(4.4, 4.8), layout="constrained")
    _global_frame(ax, alpha)
    (line,) = ax.plot([], [], "C0", lw=2.5)
    (tip,) = ax.plot([], [], "C3o", ms=5)
    label = ax.text(0.03, 0.97, "", transform=ax.transAxes, va="top", fontsize=10)
    if title:
        ax.set_title(title, fontsize=9)

    def draw(k):
        s = sampler.shape(q[k])
        line.set_data(s.Z_g, s.X_g)
        tip.set_data([s.Z_g[-1]], [s.X_g[-1]])
        if period is None:
            label.set_text(rf"$\tau$ = {t[k]:.3f}")
        else:
            label.set_text(rf"$\tau - \tau_0$ = {t[k] - t[0]:.3f}  (T = {period:.3f})")
        return line, tip, label

    return fig, draw, q.shape[0]


def render_frames(fig, draw, n_frames: int, full_redraw: bool = False) -> list:
    """The frames of an animation figure as RGBA PIL images, one per frame.

    The figure is laid out and drawn once; each frame redraws only the artists ``draw(k)``
    returns (blitting), the last of their axes in drawing order, so its pixels are a full
    redraw's.  ``full_redraw`` draws every frame whole with ``FuncAnimation(..., blit=False)``:
    the reference the blitted frames are tested against.
    """
    from PIL import Image

    if full_redraw:
        return _redrawn_frames(fig, draw, n_frames)
    canvas = fig.canvas
    artists = draw(0)
    # Constrained layout starts from the previous layout: lay out once, draw the background
    # with the second layout, and fix it.
    fig.draw_without_rendering()
    for a in artists:
        a.set_animated(True)
    engine = fig.get_layout_engine()
    try:
        canvas.draw()
        fig.set_layout_engine("none")
        background = canvas.copy_from_bbox(fig.bbox)
        size = canvas.get_width_height()
        frames = []
        for k in range(n_frames):
            canvas.restore_region(background)
            for a in draw(k):
                a.axes.draw_artist(a)
            frames.append(Image.frombuffer("RGBA", size, canvas.buffer_rgba()).copy())
    finally:
        for a in artists:
            a.set_animated(False)
        fig.set_layout_engine(engine)
    return frames


def _redrawn_frames(fig, draw, n_frames: int) -> list:
    """The frames as ``FuncAnimation(..., blit=False)`` with a ``PillowWriter`` grabs them."""
    from io import BytesIO

    from matplotlib.animation import AbstractMovieWriter, FuncAnimation
    from PIL import Image

    class Grab(AbstractMovieWriter):
        def setup(self, fig, outfile, dpi=None):
            super().setup(fig, outfile, dpi=dpi)
            self.frames = []

        def grab_frame(self, **savefig_kwargs):
            buf = BytesIO()
            self.fig.savefig(buf, **{**savefig_kwargs, "format": "rgba", "dpi": self.dpi})
            self.frames.append(
                Image.frombuffer("RGBA", self.frame_size, buf.getbuffer(), "raw", "RGBA", 0, 1)
            )

        def finish(self):
            pass

    writer = Grab(fps=20)
    # Nothing is written to the file name: the writer keeps the frames.
    FuncAnimation(fig, draw, frames=n_frames, blit=False).save("frames.gif", writer=writer)
    return writer.frames


def animate(
    path: str | os.PathLike,
    disc: Discretization,
    t,
    q,
    alpha: float,
    fps: int = 20,
    title: str | None = None,
):
    """Write an animated GIF of the moving pipe in the global frame to ``path``; returns it."""
    import matplotlib.pyplot as plt

    from fempipe.io import write_gif

    fig, draw, n = animation_figure(disc, t, q, alpha, title=title)
    try:
        frames = render_frames(fig, draw, n)
    finally:
        plt.close(fig)
    write_gif(path, frames, fps=fps)
    return path


#: The diagram keys in the column order of the paper's Figs. 7-10.
_PAPER_KEYS = ("eta_tip", "X_tip", "Z_tip")
#: 3-D diagrams: marker per attractor kind, color per direction; filled where non-planar.
_MARKS = {
    "equilibrium": "s",
    "periodic": "o",
    "whirl": "D",
    "quasi-periodic": "^",
    "non-periodic": "x",
}
_COLORS = {"up": "tab:blue", "down": "tab:red"}
_LABELS_3D = {
    "Y_tip": "Y(1) (out of plane)",
    "eta_tip": "η(1)",
    "X_tip": "X_g(1)",
    "Z_tip": "Z_g(1)",
}


def diagram_figure(result: dict, key: str):
    """The figure of ``key`` of a ``fempipe bifurcation`` result, one panel per inclination."""
    import matplotlib.pyplot as plt

    from fempipe.plotting.layout import shared_legend

    p = result["params"]
    groups = sorted({pt["alpha"] for pt in result["points"]})
    fig, axes = plt.subplots(
        1, len(groups), figsize=(5.5 * len(groups), 4.6), squeeze=False, layout="constrained"
    )
    for ax, a in zip(axes[0], groups, strict=True):
        plot_bifurcation(
            [pt for pt in result["points"] if pt["alpha"] == a],
            key,
            ax=ax,
            title=f"α = {math.degrees(a):.4g}°, β = {p['beta']:.4g}, "
            f"γ = {p['gamma']:.4g}" + paper_panel(key, a, p),
            special_points=[s for s in result.get("special_points", []) if s["alpha"] == a],
            hopf_points=[h for h in result.get("hopf_points", []) if h["alpha"] == a],
        )
    shared_legend(fig, axes[0])
    disc = result.get("discretization", {})
    name = _mesh(disc)
    if disc.get("kind") != "fe":
        name = f"{name} {disc.get('n_modes', disc.get('n_dofs', ''))}"
    caption = f"μ = {p['mu']:.4g}, {name.strip()}; " + (
        "continuation of equilibria and periodic orbits (solid stable, dashed unstable; "
        "dots: requested v)"
        if result.get("method") == "continuation"
        else "sweeps of attractors up and down"
    )
    # Wrapped to the figure's width (about 70 characters of 9 pt per 5.5 in).
    fig.suptitle(textwrap.fill(caption, 70 * len(groups)), fontsize=9)
    return fig


def paper_panel(key: str, alpha: float, params: dict) -> str:
    """`` (cf. Fig. 8(b))``: the panel of the paper's Figs. 7-10 a diagram redraws, or ``""``.

    Fig. 7 is alpha = 0 with (a) eta(1), (b) X_g(1), (c) Z_g(1); Figs. 8, 9 and 10 are eta(1),
    X_g(1) and Z_g(1) with (a)-(d) alpha = pi/4, pi/2, 3pi/4, pi, all for the reference case.
    """
    if any(not math.isclose(params.get(k, math.nan), v) for k, v in PAPER_CASE.items()):
        return ""
    if any(params.get(k) for k in VARIANT_FIELDS):
        return ""  # a variant of the pipe: the paper has no such figure
    column = _PAPER_KEYS.index(key)
    if math.isclose(alpha, 0.0, abs_tol=1e-12):
        return f" (cf. Fig. 7({'abc'[column]}))"
    for k in range(1, 5):
        if math.isclose(alpha, k * math.pi / 4):
            return f" (cf. Fig. {8 + column}({'abcd'[k - 1]}))"
    return ""


def _mesh(disc: dict) -> str:
    """``P3:16``, or the modal kind."""
    if disc.get("kind") == "fe":
        return f"{disc.get('element')}:{disc.get('n_elements')}"
    return str(disc.get("kind", ""))


def diagram_figure_3d(result: dict, key: str):
    """[min, max] of ``key`` against v of a 3-D run: marker by attractor, color by sweep
    direction (down shifted a hair right), filled where the motion is non-planar."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    fig, ax = plt.subplots(figsize=(6.4, 4.6), layout="constrained")
    pts = result["points"]
    vs = [p["v"] for p in pts]
    shift = 0.004 * (max(vs) - min(vs)) if len(set(vs)) > 1 else 0.0
    for p in pts:
        x = p["v"] + (shift if p["direction"] == "down" else 0.0)
        c = _COLORS[p["direction"]]
        face = c if p["motion"] == "nonplanar" else "none"
        ax.plot(
            [x, x], p[key], ls="", marker=_MARKS.get(p["attractor"], "x"), ms=5, color=c, mfc=face
        )
    handles = [
        Line2D([], [], ls="-", lw=3, color=c, label=f"sweep {d}")
        for d, c in _COLORS.items()
        if any(p["direction"] == d for p in pts)
    ]
    handles += [
        Line2D([], [], ls="", marker=m, color="0.3", mfc="none", label=k)
        for k, m in _MARKS.items()
        if any(p["attractor"] == k for p in pts)
    ]
    handles.append(Line2D([], [], ls="", marker="o", color="0.3", mfc="0.3", label="non-planar"))
    ax.legend(handles=handles, fontsize=8, loc="best")
    ax.set_xlabel("v")
    ax.set_ylabel(_LABELS_3D[key] + " (/L), min and max")
    ax.grid(alpha=0.3)
    p = result["params"]
    caption = (
        f"3-D attractors, α = {math.degrees(p['alpha']):.4g}°, β = {p['beta']:.4g}, "
        f"γ = {p['gamma']:.4g}, μ = {p['mu']:.4g}, {_mesh(result.get('discretization', {}))}; "
        "open: planar motion, filled: non-planar"
    )
    ax.set_title(textwrap.fill(caption, 80), fontsize=9)
    return fig

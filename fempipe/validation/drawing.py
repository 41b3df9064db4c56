"""Drawing helpers shared by the figure cases (matplotlib imported lazily).

Conventions, as in the paper's figures: shapes in the global frame with Z_g
horizontal and X_g pointing down (gravity down), equal axis scales; the
mesh-converged FE result solid, the paper's modal N = 3 dashed and N = 4
dotted, one colour per flow velocity.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "LINESTYLES",
    "draw_diagram",
    "draw_orbit_shapes",
    "draw_shapes",
    "new_figure",
    "plot_shape_panels",
    "style_for",
]

LINESTYLES = {"FE": "-", "N = 3": "--", "N = 4": ":", "N = 2": "-."}


def style_for(label: str) -> str:
    """Line style by discretisation label (FE solid, N = 3 dashed, N = 4 dotted)."""
    if label.startswith("FE"):
        return LINESTYLES["FE"]
    return LINESTYLES.get(label, "-.")


def new_figure(n_panels: int, ncols: int | None = None, size: float = 3.6):
    """A figure with ``n_panels`` axes in a grid; returns (fig, flat list of axes)."""
    import matplotlib.pyplot as plt

    ncols = ncols or min(n_panels, 2)
    nrows = int(np.ceil(n_panels / ncols))
    fig, axes = plt.subplots(nrows, ncols, figsize=(size * ncols, size * nrows), squeeze=False)
    axes = list(axes.ravel())
    for ax in axes[n_panels:]:
        ax.set_visible(False)
    return fig, axes[:n_panels]


def draw_shapes(ax, families: dict, scale: float = 1.0, unit: str = "", v_label=None):
    """Overlay the centrelines of several discretisations.

    Parameters
    ----------
    ax : matplotlib Axes
    families : dict label -> StaticShapes
    scale : float
        Multiply lengths (e.g. L in mm for Fig. 2(b)).
    unit : str
        Axis unit text.
    v_label : callable, optional
        ``v_label(i, v) -> str`` for the legend (default ``v = ...``).
    """
    import matplotlib.pyplot as plt

    first = next(iter(families.values()))
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(first.v)))
    for label, fam in families.items():
        ls = style_for(label)
        for i, v in enumerate(fam.v):
            lab = None
            if label.startswith("FE"):
                lab = v_label(i, v) if v_label else f"v = {v:g}"
            ax.plot(fam.Z_g[i] * scale, fam.X_g[i] * scale, ls, color=colors[i], lw=1.2, label=lab)
    # one legend entry per discretisation style
    for label in families:
        ax.plot([], [], style_for(label), color="k", lw=1.0, label=label)
    ax.plot([0], [0], "ks", ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()  # X_g along gravity: down
    u = f" ({unit})" if unit else ""
    ax.set_xlabel(r"$Z_g$" + u)
    ax.set_ylabel(r"$X_g$" + u + r"  (gravity $\downarrow$)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=6, loc="best")
    return ax


def plot_shape_panels(result, fig, title, **figure_options):
    """One panel of overlaid shapes per entry of ``result.data["panels"]``.

    ``title(panel)`` gives each panel's title; ``figure_options`` go to
    :func:`new_figure` when ``fig`` is None.  Returns the figure.
    """
    panels = result.data["panels"]
    if fig is None:
        fig, axes = new_figure(len(panels), **figure_options)
    else:
        axes = list(fig.subplots(1, len(panels), squeeze=False).ravel())
    for ax, p in zip(axes, panels, strict=False):
        draw_shapes(ax, p.fams)
        ax.set_title(title(p))
    fig.tight_layout()
    return fig


def draw_diagram(ax, sweeps: dict, key: str, ylabel: str):
    """Tip extrema against v: FE open circles, N = 3 '+', N = 4 'x'."""
    marks = {"FE": ("o", 4), "N = 3": ("+", 7), "N = 4": ("x", 6)}
    for label, pts in sweeps.items():
        mk, ms = marks["FE" if label.startswith("FE") else label]
        v = np.array([p.v for p in pts])
        lo = np.array([getattr(p, key)[0] for p in pts])
        hi = np.array([getattr(p, key)[1] for p in pts])
        line = ax.plot(v, hi, mk, ms=ms, label=label, mfc="none" if mk == "o" else None)[0]
        ax.plot(v, lo, mk, ms=ms, color=line.get_color(), mfc="none" if mk == "o" else None)
    ax.set_xlabel("v")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return ax


def draw_orbit_shapes(ax, shapes: dict):
    """Oscillating shapes (or the static shape) in the global frame, one colour per v."""
    import matplotlib.pyplot as plt

    colors = plt.cm.viridis(np.linspace(0, 0.85, max(len(shapes), 1)))
    for c, (v, orb) in zip(colors, shapes.items(), strict=False):
        for i, (z, x) in enumerate(orb.shapes):
            ax.plot(z, x, color=c, lw=0.8, label=f"v = {v:g}" if i == 0 else None)
    ax.plot([0], [0], "ks", ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.set_xlabel(r"$Z_g$")
    ax.set_ylabel(r"$X_g$ (gravity $\downarrow$)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return ax

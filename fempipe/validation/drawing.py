"""Drawing helpers shared by the figure cases (matplotlib imported lazily).

As in the paper: shapes in the global frame, X_g down (gravity), equal scales; FE solid,
N = 3 dashed, N = 4 dotted, one color per flow velocity.
"""

from __future__ import annotations

import textwrap

import numpy as np

from fempipe.model.params import PAPER_CASE

from ..plotting.static import UNSTABLE_COLOR

LINESTYLES = {"FE": "-", "N = 3": "--", "N = 4": ":", "N = 2": "-."}
#: Colors of the discretizations where color does not already mean v or a
#: mode (Okabe & Ito, color-blind safe): the converged FE black.
DISC_COLORS = {"FE": "k", "N = 3": "#D55E00", "N = 4": "#0072B2", "N = 2": "#009E73"}


def legend_columns(fig, handles) -> int:
    """Columns of a legend below the panels that fit the figure's width (~0.075 in per character)."""
    longest = max((len(h.get_label()) for h in handles), default=1)
    per_entry = 0.75 + 0.075 * longest  # inches: handle, gap, ~0.075 in per character at 9 pt
    return max(1, min(len(handles), int(fig.get_figwidth() // per_entry)))


def color_for(label: str) -> str:
    """Color by discretization label (FE black, N = 3 vermilion, N = 4 blue)."""
    return DISC_COLORS["FE" if label.startswith("FE") else label]


def discretization_legend(fig, labels) -> None:
    """One legend below the panels for the discretizations (style and color)."""
    legend_below(
        fig, [(lb, {"ls": style_for(lb), "color": color_for(lb), "lw": 1.4}) for lb in labels]
    )


def label_axes(ax, xlabel: str, ylabel: str, title: str | None = None, grid=True, fontsize=10):
    """A panel's axis labels, its title and its grid (``grid="both"``: minor ticks too)."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    if title is not None:
        ax.set_title(title, fontsize=fontsize)
    if grid == "both":
        ax.grid(alpha=0.3, which="both")
    elif grid:
        ax.grid(alpha=0.3)


def legend_below(fig, entries, ncols: int | None = None, fontsize: float = 9) -> None:
    """One legend below the panels; ``entries``: ``(label, Line2D options)`` pairs."""
    from matplotlib.lines import Line2D

    handles = [Line2D([], [], label=label, **kw) for label, kw in entries]
    ncols = legend_columns(fig, handles) if ncols is None else ncols
    fig.legend(handles=handles, loc="outside lower center", ncols=ncols, fontsize=fontsize)


#: Legend entries of the variant cases: the classical theory's line, fempipe's FE dots.
DOTS = {"ls": "", "marker": "o", "color": "k"}
CLASSICAL_LINE = ("classical theory", {"color": "#0072B2", "lw": 1.5})


def style_for(label: str) -> str:
    """Line style by discretization label (FE solid, N = 3 dashed, N = 4 dotted)."""
    if label.startswith("FE"):
        return LINESTYLES["FE"]
    return LINESTYLES.get(label, "-.")


def new_figure(n_panels: int, ncols: int | None = None, size: float = 3.6):
    """A figure with ``n_panels`` axes in a grid; returns (fig, flat list of axes)."""
    import matplotlib.pyplot as plt

    ncols = ncols or min(n_panels, 2)
    nrows = int(np.ceil(n_panels / ncols))
    fig, axes = plt.subplots(
        nrows, ncols, figsize=(size * ncols, size * nrows), squeeze=False, layout="constrained"
    )
    axes = list(axes.ravel())
    for ax in axes[n_panels:]:
        ax.set_visible(False)
    return fig, axes[:n_panels]


def figure_panels(fig, n_panels: int, ncols: int | None = None, size: float = 3.6):
    """``(fig, axes)``: a :func:`new_figure`, or ``n_panels`` axes in one row of ``fig``."""
    if fig is None:
        return new_figure(n_panels, ncols=ncols, size=size)
    return fig, list(fig.subplots(1, n_panels, squeeze=False).ravel())


def paper_case_line() -> str:
    """``β = 0.142, γ = 18.9, μ = 0.005``: the paper's case as a line of a figure title."""

    return f"β = {PAPER_CASE['beta']:g}, γ = {PAPER_CASE['gamma']:g}, μ = {PAPER_CASE['mu']:g}"


def finish_figure(fig, title: str, parameters: str | None = None):
    """The report style: one wrapped title (``parameters`` on a line under it), panels lettered."""
    axes = [ax for ax in fig.axes if ax.get_visible() and ax.get_label() != "<colorbar>"]
    if len(axes) > 1:
        for k, ax in enumerate(axes):
            ax.set_title(f"({chr(ord('a') + k)}) {ax.get_title()}".rstrip(), fontsize=10)
    else:
        for ax in axes:
            ax.set_title(ax.get_title(), fontsize=10)
    # Wrapped to the figure's width (about 0.6 em per character at 12 pt).
    chars = max(20, int(fig.get_figwidth() * 72 / (0.62 * 12)))
    text = textwrap.fill(title, chars)
    if parameters:
        text += "\n" + parameters
    fig.suptitle(text, fontsize=12)
    if fig.get_layout_engine() is None:
        fig.set_layout_engine("constrained")
    # Room at the edges for half a tick label: equal-aspect panels widen their
    # data limits after the layout is made, which can put a tick at the edge.
    fig.get_layout_engine().set(w_pad=0.16, h_pad=0.06)
    return fig


def draw_shapes(
    ax,
    families: dict,
    scale: float = 1.0,
    unit: str = "",
    v_label=None,
    stable=None,
    legend: bool = True,
):
    """Overlay the centerlines of ``families`` (label -> StaticShapes), lengths times ``scale``;
    ``v_label(i, v)`` names the legend entries, states not ``stable`` are grey."""
    import matplotlib.pyplot as plt

    first = next(iter(families.values()))
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(first.v)))
    unstable = [False] * len(first.v) if stable is None else [not s for s in stable]
    for label, fam in families.items():
        ls = style_for(label)
        for i, v in enumerate(fam.v):
            lab = None
            if label.startswith("FE"):
                lab = v_label(i, v) if v_label else f"v = {v:g}"
                if unstable[i]:
                    lab += " (unstable)"
            color = UNSTABLE_COLOR if unstable[i] else colors[i]
            ax.plot(fam.Z_g[i] * scale, fam.X_g[i] * scale, ls, color=color, lw=1.2, label=lab)
    # one legend entry per discretization style
    for label in families:
        ax.plot([], [], style_for(label), color="k", lw=1.0, label=label)
    if any(unstable):
        ax.plot([], [], "-", color=UNSTABLE_COLOR, lw=1.2, label="grey: unstable state")
    ax.plot([0], [0], "ks", ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()  # X_g along gravity: down
    u = f" ({unit})" if unit else r" ($/L$)"
    label_axes(ax, r"$Z_g$" + u, r"$X_g$" + u + r"  (gravity $\downarrow$)")
    if legend:
        ax.legend(fontsize=9, loc="best")
    return ax


def plot_shape_panels(result, fig, title, figure_title: str, **figure_options):
    """One panel of overlaid shapes per ``result.data["panels"]``, titled ``title(panel)``."""
    panels = result.data["panels"]
    fig, axes = figure_panels(fig, len(panels), **figure_options)
    for ax, p in zip(axes, panels, strict=False):
        draw_shapes(ax, p.fams, stable=p.stable or None, legend=False)
        ax.set_title(title(p))
    _shape_legend(fig, panels)
    finish_figure(fig, figure_title)
    return fig


def _shape_legend(fig, panels) -> None:
    """One legend below the panels: colors are v, line styles discretizations."""
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    v = panels[0].fe.v
    colors = plt.cm.viridis(np.linspace(0.0, 0.9, len(v)))
    handles = [
        Line2D([], [], color=c, lw=2, label=f"v = {x:g}") for c, x in zip(colors, v, strict=True)
    ]
    meshes = ", ".join(dict.fromkeys(next(iter(p.fams))[3:] for p in panels))
    handles.append(Line2D([], [], color="k", lw=1.2, label=f"FE {meshes} (converged)"))
    for label in list(panels[0].fams)[1:]:
        handles.append(Line2D([], [], ls=style_for(label), color="k", lw=1.2, label=label))
    if any(not s for p in panels for s in p.stable):
        handles.append(
            Line2D([], [], color=UNSTABLE_COLOR, lw=2, label="grey: linearly unstable state")
        )
    fig.legend(
        handles=handles, loc="outside lower center", ncols=legend_columns(fig, handles), fontsize=9
    )


def _runs(stable: list) -> list[tuple[int, int, bool]]:
    """(start, stop, stable) of the runs of equal stability, sharing their boundary points."""
    out, i = [], 0
    while i < len(stable):
        j = i
        while j + 1 < len(stable) and stable[j + 1] == stable[i]:
            j += 1
        out.append((max(i - 1, 0) if out else i, j + 1, bool(stable[i])))
        i = j + 1
    return out


def _with_hopf(static: list, hopf: list, key: str) -> list:
    """(v, [lo, hi], stable) of the static points with the Hopf points inserted."""
    out = [(p.v, getattr(p, key), p.stable) for p in static]
    for h in hopf:
        vh = h["v"]
        k = next((i for i, p in enumerate(out) if p[0] > vh), None)
        if k is None or k == 0:
            continue
        (va, ya, sa), (vb, yb, _) = out[k - 1], out[k]
        w = (vh - va) / (vb - va)
        y = [(1 - w) * ya[0] + w * yb[0], (1 - w) * ya[1] + w * yb[1]]
        out.insert(k, (vh, y, sa))
    return out


def draw_continued(ax, diagrams: dict, key: str, ylabel: str, attractors: dict | None = None):
    """Continued diagrams by label: every branch's extrema, solid where stable, dashed where not;
    the stable state at each v marked (FE o, N = 3 +, N = 4 x, or ``attractors``); Hopf dots.
    """
    from matplotlib.lines import Line2D

    marks = {"FE": ("o", 4), "N = 3": ("+", 7), "N = 4": ("x", 6)}
    for label, dg in diagrams.items():
        c = color_for(label)
        lines = [_with_hopf(dg.static, dg.hopf, key)]
        lines += [[(p.v, getattr(p, key), p.stable) for p in br] for br in dg.branches.values()]
        for pts in lines:
            if not pts:
                continue
            v = np.array([p[0] for p in pts])
            st = [bool(p[2]) for p in pts]
            for side in (0, 1):
                y = np.array([p[1][side] for p in pts])
                for a, b, ok in _runs(st):
                    ax.plot(v[a:b], y[a:b], ls="-" if ok else "--", lw=0.9, color=c, alpha=0.8)
        att = dg.attractors() if attractors is None else attractors[label]
        att = [p for p in att if p is not None]
        mk, ms = marks["FE" if label.startswith("FE") else label]
        mfc = "none" if mk == "o" else None
        v = np.array([p.v for p in att])
        for side in (0, 1):
            y = np.array([getattr(p, key)[side] for p in att])
            ax.plot(v, y, mk, ms=ms, color=c, mfc=mfc, label=label if side else None)
        for h in dg.hopf:
            if dg.static:
                y0 = getattr(min(dg.static, key=lambda p, h=h: abs(p.v - h["v"])), key)[0]
                ax.plot([h["v"]], [y0], ".", ms=7, color=c)
    label_axes(ax, "v", ylabel + r" ($/L$)")
    handles, _ = ax.get_legend_handles_labels()
    handles += [
        Line2D([], [], ls="-", color="0.4", label="stable"),
        Line2D([], [], ls="--", color="0.4", label="unstable"),
    ]
    ax.legend(handles=handles, fontsize=9)
    return ax


def draw_orbit_shapes(ax, shapes: dict):
    """Shapes in the global frame, one color per v: an oscillation a bundle of thin lines, a static
    state one thick line above them.
    """
    import matplotlib.pyplot as plt

    colors = plt.cm.viridis(np.linspace(0, 0.85, max(len(shapes), 1)))
    for c, (v, orb) in zip(colors, shapes.items(), strict=False):
        static = len(orb.shapes) == 1
        kind = "static" if static else "oscillating"
        for i, (z, x) in enumerate(orb.shapes):
            ax.plot(
                z,
                x,
                color=c,
                lw=2.4 if static else 0.8,
                zorder=4 if static else 2,
                label=f"v = {v:g} ({kind})" if i == 0 else None,
            )
    ax.plot([0], [0], "ks", ms=4, zorder=5)
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    label_axes(ax, r"$Z_g$ ($/L$)", r"$X_g$ ($/L$, gravity $\downarrow$)")
    # Below the axes: the bundles fill the frame wherever a legend would go.
    ax.legend(fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.16), ncols=2)
    return ax

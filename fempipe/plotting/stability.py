"""Figures of the linear stability analysis (Figs. 5 and 6 of the paper).

:func:`plot_argand` (root loci in the plane of Omega = -i lambda, Fig. 5),
:func:`plot_stability_map` (v_cr against alpha, Fig. 6), :func:`plot_branches` (static
branches, dashed where unstable, events marked) and :func:`plot_mode_shape` (a mode about
its static state).  Each takes ``ax=None`` and returns the Axes.
"""

from __future__ import annotations

import numpy as np

from .layout import declutter
from .style import EVENT_MARKERS, finish_axes, mask_edges, new_axes, parameter_text

#: The color of the v_cr line (:func:`mark_v_cr`): no branch is drawn in it.
V_CR_COLOR = "#B2182B"

__all__ = [
    "MODE_COLORS",
    "V_CR_COLOR",
    "mark_v_cr",
    "mode_color",
    "plot_argand",
    "plot_stability_map",
    "plot_branches",
    "plot_mode_shape",
]


def plot_argand(
    locus,
    ax=None,
    mark_every: float | None = None,
    label_marks: bool = True,
    title=None,
    out_of_plane=None,
):
    """Argand diagram of a :class:`~fempipe.analyses.stability.RootLocus` (Fig. 5).

    Parameters
    ----------
    locus : RootLocus
        The loci in the plane (Eq. (32)), solid, dots every ``mark_every``.
    ax : Axes, optional
    mark_every : float, optional
        Mark the loci at multiples of this v (default: about six marks).
    label_marks : bool
        Write the v values next to the marks.
    title : str, optional
    out_of_plane : RootLocus, optional
        The loci out of the plane about the same static states, dashed with open triangles;
        not drawn again where they equal the in-plane loci (the title says so).
    """
    ax = new_axes(ax)
    v = np.asarray(locus.v)
    if mark_every is None:
        span = float(v.max() - v.min()) if v.size > 1 else 1.0
        mark_every = _nice_step(span / 6.0)
    marks = np.isclose(np.mod(v + 1e-9, mark_every), 0.0, atol=1e-6)
    seen: set = set()
    labels: list = []
    same = out_of_plane is not None and same_loci(locus, out_of_plane)
    both_planes = out_of_plane is not None and not same
    # The out-of-plane loci first, under the in-plane ones (whose dots then
    # show inside the open triangles where the two meet); not drawn at all
    # where they are the in-plane loci (the title says so).
    styles = [(locus, "-", "o", None, 2.5)]
    if both_planes:
        styles.insert(0, (out_of_plane, "--", "^", "none", 2.0))
    for loc, ls, marker, mfc, z_order in styles:
        _draw_loci(ax, loc, v, marks, (ls, marker, mfc, z_order), label_marks, seen, labels)
    ax.axhline(0.0, color="0.4", lw=0.8)
    ax.set_xlabel(r"Re $\Omega$ = Im $\lambda$")
    ax.set_ylabel(r"Im $\Omega$ = $-$Re $\lambda$   (< 0 unstable)")
    p = locus.params
    head = parameter_text(p, v=False)
    if same:
        head += ": out of the plane the same loci"
    ax.set_title(
        title
        or head
        + "\n"
        + rf"dots every $\Delta v$ = {mark_every:g} (labelled with v), "
        "arrows: v increasing",
        fontsize=10,
    )
    ax.grid(alpha=0.3)
    ax.legend(handles=_argand_handles(seen, both_planes), fontsize=9, loc="best")
    # Labels that would pile up (a divergence pair on the imaginary axis) are dropped.
    declutter(ax, labels, keep_clear=[ax.get_legend()])
    return ax


def _draw_loci(ax, loc, v, marks, style, label_marks: bool, seen: set, labels: list) -> None:
    """Draw one locus's modes with ``style`` (line style, marker, face color, zorder); record ``seen``, ``labels``."""
    ls, marker, mfc, z_order = style
    Om = np.where(loc.resolved, loc.Omega, np.nan)
    for j, mode in enumerate(loc.modes):
        z = Om[:, j]
        # One member of each conjugate pair: Re Omega = Im lambda >= 0.
        z = np.where(z.real >= -1e-12, z, np.nan)
        if np.all(np.isnan(z)):
            continue
        c = mode_color(int(mode))
        ax.plot(z.real, z.imag, ls, color=c, lw=1.4, zorder=z_order)
        seen.add(int(mode))
        direction_arrow(ax, z, c)
        m = marks & ~np.isnan(z)
        ax.plot(
            z.real[m],
            z.imag[m],
            marker,
            color=c,
            ms=3.5 if mfc is None else 6.0,
            mfc=mfc,
            zorder=z_order,
        )
        if label_marks:
            for x, y, vv in zip(z.real[m], z.imag[m], v[m], strict=True):
                labels.append(
                    ax.annotate(
                        f"{vv:g}",
                        (x, y),
                        fontsize=9,
                        color=c,
                        xytext=(3, 3),
                        textcoords="offset points",
                    )
                )


def _argand_handles(seen: set, both_planes: bool) -> list:
    """Legend handles: one per mode (its color), then the planes' line styles."""
    from matplotlib.lines import Line2D

    handles = [
        Line2D([], [], color=mode_color(m), ls="-", lw=1.4, label=f"mode {m}") for m in sorted(seen)
    ]
    if both_planes:
        handles += [
            Line2D([], [], color="0.3", ls="-", marker="o", ms=3.5, label="in the plane"),
            Line2D(
                [],
                [],
                color="0.3",
                ls="--",
                marker="^",
                ms=6.0,
                mfc="none",
                label="out of the plane",
            ),
        ]
    return handles


def same_loci(a, b, rtol: float = 1e-8) -> bool:
    """Whether two root loci have the same eigenvalues mode by mode (to ``rtol`` of |lambda|, members as a set)."""
    from itertools import permutations

    if not np.array_equal(a.modes, b.modes) or not np.array_equal(a.resolved, b.resolved):
        return False
    la = np.where(a.resolved, a.lam, 0.0)
    lb = np.where(b.resolved, b.lam, 0.0)
    for mode in np.unique(a.modes):
        cols = np.flatnonzero(a.modes == mode)
        scale = rtol * np.maximum(1.0, np.abs(la[:, cols]))
        worst = np.full(la.shape[0], np.inf)
        for perm in permutations(cols):
            excess = np.abs(la[:, cols] - lb[:, list(perm)]) - scale
            worst = np.minimum(worst, excess.max(axis=1))
        if np.any(worst > 0):
            return False
    return True


#: Color-blind-safe colors of modes 1, 2, 3, ... (Okabe & Ito).
MODE_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000")


def mode_color(mode: int):
    """The color of a mode number in every stability figure."""
    return MODE_COLORS[(mode - 1) % len(MODE_COLORS)]


def direction_arrow(ax, z: np.ndarray, color) -> None:
    """An arrowhead half-way along a locus, pointing towards increasing v."""
    ok = np.flatnonzero(~np.isnan(z))
    if ok.size < 3:
        return
    k = ok[ok.size // 2]
    if k + 1 > ok[-1] or np.isnan(z[k + 1]) or z[k + 1] == z[k]:
        return
    ax.annotate(
        "",
        xy=(z[k + 1].real, z[k + 1].imag),
        xytext=(z[k].real, z[k].imag),
        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.2, "mutation_scale": 14},
    )


def _nice_step(x: float) -> float:
    """The smallest of 1, 2, 5, 10 times a power of ten at least ``x``."""
    if x <= 0:
        return 1.0
    e = 10.0 ** np.floor(np.log10(x))
    for f in (1.0, 2.0, 5.0, 10.0):
        if x <= f * e:
            return f * e
    return 10.0 * e


def plot_stability_map(smap, ax=None, title=None):
    """Flutter velocity against alpha per (beta, gamma) of a :class:`~fempipe.analyses.stability.StabilityMap`.

    Lines: the first flutter velocity of the primary branch (Fig. 6); an earlier loss of
    stability (divergence, fold) is an open square.  In three dimensions (``smap.planar``
    False) the motion out of the plane is dashed with open triangles, under a pale band along
    the 3-D v_cr.  The key is below the axes.
    """
    if not getattr(smap, "planar", True):
        return _plot_map_in_planes(smap, ax, title)
    ax = new_axes(ax)
    a = np.asarray(smap.alphas) / np.pi
    flutter, vcr = smap.array("v_flutter"), smap.array("v_cr")
    for c, (beta, gamma) in enumerate(smap.curves):
        (line,) = ax.plot(
            a,
            flutter[c],
            "o-",
            ms=4,
            mfc="none",  # open, as the title's key says
            lw=1.2,
            label=rf"$\beta$ = {beta:g}, $\gamma$ = {gamma:g}",
        )
        other = np.array([pt.get("type") in ("divergence", "fold") for pt in smap.points[c]])
        if other.any():
            ax.plot(a[other], vcr[c][other], "s", ms=5, mfc="none", color=line.get_color())
    finish_axes(
        ax,
        r"$\alpha/\pi$",
        r"$v_{cr}$",
        title
        or rf"flutter velocity (○, $\mu$ = {smap.base.mu:g}); □ earlier loss of stability "
        "(divergence, fold)",
        fontsize=10,
    )
    ax.legend(fontsize=9)
    return ax


#: The band along v_cr in three dimensions (:func:`plot_stability_map`).
_BAND = {"lw": 8.0, "alpha": 0.22, "solid_capstyle": "round"}


def _plot_map_in_planes(smap, ax, title):
    """:func:`plot_stability_map` of a map in three dimensions (its docstring)."""
    from matplotlib.lines import Line2D

    ax = new_axes(ax, size=(6.4, 5.4))
    a = np.asarray(smap.alphas) / np.pi
    vcr = smap.array("v_cr")
    for c, (beta, gamma) in enumerate(smap.curves):
        (line,) = ax.plot(
            a,
            smap.array("v_flutter_in_plane")[c],
            "o-",
            ms=4,
            mfc="none",  # open, as the title's key says
            lw=1.2,
            zorder=3,
            label=rf"$\beta$ = {beta:g}, $\gamma$ = {gamma:g}",
        )
        color = line.get_color()
        ax.plot(
            a,
            smap.array("v_flutter_out_of_plane")[c],
            "^--",
            ms=5,
            mfc="none",
            lw=1.2,
            color=color,
            zorder=2.5,
        )
        for plane, marker in (("in_plane", "s"), ("out_of_plane", "D")):
            other = np.array(
                [pt.get(f"type_{plane}") in ("divergence", "fold") for pt in smap.points[c]]
            )
            if other.any():
                v_plane = smap.array(f"v_cr_{plane}")[c]
                ax.plot(
                    a[other],
                    v_plane[other],
                    marker,
                    ms=5 if marker == "s" else 4.5,
                    mfc="none",
                    color=color,
                    zorder=3,
                )
        # The band joins flutter velocities only: v_cr jumps where the first loss
        # becomes a divergence or a fold (alpha = pi), marked by a pale disc.
        first = np.array([pt.get("type") == "flutter" for pt in smap.points[c]])
        ax.plot(a, np.where(first, vcr[c], np.nan), "-", color=color, zorder=1, **_BAND)
        if (~first).any():
            ax.scatter(
                a[~first],
                vcr[c][~first],
                s=(_BAND["lw"] + 2) ** 2,
                linewidths=0,
                color=color,
                alpha=_BAND["alpha"],
                zorder=1,
            )
    finish_axes(
        ax,
        r"$\alpha/\pi$",
        r"$v_{cr}$",
        title
        or rf"critical flow velocity, $\mu$ = {smap.base.mu:g}: in the plane ○ flutter, "
        "□ earlier loss\n(divergence, fold); out of the plane △, ◇; band: the first of the two",
        fontsize=10,
    )
    handles, _ = ax.get_legend_handles_labels()
    grey = "0.35"
    handles += [
        Line2D([], [], color=grey, ls="-", marker="o", ms=4, mfc="none", label="in the plane"),
        Line2D([], [], color=grey, ls="--", marker="^", ms=5, mfc="none", label="out of the plane"),
        Line2D([], [], color=grey, label=r"$v_{cr}$ in 3-D (first of the two)", **_BAND),
    ]
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    if isinstance(ax.figure.get_layout_engine(), ConstrainedLayoutEngine):
        ax.figure.legend(
            handles=handles, loc="outside lower center", ncols=2, fontsize=9, frameon=False
        )
    else:  # "outside" needs the constrained layout
        ax.legend(handles=handles, fontsize=9)
    return ax


def mark_v_cr(ax, event, plane: str | None = None):
    """A vertical line at the ``event``'s v_cr, its value, kind and plane in the label; None without one."""
    if event is None:
        return None
    plane = plane or {"in": " in the plane", "out": " out of the plane"}.get(event.plane, "")
    return ax.axvline(
        event.v,
        color=V_CR_COLOR,
        lw=1.1,
        zorder=1,
        label=rf"$v_{{cr}}$ = {event.v:.5g} ({event.type}{plane})",
    )


def plot_branches(result, ax=None, title=None):
    """theta_tip against v of a :class:`~fempipe.analyses.stability.StabilityResult`'s branches.

    Solid where stable, dashed where not; events marked (○ flutter, □ divergence,
    △ restabilization, ◇ fold); a vertical line at v_cr.
    """
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    ax = new_axes(ax)
    colors = plt.cm.tab10(np.arange(10))
    for i, b in enumerate(result.branches):
        c = colors[i % 10]
        stable = b.n_unstable == 0
        # Stable samples solid; unstable ones dashed, joined to their neighbours.
        ax.plot(b.v, np.where(stable, b.theta_tip, np.nan), "-", color=c, lw=1.2, label=b.name)
        dashed = ~stable | mask_edges(~stable)
        ax.plot(b.v, np.where(dashed, b.theta_tip, np.nan), "--", color=c, lw=1.2)
        for ev in b.events:
            j = int(np.argmin(np.abs(b.v - ev.v)))
            ax.plot(
                ev.v, b.theta_tip[j], EVENT_MARKERS.get(ev.type, "x"), color=c, mfc="none", ms=6
            )
    mark_v_cr(ax, result.critical)
    handles, _ = ax.get_legend_handles_labels()
    handles += [
        Line2D([], [], color="0.3", ls="", marker=EVENT_MARKERS.get(k, "x"), mfc="none", label=k)
        for k in dict.fromkeys(e.type for e in result.events)
    ]
    finish_axes(
        ax,
        "v",
        r"$\theta(1)$ of the static state (rad)",
        title or f"{parameter_text(result.params, v=False)}: solid stable, dashed unstable",
        fontsize=10,
    )
    ax.legend(handles=handles, fontsize=9)
    return ax


def plot_mode_shape(shape, ax=None, amplitude: float = 0.15, phases: int = 8, title=None):
    """A mode about its static state in the global frame: ``X + amplitude Re(dX e^{i phi})`` over ``phases``."""
    ax = new_axes(ax, size=(4.5, 5.0))
    ax.plot(shape.Z_static, shape.X_static, "k-", lw=2.0, label="static")
    for k, phi in enumerate(np.linspace(0.0, 2 * np.pi, phases, endpoint=False)):
        rot = np.exp(1j * phi)
        ax.plot(
            shape.Z_static + amplitude * (shape.Z_g * rot).real,
            shape.X_static + amplitude * (shape.X_g * rot).real,
            "-",
            lw=0.8,
            alpha=0.6,
            color="C0",
            label="mode" if k == 0 else None,
        )
    ax.invert_yaxis()
    ax.set_aspect("equal")
    ax.set_xlabel(r"$Z_g$")
    ax.set_ylabel(r"$X_g$ (along gravity)")
    lam = shape.lam
    ax.set_title(
        title or rf"mode {shape.mode}: $\lambda$ = {lam.real:.4g} {lam.imag:+.4g}i", fontsize=9
    )
    ax.legend(fontsize=9)
    return ax

"""Figures of static deformation: deformed centerlines in the global frame.

As in the paper's Figs. 2-4: gravity down the page (X_g of Eq. (28)), Z_g horizontal,
equal scales, the clamp at the origin.  A linearly unstable state is drawn grey and dashed,
one unstable only out of the plane grey and dash-dotted, each with its legend key.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

__all__ = ["OUT_OF_PLANE_STYLE", "UNSTABLE_COLOR", "plot_shapes"]

#: Color of linearly unstable static states (drawn dashed).
UNSTABLE_COLOR = "0.55"
#: Line style of the states unstable out of the plane only (grey too).
OUT_OF_PLANE_STYLE = "-."


def _as_list(alpha, n: int) -> list[float | None]:
    if alpha is None or np.ndim(alpha) == 0:
        return [alpha] * n
    alpha = list(alpha)
    if len(alpha) != n:
        raise ValueError(f"alpha must be a float or one value per shape ({n}), got {len(alpha)}")
    return alpha


def _clamp_angle(s) -> float:
    """Undeformed direction from the first segment: theta(0) = 0, so it is alpha."""
    return float(np.arctan2(s.Z_g[1] - s.Z_g[0], s.X_g[1] - s.X_g[0]))


def plot_shapes(
    shapes: Sequence,
    labels: Sequence[str] | None = None,
    ax=None,
    si_length: float | None = None,
    alpha: float | Sequence[float] | None = None,
    max_labels: int = 12,
    title: str | None = None,
    stable: Sequence[bool | None] | None = None,
    stable_in_plane: Sequence[bool | None] | None = None,
):
    """Deformed centerlines (X_g, Z_g) with gravity pointing down.

    Parameters
    ----------
    shapes : sequence of Shape
        Dimensionless (Eq. (28)).
    labels : sequence of str, optional
        One legend entry per shape.
    ax : matplotlib Axes, optional
    si_length : float, optional
        Pipe length L in m: coordinates in mm.
    alpha : float or sequence of float, optional
        Inclination(s) for the undeformed pipe; inferred from each shape if None.
    max_labels : int
        At most this many legend entries.
    title : str, optional
    stable : sequence of bool or None, optional
        Linear stability per state; False is drawn grey and dashed, "(unstable)".
    stable_in_plane : sequence of bool or None, optional
        With ``stable``, the in-plane verdict: unstable but stable in the plane is drawn
        dash-dotted, "(unstable out of the plane)".
    """
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 5.6), layout="constrained")
    n = len(shapes)
    if labels is not None and len(labels) != n:
        raise ValueError(f"got {n} shapes but {len(labels)} labels")
    scale = 1.0 if si_length is None else 1e3 * float(si_length)
    alphas = [
        a if a is not None else _clamp_angle(s)
        for a, s in zip(_as_list(alpha, n), shapes, strict=True)
    ]
    unstable, out_only, spatial = _instability_kinds(n, stable, stable_in_plane)

    for k, a in enumerate(dict.fromkeys(round(x, 12) for x in alphas)):
        tx, tz = np.cos(a), np.sin(a)  # (X, Z) direction of the undeformed pipe
        ax.plot(
            [0.0, tz * scale],
            [0.0, tx * scale],
            ls=":",
            color="k",
            lw=0.9,
            label="undeformed" if k == 0 else None,
            zorder=1,
        )
        _draw_clamp(ax, tx, tz, 0.06 * scale)

    _draw_states(ax, shapes, labels, scale, max_labels, unstable, out_only, spatial)
    _finish_axes(ax, scale, si_length)
    if labels is not None or n:
        ax.legend(fontsize=9, loc="best", framealpha=0.85)
    if title:
        ax.set_title(title)
    return ax


def _instability_kinds(n: int, stable, stable_in_plane) -> tuple[list, list, bool]:
    """``(unstable, out_only, spatial)``: flags per state, and whether in-plane verdicts were given."""
    if stable is None:
        stable = [None] * n
    elif len(stable) != n:
        raise ValueError(f"got {n} shapes but {len(stable)} stability flags")
    unstable = [flag is not None and not bool(flag) for flag in stable]
    if stable_in_plane is not None and len(stable_in_plane) != n:
        raise ValueError(f"got {n} shapes but {len(stable_in_plane)} in-plane stability flags")
    spatial = stable_in_plane is not None
    # Unstable out of the plane only: unstable, and stable in the plane.
    out_only = [
        u and spatial and stable_in_plane[i] is not None and bool(stable_in_plane[i])
        for i, u in enumerate(unstable)
    ]
    return unstable, out_only, spatial


def _draw_states(ax, shapes, labels, scale, max_labels, unstable, out_only, spatial) -> None:
    """The deformed centerlines and their tips, then the legend keys of the unstable kinds."""
    from matplotlib import colormaps

    n = len(shapes)
    cmap = colormaps["viridis"]
    colors = cmap(np.linspace(0.0, 0.9, n)) if n > 1 else [cmap(0.0)]
    every = max(1, int(np.ceil(n / max_labels)))
    for i, s in enumerate(shapes):
        lab = labels[i] if labels is not None and (i % every == 0 or i == n - 1) else None
        if lab is not None and unstable[i]:
            where = " out of the plane" if out_only[i] else " in the plane" if spatial else ""
            lab = f"{lab} (unstable{where})"
        color = UNSTABLE_COLOR if unstable[i] else colors[i]
        ls = OUT_OF_PLANE_STYLE if out_only[i] else "--" if unstable[i] else "-"
        ax.plot(
            np.asarray(s.Z_g) * scale,
            np.asarray(s.X_g) * scale,
            ls=ls,
            color=color,
            lw=1.2 if unstable[i] else 1.6,
            label=lab,
            zorder=2,
        )
        ax.plot(
            s.Z_g[-1] * scale,
            s.X_g[-1] * scale,
            "o",
            ms=3,
            color=color,
            mfc="none" if unstable[i] else color,
            zorder=3,
        )
    in_plane = [u and not o for u, o in zip(unstable, out_only, strict=True)]
    if any(in_plane):
        key = "grey dashed: unstable in the plane" if spatial else "grey dashed: unstable"
        ax.plot([], [], ls="--", color=UNSTABLE_COLOR, lw=1.2, label=key)
    if any(out_only):
        ax.plot(
            [],
            [],
            ls=OUT_OF_PLANE_STYLE,
            color=UNSTABLE_COLOR,
            lw=1.2,
            label="grey dash-dot: unstable out of the plane only",
        )


def _finish_axes(ax, scale: float, si_length: float | None) -> None:
    """Equal scales, gravity down the page, axis labels, grid and the gravity arrow."""
    ax.set_aspect("equal", adjustable="datalim")
    # Include the clamp and a margin so the clamp is never cut off.
    ax.update_datalim([(-0.1 * scale, -0.1 * scale), (0.1 * scale, 0.1 * scale)])
    ax.autoscale_view()
    ax.invert_yaxis()  # X_g points along gravity: down the page
    if si_length is None:
        ax.set_xlabel(r"$Z_g$  (horizontal, $/L$)")
        ax.set_ylabel(r"$X_g$  (along gravity, $/L$)")
    else:
        ax.set_xlabel(r"$Z_g\,L$  (mm)")
        ax.set_ylabel(r"$X_g\,L$  (mm, along gravity)")
    ax.grid(True, lw=0.4, alpha=0.5)
    # Gravity arrow in the lower right corner (the pipe hangs away from it), in axes coordinates: always points down.
    ax.annotate(
        "",
        xy=(0.97, 0.04),
        xytext=(0.97, 0.17),
        xycoords="axes fraction",
        arrowprops={"arrowstyle": "-|>", "color": "k", "lw": 1.2},
    )
    ax.text(0.95, 0.105, "$g$", transform=ax.transAxes, ha="right", va="center")


def _draw_clamp(ax, tx: float, tz: float, size: float) -> None:
    """A wall across the pipe at the origin, hatched on the side away from the pipe."""
    wx, wz = -tz, tx
    ax.plot([-wz * size, wz * size], [-wx * size, wx * size], color="k", lw=2.5, zorder=4)
    for s in np.linspace(-1.0, 1.0, 6):
        x0, z0 = s * wx * size, s * wz * size
        x1 = x0 - 0.45 * size * tx + 0.3 * size * wx
        z1 = z0 - 0.45 * size * tz + 0.3 * size * wz
        ax.plot([z0, z1], [x0, x1], color="k", lw=0.8, zorder=4)

"""The static branches and their stability in three dimensions (``fempipe critical``)."""

from __future__ import annotations

import numpy as np

from .stability import mark_v_cr
from .static import OUT_OF_PLANE_STYLE
from .style import EVENT_MARKERS, new_axes, parameter_text, place_legend, runs


def _monotone(v: np.ndarray) -> bool:
    dv = np.diff(v)
    return bool(np.all(dv >= 0) or np.all(dv <= 0))


def _unstable_at(v: np.ndarray, theta: np.ndarray, branch, monotone: bool) -> np.ndarray:
    """Whether one plane's ``branch`` is unstable at the points (v, theta(1)), by its events or nearest sample."""
    if branch is None or branch.v.size == 0:
        return np.zeros(v.size, bool)
    if monotone:
        out = np.full(v.size, branch.n_unstable[np.argmin(branch.v)] > 0)
        events = [e for e in branch.events if e.type != "fold" and not e.at_start]
        for e in sorted(events, key=lambda e: e.v):
            out[v >= e.v] = not e.stable_after
        return out
    d = np.hypot(v[:, None] - branch.v[None, :], theta[:, None] - branch.theta_tip[None, :])
    return branch.n_unstable[np.argmin(d, axis=1)] > 0


def _theta_at(b, v: float) -> float:
    """theta(1) of branch ``b`` at ``v``, interpolated about the sample nearest in v."""
    j = int(np.argmin(np.abs(b.v - v)))
    for k in (j - 1, j):
        if 0 <= k < b.v.size - 1 and (b.v[k] - v) * (b.v[k + 1] - v) <= 0 and b.v[k] != b.v[k + 1]:
            w = (v - b.v[k]) / (b.v[k + 1] - b.v[k])
            return float(b.theta_tip[k] + w * (b.theta_tip[k + 1] - b.theta_tip[k]))
    return float(b.theta_tip[j])


def branch_pieces(b, bo) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(v, theta, kind)``: the branch's samples with both planes' events inserted, kind per
    segment 0 (stable in 3-D), 1 (unstable in the plane) or 2 (unstable out of it only).

    ``b``, ``bo``: the in-plane and out-of-plane analyses of one branch (``bo`` None: in-plane alone).
    """
    v, theta = b.v, b.theta_tip
    monotone = _monotone(v)
    if monotone and v.size > 1:
        events = [e.v for br in (b, bo) if br is not None for e in br.events]
        inside = [x for x in events if min(v[0], v[-1]) < x < max(v[0], v[-1])]
        order = 1 if v[-1] >= v[0] else -1
        v = np.unique(np.concatenate([v, inside]))[::order]
        theta = np.interp(v, b.v[::order], b.theta_tip[::order])
    if v.size < 2:
        return v, theta, np.zeros(0, int)
    mid_v, mid_theta = (v[1:] + v[:-1]) / 2, (theta[1:] + theta[:-1]) / 2
    unstable_in = _unstable_at(mid_v, mid_theta, b, monotone)
    unstable_out = _unstable_at(mid_v, mid_theta, bo, monotone)
    kind = np.where(unstable_in, 1, np.where(unstable_out, 2, 0))
    return v, theta, kind


#: The marks of the events: in the plane open (a white face hides the curve) and large,
#: out of it filled, small and white-edged, drawn over them, so that events at the same
#: v show both (the straight pipe loses stability in every plane at once).
_EVENT_STYLE = {
    "in": {"ms": 13.0, "mew": 1.8, "mfc": "white", "zorder": 4},
    "out": {"ms": 6.0, "mew": 0.7, "mec": "white", "zorder": 5},
}
#: The pieces of a branch: stable in 3-D, unstable in the plane, out of it only (the
#: dash-dot of the static shapes' figure, :data:`fempipe.plotting.static.OUT_OF_PLANE_STYLE`).
_PIECES = (("-", 1.8), ("--", 1.4), (OUT_OF_PLANE_STYLE, 2.2))
#: First losses of the two planes closer than this share of the v-range get a zoomed inset.
ZOOM_BELOW = 0.05


def _draw_branches(ax, result, colors) -> list:
    """The branches' pieces and the events of both planes; returns the event marks."""
    outs = {b.name: b for b in result.out_of_plane.branches}
    marks = []
    for i, b in enumerate(result.in_plane.branches):
        c = colors[i % len(colors)]
        bo = outs.get(b.name)
        v, theta, kind = branch_pieces(b, bo)
        for k, sl in runs(kind):
            ls, lw = _PIECES[k]
            ax.plot(v[sl], theta[sl], ls=ls, color=c, lw=lw)
        for branch, plane in ((b, "in"), (bo, "out")):
            if branch is None:
                continue
            for ev in branch.events:
                if ev.type == "fold" and plane == "out":  # the static branch's: drawn once
                    continue
                (mark,) = ax.plot(
                    ev.v,
                    _theta_at(b, ev.v),
                    ls="",
                    marker=EVENT_MARKERS.get(ev.type, "x"),
                    color=c,
                    **({"mfc": c} if plane == "out" else {}),
                    gid=f"event {plane} {ev.type} {b.name}",
                    **_EVENT_STYLE[plane],
                )
                marks.append(mark)
    return marks


def _key(result, colors, v_cr_line) -> list:
    """Legend handles: the branches, the styles, the event kinds present, the planes, v_cr."""
    from matplotlib.lines import Line2D

    grey = "0.3"
    key = [
        Line2D([], [], color=colors[i % len(colors)], lw=2.0, label=f"branch {b.name}")
        for i, b in enumerate(result.in_plane.branches)
    ]
    key += [
        Line2D([], [], color=grey, ls=ls, lw=lw, label=label)
        for (ls, lw), label in zip(
            _PIECES, ("stable (3-D)", "unstable in the plane", "unstable out of the plane only"),
            strict=True,
        )
    ]  # fmt: skip
    kinds = dict.fromkeys(e.type for e in result.events)
    key += [
        Line2D([], [], color=grey, ls="", marker=EVENT_MARKERS.get(k, "x"), mfc="none", label=k)
        for k in kinds
    ]
    for plane, label in (("in", "event in the plane"), ("out", "event out of the plane")):
        style = {"mfc": grey} | {k: x for k, x in _EVENT_STYLE[plane].items() if k != "zorder"}
        key.append(Line2D([], [], color=grey, ls="", marker="o", label=label, **style))
    if v_cr_line is not None:
        key.append(v_cr_line)
    return key


def _plane_words(result) -> str | None:
    """The words ' in both planes' if both planes lose stability at the same v, else None."""
    vi, vo = result.in_plane.v_cr, result.out_of_plane.v_cr
    return " in both planes" if vi is not None and vi == vo else None


def _zoom_window(result) -> tuple[float, float] | None:
    """The v-interval about the two planes' first losses when too close to tell apart, else None."""
    vi, vo = result.in_plane.v_cr, result.out_of_plane.v_cr
    lo, hi = result.in_plane.v_range
    if vi is None or vo is None or vi == vo or abs(vi - vo) >= ZOOM_BELOW * (hi - lo):
        return None
    pad = 1.5 * abs(vi - vo)
    return max(lo, min(vi, vo) - pad), min(hi, max(vi, vo) + pad)


def _emptiest_corner(ax, size: float) -> list[float]:
    """Bounds (axes fraction) of the corner box of ``size`` that covers the fewest data points."""
    pts = [
        ax.transAxes.inverted().transform(ax.transData.transform(line.get_xydata()))
        for line in ax.get_lines()
    ]
    pts = np.vstack([p[np.isfinite(p).all(axis=1)] for p in pts])
    best, corner = None, None
    # Room for the inset's own tick labels (left of it and under it) and title (above).
    for x0 in (0.97 - size, 0.15):  # right first, then left
        for y0 in (0.12, 0.9 - size):
            box = (pts[:, 0] > x0 - 0.05) & (pts[:, 0] < x0 + size + 0.03)
            box &= (pts[:, 1] > y0 - 0.06) & (pts[:, 1] < y0 + size + 0.08)
            if best is None or box.sum() < best:
                best, corner = int(box.sum()), [x0, y0, size, size]
    return corner


def _zoom(ax, result, colors, window) -> None:
    """An inset of the branches over ``window`` in v, in the emptiest corner of ``ax``."""
    from matplotlib.ticker import MaxNLocator

    lo, hi = window
    outs = {b.name: b for b in result.out_of_plane.branches}
    ys = []
    for b in result.in_plane.branches:
        v, theta, _ = branch_pieces(b, outs.get(b.name))
        near = (v >= lo) & (v <= hi)
        ys.extend(theta[near])
        if _monotone(b.v):
            ys.extend(_theta_at(b, x) for x in (lo, hi) if min(b.v) <= x <= max(b.v))
    if not ys:
        return
    y0, y1 = min(ys), max(ys)
    pad = 0.2 * max(y1 - y0, 1e-9)
    ax.set_xlim(ax.get_xlim())  # the corner is chosen on the final limits
    ax.set_ylim(ax.get_ylim())
    inset = ax.inset_axes(_emptiest_corner(ax, 0.4))
    _draw_branches(inset, result, colors)
    mark_v_cr(inset, result.critical, _plane_words(result))
    inset.set_xlim(lo, hi)
    inset.set_ylim(y0 - pad, y1 + pad)
    inset.tick_params(labelsize=9)
    # On white: the zoom's connectors run behind it.
    inset.set_title(
        f"zoom: {lo:.4g} ≤ v ≤ {hi:.4g}", fontsize=9, bbox={"fc": "white", "ec": "none", "pad": 1}
    )
    inset.xaxis.set_major_locator(MaxNLocator(3))
    inset.yaxis.set_major_locator(MaxNLocator(3))
    ax.indicate_inset_zoom(inset, edgecolor="0.4")


def plot_branches_in_planes(result, ax=None, title=None):
    """theta(1) of the static branches against v, stable in 3-D or not, with both planes' events.

    Solid stable in 3-D, dashed unstable in the plane, dash-dot unstable out of it only.  Events:
    large open markers in the plane, small filled ones out of it.  The vertical line is the 3-D
    v_cr; an inset shows the two planes' first losses when closer than :data:`ZOOM_BELOW` of the
    range.  ``result`` is a StabilityInPlanes; returns the Axes.
    """
    import matplotlib.pyplot as plt

    ax = new_axes(ax, size=(7.6, 6.6))
    colors = plt.cm.tab10(np.arange(10))
    _draw_branches(ax, result, colors)
    v_cr_line = mark_v_cr(ax, result.critical, _plane_words(result))
    ax.set_xlabel("v (flow velocity)", fontsize=11)
    ax.set_ylabel(r"$\theta(1)$ of the static state (rad)", fontsize=11)
    ax.tick_params(labelsize=10)
    p = result.in_plane.params
    ax.set_title(
        title or f"{parameter_text(p, v=False)}: stability of the static branches in 3-D",
        fontsize=11,
    )
    ax.grid(alpha=0.3)
    window = _zoom_window(result)
    if window is not None:
        _zoom(ax, result, colors, window)
    place_legend(ax, _key(result, colors, v_cr_line), ncols=3)
    return ax

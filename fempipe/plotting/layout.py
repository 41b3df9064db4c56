"""Text placement shared by the figures: labels that would collide are dropped.

Marks along a curve (the flow velocity along a root locus, for instance) are
labelled densely where the curve is long and pile up where it is short or
where two curves run on top of each other (a divergence pair on the imaginary
axis).  :func:`declutter` keeps a label only when its box, measured by the
renderer, is clear of every label already kept and of the axes' edge.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["declutter"]


def declutter(
    ax, texts: Sequence, pad: float = 2.0, keep_clear: Sequence = (), draw: bool = True
) -> list:
    """Hide every text of ``texts`` that overlaps an earlier visible one.

    Parameters
    ----------
    ax : matplotlib Axes
        The texts' axes; a label reaching outside it is hidden too.
    texts : sequence of matplotlib Text
        In order of priority (earlier ones are kept first).
    pad : float
        Clearance between labels, pixels.
    keep_clear : sequence of Artist
        Artists (a legend) that no kept label may overlap.
    draw : bool
        Draw the figure first, to place every text (False: the caller has
        just drawn it, e.g. once for the labels of several axes).

    Returns
    -------
    list of Text
        The texts kept visible.
    """
    fig = ax.figure
    if draw:
        fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    frame = ax.get_window_extent(renderer)
    kept = []
    boxes = [a.get_window_extent(renderer) for a in keep_clear]
    for t in texts:
        b = t.get_window_extent(renderer).padded(pad)
        inside = b.x0 >= frame.x0 and b.x1 <= frame.x1 and b.y0 >= frame.y0 and b.y1 <= frame.y1
        if inside and not any(b.overlaps(k) for k in boxes):
            kept.append(t)
            boxes.append(b)
        else:
            t.set_visible(False)
    return kept

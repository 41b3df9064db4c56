"""Text placement shared by the figures: labels that would collide are dropped.

:func:`declutter` keeps a label only when its box, measured by the renderer, is clear of
every label already kept and of the axes' edge; :func:`shared_legend` gives panels one legend.
"""

from __future__ import annotations

from collections.abc import Sequence

__all__ = ["declutter", "shared_legend"]


def declutter(
    ax, texts: Sequence, pad: float = 2.0, keep_clear: Sequence = (), draw: bool = True
) -> list:
    """Hide every text of ``texts`` (by priority) that overlaps an earlier visible one, the axes'
    edge or ``keep_clear`` artists, with ``pad`` pixels of clearance; return the kept texts.

    ``draw`` False: the caller just drew the figure.
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


def shared_legend(fig, axes: Sequence, fontsize: float = 9, max_columns: int = 4):
    """One legend below panels that share their entries (constrained layout); None if nothing is labelled.

    The panels' own legends are removed; each label is listed once, with its first handle.
    """
    handles: dict = {}
    for ax in axes:
        for h, lab in zip(*ax.get_legend_handles_labels(), strict=True):
            handles.setdefault(lab, h)
        if ax.get_legend() is not None:
            ax.get_legend().remove()
    if not handles:
        return None
    return fig.legend(
        list(handles.values()),
        list(handles),
        loc="outside lower center",
        ncols=min(max_columns, len(handles)),
        fontsize=fontsize,
    )

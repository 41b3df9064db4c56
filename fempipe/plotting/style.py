"""What the figures share: new axes, event markers, joined pieces, the line of parameters
(``α = 60°``), a legend under the axes.  matplotlib is imported only for a new figure.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "EVENT_MARKERS",
    "angle_text",
    "finish_axes",
    "mask_edges",
    "new_axes",
    "parameter_text",
    "place_legend",
    "runs",
]

#: The marker of each stability event (:class:`fempipe.analyses.stability.StabilityEvent`
#: ``type``) on the branch figures; another type is drawn as ``"x"``.
EVENT_MARKERS = {"flutter": "o", "divergence": "s", "restabilization": "^", "fold": "D"}


def new_axes(ax=None, size=(6.0, 4.5)):
    """``ax``, or the Axes of a new figure of ``size`` inches with constrained layout."""
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=size, layout="constrained")
    return ax


def finish_axes(ax, xlabel: str, ylabel: str, title: str | None = None, **title_kw) -> None:
    """The axis labels, a light grid and the title if any."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    if title:
        ax.set_title(title, **title_kw)


def mask_edges(mask: np.ndarray) -> np.ndarray:
    """The samples next to a True sample of ``mask`` (so stable and unstable pieces join)."""
    out = np.zeros_like(mask)
    out[1:] |= mask[:-1]
    out[:-1] |= mask[1:]
    return out


def runs(flags) -> list[tuple]:
    """``(flag, slice)`` of each run of equal consecutive ``flags``, one point past its end so the pieces meet."""
    out, start = [], 0
    for k in range(1, len(flags) + 1):
        if k == len(flags) or flags[k] != flags[start]:
            out.append((flags[start], slice(start, k + 1)))
            start = k
    return out


def place_legend(ax, handles: list, ncols: int = 2, fontsize: float = 10):
    """The legend of ``handles`` under the axes (constrained layout), else inside, in at most ``ncols`` columns that fit."""
    from matplotlib.layout_engine import ConstrainedLayoutEngine

    fig = ax.figure
    if not isinstance(fig.get_layout_engine(), ConstrainedLayoutEngine):
        return ax.legend(handles=handles, fontsize=fontsize, loc="best")
    renderer = fig.canvas.get_renderer()
    for n in range(min(ncols, len(handles)), 0, -1):
        legend = fig.legend(
            handles=handles, loc="outside lower center", ncols=n, fontsize=fontsize, frameon=False
        )
        if n == 1 or legend.get_window_extent(renderer).width <= 0.98 * fig.bbox.width:
            return legend
        legend.remove()
    return legend


def angle_text(alpha: float) -> str:
    """``α = 60°``: the inclination as every figure's title and caption writes it."""
    return f"α = {np.degrees(alpha):.4g}°"


def parameter_text(params, v: bool = True) -> str:
    """``α = 60°, β = 0.3, γ = 10, μ = 0.005, v = 8.2``: a figure's line of parameters (``v`` False leaves v out)."""
    parts = [
        angle_text(params.alpha),
        f"β = {params.beta:.4g}",
        f"γ = {params.gamma:.4g}",
        f"μ = {params.mu:.4g}",
    ]
    if v:
        parts.append(f"v = {params.v:.4g}")
    # The variants of the pipe, named only where present.
    for key, name in (
        ("end_mass", "end mass"),
        ("external_damping", "σ"),
        ("hysteretic_damping", "μ_h"),
    ):
        if getattr(params, key, 0.0):
            parts.append(f"{name} = {getattr(params, key):.4g}")
    parts += [f"spring κ = {k:.4g} at ξ = {x:.4g}" for k, x in getattr(params, "springs", ())]
    return ", ".join(parts)

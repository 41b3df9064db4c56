"""What the figures of the package share: new axes, the markers of the events, joined pieces.

matplotlib is imported only when a new figure is made.
"""

from __future__ import annotations

import numpy as np

__all__ = ["EVENT_MARKERS", "new_axes", "mask_edges"]

#: The marker of each stability event (:class:`fempipe.analyses.stability.StabilityEvent`
#: ``type``) on the branch figures; another type is drawn as ``"x"``.
EVENT_MARKERS = {"flutter": "o", "divergence": "s", "restabilization": "^", "fold": "D"}


def new_axes(ax=None, size=(6.0, 4.5)):
    """``ax``, or the Axes of a new figure of ``size`` inches with constrained layout.

    Constrained layout keeps every label on the canvas.
    """
    if ax is None:
        import matplotlib.pyplot as plt

        _, ax = plt.subplots(figsize=size, layout="constrained")
    return ax


def mask_edges(mask: np.ndarray) -> np.ndarray:
    """The samples next to a True sample of ``mask`` (so stable and unstable pieces join)."""
    out = np.zeros_like(mask)
    out[1:] |= mask[:-1]
    out[:-1] |= mask[1:]
    return out

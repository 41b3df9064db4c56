"""The figure of ``fempipe compare``: a user's values against fempipe's, per quantity."""

from __future__ import annotations

import math
import textwrap
from collections.abc import Sequence

import numpy as np

__all__ = ["plot_comparison"]

#: Axis labels of the quantities (unit in brackets, as in the CSV files).
LABELS = {
    # fempipe compare: a user's v_cr and frequency are the planar model's (in the plane)
    "v_cr": "v_cr (planar) [1]",
    "frequency": "frequency Im λ (planar) [1/T]",
    "theta_tip": "θ(1) [rad]",
    "X_tip": "X_g(1) [L]",
    "Z_tip": "Z_g(1) [L]",
    "eta_tip": "η(1) [L]",
    "lc_amplitude": "limit-cycle amplitude of η(1) [L]",
    "lc_period": "limit-cycle period [T]",
    "v_cr_in_plane": "v_cr in the plane [1]",
    "v_cr_out_of_plane": "v_cr out of the plane [1]",
    "frequency_in_plane": "frequency in the plane [1/T]",
    "frequency_out_of_plane": "frequency out of the plane [1/T]",
    "sigma_threshold": "parametric threshold σ_th [1]",
    "omega_threshold": "ω at the threshold [1/T]",
}

_COLOR = "#0072B2"
#: Largest number of quantities side by side; more go on further rows.
_COLUMNS = 4


def _log_scale(values: np.ndarray) -> bool:
    """Log axes for positive values spanning more than a decade."""
    return bool(values.size and np.all(values > 0) and values.max() / values.min() > 10.0)


def _limits(values: np.ndarray, log: bool) -> tuple[float, float]:
    """Axis limits holding every value and error bar with a margin, at least 2 % of the values' size wide."""
    v = values[np.isfinite(values)]
    if log:
        v = v[v > 0]
        lo, hi = float(v.min()), float(v.max())
        pad = max((hi / lo) ** 0.08, 1.05)
        return lo / pad, hi * pad
    lo, hi = float(v.min()), float(v.max())
    least = 0.02 * max(abs(lo), abs(hi)) or 1e-3
    if hi - lo < least:
        mid = 0.5 * (lo + hi)
        lo, hi = mid - 0.5 * least, mid + 0.5 * least
    pad = 0.08 * (hi - lo)
    return lo - pad, hi + pad


def plot_comparison(rows: Sequence[dict], caption: str = "", title: str | None = None):
    """Two panels per quantity: user against fempipe with y = x, and the differences.

    Error bars: fempipe's error estimate; filled markers are resolved (the bar does not reach
    0); failed rows are not drawn.

    Parameters
    ----------
    rows : sequence of dict
        The ``rows`` of ``fempipe compare --json``.
    caption : str
        Text below the panels, wrapped.
    title : str, optional
    """
    import matplotlib.pyplot as plt

    from .layout import declutter

    quantities = list(dict.fromkeys(r["quantity"] for r in rows)) or ["v_cr"]
    ncol = min(len(quantities), _COLUMNS)
    blocks = math.ceil(len(quantities) / ncol)
    width = 1.2 + 3.6 * ncol
    height = 0.9 + 5.6 * blocks + 0.16 * len(textwrap.wrap(caption, int(width * 14)) or [""])
    fig, axes = plt.subplots(
        2 * blocks,
        ncol,
        figsize=(width, height),
        layout="constrained",
        squeeze=False,
        gridspec_kw={"height_ratios": [1.6, 1.0] * blocks},
    )
    labels = []
    for k in range(blocks * ncol):
        top = axes[2 * (k // ncol), k % ncol]
        bottom = axes[2 * (k // ncol) + 1, k % ncol]
        if k >= len(quantities):
            top.set_visible(False)
            bottom.set_visible(False)
            continue
        name = quantities[k]
        sel = [r for r in rows if r["quantity"] == name and r["fempipe"] is not None]
        labels.append((top, _draw(top, bottom, name, sel)))
    fig.suptitle(title or "user values against fempipe", fontsize=11)
    if caption:
        fig.supxlabel(textwrap.fill(caption, int(width * 14)), fontsize=9, ha="center")
    # The row labels: one draw places every text, then those that collide go.
    fig.canvas.draw()
    for ax, texts in labels:
        legend = ax.get_legend()
        declutter(ax, texts, keep_clear=[] if legend is None else [legend], draw=False)
    return fig


def _draw(top, bottom, name: str, rows: list[dict]) -> list:
    """Draw one quantity's panels; returns the row labels of the top panel."""
    label = LABELS.get(name, name)
    top.set_title(name, fontsize=10)
    if not rows:
        top.text(
            0.5,
            0.5,
            "no fempipe value\n(failed)",
            ha="center",
            va="center",
            transform=top.transAxes,
        )
        top.set_xticks([])
        top.set_yticks([])
        bottom.set_visible(False)
        return []
    x = np.array([r["fempipe"] for r in rows], dtype=float)
    y = np.array([r["user"] for r in rows], dtype=float)
    d = np.array([r["difference"] for r in rows], dtype=float)
    e = np.array([np.nan if r["error_estimate"] is None else r["error_estimate"] for r in rows])
    resolved = np.array([r["resolved"] is True for r in rows])
    log = _log_scale(np.concatenate([x, y]))
    lo, hi = _limits(np.concatenate([x, y, x - e, x + e]), log)
    if log:
        top.set_xscale("log")
        top.set_yscale("log")
        bottom.set_xscale("log")
    else:
        top.ticklabel_format(useOffset=False)
        bottom.ticklabel_format(axis="x", useOffset=False)
    top.plot([lo, hi], [lo, hi], color="0.5", lw=1, ls="--", label="y = x")
    for ax, yy in ((top, y), (bottom, d)):
        for mask, face, what in ((resolved, _COLOR, "resolved"), (~resolved, "white", "not")):
            if not mask.any():
                continue
            ax.errorbar(
                x[mask],
                yy[mask],
                **({"xerr": e[mask]} if ax is top else {"yerr": e[mask]}),
                fmt="o",
                ms=5,
                mfc=face,
                mec=_COLOR,
                ecolor=_COLOR,
                capsize=3,
                ls="none",
                label="differs" if what == "resolved" else "agrees",
            )
    top.set_xlim(lo, hi)
    top.set_ylim(lo, hi)
    if not log:
        top.set_aspect("equal", adjustable="box")
    top.set_xlabel(f"fempipe: {label}", fontsize=9)
    top.set_ylabel(f"user: {label}", fontsize=9)
    top.grid(alpha=0.3, which="both")
    top.legend(fontsize=8, loc="best", frameon=False)
    texts = [
        top.annotate(
            str(r["row"]),
            (xi, yi),
            xytext=(4, -10),
            textcoords="offset points",
            fontsize=8,
            color="0.3",
        )
        for r, xi, yi in zip(rows, x, y, strict=True)
    ]
    bottom.axhline(0.0, color="0.5", lw=1, ls="--")
    bottom.set_xlim(lo, hi)
    bottom.set_xlabel(f"fempipe: {label}", fontsize=9)
    bottom.set_ylabel("user − fempipe", fontsize=9)
    bottom.grid(alpha=0.3, which="both")
    bottom.ticklabel_format(axis="y", style="sci", scilimits=(-3, 3))
    return texts

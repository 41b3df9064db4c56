"""The chart of parametric resonance: regions of the (omega, sigma) plane, in the style of the
classical charts (docs/theory/parametric.md)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from fempipe.plotting.style import parameter_text

__all__ = ["plot_parametric_chart"]

_OUTLINES = ("--", ":", "-.")


def _sub(k: int) -> str:
    return str(k).translate(str.maketrans("0123456789", "₀₁₂₃₄₅₆₇₈₉"))


def _outline(region, band: tuple[float, float]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The region's boundary as a closed curve through its threshold, and which points were computed."""
    rows = [(s, lo, hi) for s, lo, hi in region.boundary if s > region.sigma_threshold]
    sig = [region.sigma_threshold] + [s for s, _, _ in rows]
    lo = [region.omega_threshold] + [w for _, w, _ in rows]
    hi = [region.omega_threshold] + [w for _, _, w in rows]
    x = np.array(lo[::-1] + hi, dtype=float)
    known = np.isfinite(x)
    half = len(lo)
    x[:half] = np.where(known[:half], x[:half], band[0])
    x[half:] = np.where(known[half:], x[half:], band[1])
    return x, np.array(sig[::-1] + sig), known


def plot_parametric_chart(chart, others: Sequence = (), ax=None):
    """The regions of ``chart`` shaded, those of ``others`` (e.g. few-mode charts) outlined,
    and the nominal frequencies of the resonances marked; parameters in the caption.

    Returns the axes.
    """
    import matplotlib.pyplot as plt

    if ax is None:
        fig, ax = plt.subplots(figsize=(7.0, 4.6), constrained_layout=True)
    lo, hi = chart.band
    sigma_top = max(chart.sigmas)
    marks = [(k, w, "0.35", "") for k, w in zip(chart.modes, chart.frequencies, strict=True)]
    marks += [
        (k, w, "tab:blue", "ᵒ")
        for k, w in zip(chart.modes_out_of_plane, chart.frequencies_out_of_plane, strict=True)
    ]
    for k, w, color, mark in marks:
        for n in (1, 2):
            x = 2 * w / n
            if lo <= x <= hi:
                ax.axvline(x, color=color, lw=0.8, ls=(0, (1, 2)), zorder=0, alpha=0.6)
                ax.text(
                    x, 1.005 * sigma_top, f"2ω{mark}{_sub(k)}" + (f"/{n}" if n > 1 else ""),
                    ha="center", va="bottom", fontsize=8, color=color,
                )  # fmt: skip
    name = chart.discretization.get("name", "FE")
    labelled = set()
    for region in chart.regions:
        plane = region.candidate.plane
        color, hatch = ("tab:blue", "//") if plane == "out" else ("tab:red", None)
        what = f"unstable, {name}" + ("" if plane is None else f", {plane} of the plane")
        x, y, known = _outline(region, chart.band)
        ax.fill(
            x, y, facecolor=color, alpha=0.35, lw=0, hatch=hatch,
            label=None if what in labelled else what,
        )  # fmt: skip
        labelled.add(what)
        ax.plot(np.where(known, x, np.nan), y, color=color, lw=1.2, marker=".", ms=5)
        ax.plot(region.omega_threshold, region.sigma_threshold, "v", color=color, ms=6)
        c = region.candidate
        label = f"mode {c.mode[0]}" if c.kind == "principal" else f"modes {c.mode[0]}, {c.mode[1]}"
        ax.annotate(
            f"{label}\nσ_th = {region.sigma_threshold:.4f}",
            (region.omega_threshold, region.sigma_threshold),
            xytext=(8, -10), textcoords="offset points", ha="left", va="top", fontsize=8,
        )  # fmt: skip
    for j, other in enumerate(others):
        style = _OUTLINES[j % len(_OUTLINES)]
        oname = other.discretization.get("name", f"other {j + 1}")
        for i, region in enumerate(other.regions):
            x, y, known = _outline(region, other.band)
            ax.plot(
                np.where(known, x, np.nan), y, color="k", ls=style, lw=1.2, marker=".", ms=3,
                label=oname if i == 0 else None,
            )  # fmt: skip
    ax.set_xlim(lo, hi)
    ax.set_ylim(0, 1.08 * sigma_top)
    ax.set_xlabel("pulsation frequency ω")
    ax.set_ylabel("pulsation amplitude σ")
    p = chart.params
    outlined = ", ".join(o.discretization.get("name", "") for o in others)
    ax.set_title(
        "Parametric resonance "
        + ("of the straight pipe" if chart.straight else "about the bent pipe's forced response")
        + ", v(τ) = v₀ (1 + σ sin ωτ)\n"
        f"{parameter_text(p, v=False)}, v₀ = {p.v:.4g}\n"
        f"shaded: {name} (dots: computed edges, ▼ thresholds"
        + ("" if chart.straight else "; blue, hatched, ᵒ: out of the plane")
        + ")"
        + (f"; outlined: {outlined}" if others else ""),
        fontsize=9,
    )
    if chart.regions or any(o.regions for o in others):
        ax.legend(loc="lower right", fontsize=8, framealpha=0.9)
    else:
        ax.text(0.5, 0.5, f"no region opens for σ ≤ {sigma_top:g}", transform=ax.transAxes,
                ha="center", va="center")  # fmt: skip
    return ax

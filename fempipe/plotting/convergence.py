"""The log-log convergence plot of a :class:`~fempipe.studies.convergence.ConvergenceStudy`."""

from __future__ import annotations

import textwrap

import numpy as np

from .style import parameter_text

#: Color-blind-safe colors (Okabe & Ito) and markers of the families.
FAMILY_STYLE = {
    "fe-P1": ("#0072B2", "o-"),
    "fe-P2": ("#E69F00", "s-"),
    "fe-P3": ("#009E73", "^-"),
    "fe-P4": ("#56B4E9", "v-"),
    "modal-sine": ("#D55E00", "d--"),
    "modal-beam": ("#CC79A7", "p--"),
}


def reference_member(study, series) -> int | None:
    """Index of the member of ``series`` that defines the reference (the finer of the two
    extrapolated), or None: its distance to the reference is an estimate, not an error."""
    if series.family != study.reference.family:
        return None
    ok = np.flatnonzero(np.isfinite(series.values))
    return int(ok[-1]) if ok.size else None


def plot_convergence(study, ax=None, title: str | None = None):
    """Error against degrees of freedom, log-log, one line per family; returns the Axes.

    The legend gives fitted and theoretical orders; the fitted points are overdrawn grey; the
    dotted line is the reference's error estimate; the reference member (:func:`reference_member`)
    is a large open marker at that estimate.  ``title`` defaults to the quantity and parameters.
    """
    import matplotlib.pyplot as plt
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    if ax is None:
        _, ax = plt.subplots(figsize=(7.0, 6.0), layout="constrained")
    ref = study.reference
    for s in study.series:
        color, style = FAMILY_STYLE.get(s.family, (None, ".-"))
        ok = np.isfinite(s.errors) & (s.errors > 0)
        own = reference_member(study, s)
        if own is not None:
            ok[own] = False
        fitted = "n/a" if not np.isfinite(s.observed_order) else f"{s.observed_order:.2f}"
        theory = "?" if s.expected_order is None else f"{s.expected_order:g}"
        if ok.any():
            (line,) = ax.loglog(
                s.dofs[ok],
                s.errors[ok],
                style,
                color=color,
                ms=6,
                lw=1.6,
                label=f"{s.family}: fitted p = {fitted} (theory {theory})",
            )
            color = line.get_color()
        if len(s.fit) >= 2:
            idx = [i for i in s.fit if i != own]
            ax.loglog(s.dofs[idx], s.errors[idx], "-", color="0.3", lw=5, alpha=0.25, zorder=0)
        if own is not None and ref.error_estimate > 0:
            ax.loglog(
                s.dofs[own],
                ref.error_estimate,
                ls="",
                marker=style[0],
                ms=11,
                mfc="none",
                mew=1.6,
                color=color,
                gid="reference member",
                label=f"{s.family}, n = {s.n[own]}: defines the reference (no measured error)",
            )
    if ref.error_estimate > 0:
        ax.axhline(
            ref.error_estimate,
            color="0.4",
            ls=":",
            lw=1.4,
            label=f"reference error estimate ({ref.error_estimate:.1e})",
            gid="reference error estimate",
        )
    # The members double: powers of 2 as plain numbers.
    ax.xaxis.set_major_locator(LogLocator(base=2, numticks=10))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda x, _: f"{x:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("degrees of freedom", fontsize=11)
    ax.set_ylabel("|value − reference|", fontsize=11)
    ax.tick_params(labelsize=10)
    ax.grid(alpha=0.3, which="both")
    q = study.quantity
    if title is None and q is not None:
        # The description wrapped to the axes' width (the critical quantities'
        # descriptions of three dimensions run to two lines).
        title = (
            textwrap.fill(q.describe(), 80)
            + f"\n{parameter_text(q.params, v=False)}; reference: {ref.family} (Richardson)"
        )
    if title:
        ax.set_title(title, fontsize=10)
    handles = sorted(ax.get_legend_handles_labels()[0], key=lambda h: h.get_gid() is not None)
    # Below the axes: a legend inside would hide the finest points.
    ax.legend(
        handles=handles,
        fontsize=9,
        loc="upper center",
        bbox_to_anchor=(0.5, -0.12),
        ncol=1,
        frameon=False,
    )
    return ax

"""The log-log convergence plot of a :class:`~fempipe.studies.convergence.ConvergenceStudy`."""

from __future__ import annotations

import textwrap

import numpy as np

#: Color-blind-safe colors (Okabe & Ito) and markers of the families.
FAMILY_STYLE = {
    "fe-P1": ("#0072B2", "o-"),
    "fe-P2": ("#E69F00", "s-"),
    "fe-P3": ("#009E73", "^-"),
    "fe-P4": ("#56B4E9", "v-"),
    "modal-sine": ("#D55E00", "d--"),
    "modal-beam": ("#CC79A7", "p--"),
}


def plot_convergence(study, ax=None, title: str | None = None):
    """Error against degrees of freedom, log-log, one line per family.

    The legend gives each family's fitted order and the theoretical one; the
    points the fit used are overdrawn by a thick grey line; the dotted line is
    the reference's error estimate (below it, errors are not resolved).

    Parameters
    ----------
    study : ConvergenceStudy
    ax : matplotlib Axes, optional
    title : str, optional
        Default: the quantity and the parameters.

    Returns
    -------
    matplotlib Axes
    """
    import matplotlib.pyplot as plt
    from matplotlib.ticker import NullFormatter

    if ax is None:
        _, ax = plt.subplots(figsize=(6.4, 5.2), layout="constrained")
    for s in study.series:
        color, style = FAMILY_STYLE.get(s.family, (None, ".-"))
        ok = np.isfinite(s.errors) & (s.errors > 0)
        if not ok.any():
            continue
        fitted = "n/a" if not np.isfinite(s.observed_order) else f"{s.observed_order:.2f}"
        theory = "?" if s.expected_order is None else f"{s.expected_order:g}"
        ax.loglog(
            s.dofs[ok],
            s.errors[ok],
            style,
            color=color,
            ms=5,
            label=f"{s.family}: fitted p = {fitted} (theory {theory})",
        )
        if len(s.fit) >= 2:
            idx = list(s.fit)
            ax.loglog(s.dofs[idx], s.errors[idx], "-", color="0.3", lw=4, alpha=0.25, zorder=0)
    ref = study.reference
    if ref.error_estimate > 0:
        ax.axhline(
            ref.error_estimate,
            color="0.4",
            ls=":",
            lw=1.2,
            label=f"reference error estimate ({ref.error_estimate:.1e})",
        )
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xlabel("degrees of freedom")
    ax.set_ylabel("|value - reference|")
    ax.grid(alpha=0.3, which="both")
    q = study.quantity
    if title is None and q is not None:
        p = q.params
        # The description wrapped to the axes' width (the critical quantities'
        # descriptions of three dimensions run to two lines).
        title = (
            textwrap.fill(q.describe(), 85) + "\n"
            rf"$\alpha$ = {np.degrees(p.alpha):.4g}°, $\beta$ = {p.beta:g}, "
            rf"$\gamma$ = {p.gamma:g}, $\mu$ = {p.mu:g}; reference: {ref.family} (Richardson)"
        )
    if title:
        ax.set_title(title, fontsize=9)
    # Below the axes: a legend inside would hide the finest points.
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2, frameon=False)
    return ax

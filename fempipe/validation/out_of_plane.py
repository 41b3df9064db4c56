"""The motion out of the plane: a second computation, the symmetries, and the first instability.

:mod:`fempipe.model.out_of_plane.model` (docs/theory/out_of_plane.md) checked five ways:
(a) the straight pipe: out-of-plane K, C, M and spectra equal the in-plane ones;
(b) the buckled standing pipe: the rotation about the vertical is an exact null vector, the
    other eigenvalues equal the strong form's;
(c) the strong form of :mod:`fempipe.validation.lateral`: v_cr and frequencies to 1e-8;
(d) the observed orders of the out-of-plane v_cr;
(e) the finding: the out-of-plane v_cr against the in-plane one (Fig. 6).
"""

from __future__ import annotations

import math

import numpy as np

from fempipe.core.parallel import single_blas

from . import out_of_plane_agreement as agreement
from . import out_of_plane_runs as runs
from .case import Case
from .checks import CaseResult
from .drawing import figure_panels, finish_figure, label_axes, legend_below

CASE = Case.load("out_of_plane")


@single_blas
def run(quick: bool = False) -> CaseResult:
    """(a)-(e) of the module docstring."""
    ref = CASE.references
    c1, t1 = runs.identity_checks(ref)
    c2, t2 = runs.buckled_checks(ref, quick)
    c3, t3, r3, strong = agreement.agreement_checks(ref, quick)
    c3.append(agreement.inclined_variants_check(ref))
    key = ("paper", round(0.5 * math.pi, 12), 0.0)
    c4, t4, r4, order_curves = agreement.order_checks(ref, quick, strong[key].v_cr)
    if not quick:
        c4.append(agreement.classical_check(ref))
    c5, t5, findings, explained, curves = agreement.finding_checks(ref, quick)
    checks, tables, requires = c1 + c2 + c3 + c4 + c5, t1 + t2 + t3 + t4 + t5, r3 + r4
    return CASE.result(
        checks,
        quick=quick,
        tables=tables,
        findings=findings,
        explained=explained,
        requires=requires,
        data={
            "curves": curves,
            "orders": order_curves,
            "strong": {k: (s.v_cr, s.frequency) for k, s in strong.items()},
            "paper_case": ref.value("paper_case"),
            "headline": _headline(curves),
        },
    )


def _headline(curves: dict) -> str:
    """The report's headline fragment: the largest lead of the out-of-plane flutter."""
    parts = []
    for mu, pts in sorted(curves.items()):
        gaps = [((vi - vo) / vi, a) for a, vi, vo in pts if 0.0 < a < math.pi - 1e-9 and vi > 0]
        if gaps:
            g, a = max(gaps)
            parts.append(
                f"for the paper's β = 0.142, γ = 18.9 with μ = {mu:g}, at every inclination "
                f"0 < α < π computed, by up to {100 * g:.1f} % of the paper's in-plane v_cr "
                f"(α = {np.degrees(a):.1f}°)"
            )
    return "; ".join(parts)


def plot(result: CaseResult, fig=None):
    """(a) v_cr(α) in and out of the plane; (b) convergence of the out-of-plane v_cr."""
    from matplotlib.ticker import NullFormatter

    d = result.data
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.2)
    ax = axes[0]
    colors = {0.0: "#0072B2", 0.005: "#D55E00"}
    for mu, pts in d["curves"].items():
        # The flutter onsets only: at alpha = pi the straight column is unstable from v = 0.
        pts = [x for x in pts if x[1] > 0.0 and x[2] > 0.0]
        a = np.degrees([x[0] for x in pts])
        c = colors.get(mu, "0.4")
        ax.plot(a, [x[1] for x in pts], "-", marker="o", ms=4, color=c, lw=1.4)
        ax.plot(a, [x[2] for x in pts], "--", marker="s", ms=4, color=c, lw=1.4)
    for (who, alpha, _mu), (v, _) in d["strong"].items():
        if who == "paper":
            ax.plot(np.degrees(alpha), v, "o", mfc="none", mec="k", ms=9, mew=1.2)
    ax.set_xlim(-8.0, 188.0)
    ax.set_xticks([0, 45, 90, 135, 180])
    label_axes(ax, "inclination α (degrees)", r"$v_{cr}$", "in and out of the plane")
    ax = axes[1]
    styles = {"P1": "#009E73", "P2": "#CC79A7", "P3": "k", "sine": "#E69F00", "beam": "#56B4E9"}
    entries = [
        ("in the plane", {"color": "0.3", "lw": 1.4}),
        ("out of the plane", {"color": "0.3", "lw": 1.4, "ls": "--"}),
        ("μ = 0", {"color": "#0072B2", "lw": 1.4}),
        ("μ = 0.005", {"color": "#D55E00", "lw": 1.4}),
        ("strong form", {"ls": "", "marker": "o", "mfc": "none", "mec": "k"}),
    ]
    for fam, (dofs, errs, slope) in d["orders"].items():
        ax.loglog(dofs, errs, "-o", ms=4, color=styles.get(fam, "0.4"), lw=1.4)
        entries.append(
            (
                f"{fam} (slope {slope:.1f})",
                {"color": styles.get(fam, "0.4"), "marker": "o", "ms": 4},
            )
        )
    # Minor ticks unlabelled: over less than a decade matplotlib labels them, overlapping.
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.yaxis.set_minor_formatter(NullFormatter())
    ylabel = r"$|v_{cr} - v_{ref}|$ out of the plane"
    label_axes(ax, "unknowns", ylabel, "convergence, α = π/2, μ = 0", grid="both")
    legend_below(fig, entries, ncols=3)
    pc = d["paper_case"]
    finish_figure(fig, CASE.title, parameters=f"β = {pc['beta']:g}, γ = {pc['gamma']:g}")
    return fig

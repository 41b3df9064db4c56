"""The onset of the non-planar oscillation of the horizontal pipe: normal form against shooting.

At alpha = pi/2 the paper's pipe first loses stability out of its plane.  On each P3 mesh:
(a) the 3-D Jacobian's critical pair crosses at the out-of-plane model's v_cr; (b) shot
cycles at v_cr + delta have A^2 / delta -> c^2 of the normal form (to 1e-4); (c) the period
tends to 2 pi / omega; (d) the mode is mirror-odd, Y_tip swings symmetrically, the Hopf point
is supercritical.
"""

from __future__ import annotations

import math

import numpy as np

from .case import Case
from .checks import CaseResult
from .drawing import figure_panels, finish_figure, label_axes, paper_case_line
from .evaluate import measure
from .space_runs import amplitude, fit_slope, onset, space_cycle_near_onset

CASE = Case.load("space_onset")


def _mesh_checks(tag: str, on, cycles, deltas, degree: int, ref, quick: bool) -> tuple:
    """The checks and the table row of one mesh."""
    nf = on.normal_form
    c = nf.amplitude_coefficients.get("Y_tip", math.nan)
    c2 = c**2
    amps = np.array([amplitude(c) for c in cycles])
    ratios = amps**2 / (c2 * np.asarray(deltas))
    r0, k = fit_slope(deltas, ratios, degree)
    periods = np.array([c.period for c in cycles])
    T0 = float(np.polyval(np.polyfit(deltas, periods, degree), 0.0))
    T_nf = 2.0 * math.pi / nf.omega
    asym = max(abs(c.tip["Y_tip"][0] + c.tip["Y_tip"][1]) for c in cycles)
    tol_v = ref.value("v_cr_tolerance")[tag.split(":")[1]]
    stable = [bool(c.stable) for c in cycles]
    d_v = abs(nf.v - nf.checks.v_out_of_plane)
    d_tr = abs(nf.transversality - nf.checks.transversality_check) / abs(nf.transversality)
    supercritical = nf.criticality == "supercritical" and all(stable)
    checks = [
        measure("v_cr_vs_out_of_plane_{tag}", d_v, limit=tol_v, tag=tag),
        measure("amplitude_slope_{tag}", abs(r0 - 1.0), tag=tag),
        measure("l1_resolved_{tag}", nf.uncertainty / abs(nf.l1), tag=tag),
        measure("period_{tag}", abs(T0 - T_nf) / T_nf, tag=tag),
        measure("transversality_{tag}", d_tr, tag=tag),
        measure("mirror_{tag}", max(nf.checks.in_plane_fraction, asym), tag=tag),
        measure("supercritical_{tag}", ok=supercritical, tag=tag, l1=nf.l1, stable=stable),
    ]
    row = (tag, nf.v, nf.checks.v_out_of_plane, nf.l1, nf.uncertainty, nf.omega, nf.transversality,
           c, r0 - 1.0, k)  # fmt: skip
    data = {"tag": tag, "deltas": list(map(float, deltas)), "amplitudes": amps.tolist(),
            "ratios": ratios.tolist(), "periods": periods.tolist(), "r0": r0, "k": k,
            "degree": degree, "c": c, "period_nf": T_nf, "normal_form": nf.to_dict()}  # fmt: skip
    return checks, row, data


#: The checks of each mesh.
_CHECKS = ("v_cr_vs_out_of_plane", "amplitude_slope", "l1_resolved", "period", "transversality",
           "mirror", "supercritical")  # fmt: skip


def run(quick: bool = False) -> CaseResult:
    """Normal form and shot cycles on each mesh (P3:3 quick; P3:4 and P3:8 full)."""
    ref = CASE.references
    alpha = ref.value("alpha")
    meshes = ref.value("deltas", quick)
    degree = ref.value("fit_degree", quick)
    checks, rows, data = [], [], []
    requires = []
    for ne, deltas in meshes.items():
        tag = f"P3:{ne}"
        requires += [f"{k}_{tag}" for k in _CHECKS]
        on = onset(int(ne), alpha)
        cycles = [space_cycle_near_onset(on, d) for d in deltas]
        ch, row, d = _mesh_checks(tag, on, cycles, np.array(deltas), degree, ref, quick)
        checks += ch
        rows.append(row)
        data.append(d)
    tables = (ref.table("onset", rows),)
    return CASE.result(checks, quick=quick, tables=tables, data={"meshes": data}, requires=requires)


#: Color-blind-safe colors (Okabe & Ito), one per mesh.
COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7")


def plot(result: CaseResult, fig=None):
    """(a) A²/(c² δ) and its fit, (b) A against δ with c √δ, (c) the period against δ."""

    fig, axes = figure_panels(fig, 3, ncols=3, size=4.0)
    ax_r, ax_a, ax_t = axes
    for color, mk, m in zip(COLORS, "osD^", result.data["meshes"], strict=False):
        d = np.array(m["deltas"])
        fine = np.linspace(0.0, d.max(), 100)
        coef = np.polyfit(d, m["ratios"], m["degree"])
        tag = m["tag"]
        ax_r.plot(1e3 * d, m["ratios"], mk, mfc="none", color=color, label=f"{tag}: shot cycles")
        ax_r.plot(1e3 * fine, np.polyval(coef, fine), "-", color=color, lw=1,
                  label=f"{tag}: fit; at δ = 0: 1 {m['r0'] - 1.0:+.1e}")  # fmt: skip
        ax_r.plot([0.0], [m["r0"]], mk, color=color, ms=4)
        ax_a.loglog(d, m["amplitudes"], mk, mfc="none", color=color, label=f"{tag}: shot cycles")
        ax_a.loglog(fine[1:], m["c"] * np.sqrt(fine[1:]), "-", color=color, lw=1,
                    label=f"{tag}: c √δ, c = {m['c']:.5f}")  # fmt: skip
        rel = (np.array(m["periods"]) - m["period_nf"]) / m["period_nf"]
        tc = np.polyfit(d, rel, m["degree"])
        ax_t.plot(1e3 * d, 1e6 * rel, mk, mfc="none", color=color, label=f"{tag}: shot cycles")
        ax_t.plot(1e3 * fine, 1e6 * np.polyval(tc, fine), "-", color=color, lw=1,
                  label=f"{tag}: fit")  # fmt: skip
    ax_t.plot([0.0], [0.0], "k*", ms=10, label="normal form: T = 2π/ω")
    ax_r.axhline(1.0, color="0.5", lw=0.8, ls=":")
    labels = {
        ax_r: ("δ = v - v_cr (10⁻³)", "A² / (c² δ)", "slope of A² against the normal form"),
        ax_a: ("δ = v - v_cr", "A = (max Y_tip - min Y_tip) / 2", "out-of-plane swing of the tip"),
        ax_t: (
            "δ = v - v_cr (10⁻³)",
            "(T - 2π/ω) / (2π/ω)  (10⁻⁶)",
            "period against the normal form's",
        ),
    }
    for ax in axes:
        label_axes(ax, *labels[ax], grid="both", fontsize=9)
        ax.legend(fontsize=9)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}", f"{paper_case_line()}, α = π/2, 3-D model")
    return fig

"""Fig. 12: phase trajectories (Z_g(1), dZ_g(1)/dtau) at v = 10 over one period, FE with
N = 3, 4 overlaid.  Checks: the orbit closes, and the truncations' distance from FE.
"""

from __future__ import annotations

import numpy as np

from .case import Case, alpha_name
from .checks import CaseResult
from .drawing import (
    color_for,
    discretization_legend,
    figure_panels,
    finish_figure,
    label_axes,
    paper_case_line,
    style_for,
)
from .dynamic_runs import cycle_traces, cycles_at, dyn_discretizations
from .evaluate import measure

CASE = Case.load("fig12")


def _loop_distance(a: dict, b: dict) -> float:
    """Largest distance from points of loop a to loop b, scaled by b's size (phase plane)."""
    sz, sv = np.ptp(b["Z_tip"]), np.ptp(b["Z_tip_rate"])
    pa = np.stack([a["Z_tip"] / sz, a["Z_tip_rate"] / sv], axis=1)
    pb = np.stack([b["Z_tip"] / sz, b["Z_tip_rate"] / sv], axis=1)
    d = np.linalg.norm(pa[:, None, :] - pb[None, :, :], axis=2)
    return float(np.max(np.min(d, axis=1)))


def run(quick: bool = False) -> CaseResult:
    """Phase portraits and checks; see the module docstring."""
    ref = CASE.references
    v = ref.value("v")
    alphas = tuple(ref.value("alpha", quick))
    discs = dyn_discretizations(quick)
    fe_label = next(iter(discs))
    cycles = cycles_at(alphas, v, quick)
    checks, rows, loops, requires = [], [], {}, []
    for a in alphas:
        name = alpha_name(a)
        # Without the FE cycle the orbit's closure is not measured, which fails the case.
        requires += [f"closed_{name}"]
        requires += [f"loop_{name}_{lb[-1]}" for lb in discs if lb != fe_label]
        tr = {
            lb: cycle_traces(discs[lb], a, cycles[(a, lb)], periods=1)
            for lb in discs
            if cycles[(a, lb)] is not None
        }
        loops[name] = tr
        if fe_label not in tr:
            continue
        fe = tr[fe_label]
        c = cycles[(a, fe_label)]
        checks.append(measure("closed_{alpha}", c.residual, alpha=name))
        rate = fe["Z_tip_rate"][:-1]
        turns = int(np.count_nonzero(np.diff(np.sign(np.append(rate, rate[0]))) != 0))
        for lb, t_ in tr.items():
            dist = 0.0 if lb == fe_label else _loop_distance(t_, fe)
            rows.append((name, lb, np.ptp(t_["Z_tip"]), np.ptp(t_["Z_tip_rate"]),
                         turns if lb == fe_label else "", dist))  # fmt: skip
            if lb == fe_label:
                continue
            fields = {"alpha": name, "n": lb[-1], "label": lb, "fe": fe_label}
            checks.append(measure("loop_{alpha}_{n}", dist, **fields))
    table = CASE.references.table("phase", tuple(rows))
    return CASE.result(
        checks, quick=quick, tables=(table,), data={"loops": loops, "v": v}, requires=requires
    )


def plot(result: CaseResult, fig=None):
    """One panel per α: dZ_g(1)/dτ against Z_g(1); FE solid, N = 3 dashed, N = 4 dotted."""

    loops = result.data["loops"]
    n = max(len(loops), 1)
    fig, axes = figure_panels(fig, n, ncols=min(n, 2), size=4.0)
    for ax, (name, tr) in zip(axes, loops.items(), strict=False):
        for lb, t_ in tr.items():
            ax.plot(t_["Z_tip"], t_["Z_tip_rate"], style_for(lb), color=color_for(lb), lw=1.3)
        label_axes(
            ax,
            r"$Z_g(1)$ ($/L$)",
            r"$\mathrm{d}Z_g(1)/\mathrm{d}\tau$",
            f"α = {name}, v = {result.data['v']:g}",
        )
    discretization_legend(fig, next(iter(loops.values()), {}))

    finish_figure(fig, f"{CASE.figure}: {CASE.title}", paper_case_line())
    return fig

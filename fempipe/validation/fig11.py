"""Fig. 11: time traces of the tip position at v = 10 for several alpha.

The limit cycle at v = 10 of each inclination, shot (Floquet multipliers from the monodromy)
for FE and N = 3, 4, drawn over three periods.  Checks: periodic and stable, tip excursion
near the pipe length, the modal period and tip ranges against FE.
"""

from __future__ import annotations

import numpy as np

from fempipe.model.discretization import parse_discretization

from .case import Case, alpha_name
from .checks import CaseResult, Table
from .drawing import (
    color_for,
    discretization_legend,
    finish_figure,
    label_axes,
    paper_case_line,
    style_for,
)
from .dynamic_runs import cycle_on, cycle_traces, cycles_at, dyn_discretizations
from .evaluate import Measured, measure

CASE = Case.load("fig11")


def run(quick: bool = False) -> CaseResult:
    """Cycles, traces and checks; see the module docstring."""
    ref = CASE.references
    v = ref.value("v")
    alphas = tuple(ref.value("alpha", quick))
    discs = dyn_discretizations(quick)
    cycles = cycles_at(alphas, v, quick)
    traces = _cycle_traces_at(alphas, discs, cycles)
    # Mesh convergence of one cycle (full suite only).
    fine = None if quick else _fine_cycle(v, discs, cycles)
    checks, requires = _case_checks(alphas, discs, cycles, traces, fine)
    tables = (_cycle_table(alphas, discs, cycles, traces),)
    data = {"traces": traces, "v": v}
    return CASE.result(checks, quick=quick, tables=tables, data=data, requires=requires)


def _cycle_traces_at(alphas, discs: dict, cycles: dict) -> dict:
    """``{α name: {label: trace}}`` of every found cycle (an α without an FE cycle is absent)."""
    fe_label = next(iter(discs))
    traces = {}
    for a in alphas:
        if cycles[(a, fe_label)] is None:
            continue
        traces[alpha_name(a)] = {
            lb: cycle_traces(discs[lb], a, cycles[(a, lb)])
            for lb in discs
            if cycles[(a, lb)] is not None
        }
    return traces


def _fine_cycle(v: float, discs: dict, cycles: dict):
    """The α = π/2 cycle on P3:16, shot from the projection of the converged FE cycle."""
    fe_label = next(iter(discs))
    c8 = cycles[(np.pi / 2, fe_label)]
    guess = (c8.q0, c8.qdot0, c8.period)
    return cycle_on(parse_discretization(fe="P3:16"), np.pi / 2, v, discs[fe_label], guess)


def _case_checks(alphas, discs: dict, cycles: dict, traces: dict, fine) -> tuple[list, list]:
    """The checks of every α (and of the mesh with ``fine``, full suite) and the names required."""
    ref = CASE.references
    fe_label = next(iter(discs))
    checks, requires = [], []
    for a in alphas:
        name = alpha_name(a)
        # The FE cycle missing fails periodic_<name> (a finding); the
        # comparisons with it are then not computed, and fail as such.
        requires += [f"periodic_{name}", f"large_{name}"]
        requires += [
            f"{k}_{name}_{lb[-1]}" for lb in discs if lb != fe_label for k in ("period", "range")
        ]
        fe = cycles[(a, fe_label)]
        found = {lb: cycles[(a, lb)] is not None for lb in discs}
        rho = {lb: cycles[(a, lb)].max_nontrivial_multiplier for lb in discs if found[lb]}
        multipliers = ", ".join(
            f"{lb}: " + (f"|ρ|max = {rho[lb]:.3g}" if found[lb] else "not periodic") for lb in discs
        )
        ok = all(found.values()) and all(r < 1 for r in rho.values())
        checks.append(measure("periodic_{alpha}", multipliers, ok=ok, alpha=name))
        if fe is None:
            continue
        tr = traces[name]
        fx = tr[fe_label]
        xr, zr = np.ptp(fx["X_tip"]), np.ptp(fx["Z_tip"])
        ok = max(xr, zr) >= ref.value("large")
        checks.append(measure("large_{alpha}", ok=ok, alpha=name, x_range=xr, z_range=zr))
        for lb in discs:
            if found[lb] and lb != fe_label:
                checks += _modal_checks(name, lb, cycles[(a, lb)], tr[lb], fe, fx, fe_label)
    if fine is not None:
        checks.append(_mesh_check(cycles[(np.pi / 2, fe_label)], fine))
    return checks, requires


def _modal_checks(name: str, lb: str, c, t_: dict, fe, fx: dict, fe_label: str) -> list:
    """Period and tip extrema of the modal cycle ``c`` against the FE cycle ``fe``."""
    dev = max(
        max(abs(t_[k].min() - fx[k].min()), abs(t_[k].max() - fx[k].max()))
        for k in ("X_tip", "Z_tip")
    )
    fields = {"alpha": name, "n": lb[-1], "label": lb, "fe": fe_label}
    return [
        measure("period_{alpha}_{n}", abs(c.period - fe.period) / fe.period, **fields),
        measure("range_{alpha}_{n}", dev, **fields),
    ]


def _mesh_check(c8, c16) -> Measured:
    """The P3:8 cycle at α = π/2 (period, tip extrema) against P3:16."""
    dev = max(
        abs(c16.period - c8.period) / c8.period,
        *(abs(c16.tip[k][j] - c8.tip[k][j]) for k in ("X_tip", "Z_tip") for j in (0, 1)),
    )
    return measure("fe_mesh_π/2", dev)


def _cycle_table(alphas, discs: dict, cycles: dict, traces: dict) -> Table:
    """The table of every found cycle: period, its error against FE, tip extrema, |ρ|max."""
    fe_label = next(iter(discs))
    rows = []
    for a in alphas:
        name = alpha_name(a)
        fe = cycles[(a, fe_label)]
        if fe is None:
            continue
        for lb in discs:
            c = cycles[(a, lb)]
            if c is None:
                continue
            t_ = traces[name][lb]
            rows.append((name, lb, c.period, (c.period - fe.period) / fe.period, t_["X_tip"].min(),
                         t_["X_tip"].max(), t_["Z_tip"].min(), t_["Z_tip"].max(),
                         c.max_nontrivial_multiplier))  # fmt: skip
    return CASE.references.table("cycles", tuple(rows))


def plot(result: CaseResult, fig=None):
    """One row per α: X_g(1)(τ) and Z_g(1)(τ) over a common τ window."""
    import matplotlib.pyplot as plt

    traces = result.data["traces"]
    n = max(len(traces), 1)
    if fig is None:
        fig = plt.figure(figsize=(10, 2.6 * n + 0.8), layout="constrained")
    axes = np.atleast_2d(fig.subplots(n, 2, squeeze=False))
    window = min((float(t_["t"][-1]) for tr in traces.values() for t_ in tr.values()), default=0)
    labels: dict = {}
    for row, (name, tr) in zip(axes, traces.items(), strict=False):
        for lb, t_ in tr.items():
            labels[lb] = None
            keep = np.asarray(t_["t"]) <= window * (1 + 1e-12)
            for ax, key in zip(row, ("X_tip", "Z_tip"), strict=True):
                t, y = np.asarray(t_["t"])[keep], np.asarray(t_[key])[keep]
                ax.plot(t, y, style_for(lb), color=color_for(lb), lw=1.3)
        for ax, lab in zip(row, (r"$X_g(1)$ ($/L$)", r"$Z_g(1)$ ($/L$)"), strict=True):
            title = f"α = {name}, v = {result.data['v']:g}"
            label_axes(ax, r"$\tau$ (from a section crossing)", lab, title)
            ax.set_xlim(0.0, window)
    discretization_legend(fig, labels)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}", paper_case_line())
    return fig

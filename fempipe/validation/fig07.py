"""Fig. 7: bifurcation diagram of the hanging pipe (alpha = 0), N = 3 against N = 4.

The static branch and the periodic orbits born at its Hopf point, by continuation, for the
converged FE mesh and N = 3, 4.  Checks the onset against the independent linear v_cr, the
continuation against integration at v = 6.3, 6.5, 10, and the paper's statements (period-1
cycle above v_cr, N = 3 and 4 agree, large amplitudes, 6.3 < v_cr < 6.5).
"""

from __future__ import annotations

import numpy as np

from fempipe.analyses.periodic.out_of_plane import cycle_verdict
from fempipe.analyses.three_d.floquet import compute_out_of_plane_floquet

from .case import Case, label_tag
from .checks import CaseResult, Table
from .drawing import (
    draw_continued,
    draw_orbit_shapes,
    figure_panels,
    finish_figure,
    paper_case_line,
)
from .dynamic_runs import (
    attractor,
    attractor_shapes,
    continued_diagram,
    dyn_discretizations,
    model_for,
    sweep_check,
)
from .evaluate import Measured, measure
from .onset import critical_velocity
from .out_of_plane_branches import (
    add_legend_entry,
    change_texts,
    continued_with_verdicts,
    fe_disc,
    leading_text,
    marks,
    survival_text,
    verdict_checks,
    verdict_rows,
    verdict_table,
)
from .static_shapes import PAPER_MODES

CASE = Case.load("fig07")


def eta_amplitude(p) -> float:
    """Half the peak-to-peak range of eta(1): the oscillation amplitude."""
    return 0.5 * (p.eta_tip[1] - p.eta_tip[0])


def onset_bracket(points) -> tuple[float, float]:
    """(last v with an equilibrium before the first periodic point, that first periodic v)."""
    lo, hi = float("nan"), float("nan")
    for p in points:
        if p is None:
            continue
        if p.attractor == "periodic":
            hi = p.v
            break
        lo = p.v
    return lo, hi


def onset_check(spec: str, diag, v_lin: float, tol: float, **fields) -> tuple:
    """The first Hopf point of ``diag`` against ``v_lin`` to ``tol``, with stable equilibria below
    and stable orbits above it; returns (measurement, v_H, last equilibrium v, first orbit v).
    """
    v_h = diag.hopf[0]["v"] if diag.hopf else float("nan")
    lo, hi = onset_bracket(diag.attractors())
    below_ok = all(diag.equilibrium_at(v).stable for v in diag.values if v < v_h)
    above_ok = all(diag.cycles_at(v) for v in diag.values if v > v_h)
    diff = abs(v_h - v_lin)
    ok = bool(np.isfinite(diff) and diff <= tol and below_ok and above_ok)
    m = measure(spec, ok=ok, v_h=v_h, v_lin=v_lin, diff=diff, lo=lo, hi=hi, **fields)
    return m, v_h, lo, hi


def sweep_agreement(spec: str, results: list, tol: float, **fields) -> Measured:
    """The attractors found by integration lie on stable continued states (``sweep_check`` results)."""
    dT = max(r["period"] for r in results)
    dtip = max(r["tip"] for r in results)
    deq = max(r["eq_tip"] for r in results)
    flagged = [f for r in results for f in r["flagged"]]
    unsettled = [f for r in results for f in r.get("unsettled", [])]
    n = sum(len(r["attractors"]) for r in results)
    text = (
        f"{n} attractors by integration: max |ΔT| {dT:.1e}, max |Δ tip extremum| {dtip:.1e} "
        f"on cycles, {deq:.1e} on equilibria; not on a stable continued state: "
        + ("; ".join(flagged) if flagged else "none")
        + ("; inconclusive (integration unsettled): " + "; ".join(unsettled) if unsettled else "")
    )
    return measure(spec, text, ok=not flagged and dT <= tol and dtip <= tol, **fields)


def period_one(spec: str, diags: dict, checked: list, **fields) -> Measured:
    """The stable continued cycles and the integrated ones are period-1, with no period doubling or
    Neimark-Sacker point on the branches.
    """
    stable_cyc = [
        p
        for dg in diags.values()
        for br in dg.branches.values()
        for p in br
        if p.stable and p.requested
    ]
    bif = [sp for dg in diags.values() for sp in dg.special if sp["type"] != "fold"]
    integ = [a for r in checked for a in r["attractors"].values() if a.kind == "periodic"]
    ok = (
        bool(stable_cyc)
        and not bif
        and all(p.max_multiplier < 1 for p in stable_cyc)
        and all(a.period_n == 1 for a in integ)
    )
    return measure(
        spec,
        ok=ok,
        stable=len(stable_cyc),
        bifurcations=len(bif),
        period_1=sum(a.period_n == 1 for a in integ),
        integrated=len(integ),
        **fields,
    )


def run(quick: bool = False) -> CaseResult:
    """Diagrams, the brute-force check, onsets and checks (module docstring)."""
    ref = CASE.references
    alpha = ref.value("alpha")
    values = ref.value("v", quick)
    discs = dyn_discretizations(quick)
    requires = [f"onset_{label_tag(lb)}" for lb in discs]
    fe_label = next(iter(discs))
    # The FE diagram with the 3-D verdicts of its orbits (out_of_plane_branches).
    fe_diag, oop = continued_with_verdicts(fe_label, alpha, values, quick)
    diags = {
        label: fe_diag if label == fe_label else continued_diagram(label, alpha, values)
        for label in discs
    }
    # What a sweep up from the sagged state ends on at each v (the stable state).
    sweeps = {label: dg.attractors() for label, dg in diags.items()}
    shape_v = ref.value("shape_v")
    checked = [sweep_check(dg, shape_v) for dg in diags.values()]
    checks, onsets = _onsets(ref, discs, alpha, diags)
    checks += _paper_checks(ref, diags, sweeps, checked, onsets, fe_label)
    checks += verdict_checks("", "0", oop, quick)
    fine_oop = None
    if not quick:  # mesh convergence of the FE amplitude (quick: see the convergence case)
        a10 = eta_amplitude({p.v: p for p in sweeps[fe_label] if p is not None}[10.0])
        fine = attractor("FE P3:16", alpha, 10.0)
        dmesh = abs(0.5 * (fine.tip["eta_tip"][1] - fine.tip["eta_tip"][0]) - a10)
        checks.append(measure("fe_mesh", dmesh, fe=fe_label))
        fine_checks, fine_oop = _oop_fine_checks(alpha, fe_label, oop)
        checks += fine_checks
    changes = change_texts("0", oop)
    return CASE.result(
        checks,
        quick=quick,
        tables=(
            _table(discs, onsets, sweeps),
            verdict_table(
                verdict_rows("0", oop) + ([fine_oop] if fine_oop else []), changes, quick
            ),
        ),
        findings=(survival_text("0", oop) + ".",),
        data={
            "diagrams": diags,
            "shapes": attractor_shapes(discs, alpha, shape_v, checked),
            "out_of_plane": oop,
        },
        requires=requires,
    )


def _onsets(ref, discs: dict, alpha: float, diags: dict) -> tuple[list[Measured], dict]:
    """``onset_<tag>`` checks and ``{label: (last equilibrium v, first periodic v, v_cr, v_H)}``."""
    checks, onsets = [], {}
    for label, d in discs.items():
        v_lin = critical_velocity(d, alpha).v_cr
        tol = ref.value("onset_tol")
        m, v_h, lo, hi = onset_check(
            "onset_{tag}", diags[label], v_lin, tol, tag=label_tag(label), label=label
        )
        checks.append(m)
        onsets[label] = (lo, hi, v_lin, v_h)
    return checks, onsets


def _paper_checks(
    ref, diags: dict, sweeps: dict, checked: list, onsets: dict, fe_label: str
) -> list[Measured]:
    """The brute-force check and the paper's statements."""
    checks = [
        sweep_agreement("sweep_agreement", checked, ref.value("sweep_tol")),
        period_one("period_one", diags, checked),
    ]
    fe_pts = {p.v: p for p in sweeps[fe_label] if p is not None}
    fe_diag = diags[fe_label]
    a63, a65 = fe_pts.get(6.3), fe_pts.get(6.5)
    kind = {6.3: a63.attractor if a63 else "none", 6.5: a65.attractor if a65 else "none"}
    ok = (
        kind[6.3] == "equilibrium"
        and kind[6.5] == "periodic"
        and not fe_diag.cycles_at(6.3)
        and not fe_diag.equilibrium_at(6.5).stable
    )
    checks.append(
        measure("paper_bracket", ok=ok, at_63=kind[6.3], at_65=kind[6.5], v_h=onsets[fe_label][3])
    )
    amps = {lb: np.array([eta_amplitude(p) for p in pts]) for lb, pts in sweeps.items()}
    checks.append(measure("n3_vs_n4", float(np.max(np.abs(amps["N = 3"] - amps["N = 4"])))))
    for n in PAPER_MODES:
        dn = float(np.max(np.abs(amps[f"N = {n}"] - amps[fe_label])))
        checks.append(measure(f"n{n}_vs_fe", dn, fe=fe_label))
    a10, z10 = eta_amplitude(fe_pts[10.0]), fe_pts[10.0].Z_tip
    checks.append(measure("large_amplitude", ok=a10 > 0.4, amplitude=a10, z_range=z10[1] - z10[0]))
    return checks


def _oop_fine_checks(alpha: float, fe_label: str, oop) -> tuple[list[Measured], tuple]:
    """The out-of-plane multiplier at v = 10 on P3:16 against FE and the 3-D model; its table row."""

    fine = attractor("FE P3:16", alpha, 10.0)
    fine_model = model_for(fe_disc("FE P3:16"), alpha, 10.0)
    got = cycle_verdict(fine_model, fine.cycle, fine.cycle.stable)
    p10 = oop.at(10.0)
    mine = p10["max_oop"] if p10 else float("nan")
    linear = got["max_nontrivial_out_of_plane_multiplier"]
    full = compute_out_of_plane_floquet(fine_model, fine.cycle, method="3d")
    neutral = got.get("neutral_out_of_plane_multiplier")
    lead = leading_text(
        [complex(*z) for z in got["out_of_plane_floquet_multipliers"]],
        None if neutral is None else complex(*neutral),
    )
    row = ("0", "FE P3:16", "(shot)", 10.0, "yes" if fine.cycle.stable else "no",
           fine.cycle.max_nontrivial_multiplier, linear, lead, "yes" if got["stable_3d"] else "no")  # fmt: skip
    checks = [
        measure("oop_mesh", abs(linear - mine), fe=fe_label),
        measure("oop_methods", abs(linear - full.max_nontrivial)),
    ]
    return checks, row


def _table(discs: dict, onsets: dict, sweeps: dict) -> Table:
    """Onset (:func:`_onsets`) and the limit cycle at v = 10 of every discretization."""
    rows = []
    for label in discs:
        lo, hi, v_lin, v_h = onsets[label]
        pts = {p.v: p for p in sweeps[label] if p is not None}
        p10 = pts[10.0]
        rows.append((label, v_lin, lo, hi, eta_amplitude(p10), p10.period, p10.X_tip[0],
                     p10.X_tip[1], p10.max_multiplier, v_h))  # fmt: skip
    return CASE.references.table("onsets", tuple(rows))


def plot(result: CaseResult, fig=None):
    """(a) η(1), (b) X_g(1), (c) Z_g(1) extrema against v; (d) shapes at v = 6.3, 6.5, 10 (FE)."""

    fig, axes = figure_panels(fig, 4, ncols=2, size=4.0)
    d = result.data
    for ax, key, lab, _tag in zip(
        axes[:3],
        ("eta_tip", "X_tip", "Z_tip"),
        (r"$\eta(1)$", r"$X_g(1)$", r"$Z_g(1)$"),
        "abc",
        strict=True,
    ):
        draw_continued(ax, d["diagrams"], key, lab)
        if "out_of_plane" in d and marks(
            ax, d["out_of_plane"], d["diagrams"][d["out_of_plane"].label], key
        ):
            add_legend_entry(ax)
        ax.set_title(f"extrema of {lab}", fontsize=10)
    draw_orbit_shapes(axes[3], d["shapes"])
    axes[3].set_title("inset of Fig. 7(c): shapes (converged FE)", fontsize=9)

    finish_figure(fig, f"{CASE.figure}: {CASE.title}", paper_case_line())
    return fig

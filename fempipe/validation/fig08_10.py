"""Figs. 8-10: bifurcation diagrams of eta(1), X_g(1), Z_g(1) for alpha = pi/4, pi/2, 3pi/4, pi.

Continued static branch and orbits (at alpha = pi the buckled equilibria below the flutter
from a sweep up), FE and N = 3, 4, checked by integration at the shape velocities.  Checks
the onset against the linear v_cr, period-1 cycles, the buckling / restabilization / flutter
sequence at alpha = pi, tip excursions near the pipe length at v = 10 and the onset brackets
implied by the paper's shape velocities.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.analyses.stability import analyse_stability
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel

from .case import Case, alpha_name, label_tag
from .checks import CaseResult
from .drawing import draw_continued, draw_orbit_shapes, finish_figure, paper_case_line
from .dynamic_runs import (
    attractor_shapes,
    continued_diagram,
    dyn_discretizations,
    sweep_check,
    sweep_up,
)
from .evaluate import Measured, measure
from .fig05 import first_flutter
from .fig07 import eta_amplitude, onset_bracket, onset_check, period_one, sweep_agreement
from .onset import critical_velocity
from .out_of_plane_branches import (
    OutOfPlaneBranches,
    add_legend_entry,
    change_texts,
    continued_with_verdicts,
    marks,
    survival_text,
    verdict_checks,
    verdict_rows,
    verdict_table,
)
from .static_shapes import PAPER_MODES

CASE = Case.load("fig08_10")


def parts(quick: bool = False) -> list[int]:
    """Independent parts (one per alpha) the suite may run in parallel, see ``run(part=...)``."""
    return list(range(len(CASE.references.value("alpha", quick))))


def _required(name: str, is_pi: bool, labels) -> list[str]:
    """The checks one inclination emits."""
    if is_pi:
        own = ["pi_sequence", "pi_fold_vs_sweep", "pi_flutter_vs_sweep", "pi_shape_velocities"]
    else:
        own = [f"onset_{name}_{label_tag(lb)}" for lb in labels] + [f"paper_bracket_{name}"]
    return (
        own + [f"period_one_{name}", f"large_{name}"] + [f"n{n}_vs_fe_{name}" for n in PAPER_MODES]
    )


@dataclass
class _Inclination:
    """The computed parts of one α: ``diags`` and ``sweeps`` by label, first Hopf points ``hopf_v``,
    the check by integration at ``check_v`` (``checked``), ``fe_pts`` by v, 3-D verdicts ``oop``.
    """

    alpha: float
    name: str
    is_pi: bool
    shape_v: tuple
    values: list
    diags: dict
    hopf_v: dict
    sweeps: dict
    check_v: list
    checked: list
    fe_pts: dict
    oop: OutOfPlaneBranches


def run(quick: bool = False, part: int | None = None) -> CaseResult:
    """Sweeps and checks (module docstring); ``part``: one alpha (:func:`parts`)."""
    ref = CASE.references
    alphas = ref.value("alpha", quick)
    if part is not None:
        alphas = [alphas[part]]
    discs = dyn_discretizations(quick)
    checks, rows, panels, requires = [], [], {}, []
    oop_rows, changes, findings = [], [], []
    for alpha in alphas:
        inc = _inclination(alpha, discs, quick)
        requires += _required(inc.name, inc.is_pi, discs) + [f"sweep_agreement_{inc.name}"]
        fields = {"alpha": inc.name, "check_v": inc.check_v}
        tol = ref.value("sweep_tol")
        checks.append(sweep_agreement("sweep_agreement_{alpha}", inc.checked, tol, **fields))
        onset_checks, onsets = _onsets(inc, discs)
        checks += onset_checks
        checks += _shape_velocity_checks(inc, discs)
        checks += _attractor_checks(inc, next(iter(discs)))
        rows += _rows(inc, discs, onsets)
        checks += verdict_checks("_{alpha}", inc.name, inc.oop, quick)
        oop_rows += verdict_rows(inc.name, inc.oop)
        found = change_texts(inc.name, inc.oop)
        changes += found
        findings.append(survival_text(inc.name, inc.oop) + ".")
        panels[inc.name] = {
            "out_of_plane": inc.oop,
            "alpha": alpha,
            "sweeps": inc.sweeps,
            "diagrams": inc.diags,
            "shapes": attractor_shapes(discs, alpha, inc.shape_v, inc.checked, inc.fe_pts),
        }
    tables = (ref.table("onsets", rows), verdict_table(oop_rows, changes, quick))
    return CASE.result(
        checks,
        quick=quick,
        tables=tables,
        findings=findings,
        data={"panels": panels},
        requires=requires,
    )


def _inclination(alpha: float, discs: dict, quick: bool) -> _Inclination:
    """The diagrams, sweeps and check by integration at ``alpha``."""
    ref = CASE.references
    is_pi = abs(alpha - np.pi) < 1e-12
    shape_v = ref.value("shape_v")[ref.value("alpha").index(alpha)]
    if quick:
        values = sorted(set(shape_v))
    else:
        values = set(ref.value("v")) | set(shape_v)
        if is_pi:
            values |= set(ref.value("v_fine_pi"))
        values = sorted(values)
    # The static branch and the orbits born at its Hopf points, by continuation
    # (FE: with the 3-D verdicts of its orbits, out_of_plane_branches).
    fe_label = next(iter(discs))
    fe_diag, oop = continued_with_verdicts(fe_label, alpha, values, quick)
    diags = {
        label: fe_diag if label == fe_label else continued_diagram(label, alpha, values)
        for label in discs
    }
    hopf_v = {lb: dg.hopf[0]["v"] if dg.hopf else float("inf") for lb, dg in diags.items()}
    # What a sweep up from the sagged state ends on at each v.  At alpha = pi
    # the continued static branch is the straight pipe; below the flutter the
    # pipe rests on the left buckled branch (not continued), so that part is a
    # sweep (equilibria only), checked against the continuation
    # where the straight pipe is stable.
    sweeps = {}
    for label, d in discs.items():
        att = diags[label].attractors()
        if is_pi:
            pre = [v for v in values if v < hopf_v[label]]
            low = {p.v: p for p in sweep_up(d, alpha, pre)} if pre else {}
            att = [low.get(v, p) for v, p in zip(values, att, strict=True)]
        sweeps[label] = att
    # The independent check by integration at a few v of each diagram (at
    # alpha = pi above the flutter: below it the sweep is the check).
    check_v = list(shape_v)
    if is_pi:
        above = [v for v in values if v > hopf_v[fe_label]]
        check_v = sorted({v for v in shape_v if v > hopf_v[fe_label]} | set(above[:1]))
    checked = [sweep_check(dg, check_v) for dg in diags.values()]
    fe_pts = {p.v: p for p in sweeps[fe_label] if p is not None}
    return _Inclination(alpha, alpha_name(alpha), is_pi, shape_v, values, diags, hopf_v, sweeps,
                        check_v, checked, fe_pts, oop)  # fmt: skip


def _onsets(inc: _Inclination, discs: dict) -> tuple[list[Measured], dict]:
    """``onset_<name>_<tag>`` checks (none at α = π) and ``{label: (v_cr, lo, hi, v_H)}``."""
    checks, onsets = [], {}
    tol = CASE.references.value("onset_tol")
    for label, d in discs.items():
        dg = inc.diags[label]
        if inc.is_pi:
            # The straight pipe buckles at v = 0; the onset of oscillation
            # is the flutter of the restabilized straight pipe.
            v_lin = _straight_flutter(d)
            lo, hi = onset_bracket(inc.sweeps[label])
            v_h = inc.hopf_v[label]
        else:
            v_lin = critical_velocity(d, inc.alpha).v_cr
            fields = {"alpha": inc.name, "tag": label_tag(label), "label": label}
            m, v_h, lo, hi = onset_check("onset_{alpha}_{tag}", dg, v_lin, tol, **fields)
            checks.append(m)
        onsets[label] = (v_lin, lo, hi, v_h)
    return checks, onsets


def _shape_velocity_checks(inc: _Inclination, discs: dict) -> list[Measured]:
    """The states at the paper's shape velocities: the onset bracket, or the α = π sequence."""
    fe_label = next(iter(discs))
    fe_pts = inc.fe_pts
    v1, v2, _ = inc.shape_v
    a1, a2 = fe_pts[v1].attractor, fe_pts[v2].attractor
    if not inc.is_pi:
        ok = a1 == "equilibrium" and a2 == "periodic"
        v_h = inc.hopf_v[fe_label]
        fields = {"alpha": inc.name, "v1": v1, "v2": v2, "a1": a1, "a2": a2, "v_h": v_h}
        return [measure("paper_bracket_{alpha}", ok=ok, **fields)]
    pts = [p for p in inc.sweeps[fe_label] if p is not None]
    fe_diag = inc.diags[fe_label]
    buckled = [p.v for p in pts if p.attractor == "equilibrium" and abs(p.Z_tip[0]) > 0.1]
    straight = [p.v for p in pts if p.attractor == "equilibrium" and abs(p.Z_tip[0]) < 1e-3]
    flutter = [p.v for p in pts if p.attractor == "periodic"]
    # The straight states the sweep rests on must be stable on the continued
    # static branch, and the buckled ones where it is unstable.
    consistent = all(fe_diag.equilibrium_at(v).stable for v in straight) and not any(
        fe_diag.equilibrium_at(v).stable for v in buckled
    )
    ordered = buckled and straight and flutter and max(buckled) < min(straight)
    seq_ok = bool(ordered and max(straight) < min(flutter) and consistent)
    sequence = measure("pi_sequence", ok=seq_ok, buckled=buckled, straight=straight,
                       periodic_from=min(flutter) if flutter else None,
                       consistent="stable" if consistent else "NOT stable")  # fmt: skip
    z1 = fe_pts[v1].Z_tip[0]
    fields = {"v1": v1, "v2": v2, "a1": a1, "a2": a2, "z1": z1, "z2": fe_pts[v2].Z_tip}
    shapes = measure("pi_shape_velocities", ok=a1 == "equilibrium" and abs(z1) > 0.1, **fields)
    return [sequence, *_pi_cross_checks(discs[fe_label], pts, fe_diag), shapes]


def _attractor_checks(inc: _Inclination, fe_label: str) -> list[Measured]:
    """Period-1, the tip excursion at v = 10, N = 3 and N = 4 against FE."""
    name = inc.name
    checks = [period_one("period_one_{alpha}", inc.diags, inc.checked, alpha=name)]
    p10 = inc.fe_pts[10.0]
    x_range, z_range = p10.X_tip[1] - p10.X_tip[0], p10.Z_tip[1] - p10.Z_tip[0]
    ok = max(x_range, z_range) >= CASE.references.value("large")
    checks.append(measure("large_{alpha}", ok=ok, alpha=name, x_range=x_range, z_range=z_range))
    for n in PAPER_MODES:
        other = {p.v: p for p in inc.sweeps[f"N = {n}"] if p is not None}
        diffs = []
        for v, p in inc.fe_pts.items():
            q = other.get(v)
            for key in ("X_tip", "Z_tip"):
                if q is None:
                    diffs.append(float("inf"))
                    continue
                a, b = getattr(p, key), getattr(q, key)
                diffs.append(max(abs(a[0] - b[0]), abs(a[1] - b[1])))
        worst = float(np.nanmax(diffs))
        checks.append(measure(f"n{n}_vs_fe_{{alpha}}", worst, alpha=name, fe=fe_label))
    return checks


def _rows(inc: _Inclination, discs: dict, onsets: dict) -> list[tuple]:
    """The table's rows of one α: onset (:func:`_onsets`) and the state at v = 10."""
    rows = []
    for label in discs:
        v_lin, lo, hi, v_h = onsets[label]
        p10 = {p.v: p for p in inc.sweeps[label] if p is not None}[10.0]
        rows.append((inc.name, label, v_lin, lo, hi, p10.attractor, p10.period,
                     p10.X_tip[1] - p10.X_tip[0], p10.Z_tip[1] - p10.Z_tip[0], eta_amplitude(p10),
                     v_h))  # fmt: skip
    return rows


def _straight_flutter(disc) -> float:
    """alpha = pi: v of the flutter that destabilizes the restabilized straight pipe."""
    m = PipeModel(disc, Params(alpha=np.pi, **PAPER_CASE))
    res = analyse_stability(m, v_max=6.0, follow_bifurcations=False)
    return first_flutter(res)


def _pi_cross_checks(disc, pts, diag) -> list[Measured]:
    """alpha = pi: the sweep's jumps (fold, flutter) against the stability analysis."""
    m = PipeModel(disc, Params(alpha=np.pi, **PAPER_CASE))
    res = analyse_stability(m, v_max=6.0, follow_bifurcations=True)
    flutter = first_flutter(res)  # destabilizes the restabilized straight pipe
    folds = [f for b in res.branches if b.name != "primary" for f in b.folds]
    fold = min(folds) if folds else float("nan")
    buckled = [p.v for p in pts if p.attractor == "equilibrium" and abs(p.Z_tip[0]) > 0.1]
    straight = [p.v for p in pts if p.attractor == "equilibrium" and abs(p.Z_tip[0]) < 1e-3]
    periodic = [p.v for p in pts if p.attractor == "periodic"]
    out = []
    if buckled and straight and max(straight) > max(buckled):
        lo, hi = max(buckled), min(v for v in straight if v > max(buckled))
        out.append(measure("pi_fold_vs_sweep", ok=lo <= fold <= hi, lo=lo, hi=hi, fold=fold))
    if straight and periodic and min(straight) < min(periodic):
        lo = max(v for v in straight if v < min(periodic))
        hi = min(periodic)
        v_h = diag.hopf[0]["v"] if diag.hopf else float("nan")
        # The orbits born at the Hopf point are the ones the integration reaches:
        # stable at the first requested v above it.
        born_stable = bool(diag.cycles_at(hi)) and not diag.equilibrium_at(hi).stable
        ok = lo <= flutter <= hi and abs(v_h - flutter) <= 1e-6 and born_stable
        out.append(measure("pi_flutter_vs_sweep", ok=ok, lo=lo, hi=hi, flutter=flutter, v_h=v_h))
    return out


#: The paper's three figures drawn from this case: file stem -> (paper
#: figure, tip quantity, its label).  Fig. 9 carries the shape insets.
FIGURES = {
    "fig08": ("Fig. 8", "eta_tip", r"$\eta(1)$", "transverse tip displacement η(1)"),
    "fig09": ("Fig. 9", "X_tip", r"$X_g(1)$", "tip position X_g(1) along gravity"),
    "fig10": ("Fig. 10", "Z_tip", r"$Z_g(1)$", "horizontal tip position Z_g(1)"),
}


def plot(result: CaseResult, fig=None, which: str = "fig09"):
    """One of Figs. 8-10 (``which``): tip extrema against v per α; Fig. 9 adds the FE shapes."""
    import matplotlib.pyplot as plt

    paper, key, lab, what = FIGURES[which]
    panels = result.data["panels"]
    n = len(panels)
    shapes = which == "fig09"
    ncols = 2 if shapes or n > 1 else 1
    rows = n if shapes else (n + ncols - 1) // ncols
    if fig is None:
        fig = plt.figure(figsize=(5.0 * ncols, 3.8 * rows + 0.6))
    fig.set_layout_engine("constrained")
    if shapes:
        grid = np.atleast_2d(fig.subplots(n, 2, squeeze=False))
        diag, insets = grid[:, 0], grid[:, 1]
    else:
        axes = list(fig.subplots(rows, ncols, squeeze=False).ravel())
        for ax in axes[n:]:
            ax.set_visible(False)
        diag, insets = axes[:n], [None] * n
    for ax, inset, (name, pan) in zip(diag, insets, panels.items(), strict=True):
        draw_continued(ax, pan["diagrams"], key, lab, attractors=pan["sweeps"])
        if "out_of_plane" in pan and marks(
            ax, pan["out_of_plane"], pan["diagrams"][pan["out_of_plane"].label], key
        ):
            add_legend_entry(ax)
        ax.set_title(f"α = {name}: tip extrema", fontsize=10)
        if inset is not None:
            draw_orbit_shapes(inset, pan["shapes"])
            inset.set_title(f"α = {name}: shapes (FE)", fontsize=10)
    finish_figure(
        fig, f"{paper}: extrema of the {what} on the attractor against v", paper_case_line()
    )
    return fig


def plots(result: CaseResult) -> dict:
    """The paper's three figures, ``{"fig08": Figure, "fig09": ..., "fig10": ...}``."""
    return {stem: plot(result, which=stem) for stem in FIGURES}

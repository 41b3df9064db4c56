"""End mass: closed forms, the classical theory and Hill & Swanson's statement.

An end mass Gamma adds inertia and weight at the tip.  fempipe (FE P3:16) against Blevins's
tip-mass frequencies (v = gamma = 0), the heavy column's Bessel solution (alpha = pi, v = 0)
and the classical v_cr(Gamma) of the hanging and the horizontal pipe (to 1e-6); Hill &
Swanson: an end mass destabilizes the horizontal undamped pipe (a ``paper`` check).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import brentq

from fempipe.analyses.stability import compute_spectrum
from fempipe.model.discretization import parse_discretization
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from . import classical
from .case import Case, References
from .checks import CaseResult
from .drawing import CLASSICAL_LINE, DOTS, figure_panels, finish_figure, label_axes, legend_below
from .evaluate import measure
from .variant_runs import FE, agreement, classical_onset, converged, fe_cell, fe_onset

CASE = Case.load("end_mass")


def _params(base: dict, end_mass: float, alpha: float = 0.0, **extra) -> Params:
    return Params(alpha=alpha, end_mass=end_mass, **base, **extra)


def run(quick: bool = False) -> CaseResult:
    """Closed forms, v_cr(Gamma) and Hill & Swanson; see the module docstring."""
    ref = CASE.references
    disc = parse_discretization(fe=FE)
    q0 = np.zeros(disc.n)
    checks = [*_blevins_checks(ref, disc, q0), _heavy_column_check(ref, disc, q0)]
    requires = [f"blevins_frequencies_G{G:g}" for G in ref.value("blevins_end_mass")]
    families, fe = _families(ref, quick)
    for fam, runs in fe.items():
        base = ref.value(fam)
        for G, f in runs.items():
            requires.append(f"fe_vs_classical_{fam}_G{G:g}")
            spec = "fe_vs_classical_{family}_G{G:g}"
            checks.append(agreement(spec, f, families[fam][G], family=fam, base=base, G=G))
    checks.append(converged(_params(ref.value("hanging"), 0.3), 12.0))
    hs_check, hs_table = _hill_swanson(ref)
    checks.append(hs_check)
    tables = [
        ref.table(
            "family",
            [(G, o.v_cr, o.frequency, fe_cell(fe[fam].get(G))) for G, o in families[fam].items()],
            family=fam,
            FE=FE,
            **ref.value(fam),
        )
        for fam in families
    ]
    tables.append(hs_table)
    return CASE.result(
        checks,
        quick=quick,
        tables=tuple(tables),
        data={
            "families": {
                fam: {G: (o.v_cr, o.kind) for G, o in c.items()} for fam, c in families.items()
            },
            "fe": {fam: {G: f.v_cr for G, f in c.items()} for fam, c in fe.items()},
            "params": {fam: ref.value(fam) for fam in families},
            "masses": ref.value("hill_swanson_masses"),
        },
        requires=requires,
    )


def _blevins_checks(ref: References, disc, q0: np.ndarray) -> list:
    """Blevins: the gravity-free cantilever with a tip mass at v = 0."""
    checks = []
    for G in ref.value("blevins_end_mass"):
        exact = classical.tip_mass_frequencies(G, 3)
        p = Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0, end_mass=G)
        lam = compute_spectrum(PipeModel(disc, p), q0).lam
        got = np.sort(lam.imag[lam.imag > 0])[:3]
        err = float(np.max(np.abs(got / exact - 1.0)))
        checks.append(measure("blevins_frequencies_G{G:g}", err, G=G, got=got, exact=exact))
    return checks


def _heavy_column_check(ref: References, disc, q0: np.ndarray):
    """The standing column under its weight and the end weight."""
    G = ref.value("heavy_column_end_mass")
    exact = classical.heavy_column_buckling(G)

    def max_real(g):
        p = Params(alpha=np.pi, beta=0.142, gamma=g, mu=5e-3, end_mass=G)
        return compute_spectrum(PipeModel(disc, p), q0).max_real

    g_fe = brentq(max_real, 0.8 * exact, 1.2 * exact, xtol=1e-12)
    return measure("heavy_column", abs(g_fe / exact - 1.0), gamma_fe=g_fe, exact=exact)


def _families(ref: References, quick: bool) -> tuple[dict, dict]:
    """v_cr(Gamma) of the hanging pipe and the horizontal one: classical and FE onsets."""
    families = {}
    fe = {}
    for fam, v_max in (("hanging", 12.0), ("horizontal", 12.0)):
        base = ref.value(fam)
        grid = sorted(set(ref.value(f"{fam}_curve", quick)) | set(ref.value(f"{fam}_fe", quick)))
        families[fam] = {G: classical_onset(_params(base, G), v_max) for G in grid}
        fe[fam] = {
            G: fe_onset(_params(base, G), families[fam][G].v_cr + 0.5)
            for G in ref.value(f"{fam}_fe", quick)
        }
    return families, fe


def _hill_swanson(ref: References) -> tuple:
    """Hill & Swanson: the end mass destabilizes the horizontal undamped pipe (check, table)."""
    masses = ref.value("hill_swanson_masses")
    hs_rows, ok = [], True
    horiz = ref.value("horizontal")
    for beta in ref.value("hill_swanson_betas"):
        base = dict(horiz, beta=beta)
        v = [classical_onset(_params(base, G), 20.0).v_cr for G in (0.0, *masses)]
        ok &= bool(v[0] > v[1] > v[2])
        hs_rows.append((beta, *v))
    measured = "; ".join(f"β = {r[0]:g}: " + " > ".join(f"{x:.4f}" for x in r[1:]) for r in hs_rows)
    check = measure("hill_swanson", measured, ok=ok)
    table = CASE.references.table("hill_swanson", hs_rows, m0=masses[0], m1=masses[1])
    return check, table


def plot(result: CaseResult, fig=None):
    """(a) v_cr(Γ) hanging, (b) v_cr(Γ) horizontal: classical lines, FE dots."""
    d = result.data
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.2)
    for ax, fam in zip(axes, ("hanging", "horizontal"), strict=True):
        curve = d["families"][fam]
        G = sorted(curve)
        ax.plot(G, [curve[g][0] for g in G], "-", color="#0072B2", lw=1.5)
        fg = sorted(d["fe"][fam])
        ax.plot(fg, [d["fe"][fam][g] for g in fg], "o", color="k", ms=6)
        if fam == "horizontal":
            v_masses = [curve[g][0] for g in d["masses"]]
            ax.plot(d["masses"], v_masses, "D", ms=9, mfc="none", mew=1.4, color="#D55E00")
        p = d["params"][fam]
        title = f"{fam}, β = {p['beta']:g}, γ = {p['gamma']:g}, μ = {p['mu']:g}"
        label_axes(ax, r"end mass $\Gamma = M_e/((m+M)L)$", r"$v_{cr}$", title)
    entries = [
        CLASSICAL_LINE,
        (f"fempipe FE {FE}", DOTS),
        ("Hill & Swanson's masses", {"ls": "", "marker": "D", "mfc": "none", "color": "#D55E00"}),
    ]
    legend_below(fig, entries, ncols=3)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

"""Fig. 7: bifurcation diagram of the hanging pipe (alpha = 0), N = 3 against N = 4.

The paper sweeps v for alpha = 0 with N = 3 and N = 4 modes and concludes
from their agreement that N = 3 is acceptable.  This case sweeps the same
range with the converged FE mesh as well, and checks

* the onset of the limit cycle against the linear critical velocity of each
  discretisation (an independent bisection on the spectrum);
* the paper's statements: equilibrium below v_cr, period-1 limit cycle above,
  N = 3 and N = 4 agreeing, large amplitudes, and the bracket 6.3 < v_cr < 6.5
  implied by the shapes of Fig. 7(c);
* how far N = 3 and N = 4 are from the converged answer.
"""

from __future__ import annotations

import time

import numpy as np

from .case import Case, label_tag
from .checks import CaseResult, Table, below, holds
from .dynamic_runs import attractor, dyn_discretizations, orbit, sweep_up
from .onset import critical_velocity
from .static_shapes import PAPER_MODES

CASE = Case(
    name="fig07",
    caption="Bifurcation diagram for α = 0 (β = 0.142, γ = 18.9, μ = 0.005): extrema of (a) η(1), (b) X_g(1), (c) Z_g(1) on the attractor reached from the sagged state at each v, sweeping v up. Open circles: the finite-element solution (FE; P3:8 = cubic elements, 8 elements, in the full suite; P3:4 in the quick suite); +: N = 3 sine modes; x: N = 4. One circle per v: a static state; two: the minimum and maximum of a limit cycle. (d) shapes (FE) at v = 6.3, 6.5, 10: a static state is one thick line, an oscillation a bundle of thin lines at 12 phases of one period.",
    figure="Fig. 7",
    title="Bifurcation diagrams of the tip, α = 0: N = 3, N = 4 and converged FE",
    paper_shows=(
        "the pipe is stable below v_cr and oscillates on a limit cycle above (Sec. 5)",
        "the onset agrees with the linear stability analysis (Sec. 5)",
        "N = 3 and N = 4 agree well, so N = 3 is acceptable (Sec. 5)",
        "the oscillation amplitudes are large",
    ),
    requires=(
        "period_one",
        "paper_bracket",
        "n3_vs_n4",
        *(f"n{n}_vs_fe" for n in PAPER_MODES),
        "large_amplitude",
    ),
)


def eta_amplitude(p) -> float:
    """Half the peak-to-peak range of eta(1): the oscillation amplitude."""
    return 0.5 * (p.eta_tip[1] - p.eta_tip[0])


def onset_bracket(points) -> tuple[float, float]:
    """(last v with an equilibrium before the first periodic point, that first periodic v)."""
    lo, hi = float("nan"), float("nan")
    for p in points:
        if p.attractor == "periodic":
            hi = p.v
            break
        lo = p.v
    return lo, hi


def run(quick: bool = False) -> CaseResult:
    """Sweeps, onsets and checks; see the module docstring."""
    t0 = time.perf_counter()
    ref = CASE.references
    alpha = ref.value("alpha")
    values = ref.value("v", quick)
    discs = dyn_discretizations(quick)
    requires = [f"onset_{label_tag(lb)}" for lb in discs] + ([] if quick else ["fe_mesh"])
    fe_label = next(iter(discs))
    sweeps = {label: sweep_up(d, alpha, values) for label, d in discs.items()}
    checks, rows = [], []
    onsets = {}
    for label, d in discs.items():
        lo, hi = onset_bracket(sweeps[label])
        v_lin = critical_velocity(d, alpha).v_cr
        onsets[label] = (lo, hi, v_lin)
        checks.append(
            holds(
                f"onset_{label_tag(label)}",
                f"{label}: the limit cycle appears where the linear analysis loses stability",
                bool(np.isfinite(v_lin) and lo <= v_lin <= hi),
                f"sweep: equilibrium at v = {lo:g}, periodic at v = {hi:g}; linear v_cr = {v_lin:.4f}",
                reference="lo ≤ v_cr ≤ hi",
                why="the sweep resolves the onset only to its spacing",
                source="fempipe.validation.onset: Brent's method on the spectral abscissa "
                "of Eqs. (31b)-(33)",
                category="numerics",
            )
        )
    periodic = [(lb, p) for lb, pts in sweeps.items() for p in pts if p.attractor == "periodic"]
    checks.append(
        holds(
            "period_one",
            "every post-flutter attractor is a period-1 limit cycle (Sec. 5)",
            all(p.period_n == 1 for _, p in periodic) and bool(periodic),
            f"{sum(p.period_n == 1 for _, p in periodic)} of {len(periodic)} periodic points are period-1",
            source="paper Sec. 5: 'all these nonlinear oscillations after flutter instability are period-1'",
        )
    )
    fe_pts = {p.v: p for p in sweeps[fe_label]}
    checks.append(
        holds(
            "paper_bracket",
            "equilibrium at v = 6.3 and limit cycle at v = 6.5 (converged FE)",
            fe_pts[6.3].attractor == "equilibrium" and fe_pts[6.5].attractor == "periodic",
            f"v = 6.3: {fe_pts[6.3].attractor}, v = 6.5: {fe_pts[6.5].attractor}",
            reference="6.3 < v_cr < 6.5",
            why="inferred: the shapes of Fig. 7(c) at v = 6.3, 6.5 straddle v_cr",
            source="paper Fig. 7 caption (shapes at v = 6.3, 6.5, 10)",
        )
    )
    amps = {lb: np.array([eta_amplitude(p) for p in pts]) for lb, pts in sweeps.items()}
    d34 = float(np.max(np.abs(amps["N = 3"] - amps["N = 4"])))
    checks.append(
        ref.below(
            "n3_vs_n4",
            "N = 3 and N = 4 agree (largest difference of the η(1) amplitude)",
            d34,
            "amplitude_tol",
            source="paper Sec. 5, Fig. 7",
            category="paper",
        )
    )
    for n in PAPER_MODES:
        dn = float(np.max(np.abs(amps[f"N = {n}"] - amps[fe_label])))
        checks.append(
            ref.below(
                f"n{n}_vs_fe",
                f"N = {n} reproduces the converged η(1) amplitude",
                dn,
                "amplitude_tol",
                source=f"fempipe converged FE ({fe_label})",
                category="paper",
            )
        )
    a10 = eta_amplitude(fe_pts[10.0])
    checks.append(
        holds(
            "large_amplitude",
            "large-amplitude oscillation at v = 10: η(1) amplitude > 0.4 L",
            a10 > 0.4,
            f"η(1) amplitude {a10:.4f} L, Z_g(1) range "
            f"{fe_pts[10.0].Z_tip[1] - fe_pts[10.0].Z_tip[0]:.4f} L",
            reference="> 0.4",
            why="'relatively large' read as almost half the pipe length",
            source="paper Sec. 5, Fig. 7",
        )
    )
    if not quick:  # mesh convergence of the FE amplitude (quick: see the convergence case)
        fine = attractor("FE P3:16", alpha, 10.0)
        dmesh = abs(0.5 * (fine.tip["eta_tip"][1] - fine.tip["eta_tip"][0]) - a10)
        checks.append(
            below(
                "fe_mesh",
                f"{fe_label} limit-cycle amplitude at v = 10 equals P3:16",
                dmesh,
                1e-4,
                why="P3 meshes; the limit cycle is computed by shooting to rtol 1e-8",
                source="fempipe, refined mesh (P3:16)",
            )
        )
    for label in discs:
        lo, hi, v_lin = onsets[label]
        pts = {p.v: p for p in sweeps[label]}
        p10 = pts[10.0]
        rows.append(
            (
                label,
                v_lin,
                lo,
                hi,
                eta_amplitude(p10),
                p10.period,
                p10.X_tip[0],
                p10.X_tip[1],
                p10.max_multiplier,
            )
        )
    table = Table(
        "Onset and the limit cycle at v = 10 (α = 0)",
        (
            "discretisation",
            "linear v_cr",
            "last equilibrium v",
            "first periodic v",
            "η(1) amplitude at v = 10",
            "period at v = 10",
            "X_g(1) min",
            "X_g(1) max",
            "max |ρ| (Floquet multipliers)",
        ),
        tuple(rows),
        note="The amplitude is half the peak-to-peak range of η(1) (units of L); the period in τ.",
    )
    shapes = {}
    for v in ref.value("shape_v"):
        p = fe_pts.get(v)
        if p is not None:
            shapes[v] = orbit(fe_label, discs[fe_label], alpha, v, p.q, p.qdot, p.period)
    return CASE.result(
        checks,
        quick=quick,
        started=t0,
        tables=(table,),
        data={"sweeps": sweeps, "shapes": shapes, "alpha": alpha},
        requires=requires,
    )


def plot(result: CaseResult, fig=None):
    """(a) η(1), (b) X_g(1), (c) Z_g(1) extrema against v; (d) shapes at v = 6.3, 6.5, 10 (FE)."""
    from .drawing import draw_diagram, draw_orbit_shapes, new_figure

    if fig is None:
        fig, axes = new_figure(4, ncols=2, size=4.0)
    else:
        axes = list(fig.subplots(2, 2).ravel())
    d = result.data
    for ax, key, lab, _tag in zip(
        axes[:3],
        ("eta_tip", "X_tip", "Z_tip"),
        (r"$\eta(1)$", r"$X_g(1)$", r"$Z_g(1)$"),
        "abc",
        strict=True,
    ):
        draw_diagram(ax, d["sweeps"], key, lab)
        ax.set_title(f"extrema of {lab}", fontsize=10)
    draw_orbit_shapes(axes[3], d["shapes"])
    axes[3].set_title("inset of Fig. 7(c): shapes (converged FE)", fontsize=9)
    from .drawing import finish_figure

    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

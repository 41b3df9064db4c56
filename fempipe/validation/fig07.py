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

from .checks import CaseResult, Table, below, holds, load_references
from .dynamic_runs import attractor, dyn_discretizations, orbit, sweep_up
from .onset import critical_velocity

CASE = "fig07"
FIGURE = "Fig. 7"
TITLE = "Bifurcation diagrams of the tip, α = 0: N = 3, N = 4 and converged FE"
PAPER_SHOWS = (
    "the pipe is stable below v_cr and oscillates on a limit cycle above (Sec. 5)",
    "the onset agrees with the linear stability analysis (Sec. 5)",
    "N = 3 and N = 4 agree well, so N = 3 is acceptable (Sec. 5)",
    "the oscillation amplitudes are large",
)


def _amp(p) -> float:
    """Half the peak-to-peak range of eta(1): the oscillation amplitude."""
    return 0.5 * (p.eta_tip[1] - p.eta_tip[0])


def _bracket(points) -> tuple[float, float]:
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
    ref = load_references(CASE)
    alpha = ref["alpha"]["value"]
    values = ref["v_quick" if quick else "v"]["value"]
    discs = dyn_discretizations(quick)
    fe_label = next(iter(discs))
    sweeps = {label: sweep_up(d, alpha, values) for label, d in discs.items()}
    checks, rows = [], []
    onsets = {}
    for label, d in discs.items():
        lo, hi = _bracket(sweeps[label])
        v_lin = critical_velocity(d, alpha).v_cr
        onsets[label] = (lo, hi, v_lin)
        checks.append(
            holds(
                f"onset_{label.replace(' ', '').replace('=', '')}",
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
    tol = ref["amplitude_tol"]["value"]
    amps = {lb: np.array([_amp(p) for p in pts]) for lb, pts in sweeps.items()}
    d34 = float(np.max(np.abs(amps["N = 3"] - amps["N = 4"])))
    checks.append(
        below(
            "n3_vs_n4",
            "N = 3 and N = 4 agree (largest difference of the η(1) amplitude)",
            d34,
            tol,
            why=ref["amplitude_tol"]["source"],
            source="paper Sec. 5, Fig. 7",
            category="paper",
        )
    )
    for n in (3, 4):
        dn = float(np.max(np.abs(amps[f"N = {n}"] - amps[fe_label])))
        checks.append(
            below(
                f"n{n}_vs_fe",
                f"N = {n} reproduces the converged η(1) amplitude",
                dn,
                tol,
                why=ref["amplitude_tol"]["source"],
                source=f"fempipe converged FE ({fe_label})",
                category="paper",
            )
        )
    a10 = _amp(fe_pts[10.0])
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
                _amp(p10),
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
            "max |Floquet multiplier|",
        ),
        tuple(rows),
        note="The amplitude is half the peak-to-peak range of η(1) (units of L); the period in τ.",
    )
    shapes = {}
    for v in ref["shape_v"]["value"]:
        p = fe_pts.get(v)
        if p is not None:
            shapes[v] = orbit(fe_label, discs[fe_label], alpha, v, p.q, p.qdot, p.period)
    return CaseResult(
        case=CASE,
        figure=FIGURE,
        title=TITLE,
        paper_shows=PAPER_SHOWS,
        checks=tuple(checks),
        tables=(table,),
        data={"sweeps": sweeps, "shapes": shapes, "alpha": alpha},
        quick=quick,
        runtime=time.perf_counter() - t0,
    )


def draw_diagram(ax, sweeps: dict, key: str, ylabel: str):
    """Tip extrema against v: FE filled circles, N = 3 '+', N = 4 'x'."""
    marks = {"FE": ("o", 4), "N = 3": ("+", 7), "N = 4": ("x", 6)}
    for label, pts in sweeps.items():
        mk, ms = marks["FE" if label.startswith("FE") else label]
        v = np.array([p.v for p in pts])
        lo = np.array([getattr(p, key)[0] for p in pts])
        hi = np.array([getattr(p, key)[1] for p in pts])
        line = ax.plot(v, hi, mk, ms=ms, label=label, mfc="none" if mk == "o" else None)[0]
        ax.plot(v, lo, mk, ms=ms, color=line.get_color(), mfc="none" if mk == "o" else None)
    ax.set_xlabel("v")
    ax.set_ylabel(ylabel)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return ax


def draw_orbit_shapes(ax, shapes: dict):
    """Oscillating shapes (or the static shape) in the global frame, one colour per v."""
    import matplotlib.pyplot as plt

    colors = plt.cm.viridis(np.linspace(0, 0.85, max(len(shapes), 1)))
    for c, (v, orb) in zip(colors, shapes.items(), strict=False):
        for i, (z, x) in enumerate(orb.shapes):
            ax.plot(z, x, color=c, lw=0.8, label=f"v = {v:g}" if i == 0 else None)
    ax.plot([0], [0], "ks", ms=4)
    ax.set_aspect("equal", adjustable="datalim")
    if not ax.yaxis_inverted():
        ax.invert_yaxis()
    ax.set_xlabel(r"$Z_g$")
    ax.set_ylabel(r"$X_g$ (gravity $\downarrow$)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    return ax


def plot(result: CaseResult, fig=None):
    """(a) η(1), (b) X_g(1), (c) Z_g(1) extrema against v; (d) shapes at v = 6.3, 6.5, 10 (FE)."""
    from .drawing import new_figure

    if fig is None:
        fig, axes = new_figure(4, ncols=2, size=4.0)
    else:
        axes = list(fig.subplots(2, 2).ravel())
    d = result.data
    for ax, key, lab, tag in zip(
        axes[:3],
        ("eta_tip", "X_tip", "Z_tip"),
        (r"$\eta(1)$", r"$X_g(1)$", r"$Z_g(1)$"),
        "abc",
        strict=True,
    ):
        draw_diagram(ax, d["sweeps"], key, lab)
        ax.set_title(f"Fig. 7({tag}): α = 0, tip extrema", fontsize=9)
    draw_orbit_shapes(axes[3], d["shapes"])
    axes[3].set_title("Fig. 7(c) inset: shapes (converged FE)", fontsize=9)
    fig.tight_layout()
    return fig

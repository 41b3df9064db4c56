"""Springs: Chen's spring-supported cantilever and a spring inside the hanging pipe.

A spring kappa at the tip of the gravity-free pipe (Chen 1971a; Paidoussis 1998 p. 158)
delays flutter and, stiff, brings divergence at the root of Eq. (3.119): v_cr(kappa) by
fempipe (FE P3:16) and the classical theory (to 1e-6), and Fig. 3.62's picture at two beta.
A spring inside the paper's hanging pipe (Sugiyama et al. 1985a): fempipe against the
classical theory, and how the beam-mode Galerkin method converges there (N^-3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fempipe.model.params import Params

from . import classical
from .case import Case, References
from .checks import CaseResult
from .drawing import DOTS, figure_panels, finish_figure, label_axes, legend_below
from .evaluate import measure
from .variant_runs import FE, agreement, classical_onset, converged, fe_cell, fe_onset

CASE = Case.load("springs")


def _tip(base: dict, kappa: float) -> Params:
    return Params(alpha=0.0, springs=((kappa, 1.0),), **base)


def _interior(base: dict, kappa: float, xi_s: float) -> Params:
    springs = ((kappa, xi_s),) if kappa else ()
    return Params(alpha=0.0, springs=springs, **base)


@dataclass(frozen=True)
class _TipRuns:
    """The tip-spring part: classical v_cr(kappa), fempipe's FE at some kappa, Fig. 3.62's kinds."""

    kappas: list  # every kappa of the curve and of the FE points, sorted
    classical: dict  # kappa -> classical onset
    fe: dict  # kappa -> fempipe's FE onset (the FE points)
    kinds: dict  # beta -> (kind at the smallest kappa, at the largest, its v_cr, Eq. (3.119) root)


@dataclass(frozen=True)
class _InteriorRuns:
    """The interior-spring part: classical and FE v_cr, and the beam-mode Galerkin v_cr."""

    classical: dict  # xi_s -> {kappa -> classical onset}
    fe: dict  # (kappa, xi_s) -> fempipe's FE onset
    modes: list  # the numbers N of beam modes
    galerkin: list  # the beam-mode Galerkin v_cr on N modes, at the first FE spring


def run(quick: bool = False) -> CaseResult:
    """v_cr(kappa) at the tip and inside; see the module docstring."""
    ref = CASE.references
    tip = _tip_runs(ref, quick)
    inner = _interior_runs(ref, quick)
    checks, requires = _checks(ref, tip, inner)
    return CASE.result(
        checks,
        quick=quick,
        tables=_tables(ref, tip, inner),
        data={
            "tip": {k: (o.v_cr, o.kind) for k, o in tip.classical.items()},
            "eq_3_119": {k: classical.tip_spring_divergence(k) for k in tip.kappas},
            "fe_tip": {k: f.v_cr for k, f in tip.fe.items()},
            "interior": {
                x: {k: (o.v_cr, o.kind) for k, o in sorted(c.items())}
                for x, c in inner.classical.items()
            },
            "fe_interior": {key: f.v_cr for key, f in inner.fe.items()},
            "tip_params": ref.value("tip"),
            "interior_params": ref.value("interior"),
        },
        requires=requires,
    )


def _tip_runs(ref: References, quick: bool) -> _TipRuns:
    """v_cr(kappa) of the gravity-free pipe with a tip spring: classical, FE, and the kinds."""
    tip = ref.value("tip")
    kappas = sorted(
        set(ref.value("tip_kappa_curve", quick)) | set(ref.value("tip_kappa_fe", quick))
    )
    tip_cl = {k: classical_onset(_tip(tip, k), 12.0) for k in kappas}
    fe_tip = {
        k: fe_onset(_tip(tip, k), tip_cl[k].v_cr + 0.5) for k in ref.value("tip_kappa_fe", quick)
    }
    # Fig. 3.62: flutter for small kappa, divergence (at Eq. (3.119)) for large kappa.
    kinds = {}
    for beta in ref.value("kind_betas"):
        base = dict(tip, beta=beta)
        lo = classical_onset(_tip(base, kappas[0]), 12.0)
        hi = classical_onset(_tip(base, kappas[-1]), 12.0)
        kinds[beta] = (lo.kind, hi.kind, hi.v_cr, classical.tip_spring_divergence(kappas[-1]))
    return _TipRuns(kappas, tip_cl, fe_tip, kinds)


def _interior_runs(ref: References, quick: bool) -> _InteriorRuns:
    """v_cr(kappa) of the hanging pipe with a spring inside, and Paidoussis' beam-mode Galerkin."""
    hb = ref.value("interior")
    grid = ref.value("interior_kappa_curve", quick)
    positions = sorted({x for _, x in ref.value("interior_springs_fe")})
    interior = {x: {k: classical_onset(_interior(hb, k, x), 15.0) for k in grid} for x in positions}
    fe_int = {}
    for k, x in ref.value("interior_springs_fe", quick):
        cl = interior[x].get(k) or classical_onset(_interior(hb, k, x), 15.0)
        interior[x][k] = cl
        fe_int[(k, x)] = fe_onset(_interior(hb, k, x), cl.v_cr + 0.5)
    # Paidoussis' beam-mode Galerkin at the interior spring.
    k_g, x_g = ref.value("interior_springs_fe")[0]
    pipe = classical.StraightPipe.from_params(_interior(hb, k_g, x_g))
    modes = ref.value("beam_modes")
    gal = [classical.critical_velocity(pipe, 15.0, method="galerkin", n=n).v_cr for n in modes]
    return _InteriorRuns(interior, fe_int, modes, gal)


def _checks(ref: References, tip: _TipRuns, inner: _InteriorRuns) -> tuple[list, list]:
    """The case's measurements and the names this run must emit."""
    checks, requires = [], []
    for k, f in tip.fe.items():
        requires.append(f"fe_vs_classical_tip_K{k:g}")
        checks.append(agreement("fe_vs_classical_tip_K{kappa:g}", f, tip.classical[k], kappa=k))
        root = classical.tip_spring_divergence(k)
        if math.isfinite(root):
            requires.append(f"divergence_eq_3_119_K{k:g}")
            diff = abs(f.v_cr - root) if f.kind == "divergence" else math.inf
            onset = {"fe_kind": f.kind, "fe_v": f.v_cr, "root": root}
            checks.append(measure("divergence_eq_3_119_K{kappa:g}", diff, kappa=k, **onset))
    kappas, kinds = tip.kappas, tip.kinds
    ok = all(
        lo == "flutter" and hi == "divergence" and abs(v - r) < 1e-6
        for lo, hi, v, r in kinds.values()
    )
    text = "; ".join(
        f"β = {b:g}: {lo} / {hi} at {v:.6f} (Eq. (3.119): {r:.6f})"
        for b, (lo, hi, v, r) in kinds.items()
    )
    bounds = {"k_lo": kappas[0], "k_hi": kappas[-1]}
    checks.append(measure("flutter_then_divergence", text, ok=ok, **bounds))
    # Springs inside the hanging pipe.
    for (k, x), f in inner.fe.items():
        requires.append(f"fe_vs_classical_interior_K{k:g}_x{x:g}")
        spec = "fe_vs_classical_interior_K{kappa:g}_x{xi:g}"
        checks.append(agreement(spec, f, inner.classical[x][k], kappa=k, xi=x))
    k_c, x_c = ref.value("interior_springs_fe")[-1]
    hb = ref.value("interior")
    checks.append(converged(_interior(hb, k_c, x_c), 15.0, kappa=k_c, xi=x_c))
    return checks, requires


def _tables(ref: References, tip: _TipRuns, inner: _InteriorRuns) -> tuple:
    """The tip-spring, interior-spring and beam-mode Galerkin tables."""
    base, hb = ref.value("tip"), ref.value("interior")
    k_g, x_g = ref.value("interior_springs_fe")[0]
    reference = inner.classical[x_g][k_g].v_cr
    tip_rows = [
        (k, o.v_cr, o.kind, _root_cell(classical.tip_spring_divergence(k)), fe_cell(tip.fe.get(k)))
        for k, o in tip.classical.items()
    ]
    inner_rows = [
        (x, k, o.v_cr, o.kind, fe_cell(inner.fe.get((k, x))))
        for x, c in inner.classical.items()
        for k, o in sorted(c.items())
    ]
    gal_rows = [(n, v, v - reference) for n, v in zip(inner.modes, inner.galerkin, strict=True)]
    return (
        ref.table("tip", tip_rows, FE=FE, **base),
        ref.table("interior", inner_rows, FE=FE, **hb),
        ref.table("galerkin", gal_rows, kappa=k_g, xi=x_g, reference=reference),
    )


def _root_cell(root: float):
    """A root of Eq. (3.119) for a table cell ("none" below 3 pi)."""
    return root if math.isfinite(root) else "none"


def _curve(ax, points: dict, color: str, xfloor: float | None = None):
    """A classical curve with circles (flutter) and squares (divergence)."""
    ks = np.array(sorted(points))
    x = ks if xfloor is None else np.where(ks > 0, ks, xfloor)
    v = np.array([points[k][0] for k in ks])
    div = np.array([points[k][1] == "divergence" for k in ks])
    ax.plot(x, v, "-", color=color, lw=1.4)
    ax.plot(x[~div], v[~div], "o", mfc="none", color=color, ms=5)
    ax.plot(x[div], v[div], "s", mfc="none", color=color, ms=5)


def plot(result: CaseResult, fig=None):
    """(a) v_cr(κ) with a tip spring, (b) v_cr(κ) with a spring inside the hanging pipe."""
    d = result.data
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.2)
    ax = axes[0]
    _curve(ax, d["tip"], "#0072B2")
    ks = sorted(d["eq_3_119"])
    ax.plot(ks, [d["eq_3_119"][k] for k in ks], "--", color="#D55E00", lw=1.3)
    fk = sorted(d["fe_tip"])
    ax.plot(fk, [d["fe_tip"][k] for k in fk], "o", color="k", ms=5)
    ax.set_xscale("log")
    p = d["tip_params"]
    title = f"tip spring, β = {p['beta']:g}, γ = 0"
    label_axes(ax, r"tip spring $\kappa = kL^3/EI$", r"$v_{cr}$", title)
    ax = axes[1]
    colors = {0.5: "#0072B2", 0.75: "#D55E00"}
    floor = None
    for x, pts in d["interior"].items():
        ks = sorted(pts)
        floor = min(k for k in ks if k > 0) / 3.0
        _curve(ax, pts, colors.get(x, "0.4"), xfloor=floor)
    for (k, _x), v in d["fe_interior"].items():
        ax.plot(k if k > 0 else floor, v, "o", color="k", ms=5)
    ax.set_xscale("log")
    p = d["interior_params"]
    xlabel = r"spring $\kappa$ at $\xi_s$ ($\kappa = 0$ at the left edge)"
    label_axes(ax, xlabel, r"$v_{cr}$", f"hanging, β = {p['beta']:g}, γ = {p['gamma']:g}")
    ring = {"ls": "", "marker": "o", "mfc": "none", "color": "0.3"}
    entries = [
        ("classical, tip / ξ_s = 0.5", {"color": "#0072B2", "lw": 1.4}),
        ("classical, ξ_s = 0.75", {"color": "#D55E00", "lw": 1.4}),
        ("Eq. (3.119), divergence", {"ls": "--", "color": "#D55E00", "lw": 1.3}),
        ("flutter", ring),
        ("divergence", dict(ring, marker="s")),
        (f"fempipe FE {FE}", DOTS),
    ]
    legend_below(fig, entries, ncols=3)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

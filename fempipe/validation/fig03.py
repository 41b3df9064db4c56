"""Fig. 3: static shapes of the horizontal pipe for gamma = 10, 30, 100.

Checks the paper's statements of Sec. 3.2: the deformation grows with the
gravity parameter, and for large gamma the pipe approaches a plumb line
(theta ~ -alpha).  The plumb-line limit is measured as the L2 distance
``||theta + alpha||`` over the pipe, which must shrink as gamma grows; near
the clamp theta(0) = 0 forces a boundary layer of width ~ gamma^(-1/3), so it
never vanishes.
"""

from __future__ import annotations

import time

import numpy as np

from .case import Case
from .checks import CaseResult, Table, holds
from .static_shapes import PANEL_CHECKS, panel_checks, panel_table, static_panel

CASE = Case(
    name="fig03",
    caption="Static shapes of the cantilevered pipe in the global frame (gravity down the page, lengths in units of L, clamp ■ at the origin), one color per flow velocity v (legend below). Solid: converged finite elements (FE, cubic elements; the mesh, P3:n = n cubic elements, is given in the legend); dashed: the paper's Galerkin method with N = 3 sine modes; dotted: N = 4. α = π/2 (horizontal clamp), β = 0.142, μ = 0.005, (a) γ = 10, (b) γ = 30, (c) γ = 100; v = 0, 2, 4, 6 (quick suite: 0 and 4). Linearly unstable states (some eigenvalue with Re λ > 0, Eq. (32)) are drawn grey: γ = 10, v = 6 is past v_cr = 5.61. All shapes are static equilibria; none oscillates.",
    figure="Fig. 3",
    title="Static shapes, α = π/2, γ = 10, 30, 100: the effect of gravity",
    paper_shows=(
        "the deformation becomes larger as γ increases (Sec. 3.2)",
        "for sufficiently large γ the pipe is close to a plumb line, θ ≈ -α (Sec. 3.2)",
    ),
    requires=(*PANEL_CHECKS, "grows_with_gamma", "plumb_line"),
)


def _plumb_distance(fam, alpha: float) -> np.ndarray:
    """L2 norm over xi of theta + alpha, per v (trapezoid on the common grid)."""
    return np.sqrt(np.trapezoid((fam.theta + alpha) ** 2, fam.xi, axis=1))


def run(quick: bool = False) -> CaseResult:
    """Shapes and checks; see the module docstring."""
    t0 = time.perf_counter()
    ref = CASE.references
    v = ref.value("v", quick)
    alpha = ref.value("alpha")
    gammas = ref.value("gamma")
    panels = [static_panel(f"γ = {g:g}", alpha, g, v) for g in gammas]
    checks = panel_checks(panels)
    drop = np.array([p.fe.tips["X_tip"] for p in panels])  # (n_gamma, n_v)
    plumb = np.array([_plumb_distance(p.fe, alpha) for p in panels])
    checks.append(
        holds(
            "grows_with_gamma",
            "the tip drop X_g(1) grows with γ at every v",
            bool(np.all(np.diff(drop, axis=0) > 0)),
            "; ".join(
                f"v = {vv:g}: " + ", ".join(f"{d:.4f}" for d in drop[:, j])
                for j, vv in enumerate(v)
            ),
            source="paper Sec. 3.2, Fig. 3",
        )
    )
    checks.append(
        holds(
            "plumb_line",
            "||θ + α|| decreases as γ grows, at every v (θ → -α for large γ)",
            bool(np.all(np.diff(plumb, axis=0) < 0)),
            "; ".join(
                f"v = {vv:g}: " + ", ".join(f"{d:.3f}" for d in plumb[:, j])
                for j, vv in enumerate(v)
            ),
            source="paper Sec. 3.2, text",
        )
    )
    plumb_table = Table(
        "Distance from the plumb line, ||θ + α||_L2, converged FE",
        ("γ", *[f"v = {vv:g}" for vv in v]),
        tuple((g, *plumb[i]) for i, g in enumerate(gammas)),
        note="||θ + α|| = 0 would be a vertical line; θ(0) = 0 keeps a boundary layer at the clamp.",
    )
    return CASE.result(
        checks,
        quick=quick,
        started=t0,
        tables=(plumb_table, panel_table(panels, "Tip values, α = π/2")),
        data={"panels": panels},
    )


def plot(result: CaseResult, fig=None):
    """One panel per γ; FE solid, N = 3 dashed, N = 4 dotted."""
    from .drawing import plot_shape_panels

    return plot_shape_panels(
        result,
        fig,
        lambda p: f"α = π/2, {p.title}",
        f"{CASE.figure}: {CASE.title}",
        ncols=len(result.data["panels"]),
    )

"""Fig. 3: static shapes of the horizontal pipe for gamma = 10, 30, 100: the deformation grows
with gamma and approaches the plumb line, measured by ||theta + alpha||_L2 (a boundary layer
of width ~ gamma^(-1/3) at the clamp keeps it above zero).
"""

from __future__ import annotations

import numpy as np

from .case import Case
from .checks import CaseResult
from .drawing import plot_shape_panels
from .evaluate import measure
from .static_shapes import panel_checks, panel_table, static_panel

CASE = Case.load("fig03")


def _plumb_distance(fam, alpha: float) -> np.ndarray:
    """L2 norm over xi of theta + alpha, per v (trapezoid on the common grid)."""
    return np.sqrt(np.trapezoid((fam.theta + alpha) ** 2, fam.xi, axis=1))


def run(quick: bool = False) -> CaseResult:
    """Shapes and checks; see the module docstring."""
    ref = CASE.references
    v = ref.value("v", quick)
    alpha = ref.value("alpha")
    gammas = ref.value("gamma")
    panels = [static_panel(f"γ = {g:g}", alpha, g, v) for g in gammas]
    drop = np.array([p.fe.tips["X_tip"] for p in panels])  # (n_gamma, n_v)
    plumb = np.array([_plumb_distance(p.fe, alpha) for p in panels])

    def per_v(a: np.ndarray, fmt: str) -> str:
        return "; ".join(
            f"v = {vv:g}: " + ", ".join(format(d, fmt) for d in a[:, j]) for j, vv in enumerate(v)
        )

    measured = [
        *panel_checks(panels),
        measure("grows_with_gamma", per_v(drop, ".4f"), ok=bool(np.all(np.diff(drop, axis=0) > 0))),
        measure("plumb_line", per_v(plumb, ".3f"), ok=bool(np.all(np.diff(plumb, axis=0) < 0))),
    ]
    velocities = " | ".join(f"v = {vv:g}" for vv in v)
    rows = [(g, *plumb[i]) for i, g in enumerate(gammas)]
    plumb_table = ref.table("plumb", rows, velocities=velocities)
    return CASE.result(
        measured,
        quick=quick,
        tables=(plumb_table, panel_table(panels, "Tip values, α = π/2")),
        data={"panels": panels},
    )


def plot(result: CaseResult, fig=None):
    """One panel per γ; FE solid, N = 3 dashed, N = 4 dotted."""

    return plot_shape_panels(
        result,
        fig,
        lambda p: f"α = π/2, {p.title}",
        f"{CASE.figure}: {CASE.title}",
        ncols=len(result.data["panels"]),
    )

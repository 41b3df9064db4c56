"""Fig. 2(a): convergence of the static shapes in the number of modes N.

The paper's Fig. 2(a) overlays static shapes (gamma = 18.9) for several N
and concludes "N = 3 is valid".  This case draws the shapes by the
mesh-converged FE and by N = 2, 3, 4 modes, and measures how far each modal
centerline is from the converged one.  FE is itself checked against a 2x
refined mesh and against an independent collocation solution of Eq. (31a).
"""

from __future__ import annotations

import time

import numpy as np

from .case import Case
from .checks import CaseResult, holds
from .static_shapes import PANEL_CHECKS, panel_checks, panel_table, static_panel

CASE = Case(
    name="fig02a",
    caption="Static shapes of the cantilevered pipe in the global frame (gravity down the page, lengths in units of L, clamp ■ at the origin), one color per flow velocity v (legend below). Solid: converged finite elements (FE, cubic elements; the mesh, P3:n = n cubic elements, is given in the legend); dashed: the paper's Galerkin method with N = 3 sine modes; dotted: N = 4; dash-dot: N = 2. γ = 18.9, α = π/3, v = 0, 2, 4, 6 (quick suite: fewer v). All shapes are static equilibria; a linearly unstable one would be grey.",
    figure="Fig. 2(a)",
    title="Static shapes, γ = 18.9, α = π/3: convergence in the number of modes N",
    paper_shows=(
        "N = 3 modes are enough for the static shapes (Sec. 3.1)",
        "the modal shapes converge as N grows",
    ),
    requires=(*PANEL_CHECKS, "modal_converges"),
)


def run(quick: bool = False) -> CaseResult:
    """Shapes and checks; see the module docstring."""
    t0 = time.perf_counter()
    ref = CASE.references
    v = ref.value("v", quick)
    alpha, gamma, modes = ref.value("alpha"), ref.value("gamma"), ref.value("modes")
    panel = static_panel("α = π/3", alpha, gamma, v, extra_modes=modes)
    checks = panel_checks([panel])
    errs = [panel.modal_error[f"N = {n}"] for n in modes]
    checks.append(
        holds(
            "modal_converges",
            "the modal shape error decreases as N grows (N = 2, 3, 4)",
            bool(np.all(np.diff(errs) < 0)),
            ", ".join(f"N = {n}: {e:.3g}" for n, e in zip(modes, errs, strict=True)),
            source="paper Sec. 3.1, Fig. 2(a)",
        )
    )
    return CASE.result(
        checks,
        quick=quick,
        started=t0,
        tables=(panel_table([panel], f"Tip values, γ = {gamma:g}, α = π/3"),),
        data={"panels": [panel]},
    )


def plot(result: CaseResult, fig=None):
    """Shapes in the global frame, FE solid, N = 2 dash-dot, N = 3 dashed, N = 4 dotted."""
    from .drawing import plot_shape_panels

    return plot_shape_panels(
        result,
        fig,
        lambda p: f"γ = {p.gamma:g}, {p.title}",
        f"{CASE.figure}: {CASE.title}",
        size=5.0,
    )

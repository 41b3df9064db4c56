"""Fig. 2(a): convergence of the static shapes in the number of modes N.

The paper's Fig. 2(a) overlays static shapes (gamma = 18.9) for several N
and concludes "N = 3 is valid".  This case draws the shapes by the
mesh-converged FE and by N = 2, 3, 4 modes, and measures how far each modal
centreline is from the converged one.  FE is itself checked against a 2x
refined mesh and against an independent collocation solution of Eq. (31a).
"""

from __future__ import annotations

import time

import numpy as np

from .checks import CaseResult, holds, load_references
from .static_shapes import panel_checks, panel_table, static_panel

CASE = "fig02a"
FIGURE = "Fig. 2(a)"
TITLE = "Static shapes, γ = 18.9, α = π/3: convergence in the number of modes N"
PAPER_SHOWS = (
    "N = 3 modes are enough for the static shapes (Sec. 3.1)",
    "the modal shapes converge as N grows",
)


def run(quick: bool = False) -> CaseResult:
    """Shapes and checks; see the module docstring."""
    t0 = time.perf_counter()
    ref = load_references(CASE)
    v = ref["v_quick" if quick else "v"]["value"]
    alpha, gamma = ref["alpha"]["value"], ref["gamma"]["value"]
    panel = static_panel("α = π/3", alpha, gamma, v, extra_modes=ref["modes"]["value"])
    checks = panel_checks([panel])
    errs = [panel.modal_error[f"N = {n}"] for n in ref["modes"]["value"]]
    checks.append(
        holds(
            "modal_converges",
            "the modal shape error decreases as N grows (N = 2, 3, 4)",
            bool(np.all(np.diff(errs) < 0)),
            ", ".join(
                f"N = {n}: {e:.3g}" for n, e in zip(ref["modes"]["value"], errs, strict=True)
            ),
            source="paper Sec. 3.1, Fig. 2(a)",
        )
    )
    return CaseResult(
        case=CASE,
        figure=FIGURE,
        title=TITLE,
        paper_shows=PAPER_SHOWS,
        checks=tuple(checks),
        tables=(panel_table([panel], "Tip values, γ = 18.9, α = π/3"),),
        data={"panels": [panel]},
        quick=quick,
        runtime=time.perf_counter() - t0,
    )


def plot(result: CaseResult, fig=None):
    """Shapes in the global frame, FE solid, N = 2 dash-dot, N = 3 dashed, N = 4 dotted."""
    from .drawing import plot_shape_panels

    return plot_shape_panels(
        result, fig, lambda p: f"Fig. 2(a): γ = {p.gamma:g}, {p.title}", size=5.0
    )

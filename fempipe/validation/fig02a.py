"""Fig. 2(a): static shapes (gamma = 18.9) by converged FE and N = 2, 3, 4 modes: how far each
modal centerline is from FE; FE against a refined mesh and the collocation solver.
"""

from __future__ import annotations

import numpy as np

from .case import Case
from .checks import CaseResult
from .drawing import plot_shape_panels
from .evaluate import measure
from .static_shapes import panel_checks, panel_table, static_panel

CASE = Case.load("fig02a")


def run(quick: bool = False) -> CaseResult:
    """Shapes and checks; see the module docstring."""
    ref = CASE.references
    v = ref.value("v", quick)
    alpha, gamma, modes = ref.value("alpha"), ref.value("gamma"), ref.value("modes")
    panel = static_panel("α = π/3", alpha, gamma, v, extra_modes=modes)
    errs = [panel.modal_error[f"N = {n}"] for n in modes]
    converges = measure(
        "modal_converges",
        ", ".join(f"N = {n}: {e:.3g}" for n, e in zip(modes, errs, strict=True)),
        ok=bool(np.all(np.diff(errs) < 0)),
    )
    return CASE.result(
        [*panel_checks([panel]), converges],
        quick=quick,
        tables=(panel_table([panel], f"Tip values, γ = {gamma:g}, α = π/3"),),
        data={"panels": [panel]},
    )


def plot(result: CaseResult, fig=None):
    """Shapes in the global frame, FE solid, N = 2 dash-dot, N = 3 dashed, N = 4 dotted."""

    return plot_shape_panels(
        result,
        fig,
        lambda p: f"γ = {p.gamma:g}, {p.title}",
        f"{CASE.figure}: {CASE.title}",
        size=5.0,
    )

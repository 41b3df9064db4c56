"""Fig. 4: static shapes for gamma = 18.9 and several alpha: alpha matters, beta does not (beta
is absent from Eq. (31a): exactly independent, reported as a finding).
"""

from __future__ import annotations

import numpy as np

from fempipe.model.discretization import parse_discretization

from .case import Case, alpha_name
from .checks import CaseResult
from .drawing import plot_shape_panels
from .evaluate import measure
from .static_shapes import CONVERGED_FE, panel_checks, panel_table, static_panel, static_shapes

CASE = Case.load("fig04")


def run(quick: bool = False) -> CaseResult:
    """Shapes and checks; see the module docstring."""
    ref = CASE.references
    v = ref.value("v", quick)
    gamma = ref.value("gamma")
    alphas = ref.value("alpha")
    panels = [static_panel(f"α = {alpha_name(a)}", a, gamma, v) for a in alphas]
    # "Strongly dependent on alpha": the tip angle relative to gravity, theta(1) + alpha,
    # and the tip position differ by O(1) between the panels.
    spread = max(
        float(
            np.max(np.hypot(a.fe.X_g[:, -1] - b.fe.X_g[:, -1], a.fe.Z_g[:, -1] - b.fe.Z_g[:, -1]))
        )
        for a in panels
        for b in panels
    )
    # beta independence: Eq. (31a) has no beta.
    fe = parse_discretization(fe=CONVERGED_FE)
    betas = ref.value("beta")
    tips = [static_shapes(fe, alphas[1], gamma, v, beta=b).tips["X_tip"] for b in betas]
    dev = float(max(np.max(np.abs(t - tips[0])) for t in tips))
    measured = [
        *panel_checks(panels),
        measure("alpha_matters", ok=spread > 0.2, spread=spread),
        measure("beta_independent", dev),
    ]
    findings = (
        "Conclusion (ii) says the static deformation is 'hardly affected' by β. In the "
        "dimensionless variables it is exactly independent of β (β is absent from Eq. (31a)); "
        f"measured: tip positions for β = {', '.join(map(str, betas))} differ by {dev:.1e}. "
        "β changes the static shape only through v = (M/EI)^½ U L when the SI flow U is held fixed.",
    )
    return CASE.result(
        measured,
        quick=quick,
        tables=(panel_table(panels, f"Tip values, γ = {gamma:g}"),),
        findings=findings,
        data={"panels": panels},
    )


def plot(result: CaseResult, fig=None):
    """One panel per α; FE solid, N = 3 dashed, N = 4 dotted."""

    return plot_shape_panels(
        result,
        fig,
        lambda p: f"γ = {p.gamma:g}, {p.title}",
        f"{CASE.figure}: {CASE.title}",
        ncols=len(result.data["panels"]),
    )

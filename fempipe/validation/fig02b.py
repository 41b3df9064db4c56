"""Fig. 2(b): the Texier-Dorbolo pipe, static shapes against flow velocity (SI units).

Checks the conversion to Eq. (29), FE against a refined mesh and the collocation solver, and
the paper's statements (largest deformation at U = 0, straightening as U grows).  Texier &
Dorbolo's measured shapes are not available: the experimental comparison is not repeated.
"""

from __future__ import annotations

import numpy as np

from fempipe.model.params import PipeSI

from .bvp import solve_static_bvp
from .case import Case
from .checks import CaseResult
from .drawing import draw_shapes, figure_panels, finish_figure
from .evaluate import measure
from .static_shapes import discretizations, refined, static_shapes

CASE = Case.load("fig02b")


def pipe() -> PipeSI:
    """The Texier-Dorbolo pipe of Sec. 3.1 in SI units."""
    ref = CASE.references
    return PipeSI(**{k: ref.value(k) for k in ("L", "EI", "m", "M", "g", "alpha")})


def run(quick: bool = False) -> CaseResult:
    """Compute the shapes and the checks; see the module docstring."""
    ref = CASE.references
    si = pipe()
    p = si.params(0.0)
    U = np.array(ref.value("U", quick))
    v = np.array([si.v_of_U(u) for u in U])
    fams, fe_label, mesh_err = _shapes(p, v)
    fe = fams[fe_label]
    bvp_X, bvp_Z = _bvp_tips(p, v, fe)
    bvp_err = max(np.max(np.abs(fe.tips[k] - b)) for k, b in (("X_tip", bvp_X), ("Z_tip", bvp_Z)))
    drop_mm = fe.tips["X_tip"] * si.L * 1e3
    modal, rows = _modal_checks(si, U, v, fams, fe_label)
    measured = [
        measure("beta", p.beta),
        measure("gamma", p.gamma),
        measure("v_over_U", si.v_of_U(1.0)),
        measure("fe_mesh_converged", mesh_err, fe=fe_label),
        measure("fe_vs_bvp", bvp_err),
        measure(
            "max_at_rest",
            ok=bool(np.argmax(drop_mm) == 0),
            drop=drop_mm,
            U_max=U[np.argmax(drop_mm)],
        ),
        measure("straightens", ok=bool(np.all(np.diff(drop_mm) < 0)), drop=drop_mm),
        *modal,
    ]
    z_mm, bvp_mm = fe.tips["Z_tip"] * si.L * 1e3, bvp_X * si.L * 1e3
    fe_rows = [(U[i], v[i], drop_mm[i], z_mm[i], fe.tips["theta_tip"][i], bvp_mm[i])
               for i in range(len(U))]  # fmt: skip
    dimensionless = {"beta": p.beta, "gamma": p.gamma, "v_over_U": si.v_of_U(1.0)}
    table_fe = ref.table("tips", fe_rows, fe=fe_label, **dimensionless)
    table_modal = ref.table("modal", rows)
    return CASE.result(
        measured,
        quick=quick,
        tables=(table_fe, table_modal),
        data={"fams": fams, "U": U, "L": si.L},
    )


def _shapes(p, v: np.ndarray) -> tuple[dict, str, float]:
    """The shapes by label (FE first), the FE label and its mesh error (tips against 2x refined)."""
    discs = discretizations()
    fams = {
        label: static_shapes(d, p.alpha, p.gamma, v, beta=p.beta, mu=0.0, name=label)
        for label, d in discs.items()
    }
    fe_label = next(iter(fams))
    fe = fams[fe_label]
    fine = static_shapes(refined(discs[fe_label]), p.alpha, p.gamma, v, beta=p.beta, mu=0.0)
    mesh_err = max(np.max(np.abs(fe.tips[k] - fine.tips[k])) for k in ("X_tip", "Z_tip"))
    return fams, fe_label, mesh_err


def _bvp_tips(p, v: np.ndarray, fe) -> tuple[np.ndarray, np.ndarray]:
    """The tip position by the independent strong-form solver, started from the FE shapes."""
    bvp_X = np.empty_like(v)
    bvp_Z = np.empty_like(v)
    for i, vi in enumerate(v):
        guess = lambda x, t=fe.theta[i]: np.interp(x, fe.xi, t)  # noqa: E731
        sol = solve_static_bvp(p.alpha, p.gamma, vi, guess=guess)
        bvp_X[i], bvp_Z[i] = sol.X_tip, sol.Z_tip
    return bvp_X, bvp_Z


def _modal_checks(si: PipeSI, U, v, fams: dict, fe_label: str) -> tuple[list, list]:
    """The paper's modal truncations against the converged FE: measurements and table rows."""
    fe = fams[fe_label]
    measured, rows = [], []
    for label, fam in fams.items():
        if label == fe_label:
            continue
        err_mm = np.abs(fam.tips["X_tip"] - fe.tips["X_tip"]) * si.L * 1e3
        shape_mm = np.max(np.hypot(fam.X_g - fe.X_g, fam.Z_g - fe.Z_g), axis=1) * si.L * 1e3
        limit = 0.01 * si.L * 1e3
        measured.append(measure(f"modal_{label[-1]}_shape", float(np.max(shape_mm)), limit=limit))
        drop = fam.tips["X_tip"] * si.L * 1e3
        rows += [(label, U[i], v[i], drop[i], err_mm[i], shape_mm[i]) for i in range(len(U))]
    return measured, rows


def plot(result: CaseResult, fig=None):
    """Shapes in mm, gravity down, one color per U; FE solid, N = 3 dashed, N = 4 dotted."""

    fig, axes = figure_panels(fig, 1, size=5.0)
    U = result.data["U"]
    label = lambda i, v: f"U = {U[i]:g} m/s"  # noqa: E731
    draw_shapes(
        axes[0], result.data["fams"], scale=result.data["L"] * 1e3, unit="mm", v_label=label
    )
    axes[0].set_title("Texier-Dorbolo pipe, α = π/2")

    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

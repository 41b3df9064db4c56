"""Static states on one branch for the figure cases of Section 3 (Figs. 2-4).

Every discretization reaches the sagged state by continuation in gamma from the straight
pipe, then follows it in v (Newton from theta = 0 may land elsewhere near alpha = 9 pi/10).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.stability import linearly_stable
from fempipe.analyses.statics import solve_path
from fempipe.model.discretization import Modal, parse_discretization
from fempipe.model.kinematics import compute_shape, compute_tip
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel

from .bvp import solve_static_bvp
from .checks import Table
from .evaluate import Measured, measure

#: The FE discretization whose static tip values are converged to < 1e-8
#: (each case checks this against a 2x refined mesh).
CONVERGED_FE = "P3:16"
#: The paper's truncations.
PAPER_MODES = (3, 4)


def discretizations(extra_modes: Sequence[int] = ()) -> dict[str, object]:
    """``{"FE P3:16": FiniteElement, "N = 3": Modal(3), "N = 4": Modal(4), ...}``."""
    out: dict[str, object] = {f"FE {CONVERGED_FE}": parse_discretization(fe=CONVERGED_FE)}
    for n in sorted(set(PAPER_MODES) | set(extra_modes)):
        out[f"N = {n}"] = Modal(n)
    return out


@dataclass(frozen=True)
class StaticShapes:
    """Static states at several ``v`` on one branch: ``q``, ``tips`` (theta_tip, varsigma_tip,
    eta_tip, X_tip, Z_tip), centerlines ``X_g``, ``Z_g``, ``theta`` on the grid ``xi``.
    """

    name: str
    params: Params
    v: np.ndarray
    q: list
    tips: dict
    xi: np.ndarray
    X_g: np.ndarray
    Z_g: np.ndarray
    theta: np.ndarray
    newton_iterations: np.ndarray


def _common_grid(disc, q, alpha, xi):
    """Centerline sampled 16 points per cell and interpolated to ``xi`` (error < 1e-5)."""
    s = compute_shape(disc, q, alpha, points_per_cell=16)
    return (np.interp(xi, s.xi, s.X_g), np.interp(xi, s.xi, s.Z_g), np.interp(xi, s.xi, s.theta))


def static_shapes(
    disc,
    alpha: float,
    gamma: float,
    v_values: Sequence[float],
    beta: float = PAPER_CASE["beta"],
    mu: float = PAPER_CASE["mu"],
    name: str = "",
    n_gamma_steps: int = 8,
    n_points: int = 201,
) -> StaticShapes:
    """Static states at ``v_values`` (ascending from >= 0) on the sagged branch; ``n_gamma_steps``
    continuation steps in gamma, ``n_points`` on the common xi grid."""
    v_values = np.asarray(v_values, dtype=float)
    if np.any(np.diff(v_values) < 0) or np.any(v_values < 0):
        raise ValueError("v_values must be ascending and >= 0")
    base = Params(alpha=alpha, beta=beta, gamma=0.0, mu=mu, v=0.0)
    model = PipeModel(disc, base)
    path = solve_path(model, np.linspace(0.0, gamma, n_gamma_steps + 1), parameter="gamma")
    q0 = path[-1].q
    model = model.with_params(Params(alpha=alpha, beta=beta, gamma=gamma, mu=mu, v=0.0))
    vs = np.concatenate([[0.0], v_values]) if v_values[0] > 0 else v_values
    sols = solve_path(model, vs, parameter="v", q0=q0)
    if v_values[0] > 0:
        sols = sols[1:]
    xi = np.linspace(0.0, 1.0, n_points)
    tips: dict[str, list] = {}
    X, Z, T = [], [], []
    for s in sols:
        for k, val in compute_tip(disc, s.q, alpha).items():
            tips.setdefault(k, []).append(val)
        x_, z_, t_ = _common_grid(disc, s.q, alpha, xi)
        X.append(x_)
        Z.append(z_)
        T.append(t_)
    return StaticShapes(
        name=name or disc.name,
        params=model.params,
        v=v_values,
        q=[s.q for s in sols],
        tips={k: np.array(v) for k, v in tips.items()},
        xi=xi,
        X_g=np.array(X),
        Z_g=np.array(Z),
        theta=np.array(T),
        newton_iterations=np.array([s.iterations for s in sols]),
    )


def shape_distance(a: StaticShapes, b: StaticShapes) -> np.ndarray:
    """max over xi of |r_a(xi) - r_b(xi)| in the global frame, per v (units of L)."""
    return np.max(np.hypot(a.X_g - b.X_g, a.Z_g - b.Z_g), axis=1)


def refined(disc):
    """The 2x refined discretization (elements split, or twice the modes)."""
    return disc.refined(2)


@dataclass(frozen=True)
class Panel:
    """One panel of a static figure: ``fams`` by label, ``mesh_error`` (tip change under 2x
    refinement), ``bvp_error`` (tip against the collocation solver), ``modal_error`` (largest
    centerline distance from FE by label), ``stable`` (each FE state's linear stability).
    """

    title: str
    alpha: float
    gamma: float
    fams: dict
    mesh_error: float
    bvp_error: float
    modal_error: dict
    stable: tuple = ()

    @property
    def fe(self) -> StaticShapes:
        return next(iter(self.fams.values()))


def static_panel(
    title: str,
    alpha: float,
    gamma: float,
    v_values: Sequence[float],
    extra_modes: Sequence[int] = (),
    max_doublings: int = 3,
) -> Panel:
    """Shapes by FE (refined from :data:`CONVERGED_FE` until the tips change by < 1e-9, at most
    ``max_doublings`` times) and modal N, with the mesh and BVP cross-checks.
    """
    discs = discretizations(extra_modes)
    fams = {
        label: static_shapes(d, alpha, gamma, v_values, name=label) for label, d in discs.items()
    }
    fe_label = next(iter(fams))
    fe_disc = discs[fe_label]
    fe = fams[fe_label]
    # Refine the FE mesh until the tip positions change by < 1e-9 under
    # doubling (a steep boundary layer at the clamp for large gamma needs it).
    for _ in range(max_doublings + 1):
        fine_disc = refined(fe_disc)
        fine = static_shapes(fine_disc, alpha, gamma, v_values)
        mesh_err = max(float(np.max(np.abs(fe.tips[k] - fine.tips[k]))) for k in ("X_tip", "Z_tip"))
        if mesh_err < 1e-9:
            break
        fe_disc, fe = fine_disc, fine
    if fe_disc is not discs[fe_label]:
        fams.pop(fe_label)
        fe_label = f"FE {fe_disc.name}"
        fams = {fe_label: replace(fe, name=fe_label), **fams}
        fe = fams[fe_label]
    errs = []
    for i, v in enumerate(fe.v):
        sol = solve_static_bvp(
            alpha, gamma, v, guess=lambda x, t=fe.theta[i]: np.interp(x, fe.xi, t)
        )
        errs.append(max(abs(sol.X_tip - fe.tips["X_tip"][i]), abs(sol.Z_tip - fe.tips["Z_tip"][i])))
    bvp_err = float(max(errs))
    modal_err = {
        label: float(np.max(shape_distance(fam, fe)))
        for label, fam in fams.items()
        if label != fe_label
    }
    return Panel(title, alpha, gamma, fams, mesh_err, bvp_err, modal_err, _stability(fe_disc, fe))


def _stability(disc, fam: StaticShapes) -> tuple[bool, ...]:
    """Linear stability of each state of a family (the criterion of ``fempipe critical``)."""

    model = PipeModel(disc, fam.params)
    return tuple(
        bool(linearly_stable(model.with_params(replace(fam.params, v=float(v))), q))
        for v, q in zip(fam.v, fam.q, strict=True)
    )


def panel_checks(panels: Sequence[Panel]) -> list[Measured]:
    """``fe_mesh_converged``, ``fe_vs_bvp``, ``modal_3_shape``, ``modal_4_shape`` (worst panel)."""
    worst = {n: max(panels, key=lambda p, n=n: p.modal_error[f"N = {n}"]) for n in PAPER_MODES}
    meshes = sorted({next(iter(p.fams))[3:] for p in panels})
    return [
        measure("fe_mesh_converged", max(p.mesh_error for p in panels), meshes=meshes),
        measure("fe_vs_bvp", max(p.bvp_error for p in panels)),
        *(
            measure(f"modal_{n}_shape", w.modal_error[f"N = {n}"], worst=w.title)
            for n, w in worst.items()
        ),
    ]


def panel_table(panels: Sequence[Panel], title: str) -> Table:
    """Tip values of every panel and discretization, with the modal errors."""
    rows = []
    for p in panels:
        fe = p.fe
        for label, fam in p.fams.items():
            for i, v in enumerate(fam.v):
                err = (
                    ""
                    if label == next(iter(p.fams))
                    else float(np.hypot(fam.X_g[i] - fe.X_g[i], fam.Z_g[i] - fe.Z_g[i]).max())
                )
                rows.append((p.title, label, v, fam.tips["X_tip"][i], fam.tips["Z_tip"][i],
                             fam.tips["theta_tip"][i], err))  # fmt: skip
    return Table(
        title,
        ("panel", "discretization", "v", "X_g(1)", "Z_g(1)", "θ(1)", "max distance to FE"),
        tuple(rows),
        note="Dimensionless (lengths in units of L). Last column: largest centerline distance "
        "from the converged FE shape.",
    )

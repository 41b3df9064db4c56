"""The whirl of the hanging pipe: a periodic orbit of the 3-D FE model and a rotating-frame BVP.

Hanging, the pipe is axisymmetric: planar cycles and whirls are born together (O(2) Hopf).
The whirl at v = 10 by (a) the BVP of :mod:`fempipe.validation.whirl_bvp` (power balance
checked), (b) the FE periodic orbit (:func:`fempipe.analyses.three_d.find_whirl`) on cubic
meshes, rate and tip radius against the BVP's, converging in h, and (b') the BVP's whirl as a
state of the FE model over half a turn; (c) the finding: the whirl is unstable, the planar
cycle is the attractor.  docs/theory/space.md.
"""

from __future__ import annotations

import math

import numpy as np

from fempipe.analyses.limit_cycle.attractor import find_attractor
from fempipe.analyses.stability.eigensolvers import quadratic_eigen
from fempipe.analyses.stability.linear import linearized_matrices
from fempipe.analyses.three_d.whirl import find_whirl, whirl_state
from fempipe.core.parallel import single_blas
from fempipe.model.discretization import FiniteElement
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D, planar_state
from fempipe.solvers.radau import Radau

from .case import Case
from .checks import CaseResult, Table
from .drawing import figure_panels, finish_figure, label_axes
from .evaluate import measure
from .whirl_bvp import solve_whirl_bvp

CASE = Case.load("space_whirl")


def _flutter_slope(disc, v_guess: float, omega_guess: float):
    """The planar flutter eigenmode's theta on 101 points: the BVP continuation's start."""

    model = PipeModel(disc, Params(alpha=0.0, v=v_guess))
    K, C, M = linearized_matrices(model, np.zeros(disc.n))
    lam, X, _ = quadratic_eigen(K, C, M)
    i = int(np.argmin(np.abs(lam - 1j * omega_guess)))
    Phi = disc.Phi.toarray() if hasattr(disc.Phi, "toarray") else np.asarray(disc.Phi)
    th = Phi @ X[:, i]
    x = np.r_[0.0, disc.quad.x]
    xi = np.linspace(0.0, 1.0, 101)
    return lam[i], np.interp(xi, x, np.r_[0, th.real]) + 1j * np.interp(xi, x, np.r_[0, th.imag])


@single_blas
def run(quick: bool = False) -> CaseResult:
    """(a)-(c) of the module docstring."""

    ref = CASE.references
    v = float(ref.value("v"))
    meshes = ref.value("meshes", quick)
    lam, slope = _flutter_slope(FiniteElement(4, 3), *ref.value("hopf_guess"))
    bvp = solve_whirl_bvp(v, hopf=(ref.value("hopf_guess")[0], abs(lam.imag)), slope=slope)
    balance = abs(bvp.supply - bvp.dissipation) / bvp.dissipation
    free_meshes = ref.value("free_meshes", quick)
    free = [_free_rotation(bvp, ne, v) for ne in free_meshes]
    hs = [1.0 / ne for ne in free_meshes]
    checks = [
        measure("bvp_power_balance", balance),
        measure("free_rate_order", -_order(hs, [abs(r - bvp.omega) for r, _ in free])),
        measure("free_rigidity_order", -_order(hs, [var for _, var in free])),
    ]
    rows, whirls = _shot_whirls(bvp, meshes, v)
    ne, w = whirls[-1]
    tag = f"P3:{ne}"
    checks += _whirl_checks(ref, bvp, whirls, quick)
    space = PipeModel3D(FiniteElement(meshes[-1], 3), Params(alpha=0.0, v=v))
    planar = find_attractor(PipeModel(space.disc, space.params))
    tips_planar = None
    if planar.cycle is not None:
        d = space.tip_coordinates(np.array([planar_state(q) for q in planar.cycle.orbit_q]))
        tips_planar = (d["Z_tip"], d["Y_tip"])
    d = space.tip_coordinates(w.cycle.orbit_q)
    table, free_table = _tables(bvp, v, rows, free_meshes, free)
    findings = [
        f"The hanging pipe at v = {v:g} whirls at ω = {bvp.omega:.6g} (period "
        f"{bvp.period:.6g}, tip radius {bvp.radius:.5g}) in the rotating frame; the FE whirl "
        f"({tag}) has ω = {w.omega:.6g}, and Floquet multipliers of modulus up to "
        f"{w.max_nontrivial:.4g}: unstable, the planar cycle is the attractor."
    ]
    data = {"v": v, "bvp": {"omega": bvp.omega, "radius": bvp.radius, "period": bvp.period}}
    data.update(whirls={n: x.to_dict() for n, x in whirls}, tip_whirl=(d["Z_tip"], d["Y_tip"]))
    tables = [table, free_table]
    return CASE.result(
        checks,
        quick=quick,
        tables=tables,
        findings=findings,
        data={**data, "tip_planar": tips_planar},
    )


def _whirl_checks(ref, bvp, whirls, quick: bool) -> list:
    """The finest shot whirl against the BVP, its rigidity and stability, its omega error's order."""
    ne, w = whirls[-1]
    tag = f"P3:{ne}"
    omega_tol, estimate = ref.value("omega_tol", quick), ""
    if len(whirls) > 1:
        # the finest mesh's own error, estimated from the last two (Richardson, order p)
        (n_a, w_a), (n_b, w_b) = whirls[-2:]
        p = ref.value("omega_estimate_order")
        error = abs(w_a.omega - w_b.omega) / ((n_b / n_a) ** p - 1.0)
        omega_tol, estimate = omega_tol * error, f": {error:.3g} from P3:{n_a} and P3:{n_b}"
    omega = {"reference": bvp.omega, "atol": omega_tol, "estimate": estimate, "tag": tag}
    checks = [
        measure("omega_vs_bvp", w.omega, **omega),
        measure("radius_vs_bvp", w.radius, reference=bvp.radius, tag=tag),
        measure("radius_constant", w.radius_variation, tag=tag),
        measure("rigid_rotation", w.rotation_defect, tag=tag),
        measure("whirl_unstable", w.max_nontrivial, ok=w.max_nontrivial > 1.0),
    ]
    if len(whirls) > 1:
        errs = [abs(x.omega - bvp.omega) for _, x in whirls]
        hs = [1.0 / n for n, _ in whirls]
        checks.append(measure("omega_order", -_order(hs, errs)))
    return checks


def _shot_whirls(bvp, meshes, v: float) -> tuple[list, list]:
    """The whirl shot on each mesh from the BVP's state: (table rows, [(mesh, Whirl)])."""

    rows, whirls = [], []
    for ne in meshes:
        space = PipeModel3D(FiniteElement(ne, 3), Params(alpha=0.0, v=v))
        U, Ud = whirl_state(space, lambda x: bvp.sol(x)[3:6], bvp.omega)
        w = find_whirl(space, U, Ud, bvp.period)
        whirls.append((ne, w))
        rows.append(
            [
                f"P3:{ne}",
                w.omega,
                w.period,
                w.radius,
                w.omega - bvp.omega,
                w.radius - bvp.radius,
                w.radius_variation,
                w.rotation_defect,
                w.max_nontrivial,
            ]
        )
    return rows, whirls


def _tables(bvp, v: float, rows, free_meshes, free) -> tuple[Table, Table]:
    """The shot whirls against the BVP, and the free motion from the BVP's state."""
    whirl = {"v": v, "omega": bvp.omega, "radius": bvp.radius, "period": bvp.period}
    table = CASE.references.table("whirl", (tuple(r) for r in rows), **whirl)
    free_table = CASE.references.table(
        "free",
        tuple(
            (f"P3:{n}", r, r - bvp.omega, var)
            for n, (r, var) in zip(free_meshes, free, strict=True)
        ),
    )
    return table, free_table


def _free_rotation(bvp, n_elements: int, v: float) -> tuple[float, float]:
    """(rate, radius variation) of the FE motion from the BVP's whirl over half a period."""

    space = PipeModel3D(FiniteElement(n_elements, 3), Params(alpha=0.0, v=v))
    U, Ud = whirl_state(space, lambda x: bvp.sol(x)[3:6], bvp.omega)
    stepper = Radau(PipeDynamics3D(space), U, Ud, rtol=1e-9)
    ts, Us = [0.0], [U]
    for t, q, _ in stepper.steps(0.5 * bvp.period):
        ts.append(t)
        Us.append(q)
    d = space.tip_coordinates(np.array(Us))
    rad = np.hypot(d["Z_tip"], d["Y_tip"])
    ang = np.unwrap(np.arctan2(d["Y_tip"], d["Z_tip"]))
    return float((ang[-1] - ang[0]) / ts[-1]), float((rad.max() - rad.min()) / rad.mean())


def _order(hs, errs) -> float:
    return math.log(errs[-2] / errs[-1]) / math.log(hs[-2] / hs[-1])


def plot(result: CaseResult, fig=None):
    """(a) The tip from above; (b) the differences against the BVP."""
    from matplotlib.ticker import NullFormatter

    d = result.data
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.2)
    ax = axes[0]
    z, y = d["tip_whirl"]
    # the finest mesh's whirl (the one drawn): unstable orbits dashed, as in every figure
    stable = d["whirls"][max(d["whirls"], key=int)]["stable"]
    lab = "whirl, FE" + ("" if stable else " (unstable)")
    ax.plot(z, y, "-" if stable else "--", color="#0072B2", lw=2.0, label=lab)
    R = d["bvp"]["radius"]
    a = np.linspace(0, 2 * np.pi, 361)
    ax.plot(R * np.cos(a), R * np.sin(a), "-", color="k", lw=0.8, label="whirl, BVP")
    if d["tip_planar"] is not None:
        zp, yp = d["tip_planar"]
        ax.plot(zp, yp, "-", color="#D55E00", lw=2.0, label="planar cycle")
    ax.set_aspect("equal")
    ax.set_ylim(-1.3 * R, 2.0 * R)  # room for the legend above the orbits
    label_axes(ax, "Z_tip", "Y_tip", f"tip from above, v = {d['v']:g}")
    ax.legend(fontsize=9, loc="upper center", ncols=2)
    ax = axes[1]
    ns = sorted(d["whirls"])
    om = [abs(d["whirls"][n]["omega"] - d["bvp"]["omega"]) for n in ns]
    rr = [abs(d["whirls"][n]["radius"] - d["bvp"]["radius"]) for n in ns]
    ax.loglog(ns, om, "-o", color="#0072B2", label="|Δω|")
    ax.loglog(ns, rr, "-s", color="#009E73", label="|Δ radius|")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_xticks(ns, [str(n) for n in ns])
    label_axes(ax, "elements (cubic)", "FE - BVP", "against the rotating-frame BVP", grid="both")
    ax.legend(fontsize=9)
    finish_figure(fig, CASE.title, parameters="α = 0, β = 0.142, γ = 18.9, μ = 0.005")
    return fig

"""Sec. 5, closing remark: the symmetries of Eq. (20).

The paper says the solution for alpha is antisymmetric with that for alpha - pi; but
alpha -> alpha - pi turns gravity upside down.  The true symmetry is (theta, alpha) ->
(-theta, -alpha), with mirror buckled branches at alpha = 0, pi.  Measured on converged static
states: ||theta_alpha + theta_{-alpha}|| (round-off), ||theta_alpha + theta_{alpha - pi}||
(O(1): the claim fails), and the mirror buckled states at alpha = pi.  0 <= alpha <= pi still
suffices, by the true symmetry and 2 pi periodicity.
"""

from __future__ import annotations

import numpy as np

from fempipe.analyses.statics import solve_static
from fempipe.model.discretization import parse_discretization
from fempipe.model.kinematics import compute_shape
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from .case import Case, alpha_name
from .checks import CaseResult
from .drawing import figure_panels, finish_figure
from .evaluate import measure
from .static_shapes import CONVERGED_FE, static_shapes

CASE = Case.load("symmetry")


def _l2(disc, q) -> float:
    th = disc.Phi @ q
    return float(np.sqrt(disc.quad.w @ th**2))


def run(quick: bool = False) -> CaseResult:
    """Static states for the symmetry pairs; see the module docstring."""
    ref = CASE.references
    gamma, v = ref.value("gamma"), ref.value("v")
    disc = parse_discretization(fe=CONVERGED_FE)
    pairs = ref.value("alpha_pairs")[: 1 if quick else None]
    a_m = ref.value("alpha_mirror")

    def state(alpha):
        return static_shapes(disc, alpha, gamma, [v])

    rows, shapes = [], {}
    mirror = [state(a_m), state(-a_m)]
    shapes[alpha_name(a_m)], shapes[alpha_name(-a_m)] = mirror
    mirror_dev = _l2(disc, mirror[0].q[0] + mirror[1].q[0])
    rows.append(
        (
            f"{alpha_name(a_m)} vs {alpha_name(-a_m)}",
            "true: (θ, α) → (−θ, −α)",
            _l2(disc, mirror[0].q[0]),
            mirror_dev,
        )
    )
    paper_dev = []
    for a, b in pairs:
        sa, sb = state(a), state(b)
        shapes.setdefault(alpha_name(a), sa)
        shapes.setdefault(alpha_name(b), sb)
        dev = _l2(disc, sa.q[0] + sb.q[0])
        paper_dev.append(dev)
        rows.append(
            (f"{alpha_name(a)} vs {alpha_name(b)}", "paper: α → α − π", _l2(disc, sa.q[0]), dev)
        )
    # alpha = pi: mirror buckled states.
    bk = ref.value("buckled")
    model = PipeModel(disc, Params(alpha=bk["alpha"], gamma=bk["gamma"], v=bk["v"]))
    # Guess theta = +/- 2.5 sin(pi xi / 2) (least squares on the quadrature
    # points): smaller guesses let Newton fall back onto the straight state.
    Phi = disc.Phi.toarray() if disc.sparse else disc.Phi
    guess = np.linalg.lstsq(Phi, 2.5 * np.sin(np.pi * disc.quad.x / 2.0), rcond=None)[0]
    up = solve_static(model, q0=guess)
    down = solve_static(model, q0=-guess)
    size = _l2(disc, up.q)
    buck_dev = _l2(disc, up.q + down.q)
    measured = [
        measure("mirror_symmetry", mirror_dev),
        measure("paper_alpha_minus_pi", ok=max(paper_dev) < 1e-6, dev=paper_dev),
        measure("buckled_exists", ok=size > 0.1, size=size),
        measure("buckled_mirror", buck_dev),
    ]
    buckled = {
        "+": compute_shape(disc, up.q, bk["alpha"]),
        "−": compute_shape(disc, down.q, bk["alpha"]),
    }
    findings = (
        "The paper's closing remark of Sec. 5 is wrong: α → α − π flips the sign of the gravity "
        "term (γ → −γ), it is not a symmetry. Measured on static states (γ = "
        f"{gamma:g}, v = {v:g}): ||θ_α + θ_(α−π)||_L2 = "
        + ", ".join(f"{d:.3f}" for d in paper_dev)
        + f" for the pairs {', '.join(f'({alpha_name(a)}, {alpha_name(b)})' for a, b in pairs)}, whereas "
        f"the true symmetry (θ, α) → (−θ, −α) holds to {mirror_dev:.1e}. The paper's conclusion "
        "that 0 ≤ α ≤ π suffices survives, by the true symmetry.",
    )
    table = CASE.references.table("antisymmetry", tuple(rows))
    return CASE.result(
        measured,
        quick=quick,
        tables=(table,),
        findings=findings,
        explained=("paper_alpha_minus_pi",),
        data={"shapes": shapes, "pairs": pairs, "mirror": a_m, "buckled": buckled},
    )


def plot(result: CaseResult, fig=None):
    """Left: α and −α (mirror images); middle: the paper's pairs α, α − π; right: α = π buckled."""

    d = result.data
    fig, axes = figure_panels(fig, 3, ncols=3)
    sh = d["shapes"]
    a = alpha_name(d["mirror"])
    groups = [
        ([a, alpha_name(-d["mirror"])], "true symmetry: α ↔ −α"),
        ([n for pair in d["pairs"] for n in map(alpha_name, pair)], "paper's claim: α ↔ α − π"),
    ]
    for ax, (names, title) in zip(axes[:2], groups, strict=True):
        for n in names:
            s = sh[n]
            ax.plot(s.Z_g[0], s.X_g[0], label=f"α = {n}")
        ax.set_title(title)
    for k, s in d["buckled"].items():
        axes[2].plot(s.Z_g, s.X_g, label=f"buckled {k}")
    axes[2].set_title("α = π: mirror buckled states")
    for ax in axes:
        ax.plot([0], [0], "ks", ms=4)
        ax.axvline(0.0, color="0.7", lw=0.8)
        ax.set_aspect("equal", adjustable="datalim")
        ax.invert_yaxis()
        ax.set_xlabel(r"$Z_g$ ($/L$)")
        ax.set_ylabel(r"$X_g$ ($/L$, gravity $\downarrow$)")
        ax.legend(fontsize=9)
        ax.grid(alpha=0.3)

    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

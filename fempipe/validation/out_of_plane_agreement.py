"""Parts (c) to (e) of the out-of-plane validation case (fempipe.validation.out_of_plane).

(c) :func:`agreement_checks`, :func:`inclined_variants_check` and
:func:`classical_check`: the strong form of :mod:`fempipe.validation.lateral`
against fempipe and the classical theory; (d) :func:`order_checks`, the
observed orders of the out-of-plane v_cr; (e) :func:`finding_checks`, the
out-of-plane v_cr against the in-plane one.  Parts (a) and (b), and the
helpers for the spectra, are in :mod:`fempipe.validation.out_of_plane_runs`.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from fempipe.analyses import stability
from fempipe.analyses.statics import solve_static
from fempipe.model.discretization import FiniteElement, Modal, discretization_from_name
from fempipe.model.operators import PipeModel
from fempipe.model.out_of_plane import out_of_plane_model
from fempipe.model.params import Params

from . import classical, lateral
from .case import alpha_name
from .checks import Table, below, holds
from .out_of_plane_runs import (
    nearest_distance,
    outside_cluster,
    pencil_eigenvalues,
    refinement_slope,
)

__all__ = [
    "agreement_checks",
    "classical_check",
    "finding_checks",
    "inclined_variants_check",
    "order_checks",
]


# ---------------------------------------------------------------------------
# (c) the strong form against fempipe


def _pair(p: Params, fe: str, v_max: float, v_min: float = 0.0, p_spec: int = 24):
    """The out-of-plane onset by fempipe (FE) and by the strong form."""
    m = out_of_plane_model(PipeModel(discretization_from_name(fe), p))
    r = stability.critical_velocity(m, v_max=v_max, v_min=v_min)
    s = lateral.critical_velocity(p, v_max, v_min=v_min, disc=lateral.HermiteSpectral(p_spec))
    c = r.critical
    fe_out = (float(r.v_cr), c.type, float(c.frequency)) if c else (math.nan, "stable", math.nan)
    return fe_out, s


def agreement_checks(ref, quick: bool):
    tol, v_max = ref.value("agreement"), ref.value("v_max")
    fe = ref.value("fe_agreement", quick)
    pp = ref.value("spectral_p")
    base = ref.value("paper_case")
    runs = []
    if quick:
        aq = ref.value("agreement_quick")
        runs.append(
            (
                Params(alpha=aq["alpha_over_pi"] * math.pi, mu=aq["mu"], **base),
                aq["v_min"],
                aq["v_max"],
                "paper",
            )
        )
    else:
        for mu in ref.value("mu"):
            for a in ref.value("agreement_alpha_over_pi"):
                runs.append((Params(alpha=a * math.pi, mu=mu, **base), 0.0, v_max, "paper"))
        runs.append((Params(**ref.value("texier")), 0.0, v_max, "texier"))
    checks, rows, requires, strong = [], [], [], {}
    for p, v_lo, v_hi, who in runs:
        (v_fe, kind_fe, w_fe), s = _pair(p, fe, v_hi, v_lo, pp[0])
        tag = f"{who}_a{alpha_name(p.alpha)}_mu{p.mu:g}"
        strong[(who, round(p.alpha, 12), p.mu)] = s
        what = (
            f"{'Texier & Dorbolo' if who == 'texier' else 'paper'} β = {p.beta:g}, "
            f"γ = {p.gamma:g}, μ = {p.mu:g}, α = {alpha_name(p.alpha)}"
            + (f" (onset searched in [{v_lo:g}, {v_hi:g}])" if v_lo > 0 else "")
        )
        same = kind_fe == s.kind
        for q, a, b in (("v_cr", v_fe, s.v_cr), ("frequency", w_fe, s.frequency)):
            name = f"strong_vs_fe_{q}_{tag}"
            requires.append(name)
            checks.append(
                below(
                    name,
                    f"{what}: fempipe's out-of-plane {q} ({fe}: {a:.10f}, {kind_fe}) equals the "
                    f"strong form's ({s.method}: {b:.10f}, {s.kind}); absolute",
                    abs(a - b) if same else math.inf,
                    tol,
                    why=ref.source("agreement"),
                    source="fempipe.validation.lateral: the out-of-plane deflection w in strong "
                    "form on C1 spectral elements about the solve_bvp static state",
                )
            )
        rows.append(
            (
                who,
                alpha_name(p.alpha),
                p.beta,
                p.gamma,
                p.mu,
                s.v_cr,
                v_fe,
                v_fe - s.v_cr,
                s.frequency,
                w_fe,
                w_fe - s.frequency,
                s.kind,
            )
        )
    # The strong form converged: the crossing eigenvalue on p and on the larger p,
    # about the same static state.
    p0 = runs[0][0]
    s0 = next(iter(strong.values()))
    state = lateral.loaded_state(replace(p0, v=s0.v_cr))
    crossing = []
    for k in pp:
        lam = lateral.eigen(*lateral.HermiteSpectral(k).matrices(state)[:3])
        crossing.append(lam[np.argmin(np.abs(lam - s0.lam))])
    diff = abs(crossing[1] - crossing[0])
    checks.append(
        below(
            "strong_converged",
            f"strong form at its onset ({alpha_name(p0.alpha)}, μ = {p0.mu:g}, v = {s0.v_cr:.10f}): "
            f"the crossing eigenvalue on p = {pp[0]} equals p = {pp[1]} (absolute)",
            float(diff),
            1e-10,
            why="spectral elements: the error falls faster than any power of p; 1e-10 is a "
            "hundred times below the agreement asked",
            source="fempipe.validation.lateral (refinement)",
        )
    )
    table = Table(
        "(c) Out-of-plane onset: strong form against fempipe " + fe,
        (
            "pipe",
            "α",
            "β",
            "γ",
            "μ",
            "v_cr strong",
            f"v_cr {fe}",
            "Δv",
            "ω strong",
            f"ω {fe}",
            "Δω",
            "kind",
        ),
        tuple(rows),
    )
    return checks, [table], requires, strong


def inclined_variants_check(ref):
    """Eigenvalues of an inclined pipe with every variant: FE against the strong form."""
    iv = dict(ref.value("inclined_variants"))
    iv["springs"] = tuple(tuple(s) for s in iv["springs"])
    p = Params(**ref.value("paper_case"), **iv)
    st = lateral.loaded_state(p)
    K, C, M, parts = lateral.HermiteSpectral(ref.value("spectral_p")[0]).matrices(st)
    lam_s = outside_cluster(lateral.eigen(K, C, M, bending=parts["bending"]), p.mu)
    lam_s = lam_s[np.abs(lam_s) < 300.0]
    m = PipeModel(discretization_from_name(ref.value("inclined_fe")), p)
    # Newton from the straight pipe reaches the sagged state at this inclination (as the
    # gravity continuation does, at 1/40 of its cost with two springs); the tips are compared.
    q = solve_static(m).q
    tip_gap = abs(float(m.disc.tip @ q) - st.theta_tip)
    lam_f = pencil_eigenvalues(*out_of_plane_model(m).linearization(q))
    err = nearest_distance(lam_f, lam_s)
    return below(
        "inclined_variants_vs_strong",
        f"α = {alpha_name(p.alpha)}, v = {p.v:g}, μ = {p.mu:g}, Γ = {p.end_mass:g}, "
        f"σ = {p.external_damping:g}, springs "
        + ", ".join(f"κ = {k:g} at ξ_s = {x:g}" for k, x in p.springs)
        + f": the out-of-plane eigenvalues with |λ| < 300 ({lam_s.size}, outside the "
        f"Kelvin-Voigt cluster) of {m.disc.name} equal the strong form's (relative; the "
        f"static tips differ by {tip_gap:.1e})",
        err if tip_gap < 1e-8 else math.inf,
        1e-7,
        why=ref.source("inclined_fe") + "; the springs' static forces enter N",
        source="fempipe.validation.lateral about the solve_bvp static state (with springs)",
    )


# ---------------------------------------------------------------------------
# (d) observed orders


def order_checks(ref, quick: bool, v_ref: float):
    base = ref.value("paper_case")
    p = Params(alpha=0.5 * math.pi, mu=0.0, **base)
    lo, hi = ref.value("orders_window")
    expected = ref.value("expected_orders")
    checks, rows, requires, curves = [], [], [], {}
    for fam, ns in ref.value("orders", quick).items():
        errs, dofs = [], []
        for n in ns:
            d = FiniteElement(n, int(fam[1])) if fam.startswith("P") else Modal(n, basis=fam)
            r = stability.critical_velocity(out_of_plane_model(PipeModel(d, p)), hi, lo)
            errs.append(abs(float(r.v_cr) - v_ref))
            dofs.append(d.n)
        slopes = [refinement_slope(ns[k : k + 2], errs[k : k + 2]) for k in range(len(ns) - 1)]
        curves[fam] = (dofs, errs, slopes[-1])
        name = f"order_{fam}"
        requires.append(name)
        e = expected[fam]
        unit = "elements" if fam.startswith("P") else "modes"
        checks.append(
            holds(
                name,
                f"out-of-plane v_cr (α = π/2, μ = 0) on {fam}, {unit} {', '.join(map(str, ns))}: "
                f"observed order {slopes[-1]:.2f} (slopes {', '.join(f'{s:.2f}' for s in slopes)})",
                abs(slopes[-1] - e) <= ref.value("order_tolerance"),
                slopes[-1],
                reference=e,
                why=ref.source("order_tolerance"),
                source=ref.source("expected_orders")
                + "; errors against the strong form (fempipe.validation.lateral)",
                category="numerics",
            )
        )
        for n, dof, err in zip(ns, dofs, errs, strict=True):
            rows.append((fam, n, dof, err))
        rows.append((fam, "slopes", "", ", ".join(f"{s:.2f}" for s in slopes)))
    table = Table(
        f"(d) Error of the out-of-plane v_cr (α = π/2, μ = 0) against the strong form "
        f"({v_ref:.12f})",
        ("discretization", "elements / modes", "unknowns", "|v_cr − v_ref|"),
        tuple(rows),
    )
    return checks, [table], requires, curves


# ---------------------------------------------------------------------------
# (e) in the plane against out of the plane


def finding_checks(ref, quick: bool):
    base = ref.value("paper_case")
    fe = ref.value("table_fe")
    alphas = [a * math.pi for a in ref.value("table_alpha_over_pi", quick)]
    lo, hi = ref.value("orders_window") if quick else (0.0, ref.value("v_max"))
    rows, curves, found = [], {}, []
    for mu in ref.value("mu")[:1] if quick else ref.value("mu"):
        for a in alphas:
            m = PipeModel(discretization_from_name(fe), Params(alpha=a, mu=mu, **base))
            ri = stability.critical_velocity(m, hi, lo)
            ro = stability.critical_velocity(out_of_plane_model(m), hi, lo)
            ci, co = ri.critical, ro.critical
            vi, vo = float(ri.v_cr), float(ro.v_cr)
            curves.setdefault(mu, []).append((a, vi, vo))
            found.append((a, mu, vi, vo))
            rows.append(
                (
                    mu,
                    alpha_name(a),
                    vi,
                    ci.type if ci else "stable",
                    ci.frequency if ci else math.nan,
                    vo,
                    co.type if co else "stable",
                    co.frequency if co else math.nan,
                    vo - vi,
                    (vo - vi) / vi if vi > 0 else "—",
                )
            )
    table = Table(
        f"(e) Critical flow velocity in and out of the plane (β = {base['beta']:g}, "
        f"γ = {base['gamma']:g}, FE {fe})",
        (
            "μ",
            "α",
            "v_cr in plane",
            "kind",
            "ω",
            "v_cr out of plane",
            "kind",
            "ω",
            "out − in",
            "relative",
        ),
        tuple(rows),
        note="At α = π the primary branch is the straight standing pipe, buckled at v = 0 "
        "(γ > 7.837) in every plane alike; on its buckled branch the out-of-plane spectrum "
        "holds the neutral rotation and is otherwise stable (checks of (b)).",
    )
    inside = [f for f in found if 0.0 < f[0] < math.pi - 1e-12]
    checks, findings, explained = [], [], []
    if inside:
        gap = [(vo - vi, a, mu, vi, vo) for a, mu, vi, vo in inside]
        d, a, mu, vi, vo = min(gap)
        ok = all(g[0] >= 0.0 for g in gap)
        lower = sum(g[0] < 0.0 for g in gap)
        checks.append(
            holds(
                "planar_v_cr_is_first",
                "the planar analysis gives the first instability of the (round) pipe: no "
                "out-of-plane mode is unstable below the in-plane v_cr, for 0 < α < π",
                ok,
                f"out-of-plane v_cr lower at {lower} of {len(inside)} (α, μ); most at "
                f"α = {alpha_name(a)}, μ = {mu:g}: {vo:.6f} against {vi:.6f} "
                f"({d:+.4f}, {100 * d / vi:+.1f} %)",
                reference="out-of-plane v_cr ≥ in-plane v_cr",
                why="a statement of the paper's scope; the out-of-plane problem is validated "
                "by (a)-(d)",
                source="paper Sec. 4 and Fig. 6: v_cr of the planar problem",
            )
        )
        if not ok:
            explained.append("planar_v_cr_is_first")
            worst = {}
            for g in gap:
                if g[0] < worst.get(g[2], (math.inf,))[0]:
                    worst[g[2]] = g
            findings.append(
                "a round pipe first loses stability out of the plane: at every inclination "
                f"0 < α < π computed ({len(inside)} (α, μ) pairs) the out-of-plane flutter sets "
                "in below the paper's in-plane v_cr, by up to "
                + "; ".join(
                    f"{-g[0]:.4f} ({-100 * g[0] / g[3]:.1f} %) at α = {alpha_name(g[1])}, "
                    f"μ = {g[2]:g} ({g[4]:.4f} against {g[3]:.4f})"
                    for g in worst.values()
                )
                + ". At α = 0 the two coincide (the straight hanging pipe has no preferred "
                "plane). Fig. 6's v_cr is therefore an upper bound for a pipe free to move "
                "out of its plane."
            )
    else:
        checks.append(
            holds(
                "planar_v_cr_is_first",
                "no inclination strictly between 0 and π computed",
                False,
                "none",
                why="needs an inclination 0 < α < π",
                source="paper Sec. 4 and Fig. 6",
            )
        )
    at0 = [r for r in rows if r[1] == "0"]
    if at0:
        checks.append(
            below(
                "alpha0_in_equals_out",
                "α = 0: the out-of-plane v_cr equals the in-plane v_cr (largest difference over μ)",
                max(abs(r[8]) for r in at0),
                1e-9,
                why="identical spectra on the straight pipe (a); both located to 1e-10",
                source="the in-plane analysis (fempipe.analyses.stability.critical_velocity)",
            )
        )
    return checks, [table], findings, explained, curves


# ---------------------------------------------------------------------------


def classical_check(ref):
    """The strong form at alpha = 0 is the classical hanging pipe (every variant but mu_h)."""
    var = dict(ref.value("variants"))
    var["springs"] = tuple(tuple(s) for s in var["springs"])
    var.pop("v")
    var["hysteretic_damping"] = 0.0
    p = Params(alpha=0.0, **ref.value("paper_case"), **var)
    cl = classical.critical_velocity(
        classical.StraightPipe.from_params(p), ref.value("v_max"), method="legendre", n=24
    )
    s = lateral.critical_velocity(p, ref.value("v_max"))
    return below(
        "strong_vs_classical",
        f"the strong form at α = 0 with μ = {p.mu:g}, Γ = {p.end_mass:g}, "
        f"σ = {p.external_damping:g}, spring κ = {p.springs[0][0]:g} at ξ_s = "
        f"{p.springs[0][1]:g}: v_cr ({s.v_cr:.12f}) equals the classical theory's "
        f"({cl.v_cr:.12f})",
        abs(s.v_cr - cl.v_cr) if s.kind == cl.kind else math.inf,
        1e-10,
        why="the same straight-pipe equation on the same kind of elements, about different "
        "static states (solve_bvp's theta = 0, the classical straight pipe): round-off and "
        "the 1e-12 crossings",
        source="fempipe.validation.classical (Paidoussis 1998, Eqs. (3.70)-(3.71))",
    )

"""Fig. 6: the critical flow velocity against the inclination alpha.

v_cr of the sagged state for several beta (gamma = 18.9) and gamma (beta = 0.142) by the
converged FE mesh (N = 3, 4 for the reference case), from the independent
:func:`fempipe.validation.onset.critical_velocity`, compared with
:mod:`fempipe.analyses.stability`.  Checks the trends of Sec. 4 on the in-plane v_cr; the
out-of-plane v_cr (``plane="out"``) comes first at every inclined alpha (checked).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.analyses import stability
from fempipe.analyses.stability import PLANES, find_critical_velocity
from fempipe.model.discretization import Modal, parse_discretization
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel

from .case import Case
from .checks import CaseResult, Table
from .drawing import figure_panels, finish_figure, label_axes
from .evaluate import Measured, measure
from .onset import Onset, critical_velocity

CASE = Case.load("fig06")
FE = "P3:8"
BASE_BETA, BASE_GAMMA, MU = PAPER_CASE["beta"], PAPER_CASE["gamma"], PAPER_CASE["mu"]


def _deg(a: float) -> str:
    return f"{np.degrees(a):.0f}°"


def _v_cr(onsets) -> np.ndarray:
    """The critical velocities of a list of :class:`~fempipe.validation.onset.Onset`."""
    return np.array([o.v_cr for o in onsets])


@dataclass(frozen=True)
class _Curves:
    """Onsets per α: ``by_beta``, ``by_gamma`` (in the plane, FE), ``out_beta``, ``out_gamma`` (out
    of it), ``modal`` (the reference case by ``"N = 3"``, ``"N = 4"``).
    """

    by_beta: dict
    by_gamma: dict
    out_beta: dict
    out_gamma: dict
    modal: dict


def run(quick: bool = False) -> CaseResult:
    """v_cr curves and checks; see the module docstring."""
    ref = CASE.references
    alphas = np.array(ref.value("alpha", quick))
    betas, gammas = ref.value("beta", quick), ref.value("gamma", quick)
    fe = parse_discretization(fe=FE)
    cv = _curves(fe, alphas, betas, gammas)
    base = cv.by_beta[BASE_BETA]
    checks = [_mesh_check(alphas, base), _flutter_check(alphas, cv)]
    checks += _trend_checks(alphas, betas, gammas, cv)
    checks.append(_stability_cross_check(fe, alphas, base))
    checks += _out_of_plane_checks(fe, alphas, cv.by_beta, cv.by_gamma, cv.out_beta, cv.out_gamma)
    requires = [f"falls_with_alpha_b{b:g}" for b in betas]
    requires += [f"falls_with_alpha_g{g:g}" for g in gammas if g != BASE_GAMMA]
    headline = _headline(alphas, cv.by_beta, cv.by_gamma, cv.out_beta, cv.out_gamma)
    data = {"alphas": alphas, "curves": cv, "headline": headline}
    tables = _tables(alphas, betas, gammas, cv)
    return CASE.result(checks, quick=quick, tables=tables, data=data, requires=requires)


def _curves(fe, alphas: np.ndarray, betas, gammas) -> _Curves:
    """The onsets of every curve (the reference curve computed once)."""

    def curve(disc, beta, gamma, plane="in"):
        return [
            critical_velocity(disc, a, beta=beta, gamma=gamma, mu=MU, plane=plane) for a in alphas
        ]

    by_beta = {b: curve(fe, b, BASE_GAMMA) for b in betas}
    by_gamma = {
        g: (by_beta[BASE_BETA] if g == BASE_GAMMA else curve(fe, BASE_BETA, g)) for g in gammas
    }
    out_beta = {b: curve(fe, b, BASE_GAMMA, "out") for b in betas}
    out_gamma = {
        g: (out_beta[BASE_BETA] if g == BASE_GAMMA else curve(fe, BASE_BETA, g, "out"))
        for g in gammas
    }
    modal = {f"N = {n}": curve(Modal(n), BASE_BETA, BASE_GAMMA) for n in (3, 4)}
    return _Curves(by_beta, by_gamma, out_beta, out_gamma, modal)


def _mesh_check(alphas: np.ndarray, base: list[Onset]) -> Measured:
    """Mesh convergence of the reference curve: P3:8 against P3:16 at three α."""
    fine = parse_discretization(fe="P3:16")
    idx = [0, len(alphas) // 2, len(alphas) - 1]
    case = {"beta": BASE_BETA, "gamma": BASE_GAMMA, "mu": MU}
    dmesh = max(abs(critical_velocity(fine, alphas[i], **case).v_cr - base[i].v_cr) for i in idx)
    return measure("fe_mesh", dmesh, fe=FE, degrees=[_deg(alphas[i]) for i in idx])


def _flutter_check(alphas: np.ndarray, cv: _Curves) -> Measured:
    """Every first instability in the plane (every β and γ) is flutter."""
    labelled = [(f"β = {b:g}, γ = {BASE_GAMMA:g}", c) for b, c in cv.by_beta.items()] + [
        (f"β = {BASE_BETA:g}, γ = {g:g}", c) for g, c in cv.by_gamma.items() if g != BASE_GAMMA
    ]
    other = [
        f"{lab}, α = {_deg(alphas[i])}: {o.kind} at v = {o.v_cr:.6f}"
        for lab, c in labelled
        for i, o in enumerate(c)
        if o.kind != "flutter"
    ]
    return measure("flutter", "all flutter" if not other else "; ".join(other), ok=not other)


def _falls_with_alpha(alphas: np.ndarray, spec: str, v, **fields) -> Measured:
    """v_cr falls with alpha: ``v`` decreases at every step of the α grid."""
    rises = [
        (_deg(alphas[i]), _deg(alphas[i + 1]), v[i + 1] - v[i])
        for i in range(len(v) - 1)
        if v[i + 1] > v[i]
    ]
    text = "rises on " + "; ".join(f"{a0}→{a1} by {d:.4f}" for a0, a1, d in rises)
    return measure(spec, text if rises else "monotone decreasing", ok=not rises, **fields)


def _trend_checks(alphas: np.ndarray, betas, gammas, cv: _Curves) -> list[Measured]:
    """v_cr falls with α, rises with β, and the effect of γ changes sign with α (Sec. 4)."""
    spec_b, spec_g = "falls_with_alpha_b{beta:g}", "falls_with_alpha_g{gamma:g}"
    checks = [
        _falls_with_alpha(alphas, spec_b, _v_cr(cv.by_beta[b]), beta=b, gamma0=BASE_GAMMA)
        for b in betas
    ]
    checks += [
        _falls_with_alpha(alphas, spec_g, _v_cr(cv.by_gamma[g]), gamma=g, beta0=BASE_BETA)
        for g in gammas
        if g != BASE_GAMMA
    ]
    # v_cr rises with beta at every alpha.
    b = sorted(betas)
    rise = np.diff([_v_cr(cv.by_beta[x]) for x in b], axis=0)
    worst = np.unravel_index(np.argmin(rise), rise.shape)
    fields = {"b0": b[worst[0]], "b1": b[worst[0] + 1], "at": _deg(alphas[worst[1]])}
    checks.append(
        measure("rises_with_beta", ok=bool(np.all(rise > 0)), increase=np.min(rise), **fields)
    )
    # gamma effect changes sign with alpha.
    G = np.array([_v_cr(cv.by_gamma[g]) for g in sorted(gammas)])
    d_small, d_large = G[-1, 0] - G[0, 0], G[-1, -1] - G[0, -1]
    fields = {
        "small": d_small,
        "large": d_large,
        "gamma_min": min(gammas),
        "gamma_max": max(gammas),
    }
    fields.update(a0=_deg(alphas[0]), a1=_deg(alphas[-1]))
    checks.append(measure("gamma_sign_change", ok=d_small > 0 and d_large < 0, **fields))
    return checks


def _tables(alphas: np.ndarray, betas, gammas, cv: _Curves) -> tuple[Table, Table, Table]:
    """The reference case against the paper's modes, in and out of the plane, and the v_cr grid."""
    base, out = cv.by_beta[BASE_BETA], cv.out_beta[BASE_BETA]
    rows, out_rows = [], []
    for i, a in enumerate(alphas):
        fe_v = base[i].v_cr
        o = out[i]
        out_rows.append(
            (_deg(a), fe_v, base[i].frequency, o.v_cr, o.frequency, (o.v_cr - fe_v) / fe_v)
        )
        rows.append((_deg(a), fe_v, base[i].frequency, cv.modal["N = 3"][i].v_cr,
                     cv.modal["N = 3"][i].v_cr - fe_v, cv.modal["N = 4"][i].v_cr,
                     cv.modal["N = 4"][i].v_cr - fe_v))  # fmt: skip
    ref, case = CASE.references, {"beta": BASE_BETA, "gamma": BASE_GAMMA, "mu": MU, "FE": FE}
    parameters = " | ".join([*[f"β = {b:g}" for b in betas], *[f"γ = {g:g}" for g in gammas]])
    grid_rows = [
        (
            _deg(a),
            *[cv.by_beta[b][i].v_cr for b in betas],
            *[cv.by_gamma[g][i].v_cr for g in gammas],
        )
        for i, a in enumerate(alphas)
    ]
    table = ref.table("modes", rows, **case)
    grid = ref.table("grid", grid_rows, parameters=parameters, **case)
    out_table = ref.table("planes", out_rows, **case)
    return table, out_table, grid


def _headline(alphas, by_beta, by_gamma, out_beta, out_gamma) -> str:
    """The report's headline fragment: how much earlier the pipe leaves the plane."""
    gaps = [
        (cin[i].v_cr - cout[i].v_cr) / cin[i].v_cr
        for fin, fout in ((by_beta, out_beta), (by_gamma, out_gamma))
        for key, cin in fin.items()
        for i, cout in ((i, fout[key]) for i in range(len(alphas)))
        if alphas[i] > 0 and cout[i].kind == "flutter" and cout[i].v_cr < cin[i].v_cr
    ]
    if not gaps:
        return ""
    return (
        f"for every β and γ of Fig. 6's grid (μ = {MU:g}, α up to {_deg(alphas[-1])}), by "
        f"{100 * min(gaps):.2f} % to {100 * max(gaps):.2f} %"
    )


def _out_of_plane_checks(fe, alphas, by_beta, by_gamma, out_beta, out_gamma) -> list[Measured]:
    """Out of the plane first at every inclined α, equal at α = 0, and against the stability module."""
    curves = [(f"β = {b:g}", by_beta[b], out_beta[b]) for b in by_beta] + [
        (f"γ = {g:g}", by_gamma[g], out_gamma[g]) for g in by_gamma if g != BASE_GAMMA
    ]
    late, gaps, same, folds = [], [], [], []
    for label, cin, cout in curves:
        for i, a in enumerate(alphas):
            vi, vo = cin[i].v_cr, cout[i].v_cr
            if a == 0.0:
                same.append(abs(vi - vo))
            elif cout[i].kind == "fold" and cin[i].kind == "fold" and vo == vi:
                # The static branch ends first: neither plane flutters before it.
                folds.append(f"{label}, α = {_deg(a)}")
            elif not vo < vi:
                late.append(f"{label}, α = {_deg(a)}: out {vo:.6f} ≥ in {vi:.6f}")
            else:
                gaps.append((vi - vo) / vi)
    fold_note = f"; the static branch folds first at {', '.join(folds)}" if folds else ""
    first = (
        f"no: the round pipe flutters out of the plane first at every inclined α of the grid "
        f"(every β and γ), {100 * min(gaps):.2f} % to {100 * max(gaps):.2f} % below the "
        f"in-plane v_cr{fold_note}"
        if not late
        else "; ".join(late)
    )
    checks = [measure("out_of_plane_first", first, ok=bool(late))]
    if same:
        checks.append(measure("out_of_plane_at_alpha_0", max(same)))

    diffs = []
    for i in (len(alphas) // 2, len(alphas) - 1):
        model = PipeModel(fe, Params(alpha=alphas[i], **PAPER_CASE))
        r = find_critical_velocity(model, v_max=10.0, planes=PLANES)
        diffs.append(abs(r.out_of_plane.v_cr - out_beta[BASE_BETA][i].v_cr))
    checks.append(measure("out_of_plane_vs_stability_module", max(diffs)))
    return checks


def _stability_cross_check(fe, alphas: np.ndarray, base: list[Onset]) -> Measured:
    """v_cr of :func:`fempipe.analyses.stability.find_critical_velocity` against the independent onset."""
    diffs = []
    for i in (0, len(alphas) // 2):
        model = PipeModel(fe, Params(alpha=alphas[i], **PAPER_CASE))
        diffs.append(abs(stability.find_critical_velocity(model).v_cr - base[i].v_cr))
    return measure("vs_stability_module", max(diffs))


#: Color-blind-safe colors (Okabe & Ito) of the non-reference curves; the
#: reference case (beta = 0.142, gamma = 18.9) is black in both panels.
CURVE_COLORS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9")


def plot(result: CaseResult, fig=None):
    """(a) v_cr(α) for each β, (b) for each γ; N = 3 dashed and N = 4 dotted on the reference."""

    cv = result.data["curves"]
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.5)
    a = result.data["alphas"] / np.pi
    panels = (
        (axes[0], cv.by_beta, cv.out_beta, "β", f"γ = {BASE_GAMMA:g}", BASE_BETA),
        (axes[1], cv.by_gamma, cv.out_gamma, "γ", f"β = {BASE_BETA:g}", BASE_GAMMA),
    )
    for ax, fam, outs, sym, fixed, ref in panels:
        folds = False
        for k, (val, onsets) in enumerate(fam.items()):
            v = _v_cr(onsets)
            # The reference case has the same color in both panels.
            is_ref = val == ref
            color = "k" if is_ref else CURVE_COLORS[k % len(CURVE_COLORS)]
            flutter = np.array([o.kind == "flutter" for o in onsets])
            # A first instability that is not flutter (a fold) is not on the flutter curve.
            lab = f"{sym} = {val:g}" + (" (reference)" if is_ref else "")
            ax.plot(a, np.where(flutter, v, np.nan), "o-", ms=3.5, lw=1.4, color=color, label=lab)
            if val in outs:
                fo = np.array([o.kind == "flutter" for o in outs[val]])
                vo = np.where(fo, _v_cr(outs[val]), np.nan)
                ax.plot(a, vo, "^-.", ms=4, mfc="none", lw=0.9, color=color)
            if not flutter.all():
                folds = True
                ax.plot(a[~flutter], v[~flutter], "D", ms=7, mfc="none", mew=1.5, color=color)
        for n, ls in ((3, "--"), (4, ":")):
            v = _v_cr(cv.modal[f"N = {n}"])
            ax.plot(a, v, ls, color="0.45", lw=1.2, label=f"N = {n} (reference)")
        if folds:
            ax.plot([], [], "D", ms=7, mfc="none", mew=1.5, color="0.3", label="fold, not flutter")
        if outs:
            ax.plot([], [], "^-.", ms=4, mfc="none", lw=0.9, color="0.3", label="out of the plane")
        label_axes(ax, r"$\alpha / \pi$", r"$v_{cr}$", f"{fixed}, several {sym}")
        # Below the panel: inside, the key would hide the beta = 0.5 and gamma = 5 curves.
        ax.legend(fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.14), ncol=2)

    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

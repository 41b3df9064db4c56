"""External viscous damping: Beck's column (Plaut & Infante 1970) and the hanging pipe.

Damping sigma raises Beck's flutter load from 20.05 to 37.7 for large damping.  v_cr^2(sigma)
by fempipe (FE P3:16) and the classical theory (to 1e-6) against the printed numbers; the
large-damping limit from the undamped roots nu of K x = nu M x
(:func:`fempipe.validation.classical.large_damping_limit`); the paper's hanging pipe with
damping against the classical theory.
"""

from __future__ import annotations

import numpy as np

from fempipe.model.params import Params

from . import classical
from .case import Case
from .checks import CaseResult
from .drawing import CLASSICAL_LINE, DOTS, figure_panels, finish_figure, label_axes, legend_below
from .evaluate import measure
from .variant_runs import FE, agreement, classical_onset, converged, fe_cell, fe_onset

CASE = Case.load("external_damping")

BECK = {"beta": 0.0, "gamma": 0.0, "mu": 0.0}
BECK_V_MAX = 7.0


def _beck(sigma: float) -> Params:
    return Params(alpha=0.0, external_damping=sigma, **BECK)


def _hanging(h: dict, sigma: float) -> Params:
    return Params(alpha=0.0, external_damping=sigma, **h)


def run(quick: bool = False) -> CaseResult:
    """v_cr(sigma) of Beck's column and of the hanging pipe; see the module docstring."""
    ref = CASE.references
    sig_curve = np.array(ref.value("sigma_curve", quick))
    beck, fe_beck = _onsets(_beck, sig_curve, ref.value("sigma_fe", quick), BECK_V_MAX)
    h = ref.value("hanging")
    hanging, fe_hanging = _onsets(
        lambda s: _hanging(h, s),
        np.array(ref.value("hanging_sigma_curve", quick)),
        ref.value("hanging_sigma_fe", quick),
        12.0,
    )
    v_inf = classical.large_damping_limit(classical.StraightPipe(), BECK_V_MAX)
    checks, requires = _agreement_checks(beck, fe_beck, hanging, fe_hanging)
    checks += _limit_and_paper_checks(beck, fe_beck, v_inf, float(sig_curve.max()))
    sigmas = sorted(beck)
    return CASE.result(
        checks,
        quick=quick,
        tables=_tables(h, beck, fe_beck, hanging, fe_hanging, v_inf),
        data={
            "beck": {s: beck[s].v_cr for s in sigmas},
            "fe_beck": {s: f.v_cr for s, f in fe_beck.items()},
            "hanging": {s: hanging[s].v_cr for s in sorted(hanging)},
            "fe_hanging": {s: f.v_cr for s, f in fe_hanging.items()},
            "v_inf": v_inf,
            "printed": (ref.value("beck_v2_zero"), ref.value("beck_v2_large")),
            "hanging_params": h,
        },
        requires=requires,
    )


def _onsets(params, curve, fe_sigmas, v_max: float) -> tuple[dict, dict]:
    """Classical onsets at ``curve`` and ``fe_sigmas``, and FE onsets at ``fe_sigmas``."""
    onsets = {s: classical_onset(params(s), v_max) for s in curve}
    for s in fe_sigmas:
        onsets.setdefault(s, classical_onset(params(s), v_max))
    fe = {s: fe_onset(params(s), onsets[s].v_cr + 0.5) for s in fe_sigmas}
    return onsets, fe


def _agreement_checks(beck, fe_beck, hanging, fe_hanging) -> tuple[list, list]:
    """The classical theory converged, and fempipe's FE against it (with the check names)."""
    checks = [converged(_beck(10.0), BECK_V_MAX)]
    requires = []
    for s, f in fe_beck.items():
        requires.append(f"fe_vs_classical_beck_s{s:g}")
        checks.append(agreement("fe_vs_classical_beck_s{sigma:g}", f, beck[s], sigma=s))
    for s, f in fe_hanging.items():
        requires.append(f"fe_vs_classical_hanging_s{s:g}")
        checks.append(agreement("fe_vs_classical_hanging_s{sigma:g}", f, hanging[s], sigma=s))
    return checks, requires


def _limit_and_paper_checks(beck, fe_beck, v_inf: float, s_top: float) -> list:
    """The approach to the sigma -> infinity limit and Plaut & Infante's statements."""
    gap = v_inf**2 - beck[s_top].v_cr ** 2
    top = {"sigma": s_top, "v2": beck[s_top].v_cr ** 2, "v2_limit": v_inf**2}
    checks = [measure("approaches_limit", gap if gap >= 0 else np.inf, **top)]
    # The printed numbers: FE where computed, otherwise the classical theory.
    f = fe_beck.get(0.0)
    v0, by0 = (f.v_cr, f"FE {FE}") if f is not None else (beck[0.0].v_cr, "classical theory")
    checks.append(measure("v2_zero", v0**2, v2=v0**2, by=by0))
    checks.append(measure("v2_large", v_inf**2, v2=v_inf**2))
    sigmas = sorted(beck)
    v2 = np.array([beck[s].v_cr ** 2 for s in sigmas])
    drops = [(sigmas[i], sigmas[i + 1]) for i in range(len(sigmas) - 1) if v2[i + 1] <= v2[i]]
    fe_sorted = sorted(fe_beck)
    fe_drops = [
        (a, b)
        for a, b in zip(fe_sorted, fe_sorted[1:], strict=False)
        if fe_beck[b].v_cr <= fe_beck[a].v_cr
    ]
    text = "monotone" if not (drops or fe_drops) else f"falls on {drops + fe_drops}"
    checks.append(measure("rises_with_damping", text, ok=not drops and not fe_drops))
    return checks


def _tables(h: dict, beck, fe_beck, hanging, fe_hanging, v_inf: float) -> tuple:
    """The tables of Beck's column and of the hanging pipe."""
    ref = CASE.references
    rows = [
        (s, beck[s].v_cr ** 2, fe_beck[s].v_cr ** 2 if s in fe_beck else "—", beck[s].frequency)
        for s in sorted(beck)
    ]
    hrows = [(s, hanging[s].v_cr, fe_cell(fe_hanging.get(s))) for s in sorted(hanging)]
    return (ref.table("beck", rows, FE=FE, v2=v_inf**2), ref.table("hanging", hrows, FE=FE, **h))


def plot(result: CaseResult, fig=None):
    """(a) v_cr²(σ) of Beck's column, (b) v_cr(σ) of the hanging pipe."""
    d = result.data
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.2)
    ax = axes[0]
    s = np.array(sorted(d["beck"]))
    floor = s[s > 0].min() / 3.0  # sigma = 0 drawn here, on the log axis
    x = np.where(s > 0, s, floor)
    ax.plot(x, [d["beck"][k] ** 2 for k in s], "-", color="#0072B2", lw=1.5)
    fe = sorted(d["fe_beck"])
    fe_x = [k if k > 0 else floor for k in fe]
    ax.plot(fe_x, [d["fe_beck"][k] ** 2 for k in fe], "o", color="k", ms=6)
    for y in d["printed"]:
        ax.axhline(y, ls="--", color="#D55E00", lw=1.2)
    ax.axhline(d["v_inf"] ** 2, ls=":", color="0.3", lw=1.4)
    ax.set_xscale("log")
    xlabel = r"external damping $\sigma$ ($\sigma = 0$ at the left edge)"
    label_axes(ax, xlabel, r"$v_{cr}^2 = PL^2/EI$", "Beck's column")
    ax = axes[1]
    hs = sorted(d["hanging"])
    ax.plot(hs, [d["hanging"][k] for k in hs], "-", color="#0072B2", lw=1.5)
    hf = sorted(d["fe_hanging"])
    ax.plot(hf, [d["fe_hanging"][k] for k in hf], "o", color="k", ms=6)
    h = d["hanging_params"]
    title = f"hanging pipe, β = {h['beta']:g}, γ = {h['gamma']:g}"
    label_axes(ax, r"external damping $\sigma$", r"$v_{cr}$", title)
    entries = [
        CLASSICAL_LINE,
        (f"fempipe FE {FE}", DOTS),
        ("Plaut & Infante: 20.05, 37.7", {"ls": "--", "color": "#D55E00"}),
        ("theory, σ → ∞", {"ls": ":", "color": "0.3", "lw": 1.4}),
    ]
    legend_below(fig, entries, ncols=2)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

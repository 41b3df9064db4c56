"""Hysteretic damping: Paidoussis' hanging cantilevers conveying air (Table 3.4).

u_cf and omega_cf of two hanging cantilevers without damping and with the hysteretic loss
mu = 0.02 (Paidoussis 1998, Table 3.4), by fempipe (FE P3:16) and the classical theory (to
1e-6), against the printed numbers (``paper`` checks).  At the onset E (1 + i mu_h) equals the
Kelvin-Voigt E (1 + mu lambda) with mu = mu_h / omega: fempipe's Kelvin-Voigt term checks how
it selects the hysteretic roots.
"""

from __future__ import annotations

import numpy as np

from fempipe.analyses.stability import compute_spectrum
from fempipe.model.discretization import parse_discretization
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from . import classical as cm
from .case import Case, References
from .checks import CaseResult
from .drawing import DOTS, figure_panels, finish_figure, label_axes, legend_below
from .evaluate import Measured, measure
from .variant_runs import FE, agreement, classical_onset, converged, fe_cell, fe_onset

CASE = Case.load("hysteretic")


def _tag(pipe: dict) -> str:
    return f"b{pipe['beta'] * 1e3:.2f}"


def _params(pipe: dict, mu_h: float) -> Params:
    return Params(
        alpha=0.0, beta=pipe["beta"], gamma=pipe["gamma"], mu=0.0, hysteretic_damping=mu_h
    )


def run(quick: bool = False) -> CaseResult:
    """Table 3.4 by fempipe and the classical theory; see the module docstring."""
    ref = CASE.references
    pipes, mu_h, v_max = ref.value("pipes"), ref.value("mu_h"), ref.value("v_max")
    dampings = {"mu0": 0.0, "muh": mu_h}
    classical = {
        (k, d): classical_onset(_params(p, m), v_max, step=0.05)
        for k, p in enumerate(pipes)
        for d, m in dampings.items()
    }
    fe_points = [(1, "muh")] if quick else list(classical)
    fe = {key: fe_onset(_params(pipes[key[0]], dampings[key[1]]), v_max) for key in fe_points}
    checks, requires = _agreement_checks(pipes, dampings, classical, fe, v_max)
    if not quick:
        # Paidoussis & Issid's pipe: a second onset up to v = 16 (full suite only).
        checks += _issid_checks()
    printed_checks, table, findings, explained = _table_3_4(ref, dampings, classical, fe, quick)
    checks += printed_checks
    grid = np.array(ref.value("mu_h_curve", quick))
    curves = {}
    for k, p in enumerate(pipes):
        ons = [classical_onset(_params(p, m), v_max, step=0.05) for m in grid]
        curves[k] = (np.array([o.v_cr for o in ons]), np.array([o.frequency for o in ons]))
    return CASE.result(
        checks,
        quick=quick,
        tables=(table,),
        findings=findings,
        explained=explained,
        data={
            "pipes": pipes,
            "grid": grid,
            "curves": curves,
            "fe": {key: (dampings[key[1]], f.v_cr, f.frequency) for key, f in fe.items()},
            "printed": {
                d: (dampings[d], ref.value(f"u_cf_{d}"), ref.value(f"omega_cf_{d}"))
                for d in dampings
            },
            "experiment": (mu_h, ref.value("u_cf_exp"), ref.value("omega_cf_exp")),
            "half_units": (ref.value("u_half_unit"), ref.value("omega_half_unit")),
        },
        requires=requires,
    )


def _agreement_checks(
    pipes: list, dampings: dict, classical: dict, fe: dict, v_max: float
) -> tuple[list, list]:
    """The classical theory converged, FE against it, Kelvin-Voigt against mu_h; the FE names."""
    mu_h = dampings["muh"]
    checks = [converged(_params(pipes[1], mu_h), v_max, step=0.05)]
    requires = []
    for (k, d), f in fe.items():
        pipe = {"beta": pipes[k]["beta"], "gamma": pipes[k]["gamma"], "mu": dampings[d]}
        requires.append(f"fe_vs_classical_{_tag(pipes[k])}_{d}")
        spec = "fe_vs_classical_{tag}_{d}"
        checks.append(agreement(spec, f, classical[(k, d)], tag=_tag(pipes[k]), d=d, **pipe))
    checks.append(_kelvin_voigt_check(pipes[1], mu_h, fe[(1, "muh")]))
    return checks, requires


def _table_3_4(ref: References, dampings: dict, classical: dict, fe: dict, quick: bool):
    """The printed theory against the converged answer: measurements, table, findings, explained."""
    pipes, v_max = ref.value("pipes"), ref.value("v_max")
    checks, rows, findings, explained = [], [], [], []
    failed: dict = {}
    for (k, d), cl in classical.items():
        f = fe.get((k, d))
        u = f.v_cr if f is not None else cl.v_cr
        w = f.frequency if f is not None else cl.frequency
        by = f"FE {FE}" if f is not None else "classical theory"
        pipe = {"beta_e3": pipes[k]["beta"] * 1e3, "gamma": pipes[k]["gamma"], "mu": dampings[d]}
        printed_u = ref.value(f"u_cf_{d}")[k]
        printed_w = ref.value(f"omega_cf_{d}")[k]
        for q, val, printed, unit in (
            ("u_cf", u, printed_u, "u_half_unit"),
            ("omega_cf", w, printed_w, "omega_half_unit"),
        ):
            fields = {"tag": _tag(pipes[k]), "reference": printed, "by": by, "val": val}
            m = measure(f"{q}_{{tag}}_{d}", val, **fields, **pipe)
            checks.append(m)
            chk = CASE.check(m, quick)
            if not chk.passed:
                failed.setdefault((k, d), []).append((chk, printed, val, ref.value(unit)))
        rows.append((f"{pipes[k]['beta'] * 1e3:.2f}", pipes[k]["gamma"], dampings[d], printed_u,
                     cl.v_cr, fe_cell(f), printed_w, cl.frequency, fe_cell(f, "frequency")))  # fmt: skip
    for (k, d), bad in failed.items():
        exp = {"u_cf": ref.value("u_cf_exp")[k], "omega_cf": ref.value("omega_cf_exp")[k]}
        findings.append(
            _finding(pipes[k], dampings[d], bad, classical[(k, d)], fe.get((k, d)), v_max, exp)
        )
        explained += [b[0].name for b in bad]
    table = ref.table("table_3_4", rows, FE=FE)
    return checks, table, findings, explained


def _issid_checks() -> list:
    """Paidoussis & Issid (1974) as quoted on p. 118 of the book: u_cf ~ 11 with mu_h = 0.1."""
    c = CASE.references.value("issid")
    p = Params(alpha=0.0, beta=c["beta"], gamma=c["gamma"], mu=0.0, hysteretic_damping=c["mu_h"])
    f = fe_onset(p, c["v_max"])
    cl = classical_onset(p, c["v_max"], step=0.05)
    return [
        agreement("fe_vs_classical_issid", f, cl),
        measure("u_cf_issid", f.v_cr, val=f.v_cr, mesh=FE),
    ]


def _finding(pipe: dict, mu_h: float, bad: list, cl, fe, v_max: float, exp: dict) -> str:
    """One finding on a row's printed numbers, with beam-mode Galerkin values on 2 to 10 modes."""

    pipe_c = cm.StraightPipe.from_params(_params(pipe, mu_h))
    trunc = {
        n: cm.critical_velocity(pipe_c, v_max, method="galerkin", n=n, step=0.05)
        for n in range(2, 11)
    }
    lab = f"β = {pipe['beta'] * 1e3:.2f}×10⁻³, γ = {pipe['gamma']:g}, μ = {mu_h:g}"
    parts = []
    for chk, printed, val, half in bad:
        q = chk.name.split("_b")[0]
        other = cl.v_cr if q == "u_cf" else cl.frequency
        by = f"FE {FE} {val:.4f}, classical {other:.4f}" if fe is not None else f"{other:.4f}"
        tr = [o.v_cr if q == "u_cf" else o.frequency for o in trunc.values()]
        near = [n for n, t in zip(trunc, tr, strict=True) if abs(t - printed) <= half]
        parts.append(
            f"{q} printed {printed:g}, converged {by} ({val - printed:+.4f}); beam-mode "
            f"Galerkin on 2-10 modes gives {min(tr):.4f}-{max(tr):.4f}"
            + (f", the printed value with N = {', '.join(map(str, near))}" if near else "")
            + (f" (the experimental column also reads {printed:g})" if exp[q] == printed else "")
        )
    return f"{lab}: " + "; ".join(parts) + "."


def _kelvin_voigt_check(pipe: dict, mu_h: float, onset) -> Measured:
    """fempipe's Kelvin-Voigt pipe with mu = mu_h/omega has the eigenvalue i omega at v_cr."""
    mu = mu_h / onset.frequency
    p = Params(alpha=0.0, beta=pipe["beta"], gamma=pipe["gamma"], mu=mu, v=onset.v_cr)
    disc = parse_discretization(fe=FE)
    lam = compute_spectrum(PipeModel(disc, p), np.zeros(disc.n)).lam
    dist = float(np.min(np.abs(lam - 1j * onset.frequency)))
    fields = {"v": onset.v_cr, "omega": onset.frequency, "mu": mu}
    return measure("kelvin_voigt_equivalence", dist, **fields)


def plot(result: CaseResult, fig=None):
    """(a) v_cr(μ_h), (b) ω_cf(μ_h): classical lines, FE dots, Table 3.4 crosses and squares."""

    d = result.data
    fig, axes = figure_panels(fig, 2, ncols=2, size=4.2)
    colors = ("#0072B2", "#D55E00")
    hu, hw = d["half_units"]
    for j, (ax, ylabel, half) in enumerate(
        ((axes[0], r"$v_{cr}$", hu), (axes[1], r"$\omega_{cf} = \mathrm{Im}\,\lambda$", hw))
    ):
        for k, p in enumerate(d["pipes"]):
            lab = f"β = {p['beta'] * 1e3:.2f}×10⁻³, γ = {p['gamma']:g}"
            ax.plot(d["grid"], d["curves"][k][j], "-", color=colors[k], lw=1.5, label=lab)
            for (kk, _), (m, v, w) in d["fe"].items():
                if kk == k:
                    ax.plot(m, (v, w)[j], "o", ms=6, color=colors[k])
            for m, us, ws in d["printed"].values():
                ax.errorbar(
                    m, (us, ws)[j][k], yerr=half, fmt="x", ms=8, mew=1.6, color="k", capsize=3
                )
            m, us, ws = d["experiment"]
            ax.plot(m, (us, ws)[j][k], "s", ms=7, mfc="none", mew=1.3, color=colors[k])
        label_axes(ax, r"hysteretic loss factor $\mu_h$", ylabel)
    entries = [
        (f"β = {p['beta'] * 1e3:.2f}×10⁻³, γ = {p['gamma']:g}", {"color": colors[k], "lw": 1.5})
        for k, p in enumerate(d["pipes"])
    ]
    entries += [
        (f"fempipe FE {FE}", dict(DOTS, color="0.3")),
        ("Table 3.4, theory", {"ls": "", "marker": "x", "mew": 1.6, "color": "k"}),
        ("Table 3.4, experiment", {"ls": "", "marker": "s", "mfc": "none", "color": "0.3"}),
    ]
    legend_below(fig, entries, ncols=3)
    axes[0].set_title("critical flow velocity", fontsize=10)
    axes[1].set_title("frequency at the onset", fontsize=10)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

"""Parametric resonance of the hanging pipe under a pulsating flow (Païdoussis & Issid 1974).

v(tau) = v0 (1 + sigma sin(omega tau)) on the pipe of Paidoussis (1998) Figs. 4.26 and 4.29
(beta = 0.2, gamma = 10, alpha = 0) with mu = 0.005, at v0 = 5 and 6: the regions of
fempipe's chart (FE P3:16, against P3:32; the paper's N = 3 and N = 4 sine modes), their noses
against the mean flow's spectrum (and Table 4.5's), a scan of the band that keeps the first
mode, and the Floquet multipliers of the independent classical equation
(:mod:`.classical_pulsation`; its flow-acceleration term checked on Leipholz's column).
Quick: the principal region of the second mode alone, located on a Ritz basis of that mode.
"""

from __future__ import annotations

import math

import numpy as np

from fempipe.analyses.parametric import PulsationPencil
from fempipe.model.params import Params

from . import classical
from .case import Case
from .checks import CaseResult
from .classical_pulsation import flutter_load, leipholz_load
from .drawing import color_for, figure_panels, finish_figure, label_axes, legend_below, style_for
from .evaluate import measure
from .parametric_runs import (
    PRINCIPAL_2,
    chart_regions,
    classical_runs,
    deviation,
    edges_at,
    model_of,
    nominal_points,
    principal_region,
    ritz,
    scan,
    scan_edges,
    scan_verdict,
    spectrum_of,
)
from .variant_runs import fe_onset

CASE = Case.load("parametric")


def run(quick: bool = False) -> CaseResult:
    """The regions at v0 = 5 and 6 and every comparison; see the module docstring."""
    ref = CASE.references
    base = Params(alpha=0.0, v=0.0, **ref.value("pipe"))
    v_cr = fe_onset(base, 10.0).v_cr
    runs = {v0: _run_v0(ref, v0, quick, v_cr) for v0 in ref.value("v0")}
    checks, text = [*_leipholz(ref)], {}
    table45, rows45 = _table45(ref, text)
    checks += table45
    for v0, r in runs.items():
        checks += _v0_checks(ref, v0, r, quick, v_cr)
    checks += _trend_checks(ref, runs, quick)
    kinds = ("spectrum",) if quick else ("spectrum", "sigma0", "p")
    families = (*_CL, *(f"classical_converged_{k}" for k in kinds))
    requires = [f"{c}_v{v0:g}" for v0 in ref.value("classical_v0", quick) for c in families]
    return CASE.result(
        checks,
        quick=quick,
        tables=_tables(ref, runs, rows45, v_cr, quick),
        findings=_findings(runs, text, v_cr),
        explained=tuple(text),
        data={v0: _figure_data(ref, r) for v0, r in runs.items()} | {"band": ref.value("band")},
        requires=requires,
    )


_CL = ("classical_multipliers", "classical_threshold")


def _labels(ref) -> tuple[str, str, list[str]]:
    modal = [f"N = {n}" for n in ref.value("modal")]
    return f"FE {ref.value('fe')}", f"FE {ref.value('refined')}", modal


def _run_v0(ref, v0: float, quick: bool, v_cr: float) -> dict:
    """The regions on every discretization, the scan and the classical theory at one v0."""
    params = Params(alpha=0.0, v=v0, **ref.value("pipe"))
    band, sigmas = tuple(ref.value("band")), ref.value("sigmas", quick)
    fe_label, refined_label, modal = _labels(ref)
    edge = [ref.value("edge_sigma")]
    if quick:
        modes, steps = ref.value("quick_locate_modes"), ref.value("quick_steps")
        fe = principal_region(fe_label, params, band, sigmas, modes, steps)
        others = {m: principal_region(m, params, band, sigmas, modes, steps) for m in modal}
    else:
        fe = chart_regions(fe_label, params, band, sigmas)
        others = {m: chart_regions(m, params, band, sigmas) for m in modal}
        modes, steps = ref.value("ritz_modes"), 128
    refined = principal_region(refined_label, params, band, edge, modes, steps)
    step = ref.value("scan_step")
    grid = np.arange(band[0], band[1] + step / 2, step)
    omegas = nominal_points(fe.spectrum, band) if quick else grid
    scan_basis = ritz(fe_label, params, fe.spectrum, ref.value("scan_modes"))
    points = scan(scan_basis, omegas, ref.value("scan_sigmas", quick))
    _, unknown, quasi = scan_verdict(points, fe, lambda s: v0 * (1 + s) > v_cr)
    found = scan_edges(scan_basis, unknown)
    cl = None
    if v0 in ref.value("classical_v0", quick) and fe.principal is not None:
        reduced = ritz(fe_label, params, fe.spectrum, ref.value("ritz_modes"))
        cl = classical_runs(ref, params, fe.principal, reduced, fe.edges(edge[0]), quick)
    return dict(
        fe=fe, refined=refined, modal=others, scan=points, classical=cl, scan_edges=found,
        quasi_static=quasi,
    )  # fmt: skip


def _leipholz(ref) -> list:
    """The classical flow-acceleration term on Leipholz's column, and fempipe's K3 against it."""
    q = leipholz_load(16)
    beta = 0.25  # any beta: K3 carries sqrt(beta)
    still = Params(alpha=0.0, beta=beta, gamma=0.0, mu=0.0, v=0.0)
    P = PulsationPencil.of(model_of(f"FE {ref.value('fe')}", still))
    fe_q = math.sqrt(beta) * flutter_load(P.K0, P.K3, P.M, (1.0, 200.0))
    return [
        measure("leipholz", q, q=q),
        measure("leipholz_fe", abs(fe_q - q) / q, q=q, fe_q=fe_q),
    ]


def _table45(ref, text: dict) -> tuple[list, list]:
    """Table 4.5: the mean flow's eigenfrequencies without dissipation, FE and classical."""
    u0 = ref.value("table45_u0")
    pipe = ref.value("pipe")
    params = Params(alpha=0.0, v=u0, beta=pipe["beta"], gamma=pipe["gamma"], mu=0.0)
    fe = spectrum_of(model_of(f"FE {ref.value('fe')}", params))
    straight = classical.StraightPipe.from_params(params)
    cols = [[fe[k] for k in (1, 2, 3)]]
    for method, n in (("galerkin", 10), ("legendre", 16)):
        lam = classical.eigenvalues(straight, u0, method=method, n=n)
        cols.append(list(lam[lam.imag > 0][:3]))
    checks, rows = [], []
    for k, printed in enumerate(ref.value("table45"), start=1):
        omegas = [complex(lam.imag, -lam.real) for lam in (c[k - 1] for c in cols)]
        err = max(abs(omegas[0].real - printed[0]), abs(omegas[0].imag - printed[1]))
        shown, computed = f"{printed[0]:.2f} + {printed[1]:.2f}i", _omega(omegas[0], 5)
        checks.append(measure("table45_mode{k}", err, k=k, printed=shown, computed=computed))
        rows.append((k, shown, *(_omega(w, 4) for w in omegas)))
        if err > ref.value("table45_half_unit"):
            text[f"table45_mode{k}"] = (
                f"Table 4.5 of Païdoussis (1998) prints ω_{k} = {shown} at u₀ = {u0:g}; the "
                f"converged mean flow has {computed} (FE, and the classical Legendre elements: "
                f"{_omega(omegas[2], 5)}), |Δ| = {err:.4f}, more than rounding the printed "
                f"digits allows. A beam-mode Galerkin solution with N = 10 modes gives "
                f"{_omega(omegas[1], 4)}, every digit of the row: the table's values are "
                "consistent with a truncated Galerkin solution, not with the converged one."
            )
    return checks, rows


def _omega(w: complex, digits: int) -> str:
    return f"{w.real:.{digits}f} {'+' if w.imag >= 0 else '−'} {abs(w.imag):.{digits}f}i"


def _v0_checks(ref, v0: float, r: dict, quick: bool, v_cr: float) -> list:
    """The checks of one mean flow (see the reference file)."""
    fe, refined = r["fe"], r["refined"]
    lam = fe.spectrum
    band = ref.value("band")
    w = {k: lam[k].imag for k in (1, 2, 3)}
    cover = {"2ω₁": 2 * w[1], "2ω₂": 2 * w[2], "ω₂ − ω₁": w[2] - w[1], "ω₂ + ω₁": w[2] + w[1]}
    cover["ω₃ − ω₂"] = w[3] - w[2]
    inside = all(band[0] <= x <= band[1] for x in cover.values())
    text = ", ".join(f"{k} = {x:.4f}" for k, x in cover.items())
    out = [measure("band_covers_v{v0:g}", text, ok=inside, v0=v0, text=text)]
    first = min(fe.regions, key=lambda g: g.sigma_threshold, default=None)
    p = fe.principal
    how = (
        "the quick run locates this candidate alone"
        if quick
        else (
            f"the chart of every candidate: {len(fe.regions)} region(s) open, {len(fe.closed)} closed"
        )
    )
    ok = first is not None and _is_principal(first)
    desc = "no region" if first is None else _describe(first)
    out.append(measure("principal_second_v{v0:g}", desc, ok=ok, v0=v0, how=how, text=desc))
    if p is None:
        return out
    nominal = 2.0 * w[2]
    shift = abs(p.omega_threshold - nominal) / nominal
    th = {"omega_th": p.omega_threshold, "sigma_th": p.sigma_threshold}
    out.append(
        measure("tip_v{v0:g}", shift, v0=v0, nominal=nominal, limit=p.sigma_threshold**2, **th)
    )
    out += _convergence_checks(ref, v0, p, refined)
    wrong, unknown, quasi = scan_verdict(r["scan"], fe, lambda s: v0 * (1 + s) > v_cr)
    sigmas = ref.value("scan_sigmas", quick)
    where = (
        "the nominal frequencies of every candidate of modes 1–4"
        if quick
        else (f"ω = {band[0]:g}, {band[0] + ref.value('scan_step'):g}, …, {band[1]:g}")
    )
    n_unstable = sum(pt[2] > 1.0 for pt in r["scan"])
    verdict = (
        f"{len(r['scan'])} points, {n_unstable} unstable; disagreeing: "
        + (", ".join(f"(σ = {s:g}, ω = {om:.4g}: |ρ| = {x:.4f})" for s, om, x in wrong) or "none")
        + f"; {len(unknown)} where the chart found no edge (not judged)"
        + (f"; {len(quasi)} unstable outside every region, the flow above v_cr" if quasi else "")
    )
    out.append(measure(
        "scan_v{v0:g}", verdict, ok=not wrong, v0=v0, where=where, sigmas=sigmas, text=verdict
    ))  # fmt: skip
    if r["classical"] is not None:
        out += _classical_checks(ref, v0, p, r["classical"])
    return out


def _classical_checks(ref, v0: float, p, cl) -> list:
    """fempipe's multipliers and critical amplitude against the classical theory's."""
    out = []
    dev = max(deviation(fe_rho, cl_rho) for _, _, fe_rho, cl_rho in cl.points.values())
    names = ", ".join(cl.points)
    out.append(measure("classical_multipliers_v{v0:g}", dev, v0=v0, points=names))
    diff = abs(cl.classical_sigma - cl.fe_sigma) / cl.fe_sigma
    out.append(measure(
        "classical_threshold_v{v0:g}", diff if math.isfinite(diff) else math.inf, v0=v0,
        omega=p.omega_threshold, classical=cl.classical_sigma, fe_sigma=cl.fe_sigma,
    ))  # fmt: skip
    p_, p16 = ref.value("classical_p"), "Legendre p = 16"
    what = {
        "spectrum": f"e^(λT) of the mean flow's eigenvalues on p = {p_} against {p16} (largest "
        "deviation of the four largest)",
        "sigma0": f"at σ = 0 the DOP853 multipliers equal e^(λT) of the {p16} spectrum "
        "(largest deviation of the four largest)",
        "p": f"p = {ref.value('classical_p')} against p = {ref.value('classical_p_check')} "
        "at tip+ (largest deviation of the two largest multipliers)",
    }
    for key, value in cl.converged.items():
        name = f"{key}_v{v0:g}"
        out.append(measure("classical_converged_{what}", value, what=name, v0=v0, text=what[key]))
    return out


def _is_principal(region) -> bool:
    c, rho = region.candidate, region.multiplier
    real = abs(rho.imag) < 1e-6
    return (c.kind, c.order, tuple(c.mode)) == PRINCIPAL_2 and real and rho.real < 0


def _describe(region) -> str:
    c, rho = region.candidate, region.multiplier
    return (
        f"{c.kind}, k = {c.order}, modes {', '.join(map(str, c.mode))}: σ_th = "
        f"{region.sigma_threshold:.8f} at ω_th = {region.omega_threshold:.5f}, ρ = "
        f"{rho.real:.6f}{rho.imag:+.1e}i"
    )


def _convergence_checks(ref, v0: float, p, refined) -> list:
    """P3:16 against P3:32: the threshold, its frequency and the edges at edge_sigma."""
    q = refined.principal
    if q is None:
        return []
    e = ref.value("edge_sigma")
    a, b = edges_at(p, e), edges_at(q, e)
    finite = [(x, y) for x, y in zip(a, b, strict=True) if math.isfinite(x) and math.isfinite(y)]
    edges = max((abs(x - y) / y for x, y in finite), default=math.inf)
    return [
        measure("fe_converged_sigma_v{v0:g}", _rel(p.sigma_threshold, q.sigma_threshold), v0=v0,
                a=p.sigma_threshold, b=q.sigma_threshold),
        measure("fe_converged_omega_v{v0:g}", _rel(p.omega_threshold, q.omega_threshold), v0=v0,
                a=p.omega_threshold, b=q.omega_threshold),
        measure("fe_converged_edges_v{v0:g}", edges, v0=v0, a=_span(a), b=_span(b)),
    ]  # fmt: skip


def _rel(a: float, b: float) -> float:
    return abs(a - b) / abs(b)


def _span(edges) -> str:
    return " to ".join("band" if math.isnan(x) else f"{x:.8f}" for x in edges)


def _trend_checks(ref, runs: dict, quick: bool) -> list:
    """The book's statements across the two mean flows, and at v0 = 5 the simple resonances only."""
    p5, p6 = runs[5.0]["fe"].principal, runs[6.0]["fe"].principal
    e = ref.value("edge_sigma")
    out = []
    if p5 and p6:
        s5, s6 = p5.sigma_threshold, p6.sigma_threshold
        text = f"σ_th(6) / σ_th(5) = {s6 / s5:.4f}"
        out.append(measure("threshold_falls", text, ok=s6 < s5, sigma5=s5, sigma6=s6, text=text))
        w5, w6 = (edges_at(p, e)[1] - edges_at(p, e)[0] for p in (p5, p6))
        text = f"width ratio {w6 / w5:.4f}" if math.isfinite(w5 * w6) else "an edge not found"
        out.append(measure("extent_grows", text, ok=w6 > w5, width5=w5, width6=w6, text=text))
    r5 = runs[5.0]
    combos = [g for g in r5["fe"].regions if g.candidate.kind != "principal"]
    pairs = [(s, w) for s, w, _, pair in r5["scan"] if pair]
    how = "chart and scan" if not quick else "scan of the nominal frequencies"
    text = f"combination regions: {len(combos)}; scanned points with a complex pair: {len(pairs)}"
    top = max(ref.value("sigmas", quick))
    out.append(measure(
        "simple_only", text, ok=not combos and not pairs, how=how, text=text, sigma_max=top
    ))  # fmt: skip
    for v0, r in runs.items():
        out.append(_n4_closer(v0, r))
    return out


def _n4_closer(v0: float, r: dict):
    """Whether N = 4 is nearer the FE threshold than N = 3 (sigma_th and omega_th)."""
    fe = r["fe"].principal
    got = {m: reg.principal for m, reg in r["modal"].items()}
    if fe is None or any(g is None for g in got.values()):
        return measure("n4_closer_v{v0:g}", "a region missing", ok=False, v0=v0, text="missing")
    d = {m: (_rel(g.sigma_threshold, fe.sigma_threshold), _rel(g.omega_threshold, fe.omega_threshold))
         for m, g in got.items()}  # fmt: skip
    ok = all(d["N = 4"][i] < d["N = 3"][i] for i in (0, 1))
    text = "; ".join(f"{m}: Δσ_th {a:.2%}, Δω_th {b:.2%}" for m, (a, b) in d.items())
    return measure("n4_closer_v{v0:g}", text, ok=ok, v0=v0, text=text)


def _tables(ref, runs: dict, rows45: list, v_cr: float, quick: bool) -> tuple:
    """The spectrum, regions, candidates, convergence, truncation, classical and Table 4.5."""
    fe_label, refined_label, modal = _labels(ref)
    names = {"fe": ref.value("fe"), "refined": ref.value("refined")}
    spectrum, regions, cands, conv, trunc, cl_rows, critical = [], [], [], [], [], [], []
    for v0, r in runs.items():
        for k, lam in sorted(r["fe"].spectrum.items())[:4]:
            zeta = -lam.real / abs(lam)
            spectrum.append((v0, k, _omega(complex(lam.real, lam.imag), 4), zeta,
                             "yes" if zeta < 1 / math.sqrt(2) else "no", 2 * lam.imag))  # fmt: skip
        for reg in (r["fe"], *r["modal"].values()):
            for g in reg.regions:
                regions.append((v0, reg.label, *_region_cells(g)))
        if r["fe"].charted:
            for c in r["fe"].closed:
                cands.append((v0, c.kind, ", ".join(map(str, c.mode)), c.order, c.omega, "closed"))
            for g in r["fe"].regions:
                c = g.candidate
                cells = (c.kind, ", ".join(map(str, c.mode)), c.order, c.omega)
                cands.append((v0, *cells, f"σ_th = {g.sigma_threshold:.6f}"))
        p, q = r["fe"].principal, r["refined"].principal
        if p is not None and q is not None:
            e = ref.value("edge_sigma")
            pairs = [("σ_th", p.sigma_threshold, q.sigma_threshold),
                     ("ω_th", p.omega_threshold, q.omega_threshold)]  # fmt: skip
            pairs += [(f"{n} at σ = {e:g}", a, b) for n, a, b in
                      zip(("ω_lo", "ω_hi"), edges_at(p, e), edges_at(q, e), strict=True)]  # fmt: skip
            conv += [(v0, n, a, b, _rel(a, b)) for n, a, b in pairs]
            for m in modal:
                g = r["modal"][m].principal
                if g is not None:
                    trunc.append((v0, m, g.sigma_threshold,
                                  f"{(g.sigma_threshold - p.sigma_threshold) / p.sigma_threshold:+.3%}",
                                  g.omega_threshold,
                                  f"{(g.omega_threshold - p.omega_threshold) / p.omega_threshold:+.3%}"))  # fmt: skip
        cl = r["classical"]
        if cl is not None:
            for name, (s, w, fe_rho, cl_rho) in cl.points.items():
                cl_rows.append((v0, name, s, w, _rhos(fe_rho), _rhos(cl_rho),
                                deviation(fe_rho, cl_rho)))  # fmt: skip
            if cl.without_acceleration is not None:
                s, w, fe_rho, _ = cl.points["tip+"]
                bare = cl.without_acceleration
                cl_rows.append((v0, "tip+, classical without the flow acceleration", s, w,
                                _rhos(fe_rho), _rhos(bare), deviation(fe_rho, bare)))  # fmt: skip
            critical.append(
                f"v₀ = {v0:g}: FE {cl.fe_sigma:.10f}, classical {cl.classical_sigma:.10f}"
            )
    refs = CASE.references
    band, top = ref.value("band"), max(ref.value("sigmas", quick))
    out = [
        refs.table("spectrum", spectrum, v_cr=v_cr, **names),
        refs.table("regions", regions, sigma_max=top, band=band),
    ]
    if cands:
        out.append(refs.table("candidates", cands, sigma_max=top, **names))
    out += [
        refs.table("convergence", conv, **names),
        refs.table("truncation", trunc, **names),
        refs.table(
            "classical",
            cl_rows,
            modes=", ".join(map(str, ref.value("ritz_modes"))),
            p=ref.value("classical_p"),
            critical="; ".join(critical),
            **names,
        ),  # fmt: skip
        refs.table("table45", rows45, u0=ref.value("table45_u0"), **names),
    ]
    return tuple(out)


def _region_cells(g) -> tuple:
    c, rho = g.candidate, g.multiplier
    name = f"{c.kind} k = {c.order}, mode {', '.join(map(str, c.mode))}"
    rows = "; ".join(f"{s:g}: {_span((lo, hi))}" for s, lo, hi in g.boundary) or "—"
    return (name, c.omega, g.sigma_threshold, g.omega_threshold, _rhos([rho], 1), rows)


def _rhos(rho, count: int = 2) -> str:
    return ", ".join(f"{r.real:.8f}{r.imag:+.2e}i" if abs(r.imag) > 1e-12 else f"{r.real:.8f}"
                     for r in list(rho)[:count])  # fmt: skip


def _findings(runs: dict, text: dict, v_cr: float) -> list[str]:
    """The table's misprints, the edges the chart did not find, the combination regions."""
    out = list(text.values())
    for v0, r in runs.items():
        p = r["fe"].principal
        for s, edges in r["scan_edges"].items():
            if not edges:
                continue
            side = "lower" if edges[0] < p.omega_threshold else "upper"
            edge = min(edges, key=lambda e: abs(e - p.omega_threshold))
            rest = [f"{e:.4f}" for e in edges if e != edge]
            above = v0 * (1 + s) > v_cr
            out.append(
                f"v₀ = {v0:g}, σ = {s:g}: fempipe's chart finds no {side} edge of the principal "
                f"region (nan, 'band' in the table); the scan finds it at ω = {edge:.4f} (Brent's "
                "method on its multipliers)"
                + (f", and stability changes again at ω = {', '.join(rest)}" if rest else "")
                + f"; complex multipliers outside the unit circle: {_pairs(r, [s])}"
                + (f"; the flow exceeds v_cr = {v_cr:.4f} for part of each period" if above else "")
                + f" (v₀(1 + σ) = {v0 * (1 + s):g})."
            )
        for s in sorted({pt[0] for pt in r["quasi_static"]}):
            ws = [w for t, w, _ in r["quasi_static"] if t == s]
            out.append(
                f"v₀ = {v0:g}, σ = {s:g}: unstable outside every region of resonance at "
                f"{len(ws)} scanned point(s), ω = {min(ws):.4g} to {max(ws):.4g}: the flow "
                f"v₀(1 + σ) = {v0 * (1 + s):g} exceeds v_cr = {v_cr:.4f} for part of each "
                "period (a quasi-static instability, not searched by the chart)."
            )
    r6 = runs.get(6.0)
    if r6 and r6["fe"].charted:
        combos = [g for g in r6["fe"].regions if g.candidate.kind != "principal"]
        lam3 = r6["fe"].spectrum[3]
        sigmas = sorted({pt[0] for pt in r6["scan"]})
        out.append(
            f"At v₀ = 6 no combination region opens either ({len(combos)} in the chart; the "
            f"scan's complex multipliers outside the unit circle: {_pairs(r6, sigmas)}), where "
            "the book, without dissipation, finds them at u₀ = 6.0: with μ = 0.005 the third "
            f"mode is damped to ζ₃ = {-lam3.real / abs(lam3):.3f}."
        )
    return out


def _pairs(r: dict, sigmas) -> str:
    """Where the scan at ``sigmas`` has a complex multiplier outside the unit circle."""
    at = {s: [w for t, w, _, pair in r["scan"] if pair and t == s] for s in sigmas}
    return "; ".join(f"σ = {s:g}, ω = {_ranges(ws)}" for s, ws in at.items() if ws) or "none"


def _ranges(ws) -> str:
    """Grid frequencies as runs ``a–b`` (consecutive within 1.5 grid steps)."""
    if not ws:
        return "none"
    runs, start = [], ws[0]
    for a, b in zip(ws, ws[1:], strict=False):
        if b - a > 1.5:
            runs.append((start, a))
            start = b
    runs.append((start, ws[-1]))
    return ", ".join(f"{a:g}" if a == b else f"{a:g}–{b:g}" for a, b in runs)


def _figure_data(ref, r: dict) -> dict:
    regions = {r["fe"].label: [_with_scan_edges(g, r["scan_edges"]) for g in r["fe"].regions]}
    regions |= {
        reg.label: [(g.sigma_threshold, g.omega_threshold, g.boundary) for g in reg.regions]
        for reg in r["modal"].values()
    }
    cl = r["classical"]
    p = r["fe"].principal
    star = (cl.classical_sigma, p.omega_threshold) if cl is not None and p is not None else None
    return {
        "regions": regions,
        "nominal": 2.0 * r["fe"].spectrum[2].imag,
        "classical": star,
        "scan": [(s, w) for s, w, x, _ in r["scan"] if x > 1.0],
        "sigma_max": max(ref.value("sigmas")),
    }


def _with_scan_edges(g, found: dict) -> tuple:
    """A region's threshold and boundary, the edges the chart did not find from the scan."""
    rows = []
    for s, lo, hi in g.boundary:
        near = found.get(s, [])
        below = [e for e in near if e < g.omega_threshold]
        above = [e for e in near if e > g.omega_threshold]
        lo = max(below) if math.isnan(lo) and below else lo
        hi = min(above) if math.isnan(hi) and above else hi
        rows.append((s, lo, hi))
    return (g.sigma_threshold, g.omega_threshold, tuple(rows))


def _outline(tip: tuple, band=None) -> tuple[list, list]:
    """A region's boundary as one curve through its threshold; an edge not found (nan) at the
    band's end if ``band`` is given, else left out (the curve breaks there)."""
    s_th, w_th, rows = tip
    rows = [row for row in rows if row[0] > s_th]
    sig = [s_th] + [s for s, _, _ in rows]
    ends = band if band is not None else (math.nan, math.nan)
    lo = [w_th] + [ends[0] if math.isnan(x) else x for _, x, _ in rows]
    hi = [w_th] + [ends[1] if math.isnan(x) else x for _, _, x in rows]
    return lo[::-1] + hi, sig[::-1] + sig


def plot(result: CaseResult, fig=None):
    """The (ω, σ) chart at each v0: FE shaded, N = 3 and N = 4 outlined, the classical star."""
    d = result.data
    band = d["band"]
    v0s = sorted(k for k in d if k != "band")
    fig, axes = figure_panels(fig, len(v0s), ncols=2, size=4.4)
    for ax, v0 in zip(axes, v0s, strict=True):
        dv = d[v0]
        ax.axvline(dv["nominal"], color="0.5", lw=1.0, ls=(0, (1, 2)))
        for label, tips in dv["regions"].items():
            for tip in tips:
                x, y = _outline(tip)
                style = {"color": color_for(label), "ls": style_for(label), "lw": 1.4}
                if label.startswith("FE"):
                    ax.fill(*_outline(tip, band), color="#E69F00", alpha=0.35, lw=0)
                    ax.plot(x, y, marker=".", ms=5, **style)
                    ax.plot(tip[1], tip[0], "v", color="k", ms=6)
                else:
                    ax.plot(x, y, **style)
        if dv["scan"]:
            ws, ss = zip(*((w, s) for s, w in dv["scan"]), strict=True)
            ax.plot(ws, ss, "x", color="#CC79A7", ms=4, ls="")
        if dv["classical"] is not None:
            ax.plot(dv["classical"][1], dv["classical"][0], "*", color="#0072B2", ms=11)
        ax.set_xlim(*band)
        ax.set_ylim(0.0, 1.05 * dv["sigma_max"])
        label_axes(ax, "pulsation frequency ω", "pulsation amplitude σ", f"v₀ = {v0:g}")
    fe_label, _, modal = _labels(CASE.references)
    entries = [(f"fempipe {fe_label} (shaded)", {"color": "k", "marker": "."})]
    entries += [(m, {"color": color_for(m), "ls": style_for(m), "lw": 1.4}) for m in modal]
    entries += [
        ("classical theory at ω_th", {"color": "#0072B2", "marker": "*", "ls": "", "ms": 11}),
        ("2ω₂ of the mean flow", {"color": "0.5", "ls": (0, (1, 2))}),
        ("scan: unstable", {"color": "#CC79A7", "marker": "x", "ls": ""}),
    ]
    legend_below(fig, entries, ncols=3)
    pipe = CASE.references.value("pipe")
    params = f"α = 0, β = {pipe['beta']:g}, γ = {pipe['gamma']:g}, μ = {pipe['mu']:g}"
    return finish_figure(fig, f"{CASE.figure}: {CASE.title}", params)

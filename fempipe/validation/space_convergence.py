"""Mesh convergence of the non-planar cycle of the horizontal pipe, against the planar cycle's.

The non-planar cycle at alpha = pi/2, v = 6 on P3 meshes of 2 to 8 elements (each shot from
the previous one projected).  Its period and tip extrema give a local order (three finest
meshes, no reference needed) and a slope against the finest mesh (meshes N <= finest / 2);
the planar cycle at v = 6.5 on the same meshes, converging as h^6, is the yardstick.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .case import Case
from .checks import CaseResult
from .drawing import finish_figure, label_axes, paper_case_line
from .evaluate import measure
from .space_runs import planar_cycles, space_cycles

CASE = Case.load("space_convergence")


def local_order(ns, values) -> float:
    """p with (Q1 - Q2) / (Q2 - Q3) = (N1^-p - N2^-p) / (N2^-p - N3^-p) in (0.5, 30), else nan."""
    (n1, n2, n3), (a, b, c) = ns, values
    if b == c or (a - b) / (b - c) <= 0:
        return math.nan

    def f(p: float) -> float:
        return (n1**-p - n2**-p) / (n2**-p - n3**-p) - (a - b) / (b - c)

    try:
        return float(brentq(f, 0.5, 30.0))
    except ValueError:
        return math.nan


def quantities(cycle, keys) -> dict:
    """Period and tip extrema of a cycle."""
    out = {"period": float(cycle.period)}
    for k in keys:
        lo, hi = cycle.tip[k]
        out[f"min {k}"], out[f"max {k}"] = float(lo), float(hi)
    return out


def orders(ns: list[int], table: dict) -> dict:
    """``{quantity: {"monotone", "values", "errors", "local", "slope", "fit"}}``."""
    out = {}
    finest = ns[-1]
    fit = [i for i, n in enumerate(ns[:-1]) if n <= finest / 2]
    for q in table[ns[0]]:
        vals = np.array([table[n][q] for n in ns])
        err = np.abs(vals - vals[-1])
        loc = local_order(ns[-3:], vals[-3:])
        slope = math.nan
        if len(fit) >= 2 and np.all(err[fit] > 0):
            slope = float(-np.polyfit(np.log([ns[i] for i in fit]), np.log(err[fit]), 1)[0])
        steps = np.diff(vals)
        out[q] = {
            "monotone": bool(np.all(steps > 0) or np.all(steps < 0)),
            "values": vals.tolist(),
            "errors": err.tolist(),
            "local": loc,
            "slope": slope,
            "fit": fit,
        }
    return out


def run(quick: bool = False) -> CaseResult:
    """The 3-D and planar cycles on every mesh, their observed orders."""
    ref = CASE.references
    alpha = ref.value("alpha")
    ns = ref.value("elements", quick)
    rtol = ref.value("rtol", quick)
    v3, v2 = ref.value("v_space"), ref.value("v_planar")
    c3 = space_cycles(ns, alpha, v3, rtol=rtol)
    c2 = planar_cycles(ns, alpha, v2, rtol=rtol)
    q3 = orders(ns, {n: quantities(c3[n], ("Y_tip", "X_tip", "Z_tip")) for n in ns})
    q2 = orders(ns, {n: quantities(c2[n], ("X_tip", "Z_tip")) for n in ns})
    p_theory = ref.value("order")
    checks = []
    # A quantity whose values do not move one way under refinement has an error constant
    # that changes sign (nearly cancels) on these meshes: no order is observed for it.
    checked = [q for q, s in q3.items() if s["monotone"]]
    # The quick meshes are pre-asymptotic for the in-plane tip extrema: there the claim
    # the run supports is a band of high orders, not P3's order itself.
    asymptotic = ref.value("asymptotic", quick) if quick else list(q3)
    band = ref.value("order_band", quick) if quick else None
    compared = [q for q in checked if q in q2 and q2[q]["monotone"] and q in asymptotic]
    for q in checked:
        local = q3[q]["local"] if math.isfinite(q3[q]["local"]) else math.inf
        fields = {"tag": q.replace(" ", "_"), "quantity": q}
        if q in asymptotic:
            checks.append(measure("order_{tag}", abs(local - p_theory), **fields))
        else:
            lo, hi = band
            checks.append(measure("order_band_{tag}", max(lo - local, local - hi, 0.0), **fields))
    # The planar cycle's orders, measured the same way, for the quantities both have.
    p2_local = float(np.median([s["local"] for s in q2.values()]))
    for q in compared:
        a, b = q3[q]["local"], q2[q]["local"]
        diff = abs(a - b) if math.isfinite(a + b) else math.inf
        checks.append(measure("order_vs_planar_{tag}", diff, tag=q.replace(" ", "_"), quantity=q))
    rows = []
    for label, qs in ((f"3-D, v = {v3:g}", q3), (f"planar, v = {v2:g}", q2)):
        for q, s in qs.items():
            rows.append((label, q, *s["values"], s["local"], s["slope"], s["monotone"]))
    extra = ""
    if quick:
        extra = ref.tables["orders_quick"]["note"]
        extra = extra.format(asymptotic=", ".join(asymptotic), lo=band[0], hi=band[1])
    meshes, last = " | ".join(f"N = {n}" for n in ns), ", ".join(map(str, ns[-3:]))
    table = ref.table("orders", rows, meshes=meshes, last=last, p2_local=p2_local, quick=extra)
    # The checks emitted depend on monotonicity; these must always be among them.
    requires = ["order_period", "order_vs_planar_period", "order_max_Y_tip"]
    skipped = [q for q in q3 if q not in checked]
    findings = [
        f"3-D cycle, {q}: not monotone under refinement (values "
        + ", ".join(f"{x:.10f}" for x in q3[q]["values"])
        + "): its error constant changes sign on these meshes, no order is observed"
        for q in skipped
    ]
    return CASE.result(
        checks,
        quick=quick,
        tables=(table,),
        findings=findings,
        data={"elements": ns, "space": q3, "planar": q2, "v_space": v3, "v_planar": v2},
        requires=requires,
    )


#: Color-blind-safe colors (Okabe & Ito) per quantity.
COLORS = {
    "period": "#000000",
    "min Y_tip": "#0072B2",
    "max Y_tip": "#56B4E9",
    "min X_tip": "#D55E00",
    "max X_tip": "#E69F00",
    "min Z_tip": "#009E73",
    "max Z_tip": "#CC79A7",
}


def _draw_errors(ax, ns, qs: dict, title: str) -> None:
    ns = np.asarray(ns)
    for q, s in qs.items():
        err = np.asarray(s["errors"][:-1])
        ok = err > 0
        slope = f", slope {s['slope']:.2f}" if math.isfinite(s["slope"]) else ""
        ax.loglog(ns[:-1][ok], err[ok], "o-", ms=4, color=COLORS.get(q),
                  label=f"{q}: p {s['local']:.2f}{slope}")  # fmt: skip
        if len(s["fit"]) >= 2:
            ax.loglog(ns[s["fit"]], err[s["fit"]], "k-", lw=3, alpha=0.2)
    # A line of slope -6 through the period's coarsest error: P3's order.
    e0 = qs["period"]["errors"][0]
    ax.loglog(ns[:-1], e0 * (ns[:-1] / ns[0]) ** -6.0, "--", color="0.5", lw=1, label="N^-6")
    ax.set_xticks(ns[:-1], [str(n) for n in ns[:-1]])
    ax.minorticks_off()
    label_axes(ax, "elements N", "|Q_N - Q_finest|", title, grid="both", fontsize=9)
    # below the axes: inside, the legend would cover the coarse meshes' errors
    ax.legend(fontsize=9, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncols=2, frameon=False)


def plot(result: CaseResult, fig=None):
    """(a) 3-D errors, (b) planar errors, (c) local orders of both."""

    if fig is None:
        import matplotlib.pyplot as plt

        # taller than wide panels: the legends of (a) and (b) sit under them
        fig, axes = plt.subplots(1, 3, figsize=(14.0, 6.2), layout="constrained")
    else:
        axes = list(fig.subplots(1, 3, squeeze=False).ravel())
    d = result.data
    ns = d["elements"]
    _draw_errors(axes[0], ns, d["space"], f"non-planar cycle (3-D), v = {d['v_space']:g}")
    _draw_errors(axes[1], ns, d["planar"], f"planar cycle (Eq. (20)), v = {d['v_planar']:g}")
    ax = axes[2]
    names = list(d["space"])
    x = np.arange(len(names))
    mono = [d["space"][q]["monotone"] for q in names]
    ax.plot(x[mono], [d["space"][q]["local"] for q, m in zip(names, mono, strict=True) if m],
            "o", color="#0072B2", label="3-D")  # fmt: skip
    if not all(mono):
        ax.plot(x[~np.array(mono)],
                [d["space"][q]["local"] for q, m in zip(names, mono, strict=True) if not m],
                "x", color="#0072B2", label="3-D, not monotone (not checked)")  # fmt: skip
    ax.plot([i for i, q in enumerate(names) if q in d["planar"]],
            [d["planar"][q]["local"] for q in names if q in d["planar"]],
            "s", mfc="none", color="#D55E00", label="planar")  # fmt: skip
    ax.axhline(6.0, color="0.5", ls=":", lw=1)
    ax.set_xticks(x, names, rotation=90, fontsize=9)
    ax.set_ylabel(f"local order p (N = {', '.join(map(str, ns[-3:]))})")
    ax.set_title("observed orders", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=9)
    finish_figure(fig, f"{CASE.figure}: {CASE.title}", f"{paper_case_line()}, α = π/2, P3")
    return fig

"""The convergence study: error against degrees of freedom, FE P1/P2/P3 and modal N.

Each quantity (a static tip value, v_cr per alpha of Fig. 6, a limit-cycle amplitude) on
refined meshes and increasing sine modes; the reference is the Richardson extrapolation of the
two finest P3 values (its correction the error estimate), the observed order the slope of the
last three errors above the reference's uncertainty.  FE tip values of P_k converge as
h^(2k), the sine modes as N^-3 (docs/theory/conventions.md).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.params import PAPER_CASE
from fempipe.studies.convergence import estimate_order, extrapolate_richardson

from .bvp import solve_static_bvp
from .case import Case
from .checks import CaseResult, Table
from .drawing import figure_panels, finish_figure, label_axes
from .dynamic_runs import cycle_on
from .evaluate import Measured, measure
from .fig02b import pipe
from .onset import critical_velocity
from .static_shapes import static_shapes

CASE = Case.load("convergence")


@dataclass(frozen=True)
class Series:
    """One discretization family: dofs, values, errors and the fitted order."""

    label: str
    dofs: np.ndarray
    values: np.ndarray
    errors: np.ndarray
    order: float  # observed order in dofs (positive: error ~ dofs^-order)
    fit: tuple[int, ...]  # indices used by the fit
    expected: float | None = None


@dataclass(frozen=True)
class Study:
    """The convergence study of one quantity."""

    quantity: str
    reference: float
    reference_error: float
    series: dict
    paper_modes: dict  # N -> value
    independent: tuple[str, float] | None = None  # (name, value) of an independent check

    def to_rows(self):
        for s in self.series.values():
            for d, v, e in zip(s.dofs, s.values, s.errors, strict=True):
                yield (self.quantity, s.label, int(d), v, e)


def run_study(
    quantity: str,
    compute: Callable[[object], float],
    fe_elements: dict,
    modes: Sequence[int],
    fe_order: dict,
    paper_modes: Sequence[int] = (3, 4),
    roundoff: float = 1e-12,
) -> Study:
    """``compute(disc)`` on every discretization (``fe_elements``: degree -> doubling element
    counts; ``modes``: N) and the fitted orders; errors below ``roundoff * max(1, |Q|)`` unfitted."""
    raw: dict[str, tuple[np.ndarray, np.ndarray, float | None]] = {}
    for deg, ns in fe_elements.items():
        deg = int(deg)
        discs = [FiniteElement(n, deg) for n in ns]
        vals = np.array([compute(d) for d in discs])
        raw[f"FE P{deg}"] = (np.array([d.n for d in discs]), vals, float(fe_order[str(deg)]))
    mvals = {int(n): compute(Modal(int(n))) for n in sorted(set(modes) | set(paper_modes))}
    raw["modal"] = (np.array(sorted(mvals)), np.array([mvals[n] for n in sorted(mvals)]), None)
    top = max(int(d) for d in fe_elements)
    _, vtop, _ = raw[f"FE P{top}"]
    ref, ref_err = extrapolate_richardson(vtop[-2], vtop[-1], float(fe_order[str(top)]))
    floor = max(10.0 * ref_err, roundoff * max(1.0, abs(ref)))
    series = {}
    for label, (dofs, vals, expected) in raw.items():
        err = np.abs(vals - ref)
        order, idx = estimate_order(dofs, err, floor)
        series[label] = Series(label, dofs, vals, err, order, idx, expected)
    return Study(quantity, ref, ref_err, series, {n: mvals[n] for n in paper_modes})


def study_names(tag: str, degrees) -> list[str]:
    """The checks :func:`study_checks` emits for FE degrees ``degrees``."""
    return [f"{tag}_order_P{int(k)}" for k in degrees] + [f"{tag}_modal_algebraic"]


def study_checks(study: Study, tag: str) -> list[Measured]:
    """Observed FE orders against theory, modal algebraic convergence: :func:`study_names`."""
    fields = {"tag": tag, "quantity": study.quantity}
    checks = [
        measure(
            "{tag}_order_{degree}", s.order, degree=k[-2:], label=k, reference=s.expected, **fields
        )
        for k, s in study.series.items()
        if s.expected is not None
    ]
    m = study.series["modal"]
    ok = bool(np.isfinite(m.order) and 0.5 < m.order < 6.0)
    checks.append(measure("{tag}_modal_algebraic", ok=ok, order=m.order, **fields))
    return checks


def static_study(quick: bool) -> tuple[Study, list]:
    """(a) The Texier-Dorbolo tip drop X_g(1) at U = 2 m/s."""
    ref = CASE.references
    si = pipe()
    p = si.params(ref.value("static_U"))

    def compute(disc) -> float:
        shapes = static_shapes(disc, p.alpha, p.gamma, [p.v], beta=p.beta, mu=0.0)
        return float(shapes.tips["X_tip"][0])

    quantity = "static tip drop X_g(1) (Texier-Dorbolo, U = 2 m/s)"
    meshes = (ref.value("fe_elements", quick), ref.value("modes", quick), ref.value("fe_order"))
    st = run_study(quantity, compute, *meshes)
    bvp = solve_static_bvp(p.alpha, p.gamma, p.v, tol=1e-11)
    st = replace(st, independent=("solve_bvp", bvp.X_tip))
    checks = study_checks(st, "static")
    atol = max(1e-10, 10 * st.reference_error)
    checks.append(measure("static_reference_vs_bvp", st.reference, reference=bvp.X_tip, atol=atol))
    return st, checks


def vcr_studies(quick: bool) -> tuple[list, list]:
    """(b) v_cr for each alpha of Fig. 6 (independent onset, Brent to 1e-12 in v)."""
    ref = CASE.references
    studies, checks = [], []
    for a in ref.value("vcr_alpha", quick):

        def compute(disc, a=a) -> float:
            return critical_velocity(disc, a, **PAPER_CASE, xtol=1e-12).v_cr

        meshes = (ref.value("vcr_fe_elements", quick), ref.value("vcr_modes", quick))
        name = f"v_cr, α = {np.degrees(a):.0f}°"
        st = run_study(name, compute, *meshes, ref.value("fe_order"), roundoff=1e-11)
        studies.append(st)
        checks += study_checks(st, f"vcr{np.degrees(a):.0f}")
    return studies, checks


def lco_study() -> tuple[Study, list]:
    """(c) the eta(1) amplitude of the limit cycle at alpha = 0, v = 10 (full suite)."""
    ref = CASE.references
    a, v = ref.value("lco")["alpha"], ref.value("lco")["v"]
    seed_disc = FiniteElement(8, 3)
    seed = cycle_on(seed_disc, a, v)
    guess = (seed.q0, seed.qdot0, seed.period)

    def compute(disc) -> float:
        c = cycle_on(disc, a, v, seed_disc, guess)
        return float("nan") if c is None else 0.5 * (c.tip["eta_tip"][1] - c.tip["eta_tip"][0])

    meshes = (ref.value(k) for k in ("lco_fe_elements", "lco_modes", "fe_order"))
    name = "limit-cycle amplitude of η(1), α = 0, v = 10"
    st = run_study(name, compute, *meshes, roundoff=ref.value("lco_floor"))
    return st, study_checks(st, "lco")


def _paper_table(studies: Sequence[Study]) -> Table:
    rows = []
    for s in studies:
        for n, val in s.paper_modes.items():
            rows.append((s.quantity, f"N = {n}", val, s.reference, val - s.reference,
                         abs(val - s.reference) / max(abs(s.reference), 1e-300)))  # fmt: skip
    return CASE.references.table("paper", tuple(rows))


def _order_table(studies: Sequence[Study]) -> Table:
    rows = []
    for s in studies:
        for ser in s.series.values():
            rows.append((s.quantity, ser.label, ser.order,
                         "" if ser.expected is None else ser.expected,
                         ", ".join(str(int(ser.dofs[i])) for i in ser.fit),
                         float(np.min(ser.errors))))  # fmt: skip
    return CASE.references.table("orders", tuple(rows))


def _reference_table(studies: Sequence[Study]) -> Table:
    rows = []
    for s in studies:
        name, val = s.independent if s.independent else ("—", "—")
        diff = abs(s.reference - val) if s.independent else "—"
        rows.append((s.quantity, s.reference, s.reference_error, name, val, diff))
    return CASE.references.table("references", tuple(rows))


def run(quick: bool = False) -> CaseResult:
    """The static and v_cr studies; the limit-cycle study in the full suite only."""
    ref = CASE.references
    requires = study_names("static", ref.value("fe_elements", quick))
    for a in ref.value("vcr_alpha", quick):
        requires += study_names(f"vcr{np.degrees(a):.0f}", ref.value("vcr_fe_elements", quick))
    st, checks = static_study(quick)
    sts, ch = vcr_studies(quick)
    studies, checks = [st, *sts], checks + ch
    if not quick:
        requires += study_names("lco", ref.value("lco_fe_elements"))
        st, ch = lco_study()
        studies, checks = [*studies, st], checks + ch
    data_table = ref.table("values", (r for s in studies for r in s.to_rows()))
    tables = (_paper_table(studies), _reference_table(studies), _order_table(studies), data_table)
    return CASE.result(
        checks, quick=quick, requires=requires, tables=tables, data={"studies": studies}
    )


#: Color-blind-safe colors (Okabe & Ito) of the discretization families.
SERIES_COLORS = {"FE P1": "#0072B2", "FE P2": "#E69F00", "FE P3": "#009E73", "modal": "#D55E00"}


def draw_study(study: Study, ax=None):
    """Log-log error against dofs with the observed slopes in the legend."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots()
    markers = {"FE P1": "o-", "FE P2": "s-", "FE P3": "^-", "modal": "d--"}
    for label, s in study.series.items():
        ok = s.errors > 0
        lab = f"{label}: p = {s.order:.2f}" + (f" (theory {s.expected:g})" if s.expected else "")
        style = markers.get(label, ".-")
        ax.loglog(s.dofs[ok], s.errors[ok], style, color=SERIES_COLORS.get(label), ms=4, label=lab)
        if len(s.fit) >= 2:
            ax.loglog(s.dofs[list(s.fit)], s.errors[list(s.fit)], "k-", lw=2.5, alpha=0.25)
    for n, val in study.paper_modes.items():
        e = abs(val - study.reference)
        # N = 3 and N = 4 lie one dof apart: N = 3 is labelled on the left, the others right.
        left = n == min(study.paper_modes)
        place = {"xytext": (-5, 4), "ha": "right", "va": "bottom"} if left else {}
        place = place or {"xytext": (5, -4), "ha": "left", "va": "top"}
        ax.annotate(f"N = {n}", (n, e), textcoords="offset points", fontsize=9, **place)
    if study.reference_error > 0:
        err = study.reference_error
        ax.axhline(err, color="0.5", ls=":", lw=1, label="reference error estimate")
    from matplotlib.ticker import NullFormatter

    ax.xaxis.set_minor_formatter(NullFormatter())
    label_axes(ax, "degrees of freedom", "|error|", study.quantity, grid="both", fontsize=9)
    ax.legend(fontsize=9)
    return ax


def draw_orders(studies: Sequence[Study], ax=None):
    """Observed order of every series against the v_cr study's alpha."""
    import matplotlib.pyplot as plt

    if ax is None:
        _, ax = plt.subplots()
    vc = [s for s in studies if s.quantity.startswith("v_cr")]
    alphas = [float(s.quantity.split("=")[1].strip().rstrip("°")) for s in vc]
    for label, mk in (("FE P1", "o-"), ("FE P2", "s-"), ("FE P3", "^-"), ("modal", "d--")):
        orders = [s.series[label].order for s in vc]
        ax.plot(alphas, orders, mk, color=SERIES_COLORS[label], ms=4, label=label)
    for p in (2, 4, 6):
        ax.axhline(p, color="0.6", lw=0.8, ls=":")
    title = "v_cr: observed orders against α (theory 2, 4, 6)"
    label_axes(ax, "α (degrees)", "observed order p", title, fontsize=9)
    ax.legend(fontsize=9, loc="center right")
    return ax


def plot(result: CaseResult, fig=None):
    """Log-log error against dofs: static tip, v_cr at α = 0 and 90°, limit cycle; orders vs α."""

    studies = result.data["studies"]
    shown = [s for s in studies if not s.quantity.startswith("v_cr")]
    vc = [s for s in studies if s.quantity.startswith("v_cr")]
    shown[1:1] = [s for s in vc if s.quantity.endswith(("= 0°", "= 90°"))]
    n = len(shown) + (1 if len(vc) > 1 else 0)
    fig, axes = figure_panels(fig, n, ncols=min(n, 3), size=4.5)
    for ax, s in zip(axes, shown, strict=False):
        draw_study(s, ax=ax)
    if len(vc) > 1:
        draw_orders(studies, ax=axes[len(shown)])

    finish_figure(fig, f"{CASE.figure}: {CASE.title}")
    return fig

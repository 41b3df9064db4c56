"""Which planar orbits of Figs. 7-10 survive in three dimensions.

The FE diagram of a case is continued once with the out-of-plane Floquet multipliers
(:func:`fempipe.analyses.periodic.out_of_plane.cycle_verdict`) of about :data:`N_FULL` orbits
per branch, its last one and v = 10 (quick suite: v = 10 only); where the largest crosses 1
between two of them the crossing is located by regula falsi (full suite only).
"""

from __future__ import annotations

import functools
import json
import tempfile
from dataclasses import dataclass
from pathlib import Path

from fempipe.analyses.periodic import compute_cycle_diagram
from fempipe.analyses.periodic.out_of_plane import Spread, locate_change
from fempipe.analyses.periodic.results import CyclePoint
from fempipe.model.discretization import parse_discretization

from .checks import Table
from .dynamic_runs import FIRST_DS, ContinuedDiagram, continued_from, model_for
from .evaluate import measure

__all__ = ["N_FULL", "OutOfPlaneBranches", "continued_with_verdicts"]

#: Orbits per branch whose out-of-plane multipliers the full suite computes.
N_FULL = 8
#: The located crossing's v is known to this (the bracket's width).
LOCATE_TOL = 2e-3


@dataclass(frozen=True)
class OutOfPlaneBranches:
    """The 3-D verdicts along the cycle branches of one continued diagram.

    ``checked``: dicts of the orbits with a verdict (``branch``, ``v``, ``stable`` in the plane,
    ``max_multiplier``, ``max_oop``, ``stable_3d``, tip extrema, ``planar_block``, ``neutral``,
    ``multipliers``); ``changes``: where the verdict changes (``branch``, ``bracket``,
    ``direction`` loses/regains, located ``v`` or None).
    """

    label: str
    alpha: float
    checked: list
    changes: list

    def at(self, v: float) -> dict | None:
        """The checked orbit at ``v`` that is stable in the plane (the paper's cycle)."""
        pts = [p for p in self.checked if abs(p["v"] - v) < 1e-9 and p["stable"]]
        return pts[0] if pts else None


@dataclass(frozen=True)
class AtVelocities:
    """The branch points at the velocities ``v_keep`` (to 1e-9): the quick suite's selection."""

    v_keep: tuple

    def __call__(self, points) -> list[int]:
        return [i for i, p in enumerate(points) if any(abs(p.v - w) < 1e-9 for w in self.v_keep)]


def continued_with_verdicts(
    label: str, alpha: float, values, quick: bool
) -> tuple[ContinuedDiagram, OutOfPlaneBranches]:
    """The continued diagram of ``label`` at ``alpha`` and the 3-D verdicts of its orbits (cached)."""
    return _cached(label, float(alpha), tuple(sorted(float(v) for v in values)), bool(quick))


def fe_disc(label: str):
    """The FE discretization of a label ``FE P3:8``."""
    if not label.startswith("FE "):
        raise ValueError(f"an FE label expected (FE Pk:n), got {label!r}")
    return parse_discretization(fe=label[3:])


@functools.lru_cache(maxsize=8)
def _cached(label: str, alpha: float, values: tuple, quick: bool):
    disc = fe_disc(label)
    select = AtVelocities((10.0,)) if quick else Spread(N_FULL, (10.0,))
    model = model_for(disc, alpha, values[0])
    with tempfile.TemporaryDirectory(prefix="fempipe-validate-3d-") as tmp:
        dg = compute_cycle_diagram(
            model, list(values), store_dir=tmp, ds=FIRST_DS, out_of_plane=select
        )
        diag = continued_from(label, alpha, values, disc, dg, Path(tmp))
        checked = [
            _summary(d)
            for d in dg.points
            if d["attractor"] == "periodic"
            and d.get("max_nontrivial_out_of_plane_multiplier") is not None
        ]
        changes = []
        for name in sorted({p["branch"] for p in checked}):
            path = Path(tmp) / f"a00-{name}.json"
            states = [CyclePoint.from_dict(s) for s in json.loads(path.read_text())["points"]]
            changes += _changes(
                model, name, states, [p for p in checked if p["branch"] == name], locate=not quick
            )
    return diag, OutOfPlaneBranches(label, alpha, checked, changes)


def _summary(d: dict) -> dict:
    neutral = d.get("neutral_out_of_plane_multiplier")
    out = {k: d[k] for k in ("branch", "index", "v")}
    out.update(stable=bool(d["stable"]), max_multiplier=d["max_multiplier"])
    out.update(max_oop=d["max_nontrivial_out_of_plane_multiplier"], stable_3d=d["stable_3d"])
    out.update({k: d[k] for k in ("eta_tip", "X_tip", "Z_tip")})
    out.update(planar_block=d["planar_block_max_multiplier"])
    out["neutral"] = None if neutral is None else complex(*neutral)
    out["multipliers"] = [complex(*z) for z in d["out_of_plane_floquet_multipliers"]]
    return out


def _changes(model, name: str, states: list, checked: list, locate: bool) -> list[dict]:
    """Brackets (and, with ``locate``, the v) of the verdict's changes along a branch."""
    out = []
    pts = sorted(checked, key=lambda p: p["index"])
    for a, b in zip(pts, pts[1:], strict=False):
        if (a["max_oop"] < 1.0) == (b["max_oop"] < 1.0):
            continue
        sa, sb = states[a["index"]], states[b["index"]]
        if abs(sa.v - a["v"]) > 1e-12 or abs(sb.v - b["v"]) > 1e-12:
            continue  # the store's layout differs from the diagram's: no location
        lo_first = a["v"] < b["v"]
        loses = (a["max_oop"] < 1.0) == lo_first
        where = None
        if locate:
            found = locate_change(model, sa, sb, a["max_oop"], b["max_oop"], tol=LOCATE_TOL)
            where = None if found is None else found["v"]
        direction = "loses" if loses else "regains"
        out.append(
            {
                "branch": name,
                "bracket": sorted([a["v"], b["v"]]),
                "direction": direction,
                "v": where,
            }
        )
    return out


def neutral_deviation(branches: OutOfPlaneBranches) -> float:
    """|ρ_neutral - 1| of the paper's cycle at v = 10 (sin alpha = 0; nan elsewhere)."""
    p = branches.at(10.0)
    return float("nan") if p is None or p["neutral"] is None else float(abs(p["neutral"] - 1.0))


def planar_block_deviation(branches: OutOfPlaneBranches) -> float:
    """Largest | |ρ| of the Floquet run's planar block - |ρ| of the planar orbit | (checked orbits)."""
    d = [
        abs(p["planar_block"] - p["max_multiplier"])
        for p in branches.checked
        if p["planar_block"] is not None and p["max_multiplier"] is not None
    ]
    return float(max(d)) if d else float("nan")


def stretches(br: OutOfPlaneBranches, branch: str) -> list[tuple[float, float, bool]]:
    """``(v_from, v_to, stable_3d)`` of a branch's stretches with one verdict (boundary nan if not
    located).
    """
    pts = [p for p in br.checked if p["branch"] == branch and p["stable"]]
    pts.sort(key=lambda p: p["index"])
    if not pts:
        return []
    cross = {tuple(c["bracket"]): c["v"] for c in br.changes if c["branch"] == branch}
    out = []
    start, ok = pts[0]["v"], pts[0]["max_oop"] < 1.0
    for a, b in zip(pts, pts[1:], strict=False):
        if (b["max_oop"] < 1.0) != ok:
            v_c = cross.get(tuple(sorted([a["v"], b["v"]])))
            v_c = float("nan") if v_c is None else v_c
            out.append((start, v_c, ok))
            start, ok = v_c, not ok
    out.append((start, pts[-1]["v"], ok))
    return out


def survival_text(name: str, br: OutOfPlaneBranches) -> str:
    """One sentence: which planar cycles at alpha = ``name`` survive in 3-D, and at v = 10."""
    parts = []
    for branch in sorted({p["branch"] for p in br.checked}):
        st = stretches(br, branch)
        if not st:
            continue
        if len(st) == 1:
            a, b, ok = st[0]
            which = (
                f"the one checked (v = {a:.4g}) is"
                if a == b
                else f"all checked ({a:.4g} ≤ v ≤ {b:.4g}) are"
            )
            parts.append(f"{branch}: {which} " + ("stable in 3-D" if ok else "unstable in 3-D"))
            continue
        words = [
            f"{'stable' if ok else 'unstable'} for {_num(a)} ≤ v ≤ {_num(b)}" for a, b, ok in st
        ]
        parts.append(f"{branch}: " + ", ".join(words))
    if not parts:
        return f"α = {name}: no planar limit cycle stable in the plane was checked in 3-D"
    text = f"α = {name}: the planar limit cycles in 3-D — " + "; ".join(parts)
    p10 = br.at(10.0)
    if p10 is not None:
        text += (
            f"; the paper's cycle at v = 10 is {'stable' if p10['stable_3d'] else 'UNSTABLE'} "
            f"in 3-D (largest out-of-plane |ρ| {p10['max_oop']:.4f}, {br.label})"
        )
    if any(c["v"] is not None for c in br.changes):
        text += " (the crossings located by regula falsi on the multiplier)"
    elif br.changes:
        text += " (the crossings, ?, not located: between the checked orbits)"
    return text


def _num(v: float) -> str:
    return "?" if v != v else f"{v:.4g}"


def unstable_runs(br: OutOfPlaneBranches, diag: ContinuedDiagram) -> list[list]:
    """Runs of orbits (stable in the plane) unstable in 3-D: each orbit takes the verdict of the
    nearer checked orbit, or the side of the located crossing (else the bracket's midpoint).
    """
    runs = []
    for name, pts in diag.branches.items():
        chk = sorted((p for p in br.checked if p["branch"] == name), key=lambda p: p["index"])
        if not chk or chk[-1]["index"] >= len(pts):
            continue
        cross = {tuple(c["bracket"]): c["v"] for c in br.changes if c["branch"] == name}
        bad = []
        for i, pt in enumerate(pts):
            if not chk[0]["index"] <= i <= chk[-1]["index"]:
                bad.append(False)  # outside the checked orbits: no verdict
                continue
            after = next((c for c in chk if c["index"] >= i), chk[-1])
            before = next((c for c in reversed(chk) if c["index"] <= i), chk[0])
            if before["stable_3d"] == after["stable_3d"] or before is after:
                verdict = (
                    before if abs(i - before["index"]) <= abs(after["index"] - i) else after
                )["max_oop"] >= 1.0
            else:
                lo, hi = sorted([before["v"], after["v"]])
                v_c = cross.get((lo, hi)) or 0.5 * (lo + hi)
                # on the side of the crossing where the nearer checked orbit lies
                side = before if (pt.v - v_c) * (before["v"] - v_c) > 0 else after
                verdict = side["max_oop"] >= 1.0
            bad.append(bool(verdict and pt.stable))
        run = []
        for pt, b in zip(pts, bad, strict=True):
            if b:
                run.append(pt)
            elif run:
                runs.append(run)
                run = []
        if run:
            runs.append(run)
    return runs


def marks(ax, br: OutOfPlaneBranches, diag: ContinuedDiagram, key: str) -> bool:
    """A red band where the orbits are unstable in 3-D and red triangles at the checked ones;
    True if any were drawn.
    """
    runs = unstable_runs(br, diag)
    bad = [p for p in br.checked if p["stable"] and p["stable_3d"] is False]
    tri = {"ms": 7, "color": "tab:red", "mfc": "none", "mew": 1.2, "zorder": 5}
    for side in (0, 1):
        ax.plot([p["v"] for p in bad], [p[key][side] for p in bad], "v", **tri)
    band = {"lw": 6, "color": "tab:red", "alpha": 0.3, "solid_capstyle": "butt", "zorder": 1}
    for run in runs:
        v = [p.v for p in run]
        for side in (0, 1):
            ax.plot(v, [getattr(p, key)[side] for p in run], "-", **band)
    return bool(runs or bad)


def add_legend_entry(ax) -> None:
    """The panel's legend below the axes with the entries of :func:`marks`."""
    from matplotlib.lines import Line2D

    leg = ax.get_legend()
    handles = list(leg.legend_handles) if leg is not None else []
    band = Line2D(
        [], [], lw=6, color="tab:red", alpha=0.3, label="stable in plane, unstable in 3-D"
    )
    tri = {"ls": "", "marker": "v", "ms": 7, "color": "tab:red", "mfc": "none"}
    handles += [band, Line2D([], [], label="checked: unstable in 3-D", **tri)]
    below = {"loc": "upper center", "bbox_to_anchor": (0.5, -0.16), "frameon": False}
    ax.legend(handles=handles, fontsize=9, ncol=3, **below)


def verdict_checks(suffix: str, name: str, br: OutOfPlaneBranches, quick: bool) -> list:
    """``planar_block<suffix>`` and, at sin alpha = 0 in the full suite, ``neutral_oop<suffix>``."""

    out = [measure(f"planar_block{suffix}", planar_block_deviation(br), alpha=name, label=br.label)]
    p10 = br.at(10.0)
    if not quick and p10 is not None and p10["neutral"] is not None:
        dev = neutral_deviation(br)
        out.append(measure(f"neutral_oop{suffix}", dev, alpha=name, label=br.label))
    return out


def verdict_rows(name: str, br: OutOfPlaneBranches) -> list[tuple]:
    """The checked orbits as rows of :func:`verdict_table`."""
    rows = []
    for p in sorted(br.checked, key=lambda p: (p["branch"], p["v"])):
        lead = leading_text(p["multipliers"], p["neutral"])
        rows.append((name, br.label, p["branch"], p["v"], "yes" if p["stable"] else "no",
                     p["max_multiplier"], p["max_oop"], lead,
                     {True: "yes", False: "no", None: "-"}[p["stable_3d"]]))  # fmt: skip
    return rows


def leading_text(multipliers, neutral) -> str:
    """The out-of-plane multiplier of largest modulus but the neutral one, as ``a ± bi``."""
    others = [complex(z) for z in multipliers if neutral is None or complex(z) != neutral]
    if not others:
        return "-"
    z = others[0]
    return f"{z.real:.4f} {'+' if z.imag >= 0 else '-'} {abs(z.imag):.4f}i"


def verdict_table(rows: list[tuple], changes: list[str], quick: bool) -> object:
    """The out-of-plane Floquet multipliers of the checked planar orbits."""

    which = (
        "the orbit at v = 10 (quick suite)"
        if quick
        else f"about {N_FULL} orbits spread along each branch, its last one and v = 10"
    )
    note = (
        f"Checked orbits: {which}. |ρ| in the plane: the largest non-trivial Floquet multiplier "
        "of the planar orbit; out of the plane: of the out-of-plane perturbations on the 3-D "
        "model (at α = 0 and π the neutral rotation about the vertical is left out). Stable in "
        "3-D: both below 1."
    )
    if changes:
        note += " Changes of the out-of-plane verdict: " + "; ".join(changes) + "."
    return Table(
        "Do the planar limit cycles survive in 3-D? Out-of-plane Floquet multipliers",
        (
            "α | discretization | branch | v | stable in plane | max |ρ| in plane | "
            "max |ρ| out of plane | leading out-of-plane ρ | stable in 3-D"
        ),
        tuple(rows),
        note=note,
    )


def change_texts(name: str, br: OutOfPlaneBranches) -> list[str]:
    """The changes of the out-of-plane verdict, in words."""
    out = []
    for c in br.changes:
        lo, hi = c["bracket"]
        at = f"at v = {c['v']:.4f}" if c["v"] is not None else f"between v = {lo:.4g} and {hi:.4g}"
        out.append(f"α = {name}, {c['branch']}: {c['direction']} out-of-plane stability {at}")
    return out

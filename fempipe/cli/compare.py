"""``fempipe compare FILE.csv``: a user's results checked against fempipe, with its error estimate.

The file holds the user's own numbers (from a modal code, another FE code, an
experiment), one case per row; for each row and each quantity given, fempipe
computes the same quantity (:class:`fempipe.studies.convergence.Quantity`, exactly
as ``fempipe convergence`` does) on the chosen discretization (``--fe``,
default P3:16, or ``--modal N``) and again on the refined one (elements
halved, twice the modes plus one for an odd N), and reports the user's value, fempipe's, the
difference user - fempipe, the relative difference (over |fempipe|),
fempipe's error estimate (the Grid Convergence Index of one refinement,
:mod:`fempipe.studies.error_estimate`) and whether the difference is *resolved*
(|difference| > error estimate: fempipe's discretization error cannot explain
it).  See :mod:`fempipe.studies.compare`.

Input file
----------
CSV with a header line; lines starting with ``#`` and blank lines are
skipped (comments: say where the numbers come from); ``row`` N in the output
and in messages counts the data rows from 1.  A header cell is a column name,
optionally with its unit in brackets as in fempipe's own CSV files
(``v_cr [1]``, ``alpha [rad]``, ``X_tip [L]``); a unit that is not the
column's is refused (``alpha [deg]``: name the column ``alpha_deg``).
Columns (:data:`COLUMNS`):

* the quantities, one or more: ``v_cr``, ``frequency`` (Im lambda of the
  critical event, per unit tau), ``theta_tip`` (rad), ``X_tip``, ``Z_tip``,
  ``eta_tip`` (static tip values, divided by L), ``lc_amplitude`` (of
  eta(1), L), ``lc_period`` (T); an empty cell: not given for that row.
  ``v_cr`` and ``frequency`` mean what they mean in every command: the round
  pipe's first loss of stability, at the smaller of ``v_cr_in_plane`` and
  ``v_cr_out_of_plane`` (``fempipe critical``'s and ``fempipe convergence``'s
  ``v_cr``; docs, "Out of the plane"); with ``--planar``, as in those commands,
  the paper's planar model, the motion in the plane of the static state (what
  a planar code computes: ``v_cr_in_plane``, ``frequency_in_plane``).
  ``v_cr_out_of_plane`` and ``frequency_out_of_plane`` are those of the motion
  out of that plane (:mod:`fempipe.model.out_of_plane`).  Each row names the
  fempipe quantity it was compared with (``fempipe_quantity``);
* the inclination ``alpha`` in rad (also ``pi/3``, ``60deg`` as for
  ``--alpha``) or ``alpha_deg`` in degrees, default 0;
* dimensionless groups ``beta``, ``gamma``, ``mu`` (Eq. (19)) and the flow
  ``v``; missing columns or empty cells of beta, gamma, mu take the paper's
  case 0.142, 18.9, 5e-3 like the options of every other command, and the
  output lists each value so taken (``defaults``);
* or the SI pipe: ``length`` (m), ``EI`` (N m^2), ``m``, ``M`` (kg/m), ``g``
  (m/s^2, default 9.81), ``a`` (s, default 0) and the flow ``U`` (m/s),
  converted by :class:`fempipe.model.params.PipeSI` as the SI options are; a file
  is either dimensionless or SI (``alpha``/``alpha_deg`` belong to both);
* the flow range of the critical quantities (``v_cr``, ``frequency`` and
  their ``_in_plane``, ``_out_of_plane`` forms): ``v_min`` (default 0),
  ``v_max`` (default ``--v-max``, 15) or, SI, ``U_min``, ``U_max`` in m/s;
  ``v``/``U`` is then not needed.  The static tip values and the limit
  cycle are at the row's ``v`` (or ``U``), which they require;
* ``label``: free text, carried into the output.

Every value is checked before anything is computed, against the ranges of
the command-line options (:mod:`fempipe.cli.parsing`); the first bad cell
ends the command with one line ``fempipe compare: error: FILE: row N (line
L), column C: message`` (``FILE: header, column C: ...`` for the header)
and exit code 2, and no file is written.

Output
------
``--json`` prints ``{"file", "rows": [{"row", "quantity", "user",
"fempipe", "difference", "relative_difference", "error_estimate",
"resolved", "verdict", "unit", "refined", "failure", "note", "alpha", "beta",
"gamma", "mu", "v", "v_min", "v_max", "defaults", ...}], "discretization",
"error_estimate": {"method", "discretization", "refined", "formula",
"floor", "floors", "resolved", ...}, "summary", "cpu_time"}`` (with the SI
pipe also ``U``, ``U_min``, ``U_max``, ``pipe_SI`` per row).  ``--out DIR``
writes compare.json, compare.csv (one line per row and quantity; ``user``,
``fempipe``, ``difference``, ``error_estimate`` and ``refined`` are in the
unit of the line's quantity, named in its column ``unit``, so their header
says ``[-]``) and compare.png (user against fempipe per quantity, the line
y = x, and the differences with fempipe's error estimate as error bars).

Each row's ``verdict`` reads the criterion: ``"differs"`` (by more than
fempipe's error estimate), ``"agrees"`` (within it), null without an estimate.
Exit codes, as diff's: 0 when every value agrees, 1 when some value differs,
has no estimate or failed (Newton, no v_cr in the flow range, no limit cycle:
its row is in the table and the files with the failure's message and no
fempipe value; the others are complete), 2 for bad input.
"""

from __future__ import annotations

import argparse
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.compare_cases import COLUMNS, DEFAULT_V_MAX, Case, fempipe_quantity, read_cases

__all__ = ["COLUMNS", "CSV_COLUMNS", "DEFAULT_V_MAX", "Case", "add_arguments", "read_cases", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "file",
        metavar="FILE.csv",
        help="the user's values: one case per row; columns: quantities (v_cr, frequency "
        "(the first loss of stability, in either plane; with --planar the paper's planar "
        "model's), theta_tip, X_tip, Z_tip, eta_tip, "
        "lc_amplitude, lc_period, v_cr_in_plane, v_cr_out_of_plane, frequency_in_plane, "
        "frequency_out_of_plane), parameters (alpha or "
        "alpha_deg, beta, gamma, mu, v; or length, EI, m, M, g, a, U in SI), the flow range "
        "v_min, v_max (or U_min, U_max) of v_cr and frequency, label; '# ...' lines are "
        "comments (see the docs, 'fempipe compare')",
    )
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("comparison")
    g.add_argument(
        "--v-max",
        metavar="V",
        type=parsing.number_type("--v-max", 0.0, parsing.V_MAX, strict_low=True),
        default=str(DEFAULT_V_MAX),
        help=f"end of the flow range of v_cr and frequency where a row has no v_max (or U_max) "
        f"cell (default {DEFAULT_V_MAX:g}; dimensionless v, also for an SI file)",
    )
    common.add_shoot_rtol_argument(
        g, "integration tolerance of the limit cycle's shooting (lc_amplitude, lc_period)"
    )
    common.add_workers_argument(g, "processes computing the comparisons in parallel (default 1)")
    common.add_planar_argument(g, "v_cr and frequency are the in-plane ones, v_cr_in_plane")
    common.add_output_arguments(parser)


# ---------------------------------------------------------------------------
# Reading and checking the file
# ---------------------------------------------------------------------------


# ---------------------------------------------------------------------------
# The command
# ---------------------------------------------------------------------------


def run(args: argparse.Namespace) -> int:
    import time

    from fempipe.io import CSV_UNITS
    from fempipe.studies.compare import compare_values, estimate_description

    t0 = time.process_time()
    setup = common.setup_from_args(args, need_flow=False)  # the discretization
    disc = setup.disc
    cases = read_cases(args.file, v_max=args.v_max)
    items = [(case, name) for case in cases for name in case.values]
    parsing.check_count(
        args.file, len(items), parsing.MAX_VALUES, parsing.allow_large(args), "comparisons"
    )
    pairs = [
        (case.quantity(name, args.shoot_rtol, args.planar), case.values[name])
        for case, name in items
    ]
    output = reporting.Output(args.out) if args.out is not None else None
    with reporting.progress(args, len(pairs), "compare") as bar:
        comparisons = compare_values(
            pairs, disc, workers=args.workers, callback=lambda done, total: bar.update()
        )
    rows = []
    for (case, name), comp in zip(items, comparisons, strict=True):
        d = comp.to_dict()
        row = {"row": case.row, "line": case.line}
        if case.label is not None:
            row["label"] = case.label
        row |= {k: d[k] for k in ("quantity", "user", "fempipe", "difference")}
        row["fempipe_quantity"] = fempipe_quantity(name, args.planar)
        row |= {k: d[k] for k in ("relative_difference", "error_estimate", "resolved")}
        row["verdict"] = VERDICTS[d["resolved"]]
        row |= {"unit": CSV_UNITS[name], "refined": d["refined"]}
        row |= {"failure": d["failure"], "note": d["note"]}
        row |= case.to_dict(name)
        row["cpu_time"] = d["cpu_time"]
        rows.append(row)
    quantities = list(dict.fromkeys(name for _, name in items))
    failed = [r for r in rows if r["failure"] is not None]
    result = {
        "file": str(args.file),
        "planar": bool(args.planar),
        "rows": rows,
        "discretization": {"name": disc.name, **disc.to_dict()},
        "error_estimate": estimate_description(disc, quantities, args.shoot_rtol),
        "summary": {
            "comparisons": len(rows),
            "resolved": sum(r["resolved"] is True for r in rows),
            "not_resolved": sum(r["resolved"] is False for r in rows),
            "no_estimate": sum(r["resolved"] is None and r["failure"] is None for r in rows),
            "failed": len(failed),
            "agree": sum(r["verdict"] == "agrees" for r in rows),
            "differ": sum(r["verdict"] == "differs" for r in rows),
        },
        "cpu_time": reporting.cpu_seconds(t0),
    }
    reporting.deliver(
        args, result, output, write=lambda out: _write(out, result), text=lambda: _print(result)
    )
    if failed:
        rows_failed = ", ".join(f"{r['row']} {r['quantity']}" for r in failed)
        print(
            f"fempipe compare: {len(failed)} of {len(rows)} comparisons failed (row {rows_failed});"
            " they are in the table with their message",
            file=sys.stderr,
        )
    differ = [r for r in rows if r["verdict"] == "differs"]
    if differ:
        where = ", ".join(f"{r['row']} {r['quantity']}" for r in differ)
        print(
            f"fempipe compare: {len(differ)} of {len(rows)} values differ from fempipe's by more "
            f"than its error estimate (row {where})",
            file=sys.stderr,
        )
    # as diff: 0 when every value agrees within fempipe's error, 1 otherwise
    return 0 if all(r["verdict"] == "agrees" for r in rows) else 1


#: The verdict of a row from ``resolved``: a difference larger than fempipe's error
#: estimate (resolved) is one fempipe's discretization cannot explain.
VERDICTS = {True: "differs", False: "agrees", None: None}


#: The columns of compare.csv, in order (those present).
CSV_COLUMNS = (
    "row",
    "label",
    "quantity",
    "unit",
    "user",
    "fempipe",
    "difference",
    "relative_difference",
    "error_estimate",
    "resolved",
    "verdict",
    "fempipe_quantity",
    "refined",
    "alpha",
    "beta",
    "gamma",
    "mu",
    "v",
    "v_min",
    "v_max",
    "U",
    "U_min",
    "U_max",
    "failure",
    "note",
)


def _write(output: reporting.Output, result: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.plotting.compare import plot_comparison

    present = {k for r in result["rows"] for k in r}
    columns = [c for c in CSV_COLUMNS if c in present]
    fig = plot_comparison(result["rows"], caption=_caption(result))
    try:
        output.json("compare.json", result)
        output.csv("compare.csv", result["rows"], columns)
        output.figure("compare.png", fig, dpi=150)
    finally:
        plt.close(fig)


def _ranges(numbers: list[int]) -> str:
    """``[1, 2, 3, 5]`` -> ``"1-3, 5"``."""
    out, start, prev = [], None, None
    for n in sorted(set(numbers)):
        if start is None:
            start = prev = n
        elif n == prev + 1:
            prev = n
        else:
            out.append(f"{start}" if start == prev else f"{start}-{prev}")
            start = prev = n
    if start is not None:
        out.append(f"{start}" if start == prev else f"{start}-{prev}")
    return ", ".join(out)


def _common(rows: list[dict], key: str, fmt: str = "{:.6g}") -> str | None:
    vals = {r.get(key) for r in rows}
    if len(vals) == 1 and None not in vals:
        return fmt.format(vals.pop())
    return None


def _caption(result: dict) -> str:
    """The parameters every row shares, the discretization and the estimate."""
    rows = result["rows"]
    est = result["error_estimate"]
    parts = []
    alpha = _common(rows, "alpha", "{:.6g}")
    if alpha is not None:
        parts.append(f"α = {math.degrees(float(alpha)):.4g}°")
    for key, sym in (("beta", "β"), ("gamma", "γ"), ("mu", "μ")):
        val = _common(rows, key)
        parts.append(f"{sym} = {val}" if val is not None else f"{sym} per row")
    if _common(rows, "alpha") is None:
        parts.insert(0, "α per row")
    disc = result["discretization"]["name"]
    text = (
        f"{', '.join(parts)} (rows: compare.csv). fempipe on {disc}; error bars: its error "
        f"estimate, {est['formula']} with {est['refined']}; filled: resolved "
        "(|user − fempipe| > estimate)."
    )
    failed = [r for r in rows if r["fempipe"] is None]
    if failed:
        text += " Not drawn (failed): " + ", ".join(
            f"row {r['row']} {r['quantity']}" for r in failed
        )
    return text


def _fmt(x, spec: str = "{:.10g}") -> str:
    return "-" if x is None else spec.format(x)


def _print(result: dict) -> None:
    rows = result["rows"]
    est = result["error_estimate"]
    n = len(rows)
    print(
        f"fempipe compare {result['file']}: {n} comparison{'s' if n != 1 else ''} on "
        f"{est['discretization']}; error estimate {est['formula']} from {est['refined']}"
    )
    used = sorted({(r["quantity"], r["fempipe_quantity"]) for r in rows})
    for name, fq in used:
        if fempipe_quantity(name, True) != name:  # a quantity whose meaning --planar changes
            what = "in the plane (--planar)" if fq != name else "in either plane (as critical's)"
            print(f"{name}: compared with fempipe's {fq}, the first loss of stability {what}")
    wq = max([12] + [len(r["quantity"]) for r in rows])
    print(
        f"{'row':>4} {'quantity':<{wq}} {'user':>15} {'fempipe':>17} {'difference':>11} "
        f"{'rel. diff.':>11} {'error est.':>10} {'verdict':>8}"
    )
    for r in rows:
        rel = (
            "-" if r["relative_difference"] is None else f"{100 * r['relative_difference']:+.3g} %"
        )
        verdict = r["verdict"] or "-"
        print(
            f"{r['row']:>4} {r['quantity']:<{wq}} {_fmt(r['user']):>15} "
            f"{_fmt(r['fempipe']):>17} "
            f"{_fmt(r['difference'], '{:+.3e}'):>11} {rel:>11} "
            f"{_fmt(r['error_estimate'], '{:.1e}'):>10} {verdict:>8}"
        )
        if r["failure"] is not None:
            print(f"       failed: {r['failure']}")
        elif r["note"]:
            print(f"       {r['note']}")
    defaults: dict[tuple[str, float], list[int]] = {}
    for r in rows:
        for k, val in r["defaults"].items():
            defaults.setdefault((k, val), []).append(r["row"])
    for (k, val), where in defaults.items():
        why = {
            "alpha": "the default inclination",
            "g": "the default gravity, m/s^2",
            "a": "no Kelvin-Voigt damping, s",
            "v_min": "the start of the flow range",
            "U_min": "the start of the flow range, m/s",
            "v_max": "--v-max",
            "U_max": "--v-max, in m/s",
        }.get(k, "the paper's case")
        print(f"not given in row {_ranges(where)}: {k} = {val:.6g} ({why})")
    s = result["summary"]
    print(
        f"{s['agree']} agree within fempipe's error estimate, {s['differ']} differ by more than "
        f"it, {s['no_estimate']} without an estimate, {s['failed']} failed"
    )

"""``fempipe compare FILE.csv``: a user's results against fempipe's, with fempipe's error estimate.

Exit codes as diff's: 0 every value agrees, 1 otherwise, 2 bad input.  The file, keys and files:
docs/cli/commands.md, "fempipe compare".
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.core.errors import ParamError
from fempipe.io import ranges
from fempipe.io.cases import DEFAULT_V_MAX, fempipe_quantity, read_cases

__all__ = ["CSV_COLUMNS", "EXAMPLES", "add_arguments", "run"]

EXAMPLES = (
    "fempipe compare validation/compare_paper_N3.csv --planar --out out-cmp/   # the paper's N = 3",
    "fempipe compare mine.csv --modal 8 --workers 2 --json",
)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "file",
        metavar="FILE.csv",
        help="the user's values: one case per row; columns: quantities (v_cr, frequency "
        "(the first loss of stability, in either plane; with --planar the paper's planar "
        "model's), theta_tip, X_tip, Z_tip, eta_tip, "
        "lc_amplitude, lc_period, v_cr_in_plane, v_cr_out_of_plane, frequency_in_plane, "
        "frequency_out_of_plane, sigma_threshold, omega_threshold), parameters (alpha or "
        "alpha_deg, beta, gamma, mu, v; or length, EI, m, M, g, a, U in SI), the flow range "
        "v_min, v_max (or U_min, U_max) of v_cr and frequency, the band omega_min, omega_max "
        "(required; 1/T) and sigma_max (default 0.5) of the thresholds at the mean flow v, "
        "label; '# ...' lines are comments (see the docs, 'fempipe compare')",
    )
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("comparison")
    g.add_argument(
        "--v-max",
        metavar="V",
        type=parsing.number_type("--v-max", 0.0, ranges.V_MAX, strict_low=True),
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


def run(args: argparse.Namespace) -> int:
    import time

    from fempipe.io import CSV_UNITS
    from fempipe.studies.compare import compare_values, estimate_description

    t0 = time.process_time()
    setup = common.setup_from_args(args, need_flow=False)  # the discretization
    disc = setup.disc
    try:
        cases = read_cases(args.file, v_max=args.v_max)
    except ParamError as exc:
        raise CLIError(args.file, str(exc)) from None
    items = [(case, name) for case in cases for name in case.values]
    parsing.check_count(
        args.file, len(items), parsing.MAX_VALUES, parsing.allow_large(args), "comparisons"
    )
    pairs = [
        (case.quantity(name, args.shoot_rtol, args.planar), case.values[name])
        for case, name in items
    ]
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
        args, result, write=lambda out: _write(out, result), text=lambda: _print(result)
    )
    differ = [r for r in rows if r["verdict"] == "differs"]
    for some, what in (
        (failed, "comparisons failed (row {}); they are in the table with their message"),
        (differ, "values differ from fempipe's by more than its error estimate (row {})"),
    ):
        if some:
            where = ", ".join(f"{r['row']} {r['quantity']}" for r in some)
            print(
                f"fempipe compare: {len(some)} of {len(rows)} {what.format(where)}", file=sys.stderr
            )
    # as diff: 0 when every value agrees within fempipe's error, 1 otherwise
    return 0 if all(r["verdict"] == "agrees" for r in rows) else 1


#: The verdict of a row from ``resolved``: a difference larger than fempipe's error
#: estimate (resolved) is one fempipe's discretization cannot explain.
VERDICTS = {True: "differs", False: "agrees", None: None}


#: The columns of compare.csv, in order (those present).
CSV_COLUMNS = tuple(
    "row label quantity unit user fempipe difference relative_difference error_estimate resolved "
    "verdict fempipe_quantity refined alpha beta gamma mu v v_min v_max U U_min U_max omega_min "
    "omega_max sigma_max failure note".split()
)


def _write(output: reporting.Output, result: dict) -> None:
    reporting.agg()
    from fempipe.plotting.compare import plot_comparison

    present = {k for r in result["rows"] for k in r}
    fig = plot_comparison(result["rows"], caption=_caption(result))
    output.json("compare.json", result)
    output.csv("compare.csv", result["rows"], [c for c in CSV_COLUMNS if c in present])
    output.figure("compare.png", fig)


def _ranges(numbers: list[int]) -> str:
    """``[1, 2, 3, 5]`` -> ``"1-3, 5"``."""
    runs = itertools.groupby(enumerate(sorted(set(numbers))), lambda p: p[1] - p[0])
    spans = [[n for _, n in run] for _, run in runs]
    return ", ".join(f"{s[0]}" if len(s) == 1 else f"{s[0]}-{s[-1]}" for s in spans)


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
            "sigma_max": "the largest pulsation amplitude searched, as convergence --sigma-max",
        }.get(k, "the paper's case")
        print(f"not given in row {_ranges(where)}: {k} = {val:.6g} ({why})")
    s = result["summary"]
    print(
        f"{s['agree']} agree within fempipe's error estimate, {s['differ']} differ by more than "
        f"it, {s['no_estimate']} without an estimate, {s['failed']} failed"
    )

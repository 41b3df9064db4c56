"""``fempipe validate``: run the validation suite (:mod:`fempipe.validation`) and write the report.

The cases and what each checks: docs/verification.md.
"""

from __future__ import annotations

import argparse
import os
import sys

from fempipe.cli import common, parsing, reporting

EXAMPLES = (
    "fempipe validate --quick                   # into fempipe-out/validate",
    "fempipe validate --out validation/report --workers 2   # regenerate the committed report",
    "fempipe validate --case fig02b --case symmetry --json",
)

#: Default ``--out``, ignored by git; the committed report is rewritten only when asked for.
DEFAULT_OUT = os.path.join("fempipe-out", "validate")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--quick",
        action="store_true",
        help="the quick suite (coarser sweeps and meshes; about 2.5 min on 2 cores)",
    )
    common.add_workers_argument(
        parser, "worker processes (default: the number of CPUs, at most 4)", default=None
    )
    parser.add_argument(
        "--case",
        metavar="NAME",
        action="append",
        default=None,
        help="run only this case (repeatable, or comma-separated); see --list",
    )
    parser.add_argument("--list", action="store_true", help="list the cases and exit")
    common.add_output_arguments(
        parser,
        out_help=f"write REPORT.md, results.json and the PNG figures into DIR "
        f"(default {DEFAULT_OUT})",
    )


def run(args: argparse.Namespace) -> int:
    from fempipe.validation import CASES

    if args.list:
        for name in CASES:
            print(name)
        return 0
    workers = args.workers or max(1, min(os.cpu_count() or 1, 4))
    cases = parsing.parse_names("--case", args.case, list(CASES), "case")
    out = args.out or DEFAULT_OUT
    reporting.check_out_dir(out)

    reporting.agg()
    from fempipe.validation.report import write_report
    from fempipe.validation.suite import run_suite

    n_cases = len(cases) if cases else len(CASES)
    with reporting.progress(args, n_cases, "validate") as bar:

        def done(outcome) -> None:
            bar.update()
            bar.set_postfix_str(f"{outcome.name}: {outcome.status}")

        suite = run_suite(quick=args.quick, out=out, workers=workers, cases=cases, callback=done)
    path = write_report(suite, out)
    summary = suite.to_dict()
    cases = [
        {"name": o.name, "status": o.status, "numerics_passed": o.ok, "runtime": o.wall_time}
        for o in suite.outcomes
    ]
    result = {k: v for k, v in summary.items() if k != "cases"} | {"report": str(path)}

    def say() -> None:
        if args.progress is not False:
            n, p = summary["numerics_checks"], summary["paper_checks"]
            print(
                f"fempipe validate: {'PASS' if suite.ok else 'FAIL'}: numerics "
                f"{n['passed']}/{n['total']}, paper statements {p['passed']}/{p['total']}, "
                f"{suite.wall_time:.1f} s; report {path}",
                file=sys.stderr,
            )

    reporting.deliver(args, result | {"cases": cases}, text=say)
    return 0 if suite.ok else 1

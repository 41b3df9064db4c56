"""``fempipe bench``: the performance benchmarks of :mod:`fempipe.bench` (``--only``, ``--list``,
``--quick`` for a smoke run); ``--out DIR`` writes bench.json.
"""

from __future__ import annotations

import argparse

from fempipe.cli import common, parsing, reporting

EXAMPLES = ("fempipe bench --list", "fempipe bench --only startup,hopf --json")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--only",
        metavar="NAME",
        action="append",
        default=None,
        help="run only these benchmarks (repeat or comma-separate); see --list",
    )
    parser.add_argument("--list", action="store_true", help="list the benchmarks and exit")
    parser.add_argument(
        "--quick", action="store_true", help="small problems, one repetition (smoke run)"
    )
    common.add_output_arguments(parser)


def run(args: argparse.Namespace) -> int:
    from fempipe import bench

    table = bench.available()
    if args.list:
        for name, fn in table.items():
            doc = (fn.__doc__ or "").strip().splitlines()
            print(f"{name:20s} {doc[0] if doc else ''}")
        return 0
    names = parsing.parse_names("--only", args.only, sorted(table), "benchmark")
    n = len(names) if names else len(table)
    with reporting.progress(args, n, "bench") as bar:
        result = bench.run(names, quick=args.quick, callback=lambda name, res: bar.update())
    reporting.deliver(
        args,
        result,
        write=lambda out: out.json("bench.json", result),
        text=lambda: print_results(result),
    )
    return 0


def _fmt(x) -> str:
    if isinstance(x, float):
        return f"{x:.4g}"
    return str(x)


def _print_value(key: str, value, indent: str) -> None:
    """``key: value``; a dict one line per entry below it, a list of numbers formatted."""
    if isinstance(value, dict):
        print(f"{indent}{key}:")
        for k, v in value.items():
            _print_value(str(k), v, indent + "  ")
    elif isinstance(value, (list, tuple)):
        print(f"{indent}{key}: {', '.join(_fmt(x) for x in value)}")
    else:
        print(f"{indent}{key}: {_fmt(value)}")


def print_results(result: dict) -> None:
    """Print a ``fempipe bench`` result: the environment, each benchmark's values and table."""
    env = result["environment"]
    print("environment: " + ", ".join(f"{k} {v}" for k, v in env.items()))
    if result["quick"]:
        print("(quick run: small problems, not a measurement)")
    for name, res in result["benchmarks"].items():
        print(f"\n== {name} ==")
        for k, v in res.items():
            if k != "table":
                _print_value(k, v, "  ")
        rows = res.get("table")
        if rows:
            cols = list(dict.fromkeys(k for r in rows for k in r))
            columns = [(c, lambda r, c=c: _fmt(r.get(c, ""))) for c in cols]
            reporting.print_table(columns, rows, indent="  ")

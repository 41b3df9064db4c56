"""Compare two validation results, leaf by leaf: did a change keep every number?

    python validation/compare_results.py BEFORE.json AFTER.json [--rtol 1e-9] [--json]

BEFORE and AFTER are ``results.json`` files written by ``fempipe validate --out DIR``.
Cases are paired by name, checks by name, table rows by position; every other leaf by its
path.  A number differs when |a - b| > rtol max(|a|, |b|) + atol; a string, a boolean or a
verdict (``passed``) differs when it is not equal.  Leaves that measure the machine, not the
model (wall and CPU times, the start time, the environment, the worker count) are skipped.
Prints each difference with its path, then a summary; exit 0 when nothing differs, 1 when
something does, 2 for unreadable input.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Iterator
from pathlib import Path

#: keys whose values depend on the machine or the run, never on the model
VOLATILE = frozenset(
    {"wall_time", "runtime", "started", "environment", "workers", "cpu_time", "cpu_seconds"}
)


def _keyed(items: list) -> dict | None:
    """A list of cases or checks as a dict by name (None if it is not one)."""
    if items and all(isinstance(x, dict) and isinstance(x.get("name"), str) for x in items):
        names = [x["name"] for x in items]
        if len(set(names)) == len(names):
            return {x["name"]: x for x in items}
    return None


def leaves(node, path: str = "") -> Iterator[tuple[str, object]]:
    """(path, value) for every leaf; lists of named items are keyed by name."""
    if isinstance(node, dict):
        for key, value in node.items():
            if key not in VOLATILE:
                yield from leaves(value, f"{path}/{key}")
    elif isinstance(node, list):
        keyed = _keyed(node)
        if keyed is not None:
            for name, value in keyed.items():
                yield from leaves(value, f"{path}[{name}]")
        else:
            for k, value in enumerate(node):
                yield from leaves(value, f"{path}[{k}]")
    else:
        yield path, node


def differs(a, b, rtol: float, atol: float) -> bool:
    numbers = (int, float)
    if (
        isinstance(a, bool)
        or isinstance(b, bool)
        or not (isinstance(a, numbers) and isinstance(b, numbers))
    ):
        return a != b
    if math.isnan(a) or math.isnan(b):
        return not (math.isnan(a) and math.isnan(b))
    if math.isinf(a) or math.isinf(b):
        return a != b
    return abs(a - b) > rtol * max(abs(a), abs(b)) + atol


def compare(before: dict, after: dict, rtol: float = 1e-9, atol: float = 0.0) -> dict:
    """The differences of two results: ``changed``, ``missing`` (only before), ``added``."""
    a, b = dict(leaves(before)), dict(leaves(after))
    changed = [
        {"path": p, "before": a[p], "after": b[p]}
        for p in a
        if p in b and differs(a[p], b[p], rtol, atol)
    ]
    return {
        "compared": sum(p in b for p in a),
        "changed": changed,
        "missing": [p for p in a if p not in b],
        "added": [p for p in b if p not in a],
        "verdict_flips": [c for c in changed if c["path"].endswith("/passed")],
    }


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("before", type=Path)
    parser.add_argument("after", type=Path)
    parser.add_argument("--rtol", type=float, default=1e-9, help="relative tolerance (1e-9)")
    parser.add_argument("--atol", type=float, default=0.0, help="absolute tolerance (0)")
    parser.add_argument("--json", action="store_true", help="the differences as JSON")
    args = parser.parse_args(argv)
    try:
        before, after = (
            json.loads(p.read_text(encoding="utf-8")) for p in (args.before, args.after)
        )
    except (OSError, ValueError) as exc:
        print(f"compare_results: error: {exc}", file=sys.stderr)
        return 2
    diff = compare(before, after, args.rtol, args.atol)
    if args.json:
        print(json.dumps(diff, indent=1, default=str))
    else:
        for c in diff["changed"]:
            print(f"changed {c['path']}: {c['before']!r} -> {c['after']!r}")
        for p in diff["missing"]:
            print(f"missing {p}")
        for p in diff["added"]:
            print(f"added   {p}")
        print(
            f"{diff['compared']} leaves compared (rtol {args.rtol:g}, atol {args.atol:g}): "
            f"{len(diff['changed'])} changed ({len(diff['verdict_flips'])} verdicts flipped), "
            f"{len(diff['missing'])} missing, {len(diff['added'])} added"
        )
    return 1 if diff["changed"] or diff["missing"] or diff["added"] else 0


if __name__ == "__main__":
    sys.exit(main())

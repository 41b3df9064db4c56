"""Side by side: the check values and table rows of two validation runs.

``python -m fempipe.validation.compare_results OLD/results.json NEW/results.json [case ...]``
prints, per case, the wall time of both runs and every check whose outcome or
measured value differs (marked ``!!``), then the table rows that differ; a
check present in one run only is shown with ``None`` on the other side.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path


def load(path: str | Path) -> dict:
    """``{case: (wall_time, {check name: check dict}, tables)}`` of a results.json."""
    r = json.loads(Path(path).read_text())
    out = {}
    for c in r["cases"]:
        res = c.get("result") or {}
        checks = {k["name"]: k for k in res.get("checks", [])}
        out[c["name"]] = (c["wall_time"], checks, res.get("tables", []))
    return out


def compare(old: dict, new: dict, only=(), changed_only: bool = True) -> list[str]:
    """Lines of the comparison (see the module docstring)."""
    lines = []
    for name in new:
        if only and name not in only:
            continue
        ta, ca, tba = old.get(name, (float("nan"), {}, []))
        tb, cb, tbb = new[name]
        lines.append(f"== {name}: wall {ta:.1f} s -> {tb:.1f} s")
        for k in sorted(set(ca) | set(cb)):
            x, y = ca.get(k), cb.get(k)
            mx = (x["passed"], x["measured"]) if x else None
            my = (y["passed"], y["measured"]) if y else None
            if mx == my and changed_only:
                continue
            lines.append(f"{'  ' if mx == my else '!!'} {k}\n     old {mx}\n     new {my}")
        for t1, t2 in zip(tba, tbb, strict=False):
            for r1, r2 in zip(t1["rows"], t2["rows"], strict=False):
                if r1 != r2:
                    lines.append(f"   table '{t1['title']}'\n     old {r1}\n     new {r2}")
    return lines


def main(argv=None) -> int:
    """Command line entry (see the module docstring)."""
    argv = sys.argv[1:] if argv is None else argv
    if len(argv) < 2:
        sys.stderr.write(__doc__)
        return 2
    for line in compare(load(argv[0]), load(argv[1]), argv[2:]):
        sys.stdout.write(line + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

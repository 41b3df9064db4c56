"""Benchmark ``simulate_output``: what writing the files of ``fempipe simulate`` costs beside
its computation (fresh processes with and without ``--out DIR``).
"""

from __future__ import annotations

import shutil
import statistics
import tempfile

from fempipe.bench.harness import child_cpu_seconds, register

#: Largest accepted ratio of the CPU seconds of ``simulate --out`` to those of
#: the same run without ``--out``.
OUTPUT_RATIO_TARGET = 3.0

#: The command (after ``python -m fempipe``): the paper's case at alpha = 0, v = 10.
SIMULATE = ("simulate", "--alpha", "0", "--v", "10", "--planar", "--json")


@register("simulate_output")
def bench_simulate_output(quick: bool = False) -> dict:
    """CPU seconds of ``fempipe simulate --alpha 0 --v 10`` with and without --out, alternating
    after one untimed run each; median of 5 pairs (quick: 1).  ``ratio`` is the median of the
    pairs' ratios, ``files_seconds`` the difference of the medians.
    """
    runs = 1 if quick else 5
    env = {"MPLBACKEND": "Agg"}
    argv = ["-m", "fempipe", *SIMULATE]

    def with_out() -> float:
        out = tempfile.mkdtemp(prefix="fempipe-bench-out-")
        try:
            return child_cpu_seconds([*argv, "--out", out], env=env)[0]
        finally:
            shutil.rmtree(out, ignore_errors=True)

    child_cpu_seconds(argv, env=env)
    with_out()
    plain, files = [], []
    for _ in range(runs):
        plain.append(child_cpu_seconds(argv, env=env)[0])
        files.append(with_out())
    ratios = [b / a for a, b in zip(plain, files, strict=True)]
    ratio = statistics.median(ratios)
    command = "simulate --alpha 0 --v 10 --planar"
    return {
        "runs": runs,
        "target_ratio": OUTPUT_RATIO_TARGET,
        "ratio": round(ratio, 3),
        "meets_target": ratio <= OUTPUT_RATIO_TARGET,
        "files_seconds": round(statistics.median(files) - statistics.median(plain), 3),
        "table": [
            {
                "command": command,
                "cpu_seconds": round(statistics.median(plain), 3),
                "min": round(min(plain), 3),
                "max": round(max(plain), 3),
            },
            {
                "command": command + " --out DIR",
                "cpu_seconds": round(statistics.median(files), 3),
                "min": round(min(files), 3),
                "max": round(max(files), 3),
            },
        ],
    }

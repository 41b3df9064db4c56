"""The benchmark ``simulate_output`` (registered with :mod:`fempipe.bench`): what writing the
files of ``fempipe simulate`` costs beside its computation.

``fempipe simulate --alpha 0 --v 10 --planar`` (the paper's case, P3:16) finds the limit cycle
and prints its JSON (``--planar``: without the out-of-plane Floquet multipliers, whose 3-D
monodromy would make the files look cheaper than they are); with ``--out DIR`` it also writes
three figures, the animation pipe.gif, trajectory.pvd with its VTU frames, tip.csv and
simulate.json.  The benchmark runs both commands as the user does, each in a fresh
``python -m fempipe`` process, and reports their CPU seconds and the ratio; the target is
that the files cost at most twice the computation (the ratio at most
:data:`OUTPUT_RATIO_TARGET`).  Most of
what the files cost is matplotlib's: importing it, the PNG figures (half of it their
constrained layout), the GIF (half of it the time label's mathtext, parsed anew for every
frame); the VTU frames are a small part.
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
    """CPU seconds of ``fempipe simulate --alpha 0 --v 10`` with and without --out.

    Target: the ratio at most :data:`OUTPUT_RATIO_TARGET`.

    Each run is a new ``python -m fempipe`` process (``sys.executable``,
    ``MPLBACKEND=Agg``); its CPU time is user + system of the finished
    process (``getrusage(RUSAGE_CHILDREN)``: what ``time.process_time()``
    counts inside it, start-up included).  The two commands alternate, after
    one untimed run of each (the bytecode cache, the font cache), so that a
    drift of the machine's speed hits both; median of 5 pairs (quick: 1).
    ``ratio`` is the median of the pairs' ratios, ``files_seconds`` the
    difference of the medians.  Every ``--out`` run writes into a new
    temporary directory, removed afterwards.
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

"""The start-up benchmark ``startup`` (registered with :mod:`fempipe.bench`): CPU seconds of
``import fempipe`` and of the start of the ``fempipe`` command, in fresh processes."""

from __future__ import annotations

import numpy as np

from fempipe.bench.harness import child_cpu_seconds, register

#: CPU seconds (user + sys) allowed for ``import fempipe`` and the start of the
#: ``fempipe`` command (``--help``, and the imports before a computation).
STARTUP_TARGET = 0.4

#: (label, argument list after the interpreter, whether the target applies):
#: numpy and scipy.linalg are the floors (what a computation pays anyway).
_STARTUP_COMMANDS: tuple[tuple[str, list[str], bool], ...] = (
    ("import numpy", ["-c", "import numpy"], False),
    ("import scipy.linalg", ["-c", "import scipy.linalg"], False),
    ("import fempipe", ["-c", "import fempipe"], True),
    ("fempipe --help", ["-m", "fempipe", "--help"], True),
    ("fempipe critical --help", ["-m", "fempipe", "critical", "--help"], True),
)


@register("startup")
def bench_startup(quick: bool = False) -> dict:
    """CPU seconds of ``import fempipe`` and ``fempipe --help`` in fresh processes, median of 5
    (quick: 1), against ``import numpy`` and ``import scipy.linalg``; :data:`STARTUP_TARGET`."""
    runs = 1 if quick else 5
    rows = []
    for label, argv, targeted in _STARTUP_COMMANDS:
        child_cpu_seconds(argv)  # fills the bytecode cache
        times = [child_cpu_seconds(argv)[0] for _ in range(runs)]
        median = float(np.median(times))
        row = {"command": label, "cpu_seconds": round(median, 3), "min": round(min(times), 3)}
        if targeted:
            row["target_seconds"] = STARTUP_TARGET
            row["meets_target"] = median < STARTUP_TARGET
        rows.append(row)
    return {"runs": runs, "target_seconds": STARTUP_TARGET, "table": rows}

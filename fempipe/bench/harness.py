"""What the benchmarks share: :func:`register`, the timers :func:`best_time`, :func:`in_turns`
(in process), :func:`child_cpu_seconds` and :func:`child_json` (a fresh ``python``), and the
cases :data:`PAPER` and :data:`TEXIER_DORBOLO`.
"""

from __future__ import annotations

import atexit
import json
import math
import os
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable

from fempipe.model.params import PAPER_CASE

__all__ = [
    "BENCHMARKS",
    "PAPER",
    "TEXIER_DORBOLO",
    "best_time",
    "child_cpu_seconds",
    "child_json",
    "in_turns",
    "register",
]

#: name -> benchmark function ``fn(quick=False) -> dict``.
BENCHMARKS: dict[str, Callable[..., dict]] = {}

#: The paper's reference case (:data:`fempipe.model.params.PAPER_CASE`) at alpha = pi/2.
PAPER = {"alpha": math.pi / 2, **PAPER_CASE}
#: Texier & Dorbolo's pipe (paper Section 3.1, Fig. 2b): SI values.
TEXIER_DORBOLO = {"L": 0.094, "EI": 1.8e-5, "m": 0.0159, "M": 0.0058, "g": 9.8}


def register(name: str) -> Callable[[Callable[..., dict]], Callable[..., dict]]:
    """Decorator: register ``fn(quick=False) -> dict`` as benchmark ``name``."""

    def deco(fn: Callable[..., dict]) -> Callable[..., dict]:
        if name in BENCHMARKS and BENCHMARKS[name] is not fn:
            raise ValueError(f"benchmark {name!r} is already registered")
        BENCHMARKS[name] = fn
        return fn

    return deco


def best_time(fn: Callable[[], object], repeats: int = 1, clock=time.perf_counter, stat=min):
    """``stat`` (min: the least disturbed run) of the ``clock`` seconds of ``repeats`` calls, and the last result."""
    times, result = [], None
    for _ in range(repeats):
        t0 = clock()
        result = fn()
        times.append(clock() - t0)
    return stat(times), result


def in_turns(fns: list[Callable], repeats: int, clock=time.process_time) -> tuple[list, list]:
    """The ``clock`` seconds of ``fns`` called in turns ``repeats`` times (per function, by round)
    and their last results; each function gets the previous one's result (None for the first)."""
    times: list[list[float]] = [[] for _ in fns]
    results: list = [None] * len(fns)
    for _ in range(repeats):
        prev = None
        for i, fn in enumerate(fns):
            t0 = clock()
            prev = results[i] = fn(prev)
            times[i].append(clock() - t0)
    return times, results


_BYTECODE_CACHE: str | None = None


def child_cpu_seconds(argv: list[str], env: dict | None = None) -> tuple[float, str]:
    """User + system CPU seconds and stdout of one fresh ``python ARGV`` (``env``: changes,
    None removes).  One shared bytecode cache, so fempipe loads bytecode as numpy and scipy do."""
    global _BYTECODE_CACHE
    if _BYTECODE_CACHE is None:
        _BYTECODE_CACHE = tempfile.mkdtemp(prefix="fempipe-bench-pycache-")
        atexit.register(shutil.rmtree, _BYTECODE_CACHE, True)
    child_env = dict(os.environ)
    child_env.pop("PYTHONDONTWRITEBYTECODE", None)
    child_env["PYTHONPYCACHEPREFIX"] = _BYTECODE_CACHE
    for name, value in (env or {}).items():
        if value is None:
            child_env.pop(name, None)
        else:
            child_env[name] = value
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    res = subprocess.run([sys.executable, *argv], capture_output=True, text=True, env=child_env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode != 0:
        raise RuntimeError(f"python {' '.join(argv)} failed: {res.stderr.strip()[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, res.stdout


def child_json(argv: list[str], env: dict | None = None) -> tuple[float, dict]:
    """:func:`child_cpu_seconds` of ``python ARGV`` with its stdout parsed as JSON."""
    cpu, out = child_cpu_seconds(argv, env)
    return cpu, json.loads(out)

"""Performance benchmarks (timings, never unit tests).

A benchmark is a function ``fn(quick: bool = False) -> dict`` registered under a name in
:data:`BENCHMARKS` with :func:`register` (``@register("my_solver")``), in a module listed in
:data:`BENCHMARK_MODULES` so that :func:`available` imports it; ``fempipe bench`` runs them all
or ``--only NAME``.  A result dict may carry a ``"table"`` (list of flat dicts), which the CLI
prints as a table; everything else is printed as ``key: value``.

The benchmarks, one module per subject: :mod:`~fempipe.bench.static`,
:mod:`~fempipe.bench.critical`, :mod:`~fempipe.bench.convergence`,
:mod:`~fempipe.bench.startup`, :mod:`~fempipe.bench.dynamics`,
:mod:`~fempipe.bench.stability`, :mod:`~fempipe.bench.bifurcation`,
:mod:`~fempipe.bench.hopf`, :mod:`~fempipe.bench.output` and :mod:`~fempipe.bench.space`.
This module is the registry and the runner, with the helpers the benchmarks share
(:func:`best_time`, :func:`child_cpu_seconds`) and the cases they share (:data:`PAPER`,
:data:`TEXIER_DORBOLO`).  What each measures: docs/cli/commands.md, "fempipe bench".
"""

from __future__ import annotations

import importlib
import logging
import math
import os
import platform
import time
from collections.abc import Callable

import numpy as np

from fempipe.model.params import PAPER_CASE

__all__ = [
    "BENCHMARKS",
    "BENCHMARK_MODULES",
    "PAPER",
    "TEXIER_DORBOLO",
    "available",
    "best_time",
    "child_cpu_seconds",
    "register",
    "run",
]

log = logging.getLogger(__name__)

#: name -> benchmark function ``fn(quick=False) -> dict``.
BENCHMARKS: dict[str, Callable[..., dict]] = {}

#: Modules imported by :func:`available` so that their ``@register`` runs.
BENCHMARK_MODULES: tuple[str, ...] = (
    "fempipe.bench.static",
    "fempipe.bench.critical",
    "fempipe.bench.convergence",
    "fempipe.bench.startup",
    "fempipe.bench.dynamics",
    "fempipe.bench.stability",
    "fempipe.bench.bifurcation",
    "fempipe.bench.hopf",
    "fempipe.bench.output",
    "fempipe.bench.space",
)

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


def available() -> dict[str, Callable[..., dict]]:
    """All registered benchmarks, after importing :data:`BENCHMARK_MODULES`."""
    for mod in BENCHMARK_MODULES:
        importlib.import_module(mod)
    return dict(BENCHMARKS)


def environment() -> dict:
    """Where the numbers were measured."""
    import scipy

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "machine": platform.machine(),
        "cpu_count": os.cpu_count(),
    }


def run(
    names: list[str] | None = None,
    quick: bool = False,
    callback: Callable[[str, dict], None] | None = None,
) -> dict:
    """Run benchmarks by name (all if None).

    Parameters
    ----------
    names : list of str, optional
    quick : bool
        Smaller problems and one repetition (a smoke run, not a measurement).
    callback : callable, optional
        Called as ``callback(name, result)`` after each benchmark.

    Returns
    -------
    dict
        ``{"environment": ..., "quick": quick, "benchmarks": {name: result}}``.

    Raises
    ------
    ValueError
        For an unknown name (naming the known ones).
    """
    table = available()
    names = list(table) if not names else list(names)
    unknown = [n for n in names if n not in table]
    if unknown:
        raise ValueError(f"unknown benchmark {unknown[0]!r}; known: {', '.join(sorted(table))}")
    out = {"environment": environment(), "quick": quick, "benchmarks": {}}
    for name in names:
        log.info("benchmark %s", name)
        res = table[name](quick=quick)
        out["benchmarks"][name] = res
        if callback:
            callback(name, res)
    return out


def best_time(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Minimum wall time of ``repeats`` calls (the least disturbed run) and the last result."""
    best, result = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


_BYTECODE_CACHE: str | None = None


def child_cpu_seconds(argv: list[str], env: dict | None = None) -> tuple[float, str]:
    """User + system CPU seconds and stdout of one fresh ``python ARGV`` (``sys.executable``).

    ``env`` changes the child's environment: ``{name: value}``, a value of
    None removes the variable.

    The CPU time is the change of ``getrusage(RUSAGE_CHILDREN)`` over the run.
    All children of a benchmark run share one bytecode cache
    (``PYTHONPYCACHEPREFIX``, a temporary directory removed at exit): an installed
    package loads its modules from compiled bytecode, and with
    PYTHONDONTWRITEBYTECODE set (as some harnesses do) fempipe's modules would
    otherwise be compiled from source at every start while numpy's and scipy's
    load their installed .pyc files.  The first run of a command fills the cache;
    benchmarks make one untimed run first.

    Raises
    ------
    RuntimeError
        If the process fails, with the end of its stderr.
    """
    import atexit
    import resource
    import shutil
    import subprocess
    import sys
    import tempfile

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

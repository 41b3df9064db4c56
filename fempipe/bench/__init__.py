"""Performance benchmarks (timings, never unit tests): the registry and the runner.

A benchmark is ``fn(quick: bool = False) -> dict``, registered with
:func:`fempipe.bench.harness.register` in a module of :data:`BENCHMARK_MODULES`.  What each
measures: docs/cli/commands.md, "fempipe bench".
"""

from __future__ import annotations

import importlib
import logging
import os
import platform
from collections.abc import Callable

import numpy as np
import scipy

from fempipe.bench.harness import BENCHMARKS

__all__ = ["BENCHMARK_MODULES", "available", "environment", "run"]

log = logging.getLogger(__name__)

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
    "fempipe.bench.three_d",
    "fempipe.bench.parametric",
)


def available() -> dict[str, Callable[..., dict]]:
    """All registered benchmarks, after importing :data:`BENCHMARK_MODULES`."""
    for mod in BENCHMARK_MODULES:
        importlib.import_module(mod)
    return dict(BENCHMARKS)


def environment() -> dict:
    """Where the numbers were measured."""
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
    """Run benchmarks by name (all if None), ``quick`` a smoke run, ``callback(name, result)``
    after each; ``{"environment": ..., "quick": quick, "benchmarks": {name: result}}``."""
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

"""Performance benchmarks (timings, never unit tests).

A benchmark is a function ``fn(quick: bool = False) -> dict`` registered under a name with
:func:`fempipe.bench.harness.register` (``@register("my_solver")``), in a module listed in
:data:`BENCHMARK_MODULES` so that :func:`available` imports it; ``fempipe bench`` runs them all
or ``--only NAME``.  A result dict may carry a ``"table"`` (list of flat dicts), which the CLI
prints as a table; everything else is printed as ``key: value``.

The benchmarks, one module per subject: :mod:`~fempipe.bench.static`,
:mod:`~fempipe.bench.critical`, :mod:`~fempipe.bench.convergence`,
:mod:`~fempipe.bench.startup`, :mod:`~fempipe.bench.dynamics`,
:mod:`~fempipe.bench.stability`, :mod:`~fempipe.bench.bifurcation`,
:mod:`~fempipe.bench.hopf`, :mod:`~fempipe.bench.output`, :mod:`~fempipe.bench.space` and
:mod:`~fempipe.bench.parametric`;
what they share (the registration, the timers, the cases) is :mod:`~fempipe.bench.harness`.
This module is the registry of the modules and the runner.  What each measures:
docs/cli/commands.md, "fempipe bench".
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
    "fempipe.bench.space",
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

"""The validation suite: the paper's figures by FE and modal Galerkin, side by side.

One importable case per figure of Chen, Hu, Dai & Wang (2020).  Each case
module defines ``CASE``, ``FIGURE``, ``TITLE``, ``PAPER_SHOWS``,
``run(quick=False) -> CaseResult`` (the data and the checks) and
``plot(result, fig=None) -> Figure`` (the figure drawn as the paper does,
with the mesh-converged FE result and modal N = 3 and N = 4 overlaid).
Reference numbers sit beside the cases in ``references/<case>.json``, each
with its source.

>>> from fempipe.validation import load_case
>>> res = load_case("fig02b").run(quick=True)      # doctest: +SKIP
>>> [c.name for c in res.checks if not c.passed]   # doctest: +SKIP

:func:`fempipe.validation.suite.run_suite` runs them all (in parallel) and
writes the Markdown report; ``fempipe validate`` is its command line.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from .checks import CaseResult, Check, Table

__all__ = ["CASES", "CaseResult", "Check", "Table", "available_cases", "load_case"]

#: Case modules in the paper's order, with what each needs beyond the core.
CASES: dict[str, tuple[str, ...]] = {
    "fig02a": (),
    "fig02b": (),
    "fig03": (),
    "fig04": (),
    "fig05": ("fempipe.stability",),
    "fig06": (),  # its own onset; compared with fempipe.stability where present
    "fig07": ("fempipe.dynamics", "fempipe.limit_cycle", "fempipe.bifurcation"),
    "fig08_10": ("fempipe.dynamics", "fempipe.limit_cycle", "fempipe.bifurcation"),
    "fig11": ("fempipe.dynamics", "fempipe.limit_cycle"),
    "fig12": ("fempipe.dynamics", "fempipe.limit_cycle"),
    "symmetry": (),
    "convergence": (),
}


def load_case(name: str) -> ModuleType:
    """Import the case module ``fempipe.validation.<name>``."""
    if name not in CASES:
        raise ValueError(f"unknown validation case {name!r}; choose from {', '.join(CASES)}")
    return importlib.import_module(f"{__name__}.{name}")


def missing_dependencies(name: str) -> list[str]:
    """The fempipe modules a case needs that are not importable (yet)."""
    missing = []
    for mod in CASES[name]:
        try:
            importlib.import_module(mod)
        except ModuleNotFoundError as exc:
            if exc.name != mod:
                raise
            missing.append(mod)
    return missing


def available_cases() -> list[str]:
    """Cases whose dependencies are all importable."""
    return [name for name in CASES if not missing_dependencies(name)]

"""The validation suite: the paper's figures by FE and modal Galerkin, side by side.

One case module per figure of Chen, Hu, Dai & Wang (2020) or per variant of the pipe.  Each
declares ``CASE`` (:class:`~fempipe.validation.case.Case`) and defines ``run(quick=False) ->
CaseResult`` and ``plot(result, fig=None) -> Figure``; ``references/<case>.json`` holds its
reference numbers with their sources, its caption and its check specs.
:func:`fempipe.validation.suite.run_suite` runs them all (``fempipe validate``).
Docs: docs/verification.md.

>>> from fempipe.validation import load_case
>>> res = load_case("fig02b").run(quick=True)      # doctest: +SKIP
"""

from __future__ import annotations

import importlib
from types import ModuleType

from .case import Case, References, load_references
from .checks import CaseResult, Check, Table

__all__ = ["CASES", "Case", "CaseResult", "Check", "References", "Table"]
__all__ += ["load_case", "load_references"]

#: Case modules in the paper's order, then the variants of the pipe.
CASES: tuple[str, ...] = (
    *(
        "fig02a",
        "fig02b",
        "fig03",
        "fig04",
        "fig05",
        "fig06",
        "fig07",
        "fig08_10",
        "fig11",
        "fig12",
    ),
    *("symmetry", "convergence"),
    # variants of the straight pipe against the classical theory (classical.py)
    *("end_mass", "external_damping", "hysteretic", "springs"),
    # the motion out of the plane against a strong form (lateral.py)
    "out_of_plane",
    # the 3-D model: Hopf onset, mesh convergence, whirl against a rotating-frame BVP
    *("space_onset", "space_convergence", "space_whirl"),
    # pulsating flow: parametric resonance against a classical Floquet solver
    "parametric",
)


def load_case(name: str) -> ModuleType:
    """Import the case module ``fempipe.validation.<name>`` (an import error propagates)."""
    if name not in CASES:
        raise ValueError(f"unknown validation case {name!r}; choose from {', '.join(CASES)}")
    return importlib.import_module(f"{__name__}.{name}")

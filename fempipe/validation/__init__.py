"""The validation suite: the paper's figures by FE and modal Galerkin, side by side.

One importable case per figure of Chen, Hu, Dai & Wang (2020).  Each case module declares
``CASE``, a :class:`~fempipe.validation.case.Case` (name, figure, title, what the paper shows),
and defines ``run(quick=False) -> CaseResult`` (the data and the measurements, judged by
:mod:`fempipe.validation.evaluate`) and ``plot(result, fig=None) -> Figure`` (the figure drawn
as the paper does, with the mesh-converged FE result and modal N = 3 and N = 4 overlaid).
``references/<case>.json`` holds a case's reference numbers with their sources, its caption
and the specs of its checks (claim, limit or reference, tolerance, why, source).

>>> from fempipe.validation import load_case
>>> res = load_case("fig02b").run(quick=True)      # doctest: +SKIP
>>> [c.name for c in res.checks if not c.passed]   # doctest: +SKIP

:func:`fempipe.validation.suite.run_suite` runs them all (in parallel) and writes the Markdown
report; ``fempipe validate`` is its command line.  Every case needs every part of fempipe: a
module that fails to import fails the case loudly.  The folder ``validation/`` at the top of
the repository (not installed) holds what is made from the suite: docs/verification.md.
"""

from __future__ import annotations

import importlib
from types import ModuleType

from .case import Case, References, load_references
from .checks import CaseResult, Check, Table

__all__ = [
    "CASES",
    "Case",
    "CaseResult",
    "Check",
    "References",
    "Table",
    "load_case",
    "load_references",
]

#: Case modules in the paper's order, then the variants of the pipe.
CASES: tuple[str, ...] = (
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
    "symmetry",
    "convergence",
    # The classical variants of the straight pipe against the classical
    # linear theory (fempipe.validation.classical) and the literature.
    "end_mass",
    "external_damping",
    "hysteretic",
    "springs",
    # The motion out of the plane (fempipe.model.out_of_plane) against an
    # independent strong form (fempipe.validation.lateral).
    "out_of_plane",
    # The pipe in three dimensions (fempipe.model.space): the non-planar oscillation's
    # onset against its Hopf normal form, its mesh convergence, and the hanging pipe's
    # whirl against a rotating-frame BVP (fempipe.validation.whirl_bvp).
    "space_onset",
    "space_convergence",
    "space_whirl",
)


def load_case(name: str) -> ModuleType:
    """Import the case module ``fempipe.validation.<name>`` (an import error propagates)."""
    if name not in CASES:
        raise ValueError(f"unknown validation case {name!r}; choose from {', '.join(CASES)}")
    return importlib.import_module(f"{__name__}.{name}")

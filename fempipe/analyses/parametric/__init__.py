"""Parametric resonance of the pipe under a pulsating flow v(tau) = v0 (1 + sigma sin(omega tau)).

The Floquet multipliers of the motions about the straight state (:mod:`.floquet`), the chart
of its regions (:mod:`.chart`), and the periodic response of a bent pipe with its multipliers
(:mod:`.forced`), the period-doubled orbit inside a principal region (:mod:`.response`);
the derivation: docs/theory/parametric.md.
"""

from __future__ import annotations

from .chart import ParametricChart, compute_parametric_chart
from .floquet import PulsationPencil, ReducedPulsation, floquet_multipliers
from .forced import ForcedResponse, solve_forced_response
from .regions import Candidate, ParametricRegion, candidates, locate_region
from .response import (
    SubharmonicBranch,
    SubharmonicOrbit,
    continue_subharmonic,
    continue_subharmonic_in_sigma,
    locate_principal_region,
)

__all__ = [
    "Candidate",
    "ForcedResponse",
    "ParametricChart",
    "ParametricRegion",
    "PulsationPencil",
    "SubharmonicBranch",
    "SubharmonicOrbit",
    "ReducedPulsation",
    "candidates",
    "floquet_multipliers",
    "solve_forced_response",
    "locate_region",
    "compute_parametric_chart",
    "continue_subharmonic",
    "continue_subharmonic_in_sigma",
    "locate_principal_region",
]

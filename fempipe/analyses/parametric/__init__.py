"""Parametric resonance of the pipe under a pulsating flow v(tau) = v0 (1 + sigma sin(omega tau)).

The Floquet multipliers of the motions about the straight state (:mod:`.floquet`); the
derivation: docs/theory/parametric.md.
"""

from __future__ import annotations

from .floquet import PulsationPencil, ReducedPulsation, floquet_multipliers

__all__ = ["PulsationPencil", "ReducedPulsation", "floquet_multipliers"]

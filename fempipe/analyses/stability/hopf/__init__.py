"""Hopf criticality of the flutter events: the first Lyapunov coefficient l1.

A flutter event is a Hopf bifurcation of the static state; the sign of l1 decides whether
the orbit born there is stable (l1 < 0) or not, and with Re lambda'(v) it predicts the
cycles' amplitudes ``(max - min)/2 ~ c sqrt(|v - v_cr|)``.  ``lyapunov``: l1 of a generic
x' = F(x); ``pipe``: the pipe's D_x F; ``normal_form``: the normal form at one state;
``flutter``: those of a stability analysis's events.  Hysteretic damping is refused.

Derivation: docs/theory/stability.md, "Hopf criticality of the flutter events".
"""

from .flutter import EVENT_KEYS, decorate_events, event_states, normal_forms
from .lyapunov import (
    DEGENERATE_FACTOR,
    FLAT_ENOUGH,
    STEP_LADDER,
    HopfCoefficient,
    jacobian_differences,
    lyapunov_coefficient,
)
from .normal_form import HopfChecks3D, HopfNormalForm, first_lyapunov_coefficient
from .pipe import pipe_derivatives, pipe_jacobian

__all__ = [
    "DEGENERATE_FACTOR",
    "STEP_LADDER",
    "FLAT_ENOUGH",
    "HopfCoefficient",
    "HopfNormalForm",
    "HopfChecks3D",
    "lyapunov_coefficient",
    "pipe_jacobian",
    "pipe_derivatives",
    "jacobian_differences",
    "first_lyapunov_coefficient",
    "event_states",
    "normal_forms",
    "decorate_events",
    "EVENT_KEYS",
]

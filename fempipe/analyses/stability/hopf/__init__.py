"""Hopf criticality of the flutter events: the first Lyapunov coefficient l1.

A flutter event of ``fempipe critical`` is a Hopf bifurcation of the static state: a complex
pair of the linearization of Eq. (20) (Eqs. (31b)-(33)) crosses the imaginary axis at
v = v_cr.  The sign of the first Lyapunov coefficient l1 of the normal form on the center
manifold decides whether the periodic orbit born there is stable (supercritical, l1 < 0) or
unstable (subcritical, l1 > 0).  l1 comes from Kuznetsov's formula on the first-order form
x' = F(x; v) of Eq. (20), whose multilinear forms are differences of its analytic Jacobian on
a ladder of steps, with q normalized in L2 over theta; with the transversality Re lambda'(v)
it predicts the cycles' amplitudes, ``(max - min)/2 ~ c sqrt(|v - v_cr|)``.  Hysteretic
damping has no normal form (refused).

Modules: ``lyapunov`` (l1 of a generic x' = F(x): :func:`lyapunov_coefficient`), ``pipe``
(the pipe's D_x F and its derivatives: :func:`pipe_jacobian`, :func:`pipe_derivatives`),
``normal_form`` (the pipe's normal form at one state: :func:`first_lyapunov_coefficient`)
and ``flutter`` (the normal forms of the flutter events of a stability analysis:
:func:`normal_forms`, :func:`decorate_events`).

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

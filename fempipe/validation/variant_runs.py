"""What the four variant cases share: fempipe's v_cr, the classical one, their agreement.

The cases ``end_mass``, ``external_damping``, ``hysteretic`` and ``springs`` each compare
fempipe's critical flow velocity of a straight pipe (hanging, standing or gravity-free: the
static state is the undeformed pipe) with the classical linear theory of
:mod:`fempipe.validation.classical`, which solves another equation (the lateral displacement
eta, not the rotation theta) by another method (spectral elements in eta).  Both are
converged far below the agreement asked for:

* fempipe's FE P3:16 (the suite's converged mesh): its v_cr of the paper's hanging pipe
  equals P3:64 to 3e-10, and the variant terms converge at the element order (a spring inside
  an element lowers the order to 3, so the cases put springs on nodes);
* the classical solver on Legendre elements of degree p + 2 = 18: p = 16 and p = 32 agree to
  1e-9 (checked in each case).

Their difference must be below the ``agreement`` of each case's reference file, 1e-6, which
leaves two orders for the v_cr tolerances of the two critical-velocity searches (fempipe's
crossing to about 1e-8, the classical Brent to 1e-12).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fempipe.analyses import stability
from fempipe.model.discretization import parse_discretization
from fempipe.model.operators import PipeModel
from fempipe.model.params import Params

from . import classical
from .evaluate import Measured, measure
from .static_shapes import CONVERGED_FE

__all__ = ["CLASSICAL_P", "FE", "FeOnset", "agreement", "classical_onset", "converged", "fe_onset"]

#: fempipe's converged discretization for the variant cases.
FE = CONVERGED_FE
#: Legendre degree of the classical solver (its v_cr converged to 1e-9).
CLASSICAL_P = 16


@dataclass(frozen=True)
class FeOnset:
    """fempipe's first loss of stability: v_cr, its type and crossing frequency."""

    v_cr: float
    kind: str
    frequency: float
    mode: int | None


def fe_onset(params: Params, v_max: float) -> FeOnset:
    """v_cr of the primary branch by :func:`fempipe.analyses.stability.find_critical_velocity` on FE P3:16."""
    model = PipeModel(parse_discretization(fe=FE), params)
    res = stability.find_critical_velocity(model, v_max)
    c = res.critical
    if c is None:
        return FeOnset(math.nan, "stable", math.nan, None)
    return FeOnset(float(res.v_cr), c.type, float(c.frequency), c.mode)


def classical_onset(
    params: Params, v_max: float, p: int = CLASSICAL_P, **kwargs
) -> classical.Onset:
    """v_cr of the same pipe by the classical solver (Legendre elements, degree ``p``)."""
    pipe = classical.StraightPipe.from_params(params)
    return classical.critical_velocity(pipe, v_max, method="legendre", n=p, **kwargs)


def agreement(spec: str, fe: FeOnset, cl: classical.Onset, **fields) -> Measured:
    """|v_cr(FE) - v_cr(classical)| (infinite unless both see the same kind of instability)."""
    diff = abs(fe.v_cr - cl.v_cr) if fe.kind == cl.kind else math.inf
    onsets = {"fe_v": fe.v_cr, "fe_kind": fe.kind, "cl_v": cl.v_cr, "cl_kind": cl.kind}
    return measure(spec, diff, mesh=FE, **onsets, **fields)


def converged(params: Params, v_max: float, step: float | None = None, **fields) -> Measured:
    """``classical_converged``: the classical v_cr on p = 16 against p = 32 (spectral
    convergence); ``step`` that of the classical search (its default if None)."""
    kw = {} if step is None else {"step": step}
    a = classical_onset(params, v_max, CLASSICAL_P, **kw).v_cr
    b = classical_onset(params, v_max, 2 * CLASSICAL_P, **kw).v_cr
    diff = abs(a - b)
    return measure("classical_converged", diff, p=CLASSICAL_P, p2=2 * CLASSICAL_P, **fields)

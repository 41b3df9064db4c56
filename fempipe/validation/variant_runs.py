"""What the four variant cases share: fempipe's v_cr, the classical one, their agreement.

``end_mass``, ``external_damping``, ``hysteretic`` and ``springs`` compare fempipe's v_cr of
a straight pipe (FE P3:16, equal to P3:64 to 3e-10) with the classical theory of
:mod:`fempipe.validation.classical` (Legendre p = 16, equal to p = 32 to 1e-9); their
difference must be below 1e-6.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fempipe.analyses import stability
from fempipe.model.discretization import parse_discretization
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from . import classical
from .evaluate import Measured, measure
from .static_shapes import CONVERGED_FE

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


def fe_cell(onset, attr: str = "v_cr"):
    """An FE onset's ``attr`` for a table cell ("—" where it was not computed: ``None``)."""
    return "—" if onset is None else getattr(onset, attr)


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
    """``classical_converged``: the classical v_cr on p = 16 against p = 32."""
    kw = {} if step is None else {"step": step}
    a = classical_onset(params, v_max, CLASSICAL_P, **kw).v_cr
    b = classical_onset(params, v_max, 2 * CLASSICAL_P, **kw).v_cr
    diff = abs(a - b)
    return measure("classical_converged", diff, p=CLASSICAL_P, p2=2 * CLASSICAL_P, **fields)

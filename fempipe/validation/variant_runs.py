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

Their difference must be below ``AGREEMENT`` = 1e-6, which leaves two orders for the v_cr
tolerances of the two critical-velocity searches (fempipe's crossing to about 1e-8, the
classical Brent to 1e-12).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from fempipe.analyses import stability
from fempipe.model.discretization import parse_discretization
from fempipe.model.operators import PipeModel
from fempipe.model.params import Params

from . import classical
from .checks import Check, below
from .static_shapes import CONVERGED_FE

__all__ = [
    "AGREEMENT",
    "CLASSICAL_P",
    "FE",
    "FeOnset",
    "agreement_check",
    "classical_onset",
    "converged_check",
    "fe_onset",
]

#: fempipe's converged discretization for the variant cases.
FE = CONVERGED_FE
#: Legendre degree of the classical solver (its v_cr converged to 1e-9).
CLASSICAL_P = 16
#: |v_cr(FE) - v_cr(classical)| allowed: see the module docstring.
AGREEMENT = 1e-6
AGREEMENT_WHY = (
    "two converged solutions of one linear problem (FE P3:16; classical Legendre p = 16, "
    "converged to 1e-9); 1e-6 leaves two orders for the crossing tolerances"
)
CLASSICAL_SOURCE = (
    "fempipe.validation.classical: the textbook equation of eta(xi, tau) (Paidoussis 1998, "
    "Eqs. (3.70)-(3.71)) on Legendre spectral elements, independent of fempipe's weak form"
)


@dataclass(frozen=True)
class FeOnset:
    """fempipe's first loss of stability: v_cr, its type and crossing frequency."""

    v_cr: float
    kind: str
    frequency: float
    mode: int | None


def fe_onset(params: Params, v_max: float) -> FeOnset:
    """v_cr of the primary branch by :func:`fempipe.analyses.stability.critical_velocity` on FE P3:16."""
    model = PipeModel(parse_discretization(fe=FE), params)
    res = stability.critical_velocity(model, v_max)
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


def agreement_check(name: str, what: str, fe: FeOnset, cl: classical.Onset) -> Check:
    """|v_cr(FE) - v_cr(classical)| <= AGREEMENT, and both see the same kind of instability."""
    diff = abs(fe.v_cr - cl.v_cr) if fe.kind == cl.kind else math.inf
    return below(
        name,
        f"{what}: fempipe's v_cr ({FE}: {fe.v_cr:.9f}, {fe.kind}) equals the classical "
        f"theory's ({cl.v_cr:.9f}, {cl.kind})",
        diff,
        AGREEMENT,
        why=AGREEMENT_WHY,
        source=CLASSICAL_SOURCE,
    )


def converged_check(name: str, what: str, params: Params, v_max: float, **kwargs) -> Check:
    """The classical v_cr on p = 16 equals p = 32 to 1e-9 (spectral convergence)."""
    a = classical_onset(params, v_max, CLASSICAL_P, **kwargs).v_cr
    b = classical_onset(params, v_max, 2 * CLASSICAL_P, **kwargs).v_cr
    return below(
        name,
        f"{what}: the classical v_cr is converged (Legendre p = {CLASSICAL_P} against "
        f"p = {2 * CLASSICAL_P})",
        abs(a - b),
        1e-9,
        why="the error of spectral elements falls faster than any power of p; 1e-9 is "
        "a thousand times below the agreement asked of fempipe",
        source="fempipe.validation.classical (refinement)",
    )

"""Does a planar attractor survive in three dimensions?

The verdict the planar ``simulate`` reports beside its attractor: for a
limit cycle, its out-of-plane Floquet multipliers
(:func:`~fempipe.analyses.space.floquet.out_of_plane_floquet`); for an
equilibrium, the out-of-plane spectrum (:mod:`fempipe.model.out_of_plane`).
A non-periodic planar motion gets no verdict.
"""

from __future__ import annotations

from ...model.operators import PipeModel
from ..limit_cycle.results import Attractor
from ..stability import linearly_stable
from .floquet import out_of_plane_floquet

__all__ = ["three_dimensional_verdict"]


def three_dimensional_verdict(model: PipeModel, att: Attractor, *, rtol: float = 1e-7) -> dict:
    """``stable_3d`` and the out-of-plane evidence for a planar attractor.

    Parameters
    ----------
    model : PipeModel
        The planar model of the attractor.
    att : Attractor
    rtol : float
        Integration tolerance of the out-of-plane monodromy.

    Returns
    -------
    dict
        ``stable_3d`` (True, False or None when nothing is decided) and, for a
        limit cycle, ``out_of_plane_floquet_multipliers`` (the six largest,
        ``[re, im]``), ``max_nontrivial_out_of_plane_multiplier`` and
        ``stable_out_of_plane``; for an equilibrium ``stable_out_of_plane``.
    """
    if att.kind == "periodic" and att.cycle is not None:
        oop = out_of_plane_floquet(model, att.cycle, rtol=rtol)
        out = oop.to_dict()
        out["stable_3d"] = bool(att.cycle.stable and oop.stable)
        out["out_of_plane_cpu_time"] = oop.cpu_time
        return out
    if att.kind == "equilibrium":
        stable = linearly_stable(model.with_plane("out"), att.q)
        return {"stable_out_of_plane": stable, "stable_3d": stable}
    return {"stable_3d": None}

"""Does a planar attractor survive in three dimensions?

The verdict the planar ``simulate`` reports beside its attractor: for a
limit cycle, its out-of-plane Floquet multipliers
(:func:`~fempipe.analyses.space.floquet.out_of_plane_floquet`); for an
equilibrium, the out-of-plane spectrum (:mod:`fempipe.model.out_of_plane`).
A non-periodic planar motion gets no verdict.
"""

from __future__ import annotations

import numpy as np

from ...model.operators import PipeModel
from ...model.out_of_plane import out_of_plane_model
from ..limit_cycle.results import Attractor
from ..stability import linearly_stable
from .floquet import OutOfPlaneFloquet, out_of_plane_floquet

__all__ = [
    "ROUGH_DEFECT",
    "cycle_entries",
    "equilibrium_verdict",
    "rough_verdict_note",
    "three_dimensional_verdict",
]

#: A neutral multiplier further than this from 1 marks a discretization whose out-of-plane
#: multipliers are rough (the hanging pipe's cycle at v = 10, linear method: finite
#: elements 1.9e-3 on P3:4, 1.5e-4 on P3:6; three sine modes 0.31, four 0.16; the 3-D
#: model's: 1.0e-3, 8.5e-6, 0.23, 0.09).
ROUGH_DEFECT = 1e-2


def rough_verdict_note(disc_name: str, defect: float | None) -> str | None:
    """A warning for the 3-D verdict of a few modes or a coarse mesh, or None.

    The rotation about the vertical (a symmetry of the continuum at alpha = 0 and pi) is
    kept by a discretization only up to its error; a few sine modes keep it poorly, and
    their out-of-plane multipliers are then off by far more than the neutral one (hanging
    pipe, v = 10, three sine modes: no multiplier is near 1, the nearest is
    0.755 +- 0.190i, and the largest 0.778 against 0.796 converged; the 3-D model's
    0.767 +- 0.032i and 0.768).
    """
    modal = disc_name.startswith("modal")
    if defect is not None and defect > ROUGH_DEFECT:
        return (
            f"the neutral multiplier of the rotation about the vertical is {defect:.2g} "
            f"from 1 on {disc_name}: the out-of-plane multipliers are rough; "
            "refine the discretization (finite elements) before trusting stable_3d"
        )
    if modal:
        return (
            f"out-of-plane multipliers on {disc_name} are rough (three sine modes: 0.778 "
            "for the hanging pipe's largest against 0.796 converged); use finite "
            "elements for the 3-D verdict"
        )
    return None


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
        return cycle_entries(model, oop, att.cycle.stable)
    if att.kind == "equilibrium":
        return equilibrium_verdict(model, att.q, True)
    return {"stable_3d": None}


def cycle_entries(model: PipeModel, oop: OutOfPlaneFloquet, stable_in_plane: bool) -> dict:
    """The verdict of a planar cycle from its out-of-plane multipliers ``oop``: their
    :meth:`~fempipe.analyses.space.floquet.OutOfPlaneFloquet.to_dict`, ``stable_3d``
    (stable in the plane and out of it), ``out_of_plane_cpu_time`` and, where the
    verdict is rough, ``stable_3d_note`` (:func:`rough_verdict_note`)."""
    out = oop.to_dict()
    out["stable_3d"] = bool(stable_in_plane and oop.stable)
    out["out_of_plane_cpu_time"] = oop.cpu_time
    note = rough_verdict_note(model.disc.name, oop.symmetry_defect)
    if note:
        out["stable_3d_note"] = note
    return out


def equilibrium_verdict(model: PipeModel, q: np.ndarray, stable_in_plane: bool | None) -> dict:
    """``stable_out_of_plane`` (the out-of-plane spectrum at ``q``) and ``stable_3d``
    (None when the planar verdict is unknown)."""
    out_stable = bool(linearly_stable(out_of_plane_model(model), q))
    both = None if stable_in_plane is None else bool(stable_in_plane and out_stable)
    return {"stable_out_of_plane": out_stable, "stable_3d": both}

"""Does a planar attractor survive in three dimensions (:func:`classify_3d`)?

For a limit cycle its out-of-plane Floquet multipliers
(:func:`~fempipe.analyses.three_d.floquet.compute_out_of_plane_floquet`), for an equilibrium
the out-of-plane spectrum (:mod:`fempipe.model.out_of_plane.model`); a non-periodic motion gets no
verdict.  Docs: docs/theory/space.md, "What it answers".
"""

from __future__ import annotations

import numpy as np

from fempipe.analyses.three_d.floquet import OutOfPlaneFloquet, compute_out_of_plane_floquet
from fempipe.model.out_of_plane.model import build_out_of_plane_model
from fempipe.model.plane.operators import PipeModel

from ..limit_cycle.results import Attractor
from ..stability import linearly_stable

__all__ = [
    "ROUGH_DEFECT",
    "classify_3d",
    "cycle_entries",
    "equilibrium_verdict",
    "rough_verdict_note",
]

#: A neutral multiplier further than this from 1 marks rough out-of-plane multipliers (the
#: hanging pipe's cycle at v = 10: 1.9e-3 on P3:4, 0.31 on three sine modes).
ROUGH_DEFECT = 1e-2


def rough_verdict_note(disc_name: str, defect: float | None) -> str | None:
    """A warning for the 3-D verdict of a modal discretization or a coarse mesh (neutral
    multiplier ``defect`` above :data:`ROUGH_DEFECT`), or None."""
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


def classify_3d(model: PipeModel, att: Attractor, *, rtol: float = 1e-7) -> dict:
    """``stable_3d`` (None when undecided) and the out-of-plane evidence for a planar attractor.

    Parameters
    ----------
    model : PipeModel
    att : Attractor
    rtol : float
        Integration tolerance of the out-of-plane monodromy.
    """
    if att.kind == "periodic" and att.cycle is not None:
        oop = compute_out_of_plane_floquet(model, att.cycle, rtol=rtol)
        return cycle_entries(model, oop, att.cycle.stable)
    if att.kind == "equilibrium":
        return equilibrium_verdict(model, att.q, True)
    return {"stable_3d": None}


def cycle_entries(model: PipeModel, oop: OutOfPlaneFloquet, stable_in_plane: bool) -> dict:
    """The verdict of a planar cycle from its out-of-plane multipliers ``oop``: their
    ``to_dict``, ``stable_3d``, ``out_of_plane_cpu_time`` and ``stable_3d_note`` if rough."""
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
    out_stable = bool(linearly_stable(build_out_of_plane_model(model), q))
    both = None if stable_in_plane is None else bool(stable_in_plane and out_stable)
    return {"stable_out_of_plane": out_stable, "stable_3d": both}

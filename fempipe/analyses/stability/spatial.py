"""Stability in three dimensions: the motions in and out of the plane of the static state.

A round pipe is free to leave the plane of its static deformation.  About a
planar static state the linearized motion splits into the in-plane problem
(Eq. (32)) and the out-of-plane one (:mod:`fempipe.model.out_of_plane`); the state
is stable in three dimensions when it is stable in both, and the pipe's
first loss of stability is the earlier of the two.
:func:`spatial_stability_analysis` follows the static branches once and
analyses both planes along the same points.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fempipe.core.parallel import single_blas
from fempipe.model.operators import PipeModel
from fempipe.model.out_of_plane import in_plane_model, out_of_plane_model

from .analysis import analyse_planes
from .canonical import RESOLUTION_TOL
from .events import StabilityEvent, StabilityResult

__all__ = [
    "SpatialStability",
    "first_of",
    "spatial_critical_velocity",
    "spatial_stability_analysis",
]

#: Two critical velocities closer than this (relative to max(1, v)) are the
#: same loss of stability: the events are located to 1e-10 in v, and where the
#: planes coincide (the straight pipe, alpha = 0 or pi) they agree to that.
SAME_V = 1e-9


def first_of(in_plane: StabilityEvent | None, out_of_plane: StabilityEvent | None):
    """The earlier of two critical events; the in-plane one when they coincide (:data:`SAME_V`).

    Where the two planes coincide (a straight pipe hanging or standing: every
    plane through its axis is alike) the in-plane event stands for both.
    """
    if out_of_plane is None:
        return in_plane
    if in_plane is None:
        return out_of_plane
    if out_of_plane.v < in_plane.v - SAME_V * max(1.0, abs(in_plane.v)):
        return out_of_plane
    return in_plane


@dataclass(frozen=True)
class SpatialStability:
    """The static branches' stability in and out of their plane.

    Attributes
    ----------
    in_plane, out_of_plane : StabilityResult
        The two analyses along the same branches (``plane`` "in" and "out").
    """

    in_plane: StabilityResult
    out_of_plane: StabilityResult

    @property
    def critical(self) -> StabilityEvent | None:
        """The first loss of stability of the primary branch in three dimensions."""
        return first_of(self.in_plane.critical, self.out_of_plane.critical)

    @property
    def v_cr(self) -> float | None:
        c = self.critical
        return None if c is None else float(c.v)

    @property
    def v_flutter(self) -> float | None:
        """The first flutter of the primary branch in either plane."""
        vs = [v for v in (self.in_plane.v_flutter, self.out_of_plane.v_flutter) if v is not None]
        return min(vs) if vs else None

    @property
    def events(self) -> tuple:
        """Every event of both planes, by branch then v (the folds once: they are the
        static branch's, listed with the in-plane events)."""
        order = {b.name: i for i, b in enumerate(self.in_plane.branches)}
        evs = list(self.in_plane.events) + [e for e in self.out_of_plane.events if e.type != "fold"]
        return tuple(sorted(evs, key=lambda e: (order.get(e.branch, len(order)), e.v)))

    @property
    def n_spectra(self) -> int:
        return self.in_plane.n_spectra + self.out_of_plane.n_spectra

    def first_instability(self) -> dict | None:
        """``{"v", "plane", "type", "frequency"}`` of :attr:`critical`, or None."""
        c = self.critical
        if c is None:
            return None
        return {"v": c.v, "plane": c.plane, "type": c.type, "frequency": c.frequency}

    def to_dict(self, samples: bool = False) -> dict:
        """The contract of ``fempipe critical --json`` (module docstring of the command)."""
        d = self.in_plane.to_dict(samples)
        ci, co = self.in_plane.critical, self.out_of_plane.critical
        c = self.critical
        d["v_cr"] = self.v_cr
        d["critical"] = None if c is None else c.details()
        d["v_flutter"] = self.v_flutter
        d["events"] = [e.to_dict() for e in self.events]
        d["n_spectra"] = self.n_spectra
        d["first_instability"] = self.first_instability()
        d["v_cr_in_plane"] = self.in_plane.v_cr
        d["frequency_in_plane"] = None if ci is None else ci.frequency
        d["v_cr_out_of_plane"] = self.out_of_plane.v_cr
        d["frequency_out_of_plane"] = None if co is None else co.frequency
        d["v_flutter_in_plane"] = self.in_plane.v_flutter
        d["v_flutter_out_of_plane"] = self.out_of_plane.v_flutter
        d["critical_in_plane"] = None if ci is None else ci.details()
        d["critical_out_of_plane"] = None if co is None else co.details()
        d["branches_out_of_plane"] = [b.to_dict(samples) for b in self.out_of_plane.branches]
        return d


@single_blas
def spatial_stability_analysis(
    model: PipeModel,
    v_max: float = 10.0,
    v_min: float = 0.0,
    *,
    follow_bifurcations: bool = True,
    max_depth: int = 1,
    q0: np.ndarray | None = None,
    ds_max: float = 0.1,
    max_steps: int = 2000,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
    stop_at_first: bool = False,
    callback: Callable[[str, float], None] | None = None,
) -> SpatialStability:
    """:func:`~fempipe.analyses.stability.stability_analysis` in and out of the plane.

    The parameters are those of :func:`~fempipe.analyses.stability.stability_analysis`
    (``model`` is the planar pipe, or its out-of-plane model: either gives
    the same branches).  The static branches are continued once; the
    out-of-plane analysis runs along the same points.
    """
    planar = in_plane_model(model)
    planes = analyse_planes(
        [planar, out_of_plane_model(planar)],
        v_min=v_min,
        v_max=v_max,
        follow_bifurcations=follow_bifurcations,
        max_depth=max_depth,
        q0=q0,
        ds_max=ds_max,
        max_steps=max_steps,
        method=method,
        tolerance=tolerance,
        stop_at_first=stop_at_first,
        callback=callback,
    )
    return SpatialStability(in_plane=planes["in"], out_of_plane=planes["out"])


def spatial_critical_velocity(
    model: PipeModel, v_max: float = 10.0, v_min: float = 0.0, **kwargs
) -> SpatialStability:
    """The first loss of stability in three dimensions of the primary branch (and of each plane).

    :func:`spatial_stability_analysis` without branch switching, each plane's
    analysis stopping at its own first loss of stability.
    """
    kwargs.setdefault("follow_bifurcations", False)
    kwargs.setdefault("stop_at_first", True)
    return spatial_stability_analysis(model, v_max, v_min, **kwargs)

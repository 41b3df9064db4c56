"""The points of a bifurcation diagram and their store (:mod:`fempipe.analyses.bifurcation`).

A :class:`BifurcationPoint` is one finished point of a sweep or a continued
branch: the kind of attractor, its period, the tip's extrema, the state it
ended on (so that a resumed run starts the next point from the same state) and
its verdict in three dimensions.  A :class:`PointStore` keeps finished points
as one JSON file each, written atomically, so that a rerun computes only the
missing ones.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from fempipe.core.files import claim_run_directory, write_text

__all__ = ["BifurcationPoint", "PointStore"]


@dataclass(frozen=True)
class BifurcationPoint:
    """One point of a sweep.

    Attributes
    ----------
    v : float
    direction : str
        ``"up"`` or ``"down"``.
    index : int
        Position in the sweep.
    alpha : float
    attractor : str
        ``"equilibrium"``, ``"periodic"`` or ``"non-periodic"``.
    eta_tip, X_tip, Z_tip : list of float
        [min, max] on the attractor.
    period : float or None
    period_n : int or None
    max_multiplier : float or None
        Largest non-trivial Floquet multiplier modulus of a periodic attractor.
    steps, rejected_steps : int
    wall_time : float
    q, qdot : ndarray
        The state the point ended on (start of the next point).
    three_d : dict or None
        The 3-D verdict (a sweep with ``out_of_plane``): ``stable_3d`` and the
        out-of-plane evidence (:mod:`fempipe.analyses.bifurcation`); its keys join the
        point's in :meth:`to_dict`.
    """

    v: float
    direction: str
    index: int
    alpha: float
    attractor: str
    eta_tip: list
    X_tip: list
    Z_tip: list
    period: float | None
    period_n: int | None
    max_multiplier: float | None
    steps: int
    rejected_steps: int
    wall_time: float
    q: np.ndarray = field(repr=False)
    qdot: np.ndarray = field(repr=False)
    three_d: dict | None = None

    def to_dict(self, state: bool = False) -> dict:
        """Plain-JSON form; with ``state`` also q and qdot (as the point store keeps them)."""
        d = {
            "v": self.v,
            "direction": self.direction,
            "index": self.index,
            "alpha": self.alpha,
            "attractor": self.attractor,
            "eta_tip": self.eta_tip,
            "X_tip": self.X_tip,
            "Z_tip": self.Z_tip,
            "period": self.period,
            "period_n": self.period_n,
            "max_multiplier": self.max_multiplier,
            "steps": self.steps,
            "rejected_steps": self.rejected_steps,
            "wall_time": self.wall_time,
        }
        if self.three_d is not None:
            d.update(self.three_d)
        if state:
            d["three_d"] = self.three_d
            # repr-exact floats: a resumed sweep restarts from exactly this state.
            d["q"] = [float(x) for x in self.q]
            d["qdot"] = [float(x) for x in self.qdot]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> BifurcationPoint:
        """Inverse of ``to_dict(state=True)``."""
        kw = {k: d[k] for k in cls.__dataclass_fields__ if k not in ("q", "qdot", "three_d")}
        return cls(
            **kw,
            q=np.asarray(d["q"], dtype=float),
            qdot=np.asarray(d["qdot"], dtype=float),
            three_d=d.get("three_d"),
        )


def _sine_basis_default(old: dict) -> None:
    """A store whose modal discretization names no basis holds sine-mode runs."""
    disc = old.get("discretization", {})
    if disc.get("kind") == "modal":
        disc.setdefault("basis", "sine")


class PointStore:
    """A directory of finished points, one JSON file each, written atomically.

    Parameters
    ----------
    directory : path
        Created if missing.
    manifest : dict
        Describes the run (discretization, parameters but v, values, options).
        A store written by a different run is refused (ValueError), so that a
        resume never mixes results.
    """

    def __init__(self, directory: str | os.PathLike, manifest: dict) -> None:
        self.manifest = json.loads(json.dumps(manifest))
        self.directory = claim_run_directory(directory, self.manifest, _sine_basis_default)

    def path(self, alpha_index: int, direction: str, index: int) -> Path:
        """File of point ``index`` of the sweep ``direction`` at the ``alpha_index``-th alpha."""
        return self.directory / f"a{alpha_index:02d}-{direction}-{index:03d}.json"

    def load(self, alpha_index: int, direction: str, index: int) -> BifurcationPoint | None:
        """The stored point, or None if it has not been finished."""
        p = self.path(alpha_index, direction, index)
        if not p.exists():
            return None
        return BifurcationPoint.from_dict(json.loads(p.read_text()))

    def save(self, alpha_index: int, point: BifurcationPoint) -> None:
        """Write a finished point with its state (atomically: complete or absent)."""
        write_text(
            self.path(alpha_index, point.direction, point.index),
            json.dumps(point.to_dict(state=True)),
        )

    def count(self) -> int:
        """Number of finished points in the store (all sweeps)."""
        # Temporary files of unfinished writes start with "." and do not match.
        return sum(1 for _ in self.directory.glob("a*-*-*.json"))

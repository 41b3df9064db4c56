"""The linearization of Eq. (20) about a static state, Eqs. (31b)-(33).

K^d, C^d, M^d at any static state (:func:`linearized_matrices`), and at the
straight state theta = 0 as functions of v alone (:class:`StraightPencil`).
"""

from __future__ import annotations

import math
import weakref
from dataclasses import replace

import numpy as np

from fempipe.core.errors import ParamError
from fempipe.model.out_of_plane.model import build_in_plane_model, build_out_of_plane_model
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

#: The planes of the linear problems about a planar static state.
PLANES = ("in", "out")


def plane_models(model: PipeModel, planes) -> list[PipeModel]:
    """The models of ``model``'s pipe linearized in each of ``planes``, in the order of PLANES.

    An out-of-plane ``model`` is accepted only where ``"out"`` is among ``planes``.
    """
    planes = (planes,) if isinstance(planes, str) else tuple(planes)
    if not planes or len(set(planes)) != len(planes) or not set(planes) <= set(PLANES):
        raise ParamError("planes", f"planes must be distinct values of {PLANES}, got {planes!r}")
    if model.plane == "out" and "out" not in planes:
        raise ParamError(
            "planes", f"model is linearized out of the plane; pass planes=('out',), got {planes!r}"
        )
    planar = build_in_plane_model(model)
    build = {"in": lambda: planar, "out": lambda: build_out_of_plane_model(model)}
    return [build[p]() for p in PLANES if p in planes]


def linearized_matrices(model: PipeModel, q: np.ndarray):
    """K^d, C^d, M^d of Eqs. (33a)-(33c) at the static state q: dR/dq, dR/dq', dR/dq'' at (q, 0, 0).

    K is not symmetric for v > 0; C holds Coriolis and Kelvin-Voigt; M is SPD.
    """
    return model.linearization(np.asarray(q, dtype=float))


class StraightPencil:
    """K^d, C^d, M^d at theta = 0 as functions of v alone: K0 + v^2 K2, C0 + v C1, M.

    Formed from :func:`linearized_matrices` at v = 0 and 1; equal to the assembled ones to
    round-off (docs/theory/stability.md, "The straight branch").  q = 0 is a static state only
    where sin(alpha) = 0 (:func:`straight_is_static`).
    """

    def __init__(self, model: PipeModel) -> None:
        q, p = np.zeros(model.n), model.params
        K0, C0, M = linearized_matrices(model.with_params(replace(p, v=0.0)), q)
        K1, C1, _ = linearized_matrices(model.with_params(replace(p, v=1.0)), q)
        self.K0, self.K2 = K0, K1 - K0
        self.C0, self.C1 = C0, C1 - C0
        self.M = M

    def matrices(self, v: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """K, C, M at flow velocity v."""
        return self.K0 + (v * v) * self.K2, self.C0 + v * self.C1, self.M

    @staticmethod
    def key(params: Params) -> Params:
        """The parameters the pencil depends on (v set to 0)."""
        return replace(params, v=0.0)


_PENCIL_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def straight_pencil(model: PipeModel) -> StraightPencil:
    """The :class:`StraightPencil` of ``model`` (cached per discretization and parameters)."""
    per_disc = _PENCIL_CACHE.setdefault(model.disc, {})
    key = (model.plane, StraightPencil.key(model.params))
    pencil = per_disc.get(key)
    if pencil is None:
        if len(per_disc) > 32:  # a stability map visits many parameter points
            per_disc.clear()
        pencil = per_disc[key] = StraightPencil(model)
    return pencil


def straight_is_static(params: Params) -> bool:
    """Whether theta = 0 solves Eq. (31a) for every v: alpha = 0 or pi (mod 2 pi)."""
    return abs(math.sin(params.alpha)) < 1e-12

"""Floquet multipliers of out-of-plane perturbations of a planar limit cycle.

By the mirror symmetry e_3 -> -e_3 a planar cycle's perturbations split into planar and
out-of-plane ones; the latter from the linear equation about the moving planar state
(``method="linear"``) or the out-of-plane block of the 3-D monodromy (``method="3d"``, gauge
left out).  At alpha = 0, pi one of them (the turned cycle) is 1 in the continuum.

Derivation: docs/theory/out_of_plane.md, "About a moving planar state"; docs/theory/space.md.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fempipe.model.out_of_plane.motion import OutOfPlaneVariation
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D, planar_state

from ...solvers.radau import Radau
from ..limit_cycle.results import LimitCycle

__all__ = ["METHODS", "OutOfPlaneFloquet", "compute_out_of_plane_floquet"]


@dataclass(frozen=True)
class OutOfPlaneFloquet:
    """The out-of-plane Floquet multipliers of a planar cycle.

    Attributes
    ----------
    multipliers, planar_multipliers : ndarray, complex
        Out-of-plane (no gauge) and the planar block's, by decreasing modulus.
    axisymmetric, trivial : bool, complex or None
        sin(alpha) = 0, and then the multiplier closest to 1.
    max_nontrivial, stable : float, bool
    gauge_largest : float
        0 for ``"linear"``.
    steps, cpu_time, method : int, float, str
    """

    multipliers: np.ndarray
    planar_multipliers: np.ndarray
    axisymmetric: bool
    trivial: complex | None
    max_nontrivial: float
    stable: bool
    gauge_largest: float
    steps: int
    cpu_time: float
    method: str = "linear"

    @property
    def symmetry_defect(self) -> float | None:
        """|trivial - 1| at an axisymmetric alpha (else None): a lower bound on the
        discretization error of the out-of-plane multipliers."""
        return None if self.trivial is None else float(abs(self.trivial - 1.0))

    def to_dict(self, n_multipliers: int = 6) -> dict:
        """The leading multipliers as [re, im] pairs, the verdict, the neutral multiplier."""
        trivial = self.trivial
        return {
            "out_of_plane_floquet_multipliers": [
                [float(z.real), float(z.imag)] for z in self.multipliers[:n_multipliers]
            ],
            "max_nontrivial_out_of_plane_multiplier": self.max_nontrivial,
            "stable_out_of_plane": self.stable,
            "neutral_out_of_plane_multiplier": (
                None if trivial is None else [float(trivial.real), float(trivial.imag)]
            ),
            "out_of_plane_symmetry_defect": self.symmetry_defect,
            "out_of_plane_method": self.method,
        }


#: The two computations of :func:`compute_out_of_plane_floquet`.
METHODS = ("linear", "3d")


def compute_out_of_plane_floquet(
    model: PipeModel,
    cycle: LimitCycle,
    *,
    rtol: float = 1e-7,
    method: str = "linear",
    flow: Callable[[float], tuple[float, float]] | None = None,
) -> OutOfPlaneFloquet:
    """The Floquet multipliers of out-of-plane perturbations of a planar limit cycle.

    Parameters
    ----------
    model : PipeModel
        The planar model of the cycle.
    cycle : LimitCycle
        Or any periodic planar motion with ``q0``, ``qdot0`` and ``period`` (e.g. a
        :class:`~fempipe.analyses.parametric.ForcedResponse`, with its ``flow``).
    rtol : float
    method : {"linear", "3d"}
        The linear out-of-plane equation (one unknown psi, the cheaper) or the 3-D model's
        out-of-plane block.
    flow : callable, optional
        tau -> (v, v_dot) of an unsteady flow (default the steady ``model.params.v``).
    """
    if method not in METHODS:
        raise ValueError(f"method must be one of {METHODS} (got {method!r})")
    start = time.process_time()
    nt = model.disc.n
    if method == "3d":
        problem = PipeDynamics3D(PipeModel3D(model.disc, model.params), flow)
        q0, p0, n_fields = planar_state(cycle.q0), planar_state(cycle.qdot0), 3
    else:
        problem = OutOfPlaneVariation(model, flow)
        zero = np.zeros(nt)
        q0, p0, n_fields = np.r_[cycle.q0, zero], np.r_[cycle.qdot0, zero], 2
    stepper = Radau(problem, q0, p0, rtol=rtol, sensitivity=True)
    for _ in stepper.steps(cycle.period):
        pass
    S = stepper.sensitivity_matrix
    N = n_fields * nt
    plane = np.r_[0:nt, N : N + nt]
    out = np.r_[nt:N, N + nt : 2 * N]
    planar = np.linalg.eigvals(S[np.ix_(plane, plane)])
    values = np.linalg.eigvals(S[np.ix_(out, out)])
    values = values[np.argsort(-np.abs(values), kind="stable")]
    mu, gauge = values[: 2 * nt], values[2 * nt :]
    axisymmetric = abs(math.sin(model.params.alpha)) < 1e-12
    trivial = None
    others = mu
    if axisymmetric and mu.size:
        k = int(np.argmin(np.abs(mu - 1.0)))
        trivial = complex(mu[k])
        others = np.delete(mu, k)
    max_nontrivial = float(np.max(np.abs(others))) if others.size else 0.0
    return OutOfPlaneFloquet(
        multipliers=mu,
        planar_multipliers=planar[np.argsort(-np.abs(planar), kind="stable")],
        axisymmetric=axisymmetric,
        trivial=trivial,
        max_nontrivial=max_nontrivial,
        stable=max_nontrivial < 1.0,
        gauge_largest=float(np.abs(gauge[0])) if gauge.size else 0.0,
        steps=stepper.stats.steps,
        cpu_time=time.process_time() - start,
        method=method,
    )

"""The quantities of a convergence study (:class:`Quantity`, one number of the user's case as
a function of the discretization) and the families of discretizations (:class:`Family`)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.kinematics import compute_tip
from fempipe.model.params import Params
from fempipe.model.projection import project

from ..error_estimate import expected_order

#: quantity -> (description, unit).  The static tip values are those of
#: :func:`fempipe.model.kinematics.compute_tip` (Eq. (5), (28)).
QUANTITIES: dict[str, tuple[str, str]] = {
    "theta_tip": ("static tip rotation theta(1)", "rad"),
    "X_tip": ("static tip position X_g(1), down the plumb line", "L"),
    "Z_tip": ("static tip position Z_g(1), horizontal", "L"),
    "eta_tip": ("static lateral tip displacement eta(1)", "L"),
    "v_cr": (
        "critical flow velocity (first loss of stability of the primary branch in three "
        "dimensions, in the plane of the static state or out of it)",
        "1",
    ),
    "frequency": ("frequency Im(lambda) of the critical event (in three dimensions)", "1"),
    "v_cr_in_plane": (
        "critical flow velocity in the plane of the static state (the paper's planar v_cr)",
        "1",
    ),
    "v_cr_out_of_plane": (
        "critical flow velocity of the motion out of the plane of the static state",
        "1",
    ),
    "frequency_in_plane": ("frequency Im(lambda) of the critical event in the plane", "1"),
    "frequency_out_of_plane": (
        "frequency Im(lambda) of the critical event out of the plane",
        "1",
    ),
    "eigenvalue": ("k-th resolved eigenvalue lambda at one v (complex)", "1"),
    "lc_amplitude": ("limit-cycle amplitude (max - min) / 2 of eta(1)", "L"),
    "lc_period": ("limit-cycle period", "1"),
    "sigma_threshold": (
        "least pulsation amplitude at which the pipe resonates (the first region of "
        "parametric resonance to open in the omega band)",
        "1",
    ),
    "omega_threshold": ("pulsation frequency where that region opens", "1/T"),
}

STATIC_QUANTITIES = ("theta_tip", "X_tip", "Z_tip", "eta_tip")
CRITICAL_QUANTITIES = (
    "v_cr",
    "frequency",
    "v_cr_in_plane",
    "frequency_in_plane",
    "v_cr_out_of_plane",
    "frequency_out_of_plane",
)
CYCLE_QUANTITIES = ("lc_amplitude", "lc_period")
PARAMETRIC_QUANTITIES = ("sigma_threshold", "omega_threshold")
#: The thresholds' tolerance in sigma (the frequency there is located to its square root,
#: where sigma is flat: docs/theory/parametric.md).
PARAMETRIC_TOL = 1e-11

#: Tolerances the quantities are computed to, relative to max(1, |Q|): Newton on static
#: states, Brent on v for the stability events.
STATIC_TOL = 1e-12
EVENT_TOL = 1e-10


def doubling(low: int, high: int) -> list[int]:
    """``[low, 2 low, 4 low, ...]`` up to ``high`` (the sizes of ``--elements 2:128``)."""
    low, high = int(low), int(high)
    if low < 1 or high < low:
        raise ValueError(f"need 1 <= low <= high, got {low}:{high}")
    out = [low]
    while out[-1] * 2 <= high:
        out.append(out[-1] * 2)
    return out


@dataclass(frozen=True)
class Family:
    """A sequence of discretizations of one ``kind`` ('fe': P_``degree`` on ``sizes``
    elements; 'modal': ``sizes`` modes of ``basis``)."""

    kind: str
    sizes: tuple[int, ...]
    degree: int = 3
    basis: str = "sine"

    @property
    def label(self) -> str:
        """``fe-P1`` ... ``fe-P10``, ``modal-sine``, ``modal-beam`` (the JSON ``family``)."""
        return f"fe-P{self.degree}" if self.kind == "fe" else f"modal-{self.basis}"

    def discretization(self, size: int):
        if self.kind == "fe":
            return FiniteElement(int(size), self.degree)
        if self.basis == "sine":
            return Modal(int(size))
        return Modal(int(size), basis=self.basis)

    def dofs(self, size: int) -> int:
        return int(size) * self.degree if self.kind == "fe" else int(size)

    def order_for(self, params: Params | None) -> float | None:
        """Theoretical order for ``params`` (:func:`~fempipe.studies.error_estimate.expected_order`)
        on the coarser of the two finest members."""
        size = self.sizes[-2] if len(self.sizes) > 1 else self.sizes[-1]
        return expected_order(self.discretization(size), params)


@dataclass(frozen=True)
class Quantity:
    """One number of the user's case as a function of the discretization; calling it returns
    the value (complex for ``eigenvalue``) or raises :class:`fempipe.core.errors.SolverError`.

    ``name`` is a key of :data:`QUANTITIES`, ``params`` the case (v the start of the flow range
    ``v_max`` of the critical quantities), ``mode`` the mode of ``eigenvalue`` (carried by
    continuity from v = 0), ``shoot_rtol`` the cycle's shooting tolerance, ``seed``
    ``(disc, q0, qdot0, period)`` a cycle to start from (:meth:`seeded`), ``planar`` takes
    ``v_cr`` and ``frequency`` in the plane, ``omega_band`` and ``sigma_max`` bound the search
    of the parametric thresholds.  ``v_cr`` and ``frequency`` are those of the first loss of
    stability in 3-D (:func:`fempipe.analyses.stability.find_critical_velocity`), ``*_in_plane``
    and ``*_out_of_plane`` those of one plane about the same static branch.
    """

    name: str
    params: Params
    v_max: float | None = None
    mode: int = 1
    shoot_rtol: float = 1e-9
    seed: tuple | None = field(default=None, repr=False, compare=False)
    planar: bool = False
    omega_band: tuple[float, float] | None = None
    sigma_max: float = 0.5

    def __post_init__(self) -> None:
        if self.name not in QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, got {self.name!r}")
        if self.name in PARAMETRIC_QUANTITIES:
            band = self.omega_band
            if band is None or not 0 < band[0] < band[1]:
                raise ValueError(f"{self.name} needs a band 0 < omega_lo < omega_hi, got {band}")
            if not 0 < self.sigma_max <= 1:
                raise ValueError(f"sigma_max must satisfy 0 < sigma_max <= 1, got {self.sigma_max}")
        if self.name in CRITICAL_QUANTITIES:
            if self.v_max is None or not self.v_max > self.params.v:
                raise ValueError(
                    f"{self.name} needs a flow range v_min < v_max, got "
                    f"{self.params.v:g}, {self.v_max}"
                )
        if int(self.mode) < 1:
            raise ValueError(f"mode must be >= 1, got {self.mode}")

    @property
    def tolerance(self) -> float:
        """Relative accuracy the solver delivers (the noise floor of the study)."""
        if self.name in STATIC_QUANTITIES:
            return 10 * STATIC_TOL
        if self.name in CRITICAL_QUANTITIES:
            return EVENT_TOL
        if self.name in CYCLE_QUANTITIES:
            return 10 * self.shoot_rtol
        if self.name in PARAMETRIC_QUANTITIES:
            return 100 * PARAMETRIC_TOL if self.name == "sigma_threshold" else 1e-5
        return 1e-11

    def describe(self) -> str:
        """One line: what is computed, at which v."""
        text, unit = QUANTITIES[self.name]
        if self.planar and self.name in ("v_cr", "frequency"):
            text = QUANTITIES[self.name + "_in_plane"][0]
        p = self.params
        if self.name in CRITICAL_QUANTITIES:
            where = f"over {p.v:g} <= v <= {self.v_max:g}"
        elif self.name == "eigenvalue":
            where = f"mode {self.mode} at v = {p.v:g}"
        elif self.name in PARAMETRIC_QUANTITIES:
            lo, hi = self.omega_band
            where = f"at v0 = {p.v:g}, {lo:g} <= omega <= {hi:g}, sigma <= {self.sigma_max:g}"
        else:
            where = f"at v = {p.v:g}"
        return f"{text} {where} [{unit}]"

    def __call__(self, disc) -> float | complex:
        # Imported here: the CLI loads this module at start-up (--help); these load scipy.
        from fempipe.model.plane.operators import PipeModel

        model = PipeModel(disc, self.params)
        if self.name in STATIC_QUANTITIES:
            return _static_tip(model, self.name)
        if self.name in CRITICAL_QUANTITIES:
            return self._critical(model)
        if self.name == "eigenvalue":
            return _eigenvalue(model, self.mode)
        if self.name in PARAMETRIC_QUANTITIES:
            return self._parametric(model)
        cycle = self.cycle(disc)
        if self.name == "lc_period":
            return float(cycle.period)
        lo, hi = cycle.tip["eta_tip"]
        return 0.5 * float(hi - lo)

    def _parametric(self, model) -> float:
        """The threshold of the first region of parametric resonance to open in the band."""
        from fempipe.analyses.parametric import compute_parametric_chart

        chart = compute_parametric_chart(
            model, self.params.v, self.omega_band, [self.sigma_max], sigma_tol=PARAMETRIC_TOL
        )
        if not chart.regions:
            raise SolverError(
                f"no region of parametric resonance opens for sigma <= {self.sigma_max:g} in "
                f"{self.omega_band[0]:g} <= omega <= {self.omega_band[1]:g} on {model.disc.name}"
            )
        first = min(chart.regions, key=lambda r: r.sigma_threshold)
        return first.sigma_threshold if self.name == "sigma_threshold" else first.omega_threshold

    def _critical(self, model) -> float:
        """v_cr or the frequency of the critical event, in 3-D or in one plane."""
        from fempipe.analyses.stability import PLANES, find_critical_velocity

        name, plane = self.name, "3-D"
        for suffix, which in (("_in_plane", "in"), ("_out_of_plane", "out")):
            if name.endswith(suffix):
                name, plane = name.removesuffix(suffix), which
        if self.planar:
            plane = "in"
        kw = {"v_max": self.v_max, "v_min": self.params.v}
        planes = PLANES if plane == "3-D" else (plane,)
        res = find_critical_velocity(model, planes=planes, **kw)
        if res.v_cr is None:
            where = {"3-D": "", "in": " in its plane", "out": " out of its plane"}[plane]
            raise SolverError(
                f"the primary branch is stable{where} over {self.params.v:g} <= v <= "
                f"{self.v_max:g} on {model.disc.name}: no v_cr in the range"
            )
        return float(res.v_cr if name == "v_cr" else res.critical.frequency)

    def cycle(self, disc):
        """The limit cycle of ``disc`` (from :attr:`seed` if given, else a transient)."""
        from fempipe.analyses.limit_cycle import ShootingError, find_attractor, shoot
        from fempipe.model.dynamics_problem import PipeDynamics
        from fempipe.model.plane.operators import PipeModel

        model = PipeModel(disc, self.params)
        rtol = self.shoot_rtol
        if self.seed is not None:
            src, q0, p0, period = self.seed
            q, p = project(src, q0, disc), project(src, p0, disc)
            try:
                return shoot(PipeDynamics(model), q, p, period, rtol=rtol, tol=10 * rtol)
            except ShootingError:
                pass  # too far from the seed: find the attractor from the static state
        att = find_attractor(model, shoot_rtol=rtol, shoot_tol=10 * rtol)
        if att.kind != "periodic" or att.cycle is None:
            raise SolverError(
                f"no limit cycle at v = {self.params.v:g} on {disc.name}: the attractor is "
                f"{att.kind}"
            )
        return att.cycle

    def seeded(self, disc) -> Quantity:
        """A copy whose limit cycles start from the cycle of ``disc`` (computed once)."""
        if self.name not in CYCLE_QUANTITIES:
            return self
        c = self.cycle(disc)
        return replace(self, seed=(disc, c.q0, c.qdot0, c.period))

    def to_dict(self) -> dict:
        out = {"name": self.name, "description": self.describe(), "unit": QUANTITIES[self.name][1]}
        if self.name in CRITICAL_QUANTITIES:
            out["v_range"] = [self.params.v, self.v_max]
        else:
            out["v"] = self.params.v
        if self.name == "eigenvalue":
            out["mode"] = int(self.mode)
        if self.name in CYCLE_QUANTITIES:
            out["shoot_rtol"] = self.shoot_rtol
        if self.planar and self.name in ("v_cr", "frequency"):
            out["planar"] = True
        return out


def static_tip_state(disc, params: Params) -> np.ndarray:
    """The static state at ``params.v`` on the primary branch, followed from v = 0 by
    :func:`~fempipe.analyses.statics.solve_path` to :data:`STATIC_TOL`."""
    from fempipe.analyses.statics import solve_path
    from fempipe.model.plane.operators import PipeModel

    v = params.v
    # Steps of at most 0.5 in v keep the path on the branch the pipe follows
    # as the flow is turned up (the branch of `fempipe static`).
    values = np.linspace(0.0, v, max(2, math.ceil(v / 0.5) + 1)) if v > 0 else [0.0]
    model = PipeModel(disc, replace(params, v=0.0))
    return solve_path(model, values, tol=STATIC_TOL)[-1].q


def _static_tip(model, key: str) -> float:
    q = static_tip_state(model.disc, model.params)
    return float(compute_tip(model.disc, q, model.params.alpha)[key])


def _eigenvalue(model, mode: int) -> complex:
    from fempipe.analyses.stability import compute_spectrum

    q = static_tip_state(model.disc, model.params)
    spec = compute_spectrum(model, q)
    upper = [(m, lam) for m, lam in zip(spec.mode, spec.lam, strict=True) if lam.imag >= 0]
    for m, lam in upper:
        if int(m) == int(mode):
            return complex(lam)
    raise SolverError(
        f"mode {mode} is not among the resolved modes of {model.disc.name} at v = {model.params.v:g} "
        f"(resolved: {sorted({int(m) for m, _ in upper})})"
    )

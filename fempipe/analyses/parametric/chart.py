"""The chart of parametric resonance: every region of (omega, sigma).

Every principal and combination resonance with nominal frequency in the band that opens for
sigma up to the largest requested.  On the straight pipe (alpha = 0, pi; round and
axisymmetric) every region holds in both planes; a bent pipe's regions are those of its forced
periodic response (:mod:`.forced`), in the plane and out of it, each plane with its own
frequencies.  Derivation: docs/theory/parametric.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.stability import compute_spectrum
from fempipe.analyses.stability.linear import straight_is_static
from fempipe.analyses.statics import solve_sagged
from fempipe.core.parallel import single_blas
from fempipe.model.out_of_plane.model import STRAIGHT_TOL, axisymmetric, build_out_of_plane_model
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from .floquet import PulsationPencil, ReducedPulsation
from .forced import ForcedResponse, solve_forced_response
from .regions import Candidate, ParametricRegion, candidates, locate_region

__all__ = ["ParametricChart", "compute_parametric_chart"]

#: Half-width of the frequency window searched for a region's tip, relative to its nominal
#: frequency (also bounded by the midpoints to the neighbouring candidates).
TIP_WINDOW = 0.15


@dataclass(frozen=True)
class ParametricChart:
    """The regions of instability of a pulsating flow in the (omega, sigma) plane.

    ``params`` has v = v0; ``eigenvalues`` are the mean flow's about its static state, one per
    oscillating mode (damped below the ratio 1/sqrt(2); their imaginary parts the omega_k),
    numbered ``modes`` as :func:`~fempipe.analyses.stability.compute_spectrum` does, in the
    plane (on the straight pipe: in both); ``eigenvalues_out_of_plane``, ``modes_out_of_plane``
    those out of the plane of a bent pipe (else empty).  ``regions`` by increasing threshold
    frequency; ``closed`` the candidates that stay closed up to max(``sigmas``);
    ``evaluations`` the monodromy matrices computed (on a bent pipe: forced orbits solved);
    ``straight`` whether about the straight state (every region in both planes).
    """

    params: Params
    discretization: dict
    band: tuple[float, float]
    sigmas: tuple[float, ...]
    eigenvalues: tuple[complex, ...]
    modes: tuple[int, ...]
    regions: tuple[ParametricRegion, ...]
    closed: tuple[Candidate, ...]
    omega_tol: float
    sigma_tol: float
    evaluations: int
    eigenvalues_out_of_plane: tuple[complex, ...] = ()
    modes_out_of_plane: tuple[int, ...] = ()
    straight: bool = True

    @property
    def frequencies(self) -> tuple[float, ...]:
        return tuple(float(lam.imag) for lam in self.eigenvalues)

    @property
    def frequencies_out_of_plane(self) -> tuple[float, ...]:
        return tuple(float(lam.imag) for lam in self.eigenvalues_out_of_plane)

    def to_dict(self) -> dict:
        """The JSON of ``fempipe parametric``: on the straight pipe each region once per plane."""
        regions = [
            {
                "mode": list(r.candidate.mode),
                "kind": r.candidate.kind,
                "order": r.candidate.order,
                "plane": plane,
                "omega_nominal": r.candidate.omega,
                "sigma_threshold": r.sigma_threshold,
                "omega_threshold": r.omega_threshold,
                "multiplier": [r.multiplier.real, r.multiplier.imag],
                "boundary": [list(row) for row in r.boundary],
            }
            for r in self.regions
            for plane in ((r.candidate.plane,) if r.candidate.plane else ("in", "out"))
        ]
        out = {
            "params": self.params.to_dict(),
            "discretization": self.discretization,
            "v0": self.params.v,
            "omega_band": list(self.band),
            "sigmas": list(self.sigmas),
            "modes": list(self.modes),
            "frequencies": list(self.frequencies),
            "eigenvalues": [[lam.real, lam.imag] for lam in self.eigenvalues],
            "regions": regions,
            "closed": [
                {
                    "mode": list(c.mode),
                    "kind": c.kind,
                    "order": c.order,
                    "plane": c.plane,
                    "omega_nominal": c.omega,
                }
                for c in self.closed
            ],
            "omega_tol": self.omega_tol,
            "sigma_tol": self.sigma_tol,
            "evaluations": self.evaluations,
        }
        if self.straight:
            out["planes_note"] = "straight pipe: the motion out of the plane is the motion in it"
        else:
            out["modes_out_of_plane"] = list(self.modes_out_of_plane)
            out["frequencies_out_of_plane"] = list(self.frequencies_out_of_plane)
            out["eigenvalues_out_of_plane"] = [
                [lam.real, lam.imag] for lam in self.eigenvalues_out_of_plane
            ]
        return out


class _ForcedMultipliers:
    """(sigma, omega) -> the multipliers of a bent pipe's forced orbit in one plane; each
    orbit solved once (for both planes) from the nearest one solved before."""

    def __init__(self, model: PipeModel, steps: int, rtol: float, out_of_plane: bool) -> None:
        self.model, self.steps, self.rtol, self.out_of_plane = model, steps, rtol, out_of_plane
        self.orbits: dict[tuple[float, float], ForcedResponse] = {}

    def orbit(self, sigma: float, omega: float) -> ForcedResponse:
        key = (float(sigma), float(omega))
        found = self.orbits.get(key)
        if found is None:
            near = min(
                self.orbits,
                key=lambda k: abs(k[0] - sigma) + abs(k[1] - omega) / omega,
                default=None,
            )
            guess = None if near is None else (self.orbits[near].q0, self.orbits[near].qdot0)
            found = self.orbits[key] = solve_forced_response(
                self.model,
                sigma,
                omega,
                guess=guess,
                steps=self.steps,
                rtol=self.rtol,
                out_of_plane=self.out_of_plane,
            )
        return found

    def plane(self, plane: str) -> Callable[[float, float], np.ndarray]:
        if plane == "in":
            return lambda s, w: self.orbit(s, w).multipliers
        if not axisymmetric(self.model.params):
            return lambda s, w: self.orbit(s, w).out_of_plane_multipliers

        def turned_apart(s: float, w: float) -> np.ndarray:
            # the buckled standing pipe: its orbit turned about the vertical is one too
            rho = self.orbit(s, w).out_of_plane_multipliers
            return np.delete(rho, np.argmin(np.abs(rho - 1.0)))

        return turned_apart


def _oscillating(model: PipeModel, q: np.ndarray, spectrum=None) -> dict[int, complex]:
    """Mode number -> eigenvalue of each mode damped below the critical ratio 1/sqrt(2) (a
    mode damped more, or overdamped, is not a resonator); ``spectrum`` at q if computed."""
    if spectrum is None:
        spectrum = compute_spectrum(model, q)
    if spectrum.max_real >= 0:
        raise ValueError(
            f"v0 = {model.params.v:g}: the pipe is already unstable without pulsation"
            + ("" if model.plane == "in" else " (out of the plane)")
        )
    modes: dict[int, complex] = {}
    for lam, k in zip(spectrum.lam, spectrum.mode, strict=True):
        if lam.imag > -lam.real:
            modes.setdefault(int(k), complex(lam))
    return modes


def _character_fits(candidate: Candidate, rho: complex) -> bool:
    """Whether the critical multiplier is of the kind of the resonance: -1 for an odd-order
    principal region, +1 for an even one, a complex pair for a combination."""
    real = abs(rho.imag) < 1e-6
    if candidate.kind == "principal":
        return real and (rho.real < 0) == (candidate.order % 2 == 1)
    return not real


def _same_tip(a: ParametricRegion, b: ParametricRegion) -> bool:
    return math.isclose(a.omega_threshold, b.omega_threshold, rel_tol=1e-4) and math.isclose(
        a.sigma_threshold, b.sigma_threshold, rel_tol=1e-4
    )


def _scan(
    found: list[Candidate],
    source,
    band: tuple[float, float],
    sigmas: tuple[float, ...],
    callback,
    **kw,
) -> tuple[list[ParametricRegion], list[Candidate], int]:
    """The regions of the candidates ``found`` (by increasing omega) for the multipliers of
    ``source``: each tip searched between its neighbours' nominal frequencies."""
    lo, hi = band
    regions, closed, evaluations = [], [], 0
    for i, cand in enumerate(found):
        left = 0.5 * (found[i - 1].omega + cand.omega) if i > 0 else lo
        right = 0.5 * (cand.omega + found[i + 1].omega) if i + 1 < len(found) else hi
        window = (
            max(lo, left, cand.omega * (1 - TIP_WINDOW)),
            min(hi, right, cand.omega * (1 + TIP_WINDOW)),
        )
        region, count = locate_region(source, cand, window, sigmas, limits=(lo, hi), **kw)
        evaluations += count
        if region is not None and not _character_fits(cand, region.multiplier):
            region = None
        twin = next((r for r in regions if region is not None and _same_tip(r, region)), None)
        if twin is not None:  # one region found from two candidates: the nearer names it
            if abs(cand.omega - region.omega_threshold) < abs(
                twin.candidate.omega - twin.omega_threshold
            ):
                regions[regions.index(twin)] = region
                closed.append(twin.candidate)
            else:
                closed.append(cand)
        elif region is None:
            closed.append(cand)
        else:
            regions.append(region)
        if callback is not None:
            callback(cand, region)
    return regions, closed, evaluations


@single_blas
def compute_parametric_chart(
    model: PipeModel,
    v0: float,
    band: tuple[float, float],
    sigmas: Sequence[float],
    *,
    max_order: int = 2,
    pairs: int | None = None,
    omega_tol: float = 1e-8,
    sigma_tol: float = 1e-8,
    steps: int | None = None,
    forced_rtol: float = 1e-6,
    planes: Sequence[str] = ("in", "out"),
    callback: Callable[[Candidate, ParametricRegion | None], None] | None = None,
) -> ParametricChart:
    """Every region of parametric resonance with frequency in ``band``.

    Parameters
    ----------
    model : PipeModel
        Any alpha; its v is replaced by ``v0`` (below v_cr).  At alpha = 0, pi the straight
        state (Floquet on a Ritz basis, :mod:`.floquet`), else the forced periodic response
        (:mod:`.forced`).
    v0 : float
    band : (float, float)
        The pulsation frequencies searched, 0 < lo < hi.
    sigmas : sequence of float
        Amplitudes in (0, 1] of the boundaries; the largest bounds the threshold search.
    max_order : int
        The largest order n searched (omega near 2 omega_k / n).
    pairs : int, optional
        Straight pipe: modes of the mean flow in the Ritz basis (default: up to the band's
        top, and one more).
    omega_tol, sigma_tol : float
        Relative tolerances of the edges and of the thresholds.
    steps : int, optional
        Radau IIA steps per period (default 128 about the straight state; on a bent pipe at
        least 32, more where ``forced_rtol`` asks for them).
    forced_rtol : float
        Bent pipe: the integrator's tolerance on the forced orbit.
    planes : sequence of {"in", "out"}
        Bent pipe: the planes searched (the straight pipe's regions hold in both).
    callback : callable, optional
        ``callback(candidate, region_or_None)`` after each candidate.
    """
    lo, hi = float(band[0]), float(band[1])
    if not (math.isfinite(lo) and math.isfinite(hi)) or not 0 < lo < hi:
        raise ValueError(f"need 0 < omega_lo < omega_hi, got omega = {lo}:{hi}")
    sigmas = tuple(sorted(float(s) for s in sigmas))
    if not sigmas or not all(0 < s <= 1 for s in sigmas):
        raise ValueError(f"every sigma must satisfy 0 < sigma <= 1, got {list(sigmas)}")
    if max_order < 1:
        raise ValueError(f"max_order must be >= 1, got {max_order}")
    planes = tuple(dict.fromkeys(planes))
    if not planes or not set(planes) <= {"in", "out"}:
        raise ValueError(f"planes must be 'in' and/or 'out', got {planes}")
    model = model.with_params(replace(model.params, v=float(v0)))
    q = np.zeros(model.n)
    spectrum = compute_spectrum(model, q) if straight_is_static(model.params) else None
    if spectrum is None or spectrum.max_real >= 0:  # bent, or buckled by its weight
        q, spectrum = solve_sagged(model).q, None
    straight = float(np.max(np.abs(q))) <= STRAIGHT_TOL
    if steps is None:
        steps = 128 if straight else 32
    kw = {"omega_tol": omega_tol, "sigma_tol": sigma_tol, "steps": steps}
    out_modes: dict[int, complex] = {}
    if straight:
        modes = _oscillating(model, q, spectrum)
        numbers = sorted(modes)
        if pairs is None:
            pairs = max(3, sum(modes[k].imag <= hi for k in numbers) + 1)
        kept = numbers[: min(pairs, len(numbers))]
        modes = {k: modes[k] for k in kept}
        reduced = ReducedPulsation(PulsationPencil.of(model), v0, targets=list(modes.values()))
        found = candidates({k: lam.imag for k, lam in modes.items()}, (lo, hi), max_order)
        regions, closed, evaluations = _scan(found, reduced, (lo, hi), sigmas, callback, **kw)
    else:
        modes = _oscillating(model, q) if "in" in planes else {}
        if "out" in planes:
            out_modes = _oscillating(build_out_of_plane_model(model), q)
        source = _ForcedMultipliers(model, steps, forced_rtol, "out" in planes)
        regions, closed, evaluations = [], [], 0
        for plane, ms in (("in", modes), ("out", out_modes)):
            if plane not in planes:
                continue
            found = candidates({k: lam.imag for k, lam in ms.items()}, (lo, hi), max_order, plane)
            r, c, _ = _scan(found, source.plane(plane), (lo, hi), sigmas, callback, **kw)
            regions, closed = regions + r, closed + c
        evaluations = len(source.orbits)
    return ParametricChart(
        params=model.params,
        discretization={"name": model.disc.name, **model.disc.to_dict()},
        band=(lo, hi),
        sigmas=sigmas,
        eigenvalues=tuple(modes.values()),
        modes=tuple(modes),
        regions=tuple(sorted(regions, key=lambda r: r.omega_threshold)),
        closed=tuple(closed),
        omega_tol=omega_tol,
        sigma_tol=sigma_tol,
        evaluations=evaluations,
        eigenvalues_out_of_plane=tuple(out_modes.values()),
        modes_out_of_plane=tuple(out_modes),
        straight=straight,
    )

"""The chart of parametric resonance of the straight pipe: every region of (omega, sigma).

Every principal and combination resonance with nominal frequency in the band that opens for
sigma up to the largest requested; on the straight (round, axisymmetric) pipe every region
holds in both planes.  Derivation: docs/theory/parametric.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import numpy as np

from fempipe.analyses.stability import compute_spectrum
from fempipe.core.parallel import single_blas
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from .floquet import PulsationPencil, ReducedPulsation
from .regions import Candidate, ParametricRegion, candidates, locate_region

__all__ = ["ParametricChart", "compute_parametric_chart"]

#: Half-width of the frequency window searched for a region's tip, relative to its nominal
#: frequency (also bounded by the midpoints to the neighbouring candidates).
TIP_WINDOW = 0.15


@dataclass(frozen=True)
class ParametricChart:
    """The regions of instability of a pulsating flow in the (omega, sigma) plane.

    ``params`` has v = v0; ``eigenvalues`` are the mean flow's, one per oscillating mode
    (damped below the ratio 1/sqrt(2); their imaginary parts the omega_k), numbered ``modes``
    as :func:`~fempipe.analyses.stability.compute_spectrum` does; ``regions`` by increasing
    threshold frequency; ``closed`` the candidates that stay closed up to max(``sigmas``);
    ``evaluations`` the monodromy matrices computed.
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

    @property
    def frequencies(self) -> tuple[float, ...]:
        return tuple(float(lam.imag) for lam in self.eigenvalues)

    def to_dict(self) -> dict:
        """The JSON of ``fempipe parametric``: each region once per plane."""
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
            for plane in ("in", "out")
        ]
        return {
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
                {"mode": list(c.mode), "kind": c.kind, "order": c.order, "omega_nominal": c.omega}
                for c in self.closed
            ],
            "planes_note": "straight pipe: the motion out of the plane is the motion in it",
            "omega_tol": self.omega_tol,
            "sigma_tol": self.sigma_tol,
            "evaluations": self.evaluations,
        }


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
    steps: int = 128,
    callback: Callable[[Candidate, ParametricRegion | None], None] | None = None,
) -> ParametricChart:
    """Every region of parametric resonance of the straight pipe with frequency in ``band``.

    Parameters
    ----------
    model : PipeModel
        alpha = 0 or pi; its v is replaced by ``v0`` (below v_cr).
    v0 : float
    band : (float, float)
        The pulsation frequencies searched, 0 < lo < hi.
    sigmas : sequence of float
        Amplitudes in (0, 1] of the boundaries; the largest bounds the threshold search.
    max_order : int
        The largest order n searched (omega near 2 omega_k / n).
    pairs : int, optional
        Modes of the mean flow in the Ritz basis (default: up to the band's top, and one more).
    omega_tol, sigma_tol : float
        Relative tolerances of the edges and of the thresholds.
    steps : int
        Radau IIA steps per period.
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
    model = model.with_params(replace(model.params, v=float(v0)))
    pencil = PulsationPencil.of(model)
    mean = compute_spectrum(model, np.zeros(model.n))
    if mean.max_real >= 0:
        raise ValueError(f"v0 = {v0:g}: the straight pipe is already unstable without pulsation")
    # one eigenvalue per oscillating mode: damped below the critical ratio 1/sqrt(2) (a mode
    # damped more, or overdamped, is not a resonator)
    modes: dict[int, complex] = {}
    for lam, k in zip(mean.lam, mean.mode, strict=True):
        if lam.imag > -lam.real:
            modes.setdefault(int(k), complex(lam))
    numbers = sorted(modes)
    if pairs is None:
        pairs = max(3, sum(modes[k].imag <= hi for k in numbers) + 1)
    kept = numbers[: min(pairs, len(numbers))]
    reduced = ReducedPulsation(pencil, v0, targets=[modes[k] for k in kept])
    frequencies = {k: modes[k].imag for k in kept}
    found = candidates(frequencies, (lo, hi), max_order)
    regions, closed, evaluations = [], [], 0
    for i, cand in enumerate(found):
        left = 0.5 * (found[i - 1].omega + cand.omega) if i > 0 else lo
        right = 0.5 * (cand.omega + found[i + 1].omega) if i + 1 < len(found) else hi
        window = (
            max(lo, left, cand.omega * (1 - TIP_WINDOW)),
            min(hi, right, cand.omega * (1 + TIP_WINDOW)),
        )
        region, count = locate_region(
            reduced,
            cand,
            window,
            sigmas,
            limits=(lo, hi),
            omega_tol=omega_tol,
            sigma_tol=sigma_tol,
            steps=steps,
        )
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
    return ParametricChart(
        params=model.params,
        discretization={"name": model.disc.name, **model.disc.to_dict()},
        band=(lo, hi),
        sigmas=sigmas,
        eigenvalues=tuple(modes[k] for k in kept),
        modes=tuple(kept),
        regions=tuple(sorted(regions, key=lambda r: r.omega_threshold)),
        closed=tuple(closed),
        omega_tol=omega_tol,
        sigma_tol=sigma_tol,
        evaluations=evaluations,
    )

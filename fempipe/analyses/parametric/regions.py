"""The regions of the (omega, sigma) plane where a pulsating flow destabilizes the straight pipe.

Each candidate (principal, omega ~ 2 omega_k / n; combination, (omega_j +- omega_k) / n) has
a threshold, the least sigma at which the largest multiplier reaches modulus 1, and at each
requested sigma a boundary, where that modulus crosses 1.  Derivation: docs/theory/parametric.md.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq, minimize_scalar

from .floquet import ReducedPulsation, floquet_multipliers

__all__ = ["Candidate", "ParametricRegion", "candidates", "locate_region"]


@dataclass(frozen=True)
class Candidate:
    """A resonance that may open a region: its nominal frequency and what it involves.

    ``kind`` is "principal" (omega = 2 omega_k / order), "sum" or "difference" (omega =
    (omega_j +- omega_k) / order); ``mode`` the mode numbers (1 = the lowest frequency);
    ``plane`` "in" or "out" of the plane of a bent pipe, None on the straight pipe (both).
    """

    kind: str
    order: int
    mode: tuple[int, ...]
    omega: float
    plane: str | None = None


@dataclass(frozen=True)
class ParametricRegion:
    """One region of instability: its threshold and its boundary.

    Attributes
    ----------
    candidate : Candidate
    sigma_threshold, omega_threshold : float
    multiplier : complex
        The critical multiplier at the threshold (real < 0 odd principal, > 0 even, complex
        combination).
    boundary : tuple of (sigma, omega_lo, omega_hi)
        At each requested sigma from the threshold; ``nan`` where the region runs into another
        or out of the band.
    evaluations : int
    """

    candidate: Candidate
    sigma_threshold: float
    omega_threshold: float
    multiplier: complex
    boundary: tuple[tuple[float, float, float], ...] = field(default=())
    evaluations: int = 0


def candidates(
    frequencies: Mapping[int, float] | Sequence[float],
    band: tuple[float, float],
    max_order: int = 2,
    plane: str | None = None,
) -> list[Candidate]:
    """Every principal and combination resonance of ``frequencies`` (mode number ->
    frequency, or a sequence numbered from 1) whose nominal frequency lies in ``band``, by
    increasing omega; in ``plane``."""
    if not isinstance(frequencies, Mapping):
        frequencies = dict(enumerate(frequencies, start=1))
    lo, hi = band
    out = []
    for order in range(1, max_order + 1):
        for k, w in frequencies.items():
            out.append(Candidate("principal", order, (k,), 2.0 * w / order, plane))
        for (j, wj), (k, wk) in itertools.combinations(sorted(frequencies.items()), 2):
            out.append(Candidate("sum", order, (j, k), (wj + wk) / order, plane))
            out.append(Candidate("difference", order, (j, k), abs(wk - wj) / order, plane))
    return sorted((c for c in out if lo <= c.omega <= hi), key=lambda c: c.omega)


class _Margin:
    """log of the largest multiplier's modulus (> 0: unstable), counting evaluations.

    ``source`` is a :class:`ReducedPulsation` (the straight pipe) or any callable
    ``(sigma, omega) -> multipliers`` (e.g. the forced response of a bent pipe).
    """

    def __init__(self, source, steps: int) -> None:
        if isinstance(source, ReducedPulsation):
            self.source = lambda s, w: floquet_multipliers(source, s, w, steps)
        else:
            self.source = source
        self.count = 0

    def multipliers(self, sigma: float, omega: float) -> np.ndarray:
        self.count += 1
        rho = np.asarray(self.source(sigma, omega))
        return rho[np.argsort(-np.abs(rho))]

    def __call__(self, sigma: float, omega: float) -> float:
        return float(np.log(np.abs(self.multipliers(sigma, omega)[0])))


def _edge(margin: Callable[[float], float], inside: float, limit: float, tol: float) -> float:
    """The frequency between ``inside`` (unstable) and ``limit`` where the margin crosses 0,
    bracketed by steps that double outward up to 1/16 of the way (a stable gap narrower than
    that may be stepped over); nan if it stays unstable up to ``limit``."""
    span = abs(limit - inside)
    step, cap = 1e-3 * span, span / 16
    a = b = inside
    while True:
        b = b + math.copysign(min(step, abs(limit - b)), limit - inside)
        if margin(b) < 0:
            break
        if b == limit:
            return math.nan
        a, step = b, min(2 * step, cap)
    return brentq(margin, a, b, xtol=tol * max(1.0, abs(b)), rtol=4 * np.finfo(float).eps)


def locate_region(
    reduced: ReducedPulsation | Callable[[float, float], np.ndarray],
    candidate: Candidate,
    window: tuple[float, float],
    sigmas: Sequence[float],
    *,
    limits: tuple[float, float] | None = None,
    omega_tol: float = 1e-8,
    sigma_tol: float = 1e-8,
    steps: int = 128,
) -> tuple[ParametricRegion | None, int]:
    """The region of ``candidate`` whose tip lies in ``window``, and the monodromy matrices
    computed, for the multipliers of ``reduced`` (or of a callable (sigma, omega) -> them).

    None if it stays closed up to max(``sigmas``), or if the instability in the window is
    strongest at its edge down to where it closes (the tip of another candidate's region).
    Edges are searched up to ``limits`` (default the window).
    """
    margin = _Margin(reduced, steps)
    level = float(max(sigmas))
    lo, hi = window
    limits = tuple(limits if limits is not None else window)
    # where the region is widest open: a grid, then Brent, at a sigma low enough for the
    # widest point to lie inside the window (a wide region leans on its neighbours)
    grid = np.linspace(lo, hi, 17)
    while True:
        values = [margin(level, w) for w in grid]
        k = int(np.argmax(values))
        if values[k] <= 0 or level < 1e-3 * max(sigmas):
            return None, margin.count
        if k not in (0, grid.size - 1):
            break
        if grid[k] in limits:  # widest at the band's end: its tip may still lie inside
            k = min(max(k, 1), grid.size - 2)
            break
        level *= 0.5
    best = minimize_scalar(
        lambda w: -margin(level, w), bounds=(grid[k - 1], grid[k + 1]), method="bounded"
    )
    peak = float(best.x)
    # its edges at that sigma bound the frequencies where it opens first
    edges = [_edge(lambda w: margin(level, w), peak, x, omega_tol) for x in limits]
    span = tuple(x if math.isnan(e) else e for x, e in zip(limits, edges, strict=True))

    def critical_sigma(w: float) -> float:
        if margin(level, w) <= 0:
            return level
        if margin(0.0, w) >= 0:
            return 0.0
        return brentq(lambda s: margin(s, w), 0.0, level, xtol=sigma_tol)

    # sigma_c is flat at its minimum: an error d in omega costs O(d^2) in sigma
    xatol = math.sqrt(sigma_tol) * max(1.0, peak)
    tip = minimize_scalar(critical_sigma, bounds=span, method="bounded", options={"xatol": xatol})
    sigma_th, omega_th = float(tip.fun), float(tip.x)
    if min(abs(omega_th - x) for x in limits) <= 10 * xatol:  # the tip lies beyond the band
        return None, margin.count
    rho = margin.multipliers(sigma_th, omega_th)[0]
    rows = []
    for s in sorted(sigmas):
        if s < sigma_th:
            continue
        inside = omega_th
        if margin(s, inside) <= 0:  # a tilted region: its widest point at this sigma
            inside = float(
                minimize_scalar(lambda w, s=s: -margin(s, w), bounds=span, method="bounded").x
            )
        edges = [_edge(lambda w, s=s: margin(s, w), inside, x, omega_tol) for x in limits]
        rows.append((float(s), *edges))
    region = ParametricRegion(
        candidate, sigma_th, omega_th, complex(rho), tuple(rows), evaluations=margin.count
    )
    return region, margin.count

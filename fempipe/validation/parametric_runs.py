"""What the ``parametric`` case computes: regions, a scan of the band, the classical multipliers.

The regions are fempipe's chart (:func:`~fempipe.analyses.parametric.compute_parametric_chart`)
or, for one candidate, its :func:`~fempipe.analyses.parametric.locate_region`; the scan and
the comparison with :class:`~.classical_pulsation.ClassicalPulsation` evaluate Floquet
multipliers at given points.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import brentq

from fempipe.analyses.parametric import (
    Candidate,
    ParametricRegion,
    PulsationPencil,
    ReducedPulsation,
    candidates,
    compute_parametric_chart,
    floquet_multipliers,
    locate_region,
)
from fempipe.analyses.parametric.chart import TIP_WINDOW
from fempipe.analyses.stability import compute_spectrum
from fempipe.core.parallel import single_blas
from fempipe.model.discretization import Modal, parse_discretization
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from . import classical
from .classical_pulsation import ClassicalPulsation

#: The candidate every run locates: the principal primary region of the second mode.
PRINCIPAL_2 = ("principal", 1, (2,))


def model_of(label: str, params: Params) -> PipeModel:
    """The model on ``"FE Pk:n"`` or ``"N = n"`` (the paper's sine modes)."""
    if label.startswith("N = "):
        return PipeModel(Modal(int(label[4:]), basis="sine"), params)
    return PipeModel(parse_discretization(fe=label.removeprefix("FE ")), params)


def spectrum_of(model: PipeModel) -> dict[int, complex]:
    """The mean flow's eigenvalue of each mode (Im >= 0), by mode number."""
    sp = compute_spectrum(model, np.zeros(model.n))
    out: dict[int, complex] = {}
    for lam, k in zip(sp.lam, sp.mode, strict=True):
        if lam.imag >= 0:
            out.setdefault(int(k), complex(lam))
    return out


@dataclass(frozen=True)
class Regions:
    """One discretization's regions at one v0: ``closed`` the chart's closed candidates,
    ``spectrum`` its mean flow's eigenvalues by mode."""

    label: str
    regions: tuple[ParametricRegion, ...]
    spectrum: dict
    closed: tuple[Candidate, ...] = ()
    charted: bool = False

    @property
    def principal(self) -> ParametricRegion | None:
        """The principal primary region of the second mode (None if it stays closed)."""
        return next((r for r in self.regions if _key(r.candidate) == PRINCIPAL_2), None)

    def edges(self, sigma: float) -> tuple[float, float]:
        """The principal region's edges at ``sigma`` (nan: not found or not computed)."""
        return edges_at(self.principal, sigma)


def edges_at(region: ParametricRegion | None, sigma: float) -> tuple[float, float]:
    """A region's edges at ``sigma`` (nan: not found or not computed)."""
    rows = [row for row in (region.boundary if region else ()) if math.isclose(row[0], sigma)]
    return (rows[0][1], rows[0][2]) if rows else (math.nan, math.nan)


def _key(c: Candidate) -> tuple:
    return (c.kind, c.order, tuple(c.mode))


def chart_regions(label: str, params: Params, band, sigmas) -> Regions:
    """Every region of fempipe's chart on ``label``."""
    model = model_of(label, params)
    chart = compute_parametric_chart(model, params.v, band, sigmas)
    return Regions(label, chart.regions, spectrum_of(model), chart.closed, charted=True)


@single_blas
def principal_region(label: str, params: Params, band, sigmas, modes, steps=128) -> Regions:
    """The principal region of the second mode alone, on a Ritz basis of ``modes``, searched
    as the chart searches a candidate (window of :data:`TIP_WINDOW` about 2 omega_2)."""
    model = model_of(label, params)
    spectrum = spectrum_of(model)
    reduced = _reduced(model, spectrum, modes)
    w = 2.0 * spectrum[2].imag
    window = (max(band[0], w * (1 - TIP_WINDOW)), min(band[1], w * (1 + TIP_WINDOW)))
    cand = Candidate(*PRINCIPAL_2, w)
    region, _ = locate_region(reduced, cand, window, sigmas, limits=band, steps=steps)
    return Regions(label, () if region is None else (region,), spectrum)


def ritz(label: str, params: Params, spectrum: dict, modes) -> ReducedPulsation:
    """fempipe's reduced pulsating problem on the Ritz basis of ``modes``."""
    return _reduced(model_of(label, params), spectrum, modes)


def _reduced(model: PipeModel, spectrum: dict, modes) -> ReducedPulsation:
    return ReducedPulsation(
        PulsationPencil.of(model), model.params.v, targets=[spectrum[k] for k in modes]
    )


def nominal_points(spectrum: dict, band, modes=(1, 2, 3, 4)) -> list[float]:
    """The nominal frequencies of every candidate of ``modes`` (orders 1, 2) in ``band``."""
    freqs = {k: spectrum[k].imag for k in modes if k in spectrum}
    return sorted({round(c.omega, 10) for c in candidates(freqs, band)})


@single_blas
def scan(reduced: ReducedPulsation, omegas, sigmas) -> list[tuple[float, float, float, bool]]:
    """``(sigma, omega, max |rho|, a complex multiplier outside the unit circle)`` per point."""
    out = []
    for s in sigmas:
        for w in omegas:
            rho = floquet_multipliers(reduced, s, w)
            out_of = np.abs(rho) > 1.0
            pair = bool(np.any(out_of & (np.abs(rho.imag) > 1e-6 * np.abs(rho))))
            out.append((float(s), float(w), float(abs(rho[0])), pair))
    return out


def _inside(region: ParametricRegion, sigma: float, omega: float) -> bool | None:
    """Whether the chart puts (sigma, omega) in ``region``; None where it did not find the edge
    (between the threshold and the band's end on that side)."""
    if sigma < region.sigma_threshold:
        return False
    lo, hi = edges_at(region, sigma)
    below = omega < region.omega_threshold
    if math.isnan(lo if below else hi):
        return None
    return lo < omega if below else omega < hi


def scan_verdict(points, regions: Regions, quasi_static=lambda s: False) -> tuple[list, ...]:
    """The scanned points where the scan and the chart disagree, those the chart leaves open
    (:func:`_inside` None), and those unstable outside every region at a sigma where
    ``quasi_static(sigma)`` (the flow exceeds v_cr for part of each period: an instability the
    chart does not search); the scan's sigmas must be the chart's."""
    wrong, unknown, quasi = [], [], []
    for s, w, rho, _ in points:
        verdicts = [_inside(r, s, w) for r in regions.regions]
        if rho > 1.0 and not any(verdicts) and None not in verdicts and quasi_static(s):
            quasi.append((s, w, rho))
        elif True in verdicts or None not in verdicts:
            if (rho > 1.0) != (True in verdicts):
                wrong.append((s, w, rho))
        else:
            unknown.append((s, w, rho))
    return wrong, unknown, quasi


@single_blas
def scan_edges(reduced: ReducedPulsation, unknown, xtol: float = 1e-8) -> dict:
    """Where the chart found no edge (``unknown`` of :func:`scan_verdict`): the frequencies
    where stability changes between neighbouring scanned points, by Brent's method on
    log max |rho|; ``{sigma: [omega, ...]}``."""
    out = {}
    for s in sorted({pt[0] for pt in unknown}):
        row = sorted((w, x > 1.0) for t, w, x in unknown if t == s)
        out[s] = [
            brentq(lambda om, s=s: _log(floquet_multipliers(reduced, s, om)), a, b, xtol=xtol * b)
            for (a, ua), (b, ub) in zip(row, row[1:], strict=False)
            if ua != ub
        ]
    return out


def deviation(fe: np.ndarray, cl: np.ndarray, count: int = 2) -> float:
    """Largest distance of the ``count`` largest FE multipliers to the nearest classical one."""
    return max(float(np.min(np.abs(cl - r))) for r in fe[:count])


def crossing(lo: tuple[float, float], hi: tuple[float, float]) -> float:
    """The sigma where log|rho| crosses 0, linear between ``(sigma, log|rho|)`` pairs
    ``lo``, ``hi`` (nan unless it changes sign there)."""
    (s0, m0), (s1, m1) = lo, hi
    return s0 + (s1 - s0) * m0 / (m0 - m1) if m0 < 0.0 < m1 else math.nan


def _exp(pipe, v: float, p: int, period: float) -> np.ndarray:
    """exp(lambda T) of the classical eigenvalues on Legendre degree ``p``, largest first."""
    rho = np.exp(classical.eigenvalues(pipe, v, method="legendre", n=p) * period)
    return rho[np.argsort(-np.abs(rho))]


def _log(rho: np.ndarray) -> float:
    return float(np.log(abs(rho[0])))


@dataclass
class ClassicalRuns:
    """The classical theory at the FE threshold of one v0: multipliers at ``points``
    (name -> (sigma, omega, FE, classical)), the critical amplitudes at omega_th."""

    points: dict = field(default_factory=dict)
    fe_sigma: float = math.nan
    classical_sigma: float = math.nan
    converged: dict = field(default_factory=dict)
    without_acceleration: np.ndarray | None = None


@single_blas
def classical_runs(ref, params: Params, region: ParametricRegion, reduced, edges, quick: bool):
    """The FE and classical multipliers near and in ``region`` (see the case's references)."""
    pipe = classical.StraightPipe.from_params(params)
    p, rtol = ref.value("classical_p"), ref.value("classical_rtol")
    cl = ClassicalPulsation(pipe, params.v, p, rtol)
    s, w, d = region.sigma_threshold, region.omega_threshold, ref.value("bracket")
    points = {"tip−": (s * (1 - d), w), "tip+": (s * (1 + d), w)}
    if not quick:
        points = {"below": (s / 2, w), **points, "inside": (s + ref.value("inside_step"), w)}
        e = ref.value("edge_sigma")
        points.update({n: (e, x) for n, x in zip(("lower edge", "upper edge"), edges, strict=True)})
    out = ClassicalRuns()
    for name, (sig, om) in points.items():
        if math.isfinite(om):
            fe = floquet_multipliers(reduced, sig, om)
            out.points[name] = (sig, om, fe, cl.multipliers(sig, om))
    (s0, _, f0, c0), (s1, _, f1, c1) = out.points["tip−"], out.points["tip+"]
    out.fe_sigma = crossing((s0, _log(f0)), (s1, _log(f1)))
    out.classical_sigma = crossing((s0, _log(c0)), (s1, _log(c1)))
    # at sigma = 0 the multipliers are exp(lambda T) of the mean flow's classical spectrum
    exact, coarse = (_exp(pipe, params.v, n, 2 * math.pi / w) for n in (16, p))
    out.converged["spectrum"] = deviation(exact, coarse, 4)
    if not quick:
        out.converged["sigma0"] = deviation(exact, cl.multipliers(0.0, w), 4)
        fine = ClassicalPulsation(pipe, params.v, ref.value("classical_p_check"), rtol)
        out.converged["p"] = deviation(c1, fine.multipliers(s1, w))
        bare = ClassicalPulsation(pipe, params.v, p, rtol, acceleration=False)
        out.without_acceleration = bare.multipliers(s1, w)
    return out

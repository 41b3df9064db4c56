"""The classical linear theory of the straight pipe: an independent check of fempipe.

Small lateral motions eta(xi, tau) of a cantilevered pipe conveying fluid (Paidoussis,
*Fluid-Structure Interactions* vol. 1, 1998, Eqs. (3.70)-(3.71)) with end mass, external
damping, hysteretic loss and springs, written from that equation alone (no theta, no weak form
of :mod:`fempipe.model.plane.operators`); valid for the straight pipe only (alpha = 0, pi, or
gamma = 0).  :func:`eigenvalues`, :func:`spectral_abscissa`, :func:`critical_velocity`; the
discretizations (:mod:`.classical_galerkin`) and closed forms (:mod:`.classical_limits`) are
re-exported here.  Derivation and errors: docs/theory/independent.md.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from fempipe.core.parallel import single_blas

from .classical_galerkin import (
    BeamGalerkin,
    LegendreGalerkin,
    beam_mode_values,
    cantilever_roots,
    discretization,
)
from .classical_limits import (
    heavy_column_buckling,
    large_damping_limit,
    stiffness_roots,
    tip_mass_frequencies,
    tip_spring_divergence,
)
from .straight_pipe import StraightPipe

__all__ = [
    "BeamGalerkin",
    "LegendreGalerkin",
    "Onset",
    "StraightPipe",
    "beam_mode_values",
    "cantilever_roots",
    "critical_velocity",
    "discretization",
    "eigenvalues",
    "heavy_column_buckling",
    "large_damping_limit",
    "spectral_abscissa",
    "stiffness_roots",
    "tip_mass_frequencies",
    "tip_spring_divergence",
]

#: Relative size of a real part that counts as unstable (round-off of the
#: undamped problems on the modes that decide is below 1e-11 |lambda|).
TOL = 1e-9
#: Only eigenvalues with |lambda| below this decide stability: the lowest
#: eight modes of the cantilever (lambda_8^2 = 61.7 ... 545; 1000 > mode 9).
LAM_MAX = 1000.0


# Spectra and the critical velocity


class _Problem:
    """A pipe on a discretization, with the v-independent matrices formed once."""

    def __init__(self, pipe: StraightPipe, disc) -> None:
        self.pipe, self.disc = pipe, disc
        self.pieces = disc.pencil(pipe, 1.0)
        self.real_pieces = disc.pencil(replace(pipe, mu_h=0.0)) if pipe.mu_h else None

    def eigenvalues(self, v: float) -> np.ndarray:
        lam = self.disc.solve(self.pieces, v)
        if self.real_pieces is None:
            return lam
        # Hysteretic: Im > 0 from the 1 + i mu_h problem, their conjugates,
        # and the real eigenvalues of the problem without mu_h.
        up = lam[lam.imag > 0.0]
        lam0 = self.disc.solve(self.real_pieces, v)
        real = lam0[np.abs(lam0.imag) <= 1e-10 * np.maximum(1.0, np.abs(lam0))].real
        return np.concatenate([up, up.conj(), real.astype(complex)])


@single_blas
def eigenvalues(
    pipe: StraightPipe, v: float, method: str = "galerkin", n: int | None = None
) -> np.ndarray:
    """The consistent eigenvalues lambda (eta ~ e^{lambda tau}) at ``v``, sorted by |lambda|.

    With hysteretic damping: Im > 0 from 1 + i mu_h, their conjugates and the real ones.
    ``method``, ``n``: the discretization (:func:`discretization`).
    """
    lam = _Problem(pipe, discretization(method, n)).eigenvalues(v)
    return lam[np.argsort(np.abs(lam))]


def margin_of(lam: np.ndarray, lam_max: float, tol: float):
    """max Re lambda - tol max(1, |lambda|) over |lambda| < lam_max, and its eigenvalue."""
    keep = lam[np.abs(lam) < lam_max]
    score = keep.real - tol * np.maximum(1.0, np.abs(keep))
    i = int(np.argmax(score))
    return float(score[i]), complex(keep[i])


@single_blas
def spectral_abscissa(
    pipe: StraightPipe,
    v: float,
    method: str = "galerkin",
    n: int | None = None,
    lam_max: float = LAM_MAX,
    tol: float = TOL,
) -> tuple[float, complex]:
    """``(margin, lam)``: max(Re lambda - tol max(1, |lambda|)) over |lambda| < ``lam_max``
    (positive: unstable) and the eigenvalue attaining it.
    """
    return margin_of(_Problem(pipe, discretization(method, n)).eigenvalues(v), lam_max, tol)


@dataclass(frozen=True)
class Onset:
    """The first loss of stability: ``v_cr`` (nan if none), the crossing eigenvalue ``lam``
    (Im >= 0), ``kind`` (flutter, divergence, unstable at v_min, stable), ``method``.
    """

    v_cr: float
    lam: complex
    kind: str
    method: str

    @property
    def frequency(self) -> float:
        """omega = Im lambda at the onset."""
        return abs(self.lam.imag)


@single_blas
def critical_velocity(
    pipe: StraightPipe,
    v_max: float = 20.0,
    v_min: float = 0.0,
    method: str = "galerkin",
    n: int | None = None,
    step: float = 0.1,
    xtol: float = 1e-12,
    lam_max: float = LAM_MAX,
    tol: float = TOL,
) -> Onset:
    """The first v in [v_min, v_max] at which the straight pipe loses stability.

    A scan with ``step`` (a narrower stability window can be missed), then Brent's method to
    ``xtol`` on the margin of :func:`spectral_abscissa`; ``method``, ``n``: the discretization.
    """
    prob = _Problem(pipe, discretization(method, n))

    def margin(v):
        return margin_of(prob.eigenvalues(v), lam_max, tol)

    def abscissa(v):
        return margin_of(prob.eigenvalues(v), lam_max, 0.0)[0]

    return scan_onset(margin, abscissa, v_min, v_max, step, xtol, prob.disc.label())


def scan_onset(margin, abscissa, v_min, v_max, step, xtol, label, probe=None) -> Onset:
    """The first v where ``probe(v)`` (default ``margin(v)[0]``) turns positive on a grid of
    ``step``, then Brent's method to ``xtol`` on ``abscissa`` (the largest Re lambda) if it is
    negative below (damped), else on the margin; the eigenvalue from ``margin`` just above."""
    f0, lam0 = margin(v_min)
    if f0 > 0.0:
        return Onset(v_min, lam0, "unstable at v_min", label)
    probe = probe or (lambda v: margin(v)[0])
    v_prev = v_min
    rtol = 4 * np.finfo(float).eps
    for v in np.arange(v_min, v_max + step / 2, step)[1:]:
        if probe(v) > 0.0:
            f = abscissa if abscissa(v_prev) < 0.0 else (lambda s: margin(s)[0])
            v_cr = brentq(f, v_prev, v, xtol=xtol, rtol=rtol)
            _, lam = margin(v_cr + 2 * xtol)
            lam = complex(lam.real, abs(lam.imag))
            kind = "flutter" if abs(lam.imag) > 1e-6 * max(1.0, abs(lam)) else "divergence"
            return Onset(float(v_cr), lam, kind, label)
        v_prev = v
    return Onset(float("nan"), complex("nan"), "stable", label)

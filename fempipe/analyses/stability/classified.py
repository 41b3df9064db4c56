"""Spectra classified by the canonical modes: resolved eigenvalues and mode numbers.

Rules: docs/theory/stability.md, "Resolved modes" and "Mode numbers".
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from fempipe.core.matching import assignment
from fempipe.model.plane.operators import PipeModel

from .canonical import RESOLVED_SHARE, Resolution, canonical_weights
from .eigensolvers import quadratic_eigen
from .hysteretic import HYSTERETIC_HEAVY, RELEVANT_SHARE, hysteretic_roots
from .linear import linearized_matrices

#: Re(lambda) <= STABILITY_TOL * max(1, |lambda|) counts as not unstable.
STABILITY_TOL = 1e-8


@dataclass
class ClassifiedSpectrum:
    """Every eigenvalue of one state with the share of its eigenvector on resolved modes.

    The working record of the analyses.  ``X``: theta-parts of the eigenvectors (None when
    the classification is inherited, from the eigenvectors at ``origin_v``); ``weights``:
    squared canonical coefficients (n_canonical, m); ``resolved``: share >= RESOLVED_SHARE;
    ``s``: position along a path (arclength proxy); ``fold``: a fold of its branch.
    """

    v: float
    q: np.ndarray
    lam: np.ndarray
    X: np.ndarray | None
    share: np.ndarray
    weights: np.ndarray
    resolved: np.ndarray
    method: str
    s: float = 0.0
    fold: bool = False
    origin_v: float | None = None

    @property
    def unstable(self) -> np.ndarray:
        """Mask of the resolved eigenvalues with Re lambda > STABILITY_TOL max(1, |lambda|)."""
        return self.resolved & (self.lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(self.lam)))

    @property
    def max_real(self) -> float:
        """Largest Re lambda of the resolved eigenvalues (-inf if none)."""
        r = self.lam.real[self.resolved]
        return float(r.max()) if r.size else -math.inf


def classify_spectrum(
    model: PipeModel,
    q: np.ndarray,
    res: Resolution,
    method: str,
    matrices: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> ClassifiedSpectrum:
    """Every eigenvalue of Eq. (32) at the static state q, classified by the canonical modes.

    ``matrices`` (K, C, M) if known (the straight pencil); with hysteretic damping the
    roots are continued in mu_h (:func:`~.hysteretic.hysteretic_roots`).
    """
    K, C, M = linearized_matrices(model, q) if matrices is None else matrices
    lam, X, used = quadratic_eigen(K, C, M, method)
    W, share = canonical_weights(res, X)
    mu_h = model.params.hysteretic_damping
    if mu_h > 0.0:
        Kb = model.hysteretic_stiffness(q)
        lam, X = hysteretic_roots(
            K, C, M, Kb, mu_h, lam, X, relevant=share >= RELEVANT_SHARE, method=used
        )
        W, share = canonical_weights(res, X)
    return ClassifiedSpectrum(
        v=model.params.v,
        q=np.asarray(q, dtype=float),
        lam=lam,
        X=X,
        share=share,
        weights=W,
        resolved=share >= RESOLVED_SHARE,
        method=used,
    )


#: Classification inherited from a spectrum with eigenvectors only within this distance
#: in v of it (:func:`classify_inherited`).
INHERIT_SPAN = 2.0
#: ... only from eigenvalues whose share is this far from RESOLVED_SHARE ...
INHERIT_MARGIN = 0.2
#: ... and only when every eigenvalue's nearest old one is closer than this
#: fraction of the distance to the nearest old one classified otherwise.
INHERIT_MATCH = 0.25


def classify_inherited(
    model: PipeModel,
    q: np.ndarray,
    res: Resolution,
    method: str,
    matrices: tuple[np.ndarray, np.ndarray, np.ndarray],
    ref: ClassifiedSpectrum,
) -> ClassifiedSpectrum:
    """:func:`classify_spectrum` with eigenvalues only, each taking the share and weights of its
    nearest eigenvalue of ``ref`` (the same straight pencil) when the match is sure
    (:data:`INHERIT_SPAN`, :data:`INHERIT_MARGIN`, :data:`INHERIT_MATCH`); otherwise, and with
    hysteretic damping, solved with eigenvectors.
    """
    origin = ref.v if ref.origin_v is None else ref.origin_v
    if model.params.hysteretic_damping > 0.0 or abs(model.params.v - origin) > INHERIT_SPAN:
        return classify_spectrum(model, q, res, method, matrices)
    K, C, M = matrices
    lam, _, used = quadratic_eigen(K, C, M, method, vectors=False)
    if lam.size == ref.lam.size:
        D = np.abs(lam[:, None] - ref.lam[None, :])
        j = np.argmin(D, axis=1)
        rows = np.arange(lam.size)
        d1 = D[rows, j]
        cls = ref.resolved[j]
        other = np.where(ref.resolved[None, :] != cls[:, None], D, np.inf).min(axis=1)
        sure = np.abs(ref.share[j] - RESOLVED_SHARE) >= INHERIT_MARGIN
        # Heavily damped roots (the Kelvin-Voigt cluster near -1/mu, whose eigenvectors
        # are arbitrary mixes) are never unstable: they need only stay below max_real.
        heavy = -lam.real >= HYSTERETIC_HEAVY * np.abs(lam)
        light_res = cls & ~heavy
        top = lam.real[light_res].max() if light_res.any() else -np.inf
        ok = heavy | (sure & (d1 <= INHERIT_MATCH * other))
        if np.all(ok) and np.all(lam.real[heavy] < top):
            return ClassifiedSpectrum(
                v=model.params.v,
                q=np.asarray(q, dtype=float),
                lam=lam,
                X=None,
                share=ref.share[j],
                weights=ref.weights[:, j],
                resolved=cls,
                method=used,
                origin_v=origin,
            )
    return classify_spectrum(model, q, res, method, matrices)


def canonical_labels(e: ClassifiedSpectrum, idx: np.ndarray) -> np.ndarray:
    """Mode numbers (1-based) of eigenvalues idx by optimal assignment to canonical modes
    (two slots per mode: a conjugate pair or two real roots)."""
    if idx.size == 0:
        return np.zeros(0, dtype=int)
    W = e.weights[:, idx].T  # (k, n_can)
    cost = -np.repeat(W, 2, axis=1)
    rows, cols = assignment(cost)
    labels = np.empty(idx.size, dtype=int)
    labels[rows] = cols // 2 + 1
    return labels


def mode_order(lam: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Sort by mode number, then upper half-plane first."""
    return np.lexsort((-lam.imag, labels))


def eigenvalue_dict(lam: complex, mode: int) -> dict:
    """One eigenvalue in both conventions (JSON): lambda and Omega = -i lambda."""
    return {
        "mode": mode,
        "re": float(lam.real),
        "im": float(lam.imag),
        "Omega_re": float(lam.imag),
        "Omega_im": float(-lam.real),
    }

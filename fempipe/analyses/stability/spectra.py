"""The resolved spectrum of Eq. (32) about one static state, and its mode shapes
(docs/theory/stability.md)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fempipe.analyses.statics import solve_sagged
from fempipe.core.parallel import single_blas
from fempipe.model.kinematics import compute_shape
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from .canonical import RESOLUTION_TOL, resolution
from .classified import STABILITY_TOL, classify_spectrum, eigenvalue_dict, mode_order
from .tracking import reference_tracker


@dataclass(frozen=True)
class Spectrum:
    """The resolved spectrum of Eq. (32) about one static state q.

    Attributes
    ----------
    lam, mode : ndarray of complex, ndarray of int, shape (m,)
        Resolved eigenvalues, upper half first, and their mode numbers (from v = 0).
    vectors : ndarray of complex, shape (n, m)
        theta-parts of the eigenvectors (unit norm).
    share : ndarray, shape (m,)
        Share of each eigenvector on resolved canonical modes (>= 1/2).
    """

    params: Params
    q: np.ndarray = field(repr=False)
    lam: np.ndarray
    mode: np.ndarray
    vectors: np.ndarray = field(repr=False)
    share: np.ndarray = field(repr=False)
    n_computed: int
    n_resolved_modes: int
    max_real_unresolved: float
    static_residual: float
    method: str

    @property
    def Omega(self) -> np.ndarray:
        """The paper's eigenvalues Omega = -i lambda (Im Omega < 0 unstable)."""
        return -1j * self.lam

    @property
    def max_real(self) -> float:
        """Largest Re lambda of the resolved eigenvalues."""
        return float(self.lam.real.max()) if self.lam.size else -math.inf

    @property
    def unstable(self) -> np.ndarray:
        """Mask of the unstable resolved eigenvalues (Re lambda > 1e-8 max(1, |lambda|))."""
        return self.lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(self.lam))

    @property
    def stable(self) -> bool:
        """No resolved eigenvalue is unstable (marginal counts as stable)."""
        return not bool(self.unstable.any())

    def to_dict(self) -> dict:
        return {
            "params": self.params.to_dict(),
            "stable": self.stable,
            "max_real": self.max_real,
            "eigenvalues": [
                eigenvalue_dict(lam, int(m)) for lam, m in zip(self.lam, self.mode, strict=True)
            ],
            "n_computed": self.n_computed,
            "n_resolved_modes": self.n_resolved_modes,
            "max_real_unresolved": self.max_real_unresolved,
            "static_residual": self.static_residual,
            "method": self.method,
        }


@single_blas
def compute_spectrum(
    model: PipeModel,
    q: np.ndarray | None = None,
    *,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
) -> Spectrum:
    """Every resolved eigenvalue about a static state, with its mode number. Eq. (32).

    Parameters
    ----------
    model : PipeModel
    q : ndarray, shape (n,), optional
        The static state; default :func:`fempipe.analyses.statics.solve_sagged`.
    method : {'auto', 'qz', 'shift-invert'}
    tolerance : float
        :data:`RESOLUTION_TOL`.

    Returns
    -------
    Spectrum

    Raises
    ------
    ValueError, NewtonError
        No resolved mode; no branch back to v = 0.
    """
    res = resolution(model.disc, tolerance)
    if res.n_resolved == 0:
        raise ValueError(
            f"discretization {model.disc.name} resolves no mode within {tolerance:.0%} "
            "of the clamped-free beam frequencies; refine it"
        )
    if q is None:
        q = solve_sagged(model).q
    e = classify_spectrum(model, q, res, method)
    tracker, _ = reference_tracker(model, e, res, method)
    keep = e.resolved[tracker.first_idx]
    idx, labels = tracker.first_idx[keep], tracker.labels[keep]
    o = mode_order(e.lam[idx], labels)
    idx, labels = idx[o], labels[o]
    unres = e.lam.real[~e.resolved]
    return Spectrum(
        params=model.params,
        q=np.array(q, dtype=float),
        lam=e.lam[idx],
        mode=labels,
        vectors=e.X[:, idx],
        share=e.share[idx],
        n_computed=int(e.lam.size),
        n_resolved_modes=res.n_resolved,
        max_real_unresolved=float(unres.max()) if unres.size else -math.inf,
        static_residual=float(np.linalg.norm(model.static_residual(q))),
        method=e.method,
    )


@dataclass(frozen=True)
class ModeShape:
    """A mode shape ``Re(a e^{lambda tau})`` about a static state, max |theta^d| = 1 (real > 0):
    theta^d and the centerline's displacement ``X_g``, ``Z_g`` (Eq. (28) linearized) at ``xi``."""

    xi: np.ndarray
    theta: np.ndarray
    X_g: np.ndarray
    Z_g: np.ndarray
    X_static: np.ndarray
    Z_static: np.ndarray
    lam: complex
    mode: int

    def to_dict(self) -> dict:
        return {
            "mode": self.mode,
            "lambda": [float(self.lam.real), float(self.lam.imag)],
            "xi": self.xi.tolist(),
            "theta_re": self.theta.real.tolist(),
            "theta_im": self.theta.imag.tolist(),
            "X_g_re": self.X_g.real.tolist(),
            "X_g_im": self.X_g.imag.tolist(),
            "Z_g_re": self.Z_g.real.tolist(),
            "Z_g_im": self.Z_g.imag.tolist(),
        }


def mode_shape(disc, spec: Spectrum, index: int, points_per_cell: int = 4) -> ModeShape:
    """Shape of the resolved eigenvalue ``spec.lam[index]`` in theta and in the global frame
    (the complex-step derivative of :func:`fempipe.model.kinematics.compute_shape` along the mode)."""
    if not -spec.lam.size <= index < spec.lam.size:
        raise ValueError(f"index must be in [0, {spec.lam.size}), got {index}")
    x = spec.vectors[:, index]
    alpha = spec.params.alpha
    base = compute_shape(disc, spec.q, alpha, points_per_cell)
    theta = disc.evaluate(x, base.xi)
    k = int(np.argmax(np.abs(theta)))
    scale = np.abs(theta[k]) / theta[k] if theta[k] != 0 else 1.0
    x = x * scale / np.abs(theta[k])
    h = 1e-30  # complex step: Im f(q + i h d) / h = f'(q) d exactly
    parts = []
    for d in (x.real, x.imag):
        s = compute_shape(disc, spec.q + 1j * h * d, alpha, points_per_cell)
        parts.append((np.imag(s.X_g) / h, np.imag(s.Z_g) / h))
    return ModeShape(
        xi=base.xi,
        theta=disc.evaluate(x, base.xi),
        X_g=parts[0][0] + 1j * parts[1][0],
        Z_g=parts[0][1] + 1j * parts[1][1],
        X_static=base.X_g,
        Z_static=base.Z_g,
        lam=complex(spec.lam[index]),
        mode=int(spec.mode[index]),
    )

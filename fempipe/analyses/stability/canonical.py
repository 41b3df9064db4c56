"""The canonical modes of a discretization (the clamped-free beam's) and the eigenvalues it
resolves (docs/theory/stability.md, "Resolved modes")."""

from __future__ import annotations

import weakref
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from fempipe.core.rootfinding import brentq
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

#: Relative frequency error up to which a discretization resolves a canonical mode.
RESOLUTION_TOL = 0.05
#: Share of an eigenvector's squared M(0)-norm on resolved modes for a resolved eigenvalue.
RESOLVED_SHARE = 0.5


def cantilever_frequencies(n: int) -> np.ndarray:
    """Exact frequencies beta_r^2 of the clamped-free beam, r = 1..n (time scale of Eq. (19)).

    beta_r solves cos(beta) + sech(beta) = 0 (overflow-free); beta_r = (r - 1/2) pi above 40.
    """
    out = np.empty(int(n))
    for r in range(1, int(n) + 1):
        c = (r - 0.5) * np.pi
        f = lambda x: np.cos(x) + 1.0 / np.cosh(x)  # noqa: E731
        b = c if c > 40.0 else brentq(f, c - 0.4, c + 0.4, xtol=1e-15)
        out[r - 1] = b**2
    return out


@dataclass(frozen=True)
class Resolution:
    """Which modes a discretization resolves: ``n_resolved`` leading canonical modes within
    ``tolerance`` of the exact frequencies; ``basis``: the canonical modes, M(0)-orthonormal
    columns, ``mass``: M(0)."""

    n_resolved: int
    frequencies: np.ndarray
    exact: np.ndarray
    rel_error: np.ndarray
    tolerance: float
    basis: np.ndarray = field(repr=False)
    mass: np.ndarray = field(repr=False)

    def to_dict(self) -> dict:
        k = min(self.n_resolved + 1, self.frequencies.size)
        return {
            "n_resolved_modes": self.n_resolved,
            "tolerance": self.tolerance,
            "canonical_rel_error": self.rel_error[:k].tolist(),
        }


_RESOLUTION_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def resolution(disc, tolerance: float = RESOLUTION_TOL) -> Resolution:
    """The canonical modes of ``disc`` and how many it resolves within ``tolerance`` in (0, 1)
    (cached per discretization)."""
    if not 0.0 < tolerance < 1.0:
        raise ValueError(f"tolerance must be in (0, 1), got {tolerance}")
    per_disc = _RESOLUTION_CACHE.setdefault(disc, {})
    if tolerance in per_disc:
        return per_disc[tolerance]
    model = PipeModel(disc, Params(alpha=0.0, beta=0.0, gamma=0.0, mu=0.0, v=0.0))
    M0 = model.mass_matrix(np.zeros(disc.n))
    K = disc.K.toarray() if sp.issparse(disc.K) else np.asarray(disc.K)
    w2, basis = sla.eigh(K, M0)
    omega = np.sqrt(np.maximum(w2, 0.0))
    exact = cantilever_frequencies(omega.size)
    err = np.abs(omega / exact - 1.0)
    bad = np.flatnonzero(err > tolerance)
    n_res = int(bad[0]) if bad.size else omega.size
    per_disc[tolerance] = res = Resolution(n_res, omega, exact, err, float(tolerance), basis, M0)
    return res


def canonical_weights(res: Resolution, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(W, share): |c_rj|^2 of the columns of X in the canonical modes, normalized per
    column, shape (n_canonical, m), and their sum over the resolved modes."""
    c = res.basis.T @ (res.mass @ X)
    W = np.abs(c) ** 2
    W = W / W.sum(axis=0)
    return W, W[: res.n_resolved].sum(axis=0)

"""The roots of Eq. (32) with hysteretic damping, continued in the loss factor mu_h.

Derivation: docs/theory/conventions.md, "Hysteretic damping".  The steps are shared with the
sparse criterion (:mod:`fempipe.analyses.stability.criterion`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.core.matching import assignment

from .eigensolvers import quadratic_eigen

#: A continuation step in mu_h is halved while a relevant root's match is
#: farther than this fraction of the distance to the next candidate.
HYSTERETIC_MATCH = 0.35
#: Smallest continuation step, as a fraction of mu_h, and most eigenproblems
#: solved per state; beyond, the nearest match is taken as it is.
HYSTERETIC_MIN_STEP = 1.0 / 64.0
HYSTERETIC_MAX_SOLVES = 16
#: Share on resolved canonical modes above which a lightly damped root's match must be
#: unambiguous (half of RESOLVED_SHARE: the eigenvector changes with mu_h).
RELEVANT_SHARE = 0.25


@dataclass(frozen=True)
class ConjugateHalves:
    """The roots of a real quadratic problem sorted by the sign of their frequency.

    ``pos``: Im lambda > 0, and Im lambda < 0 without a conjugate (``flip``: a partial
    spectrum can split a pair); ``paired``: the other Im lambda < 0, ``partner`` their
    conjugates' positions in ``pos``.  Real roots are in neither.
    """

    pos: np.ndarray
    flip: np.ndarray
    paired: np.ndarray
    partner: np.ndarray

    @classmethod
    def of(cls, lam: np.ndarray) -> ConjugateHalves:
        upper = np.flatnonzero(lam.imag > 0.0)
        lower = np.flatnonzero(lam.imag < 0.0)
        partner = np.full(lower.size, -1)
        if lower.size and upper.size:
            # The real eigensolvers return exact conjugate pairs.
            D = np.abs(np.conj(lam[lower])[:, None] - lam[upper][None, :])
            rows, cols = assignment(D)
            scale = np.maximum(1.0, np.abs(lam[lower][rows]))
            ok = D[rows, cols] <= 1e-12 * scale
            partner[rows[ok]] = cols[ok]
        single = lower[partner < 0]
        return cls(
            pos=np.concatenate([upper, single]),
            flip=np.concatenate([np.zeros(upper.size, bool), np.ones(single.size, bool)]),
            paired=lower[partner >= 0],
            partner=partner[partner >= 0],
        )

    def targets(self, lam: np.ndarray, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The positive-frequency roots to continue, and their unit vectors."""
        t, Xt = lam[self.pos].astype(complex), np.asarray(X, dtype=complex)[:, self.pos]
        Xt = Xt / np.linalg.norm(Xt, axis=0)
        return np.where(self.flip, np.conj(t), t), np.where(self.flip, np.conj(Xt), Xt)

    def assemble(self, lam, X, r, Xr, keep) -> tuple[np.ndarray, np.ndarray]:
        """``lam``, ``X`` with the pos roots replaced by r, Xr (except where ``keep``), the
        negative half conjugated."""
        out, Xout = np.asarray(lam, dtype=complex).copy(), np.array(X, dtype=complex)
        t, Xt = self.targets(lam, X)
        r = np.where(keep, t, r)
        Xr = np.where(keep, Xt, Xr)
        out[self.pos] = np.where(self.flip, np.conj(r), r)
        Xout[:, self.pos] = np.where(self.flip, np.conj(Xr), Xr)
        out[self.paired] = np.conj(r[self.partner])
        Xout[:, self.paired] = np.conj(Xr[:, self.partner])
        return out, Xout


#: Damping ratio -Re lambda / |lambda| above which a root's match need not be unambiguous
#: (far from instability; the Kelvin-Voigt roots crowd near -1/mu).
HYSTERETIC_HEAVY = 0.5


def relevant_roots(targets: np.ndarray, relevant: np.ndarray | None) -> np.ndarray:
    """The targets whose match must be unambiguous: ``relevant`` and not heavily damped."""
    light = -targets.real < HYSTERETIC_HEAVY * np.abs(targets)
    return light if relevant is None else light & relevant


def match_roots(pred: np.ndarray, Xpred: np.ndarray, lam: np.ndarray, X: np.ndarray, relevant):
    """Indices in ``lam`` of the predicted roots, and which relevant matches are ambiguous.

    Optimal assignment on ``min(1, |lambda - pred| / max(1, |pred|)) + 1 - |x_pred^H x|``;
    ambiguous: cost above ``HYSTERETIC_MATCH`` times the next candidate's.
    """
    dist = np.abs(pred[:, None] - lam[None, :]) / np.maximum(1.0, np.abs(pred))[:, None]
    Xu = X / np.linalg.norm(X, axis=0)
    D = np.minimum(1.0, dist) + 1.0 - np.abs(Xpred.conj().T @ Xu)
    rows, cols = assignment(D)
    pick = np.empty(pred.size, dtype=int)
    pick[rows] = cols
    k = np.arange(pred.size)
    d1 = D[k, pick]
    D[k, pick] = np.inf
    d2 = D.min(axis=1) if lam.size > 1 else np.full(pred.size, np.inf)
    return pick, relevant & (d1 > HYSTERETIC_MATCH * d2)


def hysteretic_roots(
    K: np.ndarray,
    C: np.ndarray,
    M: np.ndarray,
    Kb: np.ndarray,
    mu_h: float,
    lam0: np.ndarray,
    X0: np.ndarray,
    *,
    relevant: np.ndarray | None = None,
    method: str = "auto",
) -> tuple[np.ndarray, np.ndarray]:
    """The roots of Eq. (32) with the hysteretic bending stiffness Kb (1 + i mu_h sgn(omega)).

    Each root of the real problem with Im lambda > 0 continued in mu_h, its conjugate mirrored,
    real roots kept (docs/theory/conventions.md, "Hysteretic damping").

    Parameters
    ----------
    K, C, M, Kb : ndarray, shape (n, n)
        K^d, C^d, M^d of Eqs. (33a)-(33c) and the bending part of K^d.
    mu_h : float
        Loss factor, > 0.
    lam0, X0 : ndarray
        Eigenvalues of the real problem (exact conjugate pairs) and their theta-parts.
    relevant : ndarray of bool, optional
        Roots whose match must be unambiguous if lightly damped (default: all).
    method : str
        Eigensolver of :func:`quadratic_eigen`.

    Returns
    -------
    lam, X : ndarray of complex
        As many roots as ``lam0``, conjugate-symmetric; unit-norm theta-parts.
    """
    lam0 = np.asarray(lam0)
    halves = ConjugateHalves.of(lam0)
    cur, Xcur = halves.targets(lam0, X0)
    rel = relevant_roots(cur, None if relevant is None else np.asarray(relevant)[halves.pos])
    crossed = np.zeros(cur.size, bool)
    mu, step, slope, solves = 0.0, float(mu_h), None, 0
    while mu < mu_h and cur.size:
        nxt = min(float(mu_h), mu + step)
        lam, X, _ = quadratic_eigen(K + 1j * nxt * Kb, C, M, method)
        solves += 1
        pred = cur if slope is None else cur + (nxt - mu) * slope
        idx, ambiguous = match_roots(pred, Xcur, lam, X, rel & ~crossed)
        if ambiguous.any() and step > HYSTERETIC_MIN_STEP * mu_h and solves < HYSTERETIC_MAX_SOLVES:
            step *= 0.5
            continue
        slope = (lam[idx] - cur) / (nxt - mu)
        cur, Xcur, mu = lam[idx], X[:, idx], nxt
        crossed |= cur.imag <= 0.0
    return halves.assemble(lam0, X0, cur, Xcur, crossed)

"""Linearised matrices, eigensolvers and the resolution of a discretisation.

The linearisation of Eq. (20) about a static state, Eqs. (31b)-(33), its
dense eigensolvers (QZ, shift-invert), the roots with hysteretic damping
(:func:`hysteretic_roots`) and the canonical modes that decide which
eigenvalues a discretisation resolves (package docstring, "Resolved modes").
"""

from __future__ import annotations

import functools
import logging
import math
import weakref
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from fempipe.core.matching import assignment
from fempipe.core.parallel import single_blas_thread
from fempipe.core.rootfinding import brentq
from fempipe.model.operators import PipeModel
from fempipe.model.params import Params

log = logging.getLogger(__name__)
#: Relative error of the clamped-free beam frequency up to which a
#: discretisation is said to resolve a canonical mode.
RESOLUTION_TOL = 0.05
#: Share of an eigenvector's squared M(0)-norm that must lie on resolved
#: canonical modes for its eigenvalue to be resolved.
RESOLVED_SHARE = 0.5
#: Re(lambda) <= STABILITY_TOL * max(1, |lambda|) counts as not unstable.
STABILITY_TOL = 1e-8
#: Largest state dimension solved by QZ; above, dense shift-invert.
QZ_MAX_N = 200


def single_blas(fn):
    """Run ``fn`` under :func:`fempipe.core.parallel.single_blas_thread`.

    The dense eigenproblems are small (2n = 96 for P3:16), where one BLAS
    thread is fastest (measurements in :mod:`fempipe.core.parallel`).
    """

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_blas_thread():
            return fn(*args, **kwargs)

    return wrapper


def cantilever_frequencies(n: int) -> np.ndarray:
    """Exact frequencies beta_r^2 of the clamped-free Euler-Bernoulli beam, r = 1..n.

    beta_r solves cos(beta) cosh(beta) = -1 (1.8751, 4.6941, 7.8548, ...);
    written as cos(beta) + sech(beta) = 0 to avoid overflow.  For
    beta > 40 the sech term is below 1e-17 and beta_r = (r - 1/2) pi.

    Returns
    -------
    ndarray, shape (n,)
        Dimensionless angular frequencies (time scale of Eq. (19)).
    """
    out = np.empty(int(n))
    for r in range(1, int(n) + 1):
        c = (r - 0.5) * np.pi
        if c > 40.0:
            out[r - 1] = c**2
            continue
        b = brentq(lambda x: np.cos(x) + 1.0 / np.cosh(x), c - 0.4, c + 0.4, xtol=1e-15)
        out[r - 1] = b**2
    return out


@dataclass(frozen=True)
class Resolution:
    """Which modes a discretisation resolves (see the module docstring).

    Attributes
    ----------
    n_resolved : int
        Number of leading canonical modes within ``tolerance`` of the exact
        clamped-free beam frequencies.
    frequencies, exact, rel_error : ndarray, shape (n,)
        Discrete and exact canonical frequencies and |omega_h / omega - 1|.
    tolerance : float
    basis : ndarray, shape (n, n)
        Canonical modes, M(0)-orthonormal (columns).
    mass : ndarray, shape (n, n)
        M(0), the mass matrix of the straight pipe.
    """

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
    """The canonical modes of ``disc`` and how many it resolves (cached per discretisation).

    Parameters
    ----------
    disc : FiniteElement or Modal
    tolerance : float
        Relative frequency error allowed for a resolved canonical mode, in (0, 1).
    """
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
    res = Resolution(n_res, omega, exact, err, float(tolerance), basis, M0)
    per_disc[tolerance] = res
    return res


# ---------------------------------------------------------------------------
# Linearised matrices and the eigenproblem
# ---------------------------------------------------------------------------


def linearized_matrices(model: PipeModel, q: np.ndarray):
    """K^d, C^d, M^d of Eqs. (33a)-(33c) at the static state q.

    They are the analytic Jacobians dR/dq, dR/dq', dR/dq'' of the residual of
    Eq. (20) at (q, 0, 0): the same code that drives Newton's method and the
    time integrators, so the physics is written once
    (:meth:`~fempipe.model.operators.PipeModel.static_jacobians`, which leaves out
    the terms of ``jacobians`` that vanish at q' = q'' = 0).

    Returns
    -------
    K, C, M : ndarray, shape (n, n)
        Stiffness (bending, gravity, follower: not symmetric for v > 0),
        damping (Coriolis 2 v sqrt(beta) and Kelvin-Voigt mu), mass (SPD).
    """
    return model.linearization(np.asarray(q, dtype=float))


_GEEV_LWORK: dict = {}


def _dense_eig(T: np.ndarray, rows: int, vectors: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """Eigenvalues of the real matrix T and the first ``rows`` rows of its right eigenvectors.

    LAPACK's geev as :func:`scipy.linalg.eig` calls it (same workspace size,
    so the same results to the bit), without its per-call workspace query
    and with the complex eigenvectors formed for the rows asked for only:
    the shift-invert solve needs the theta part, half of each vector.
    """
    if T.dtype != np.float64:
        out = sla.eig(T, right=vectors)
        return (out[0], out[1][:rows]) if vectors else (out, None)
    if not np.isfinite(T).all():
        raise ValueError("array must not contain infs or NaNs")
    geev, geev_lwork = sla.get_lapack_funcs(("geev", "geev_lwork"), (T,))
    key = (T.shape[0], bool(vectors))
    lwork = _GEEV_LWORK.get(key)
    if lwork is None:
        from scipy.linalg.lapack import _compute_lwork

        lwork = _GEEV_LWORK[key] = _compute_lwork(
            geev_lwork, T.shape[0], compute_vl=0, compute_vr=int(vectors)
        )
    wr, wi, _, vr, info = geev(T, lwork=lwork, compute_vl=0, compute_vr=int(vectors))
    if info != 0:
        raise sla.LinAlgError(f"eig algorithm (geev) did not converge (info = {info})")
    w = wr + 1j * wi
    if not vectors:
        return w, None
    top = vr[:rows]
    if np.all(wi == 0.0):
        return w, top
    # The pairs as scipy.linalg.eig forms them (its _make_complex_eigvecs).
    m = wi > 0
    m[:-1] |= wi[1:] < 0
    V = np.array(top, dtype=complex)
    for i in np.flatnonzero(m):
        V.imag[:, i] = top[:, i + 1]
        np.conj(V[:, i], V[:, i + 1])
    return w, V


def _eigen(
    K, C, M, method: str = "auto", vectors: bool = True
) -> tuple[np.ndarray, np.ndarray | None, str]:
    """All eigenvalues and theta-parts of the eigenvectors of (lambda^2 M + lambda C + K) x = 0.

    ``qz``: the generalised Schur decomposition of the first-order pencil
    (backward stable; used up to n = 200).  ``shift-invert``: the standard
    eigenproblem of (A - sigma B)^{-1} B with a real shift, for larger n: the
    low modes, the ones that matter, are its largest eigenvalues and come out
    with full relative accuracy, and it is 5-20 times faster than QZ at
    n = 768.  Both keep exact conjugate pairs (real arithmetic).  With
    ``vectors=False`` only the eigenvalues are computed (X is None): 40 % less
    work for the dense eigensolver.
    """
    n = K.shape[0]
    if method == "auto":
        method = "qz" if n <= QZ_MAX_N else "shift-invert"
    if method == "qz":
        Z, I = np.zeros((n, n)), np.eye(n)
        A = np.block([[Z, I], [-K, -C]])
        B = np.block([[I, Z], [Z, M]])
        out = sla.eig(A, B, right=vectors)
        lam, V = out if vectors else (out, None)
    elif method == "shift-invert":
        for sigma in (-1.0, -0.618, -1.618, -0.25):
            # (A - sigma B)(u, w) = (b1, b2): w = b1 + sigma u,
            # (K + sigma C + sigma^2 M) u = -b2 - (C + sigma M) b1; here (b1, b2) = B.
            P = K + sigma * C + sigma**2 * M
            try:
                lu = sla.lu_factor(P, check_finite=True)
            except (sla.LinAlgError, ValueError):
                continue
            if not np.all(np.isfinite(lu[0])) or np.min(np.abs(np.diag(lu[0]))) == 0.0:
                continue
            rhs = np.hstack([-(C + sigma * M), -M])
            U = sla.lu_solve(lu, rhs)
            T = np.vstack([U, np.hstack([np.eye(n), np.zeros((n, n))]) + sigma * U])
            nu, V = _dense_eig(T, n, vectors)
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = sigma + 1.0 / nu
            break
        else:  # pragma: no cover - four singular shifts in a row
            raise np.linalg.LinAlgError("shift-invert: the quadratic pencil is singular")
    else:
        raise ValueError(f"method must be 'auto', 'qz' or 'shift-invert', got {method!r}")
    ok = np.isfinite(lam)
    if not vectors:
        return lam[ok], None, method
    lam, X = lam[ok], V[:n, ok]  # (shift-invert: V holds these rows only)
    X = X / np.linalg.norm(X, axis=0)
    return lam, X, method


#: A continuation step in mu_h is halved while a relevant root's match is
#: farther than this fraction of the distance to the next candidate.
HYSTERETIC_MATCH = 0.35
#: Smallest continuation step, as a fraction of mu_h, and most eigenproblems
#: solved per state; beyond, the nearest match is taken as it is.
HYSTERETIC_MIN_STEP = 1.0 / 64.0
HYSTERETIC_MAX_SOLVES = 16
#: Share of an eigenvector on resolved canonical modes above which its match
#: (if lightly damped) must be unambiguous (half of RESOLVED_SHARE: margin for the change of the
#: eigenvector with mu_h).
RELEVANT_SHARE = 0.25


@dataclass(frozen=True)
class _Halves:
    """The roots of a real quadratic problem sorted by the sign of their frequency.

    ``pos`` are the roots represented on the positive-frequency side: those
    with Im lambda > 0, and those with Im lambda < 0 whose conjugate is
    missing (``flip``; only a partial spectrum, such as Arnoldi's, can split
    a pair).  ``paired`` are the other roots with Im lambda < 0, and
    ``partner`` the position in ``pos`` of their conjugates.  Real roots are
    in neither.
    """

    pos: np.ndarray
    flip: np.ndarray
    paired: np.ndarray
    partner: np.ndarray

    @classmethod
    def of(cls, lam: np.ndarray) -> _Halves:
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


#: Damping ratio -Re lambda / |lambda| above which a root's match need not be
#: unambiguous: such roots are far from instability, and where many crowd
#: (the Kelvin-Voigt roots near -1/mu) no continuation can tell them apart.
HYSTERETIC_HEAVY = 0.5


def _relevant(targets: np.ndarray, relevant: np.ndarray | None) -> np.ndarray:
    """The targets whose match must be unambiguous: ``relevant`` and not heavily damped."""
    light = -targets.real < HYSTERETIC_HEAVY * np.abs(targets)
    return light if relevant is None else light & relevant


def _match(pred: np.ndarray, Xpred: np.ndarray, lam: np.ndarray, X: np.ndarray, relevant):
    """Indices in ``lam`` of the predicted roots, and which matches are ambiguous.

    Optimal assignment on the cost ``min(1, |lambda - pred| / max(1, |pred|))
    + 1 - |x_pred^H x|`` (unit vectors): the eigenvector tells apart roots
    whose eigenvalues crowd.  A relevant root is ambiguous when its cost
    exceeds ``HYSTERETIC_MATCH`` times that of the next candidate.
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

    With theta^d ∝ e^{lambda tau} = e^{i Omega tau} the frequency is
    omega = Re Omega = Im lambda, and the quadratic eigenproblem becomes

        (lambda^2 M + lambda C + K + i mu_h sgn(Im lambda) Kb) x = 0,

    with K = K^d (bending Kb, gravity and follower parts) and sgn(0) = 0.
    The problem is not analytic in lambda; it is solved from the roots
    ``lam0`` of the real problem (mu_h = 0) at the same state (package
    docstring, "Hysteretic damping"):

    * a root with Im lambda > 0 is continued in mu_h' from 0 to mu_h along
      the roots of the complex quadratic problem with stiffness
      K + i mu_h' Kb (each step: the optimal assignment to a linear
      prediction by eigenvalue and eigenvector, the step halved while a
      lightly damped root whose eigenvector lies on resolved modes is not
      matched clearly better than by its next candidate);
    * a root with Im lambda < 0 becomes the complex conjugate of its
      partner's continuation (eigenvector conjugated too): the problem with
      sgn = -1 is the conjugate of the one with sgn = +1;
    * a real root (no oscillation, sgn 0: divergence, an overdamped mode) is
      a root of the hysteretic problem as it is, and is kept; so is a pair
      whose continuation reaches Im lambda <= 0, a root whose frequency is
      smaller than the shift the loss would give it (in practice the nearly
      real Kelvin-Voigt roots near -1/mu that the Coriolis force pairs up):
      its frequency has no sign the loss could act on consistently, and it
      is treated as not oscillating.

    The result has as many roots as ``lam0`` and is conjugate-symmetric.  A
    pair whose frequency goes to zero as v varies (a collision on the real
    axis) jumps there from its continued roots to the real roots of the real
    problem: the sgn(omega) law is discontinuous at omega = 0.  The complex
    problem also has roots with Im lambda > 0 that continue real roots of the
    real problem (a slow oscillation of a mode that does not oscillate); they
    are not reported, since the real root itself stands for that mode.

    Parameters
    ----------
    K, C, M : ndarray, shape (n, n)
        K^d, C^d, M^d of Eqs. (33a)-(33c).
    Kb : ndarray, shape (n, n)
        The bending part of K^d (``disc.K``).
    mu_h : float
        Loss factor, > 0.
    lam0 : ndarray, shape (m,)
        Eigenvalues of the real problem (exact conjugate pairs, real roots
        with Im = 0), as returned by :func:`_eigen`.
    X0 : ndarray, shape (n, m)
        Their theta-parts.
    relevant : ndarray of bool, shape (m,), optional
        Roots whose match must be unambiguous if lightly damped (default: all).
    method : str
        Eigensolver of :func:`_eigen`.

    Returns
    -------
    lam : ndarray of complex, shape (m,)
    X : ndarray of complex, shape (n, m)
        Unit-norm theta-parts, in the order of ``lam0``.
    """
    lam0 = np.asarray(lam0)
    halves = _Halves.of(lam0)
    cur, Xcur = halves.targets(lam0, X0)
    rel = _relevant(cur, None if relevant is None else np.asarray(relevant)[halves.pos])
    crossed = np.zeros(cur.size, bool)
    mu, step, slope, solves = 0.0, float(mu_h), None, 0
    while mu < mu_h and cur.size:
        nxt = min(float(mu_h), mu + step)
        lam, X, _ = _eigen(K + 1j * nxt * Kb, C, M, method)
        solves += 1
        pred = cur if slope is None else cur + (nxt - mu) * slope
        idx, ambiguous = _match(pred, Xcur, lam, X, rel & ~crossed)
        if ambiguous.any() and step > HYSTERETIC_MIN_STEP * mu_h and solves < HYSTERETIC_MAX_SOLVES:
            step *= 0.5
            continue
        slope = (lam[idx] - cur) / (nxt - mu)
        cur, Xcur, mu = lam[idx], X[:, idx], nxt
        crossed |= cur.imag <= 0.0
    return halves.assemble(lam0, X0, cur, Xcur, crossed)


@dataclass
class _Eig:
    """All eigenvalues of one state with their resolved-share classification."""

    v: float
    q: np.ndarray
    lam: np.ndarray
    X: np.ndarray | None  # None: classification inherited (:func:`_analyse_inherited`)
    share: np.ndarray
    weights: np.ndarray  # (n_canonical, m) squared canonical coefficients, normalised
    resolved: np.ndarray
    method: str
    s: float = 0.0  # position along a path (arclength proxy)
    fold: bool = False
    origin_v: float | None = None  # v of the eigenvectors the classification comes from

    @property
    def unstable(self) -> np.ndarray:
        return self.resolved & (self.lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(self.lam)))

    @property
    def max_real(self) -> float:
        r = self.lam.real[self.resolved]
        return float(r.max()) if r.size else -math.inf


def _weights(res: Resolution, X: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Squared canonical coefficients of the columns of X (normalised) and their resolved share."""
    c = res.basis.T @ (res.mass @ X)
    W = np.abs(c) ** 2
    W = W / W.sum(axis=0)
    return W, W[: res.n_resolved].sum(axis=0)


class StraightPencil:
    """K^d, C^d, M^d at the straight state theta = 0 as functions of v alone.

    At q = 0 every term of Eqs. (33a)-(33c) is a fixed matrix times 1, v or
    v^2 (fields at theta = 0 do not depend on v): the follower term carries
    v^2, the Coriolis term 2 v sqrt(beta), everything else (bending, gravity
    with cos(alpha), Kelvin-Voigt, external damping, end mass, springs) none.
    So K = K0 + v^2 K2, C = C0 + v C1 and M are formed from three calls of
    :func:`linearized_matrices` (at v = 0 and v = 1) and then cost two
    matrix sums per state instead of a Jacobian assembly; they equal the
    assembled ones to round-off.  This holds at q = 0 for any alpha; q = 0 is
    a static state only where sin(alpha) = 0 (:func:`straight_is_static`).
    """

    def __init__(self, model: PipeModel) -> None:
        n = model.n
        q = np.zeros(n)
        p = model.params
        K0, C0, M = linearized_matrices(model.with_params(replace(p, v=0.0)), q)
        K1, C1, _ = linearized_matrices(model.with_params(replace(p, v=1.0)), q)
        self.K0, self.K2 = K0, K1 - K0
        self.C0, self.C1 = C0, C1 - C0
        self.M = M

    def matrices(self, v: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """K, C, M at flow velocity v."""
        return self.K0 + (v * v) * self.K2, self.C0 + v * self.C1, self.M

    @staticmethod
    def key(params: Params) -> Params:
        """The parameters the pencil depends on (v set to 0)."""
        return replace(params, v=0.0)


_PENCIL_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def straight_pencil(model: PipeModel) -> StraightPencil:
    """The :class:`StraightPencil` of ``model`` (cached per discretisation and parameters)."""
    per_disc = _PENCIL_CACHE.setdefault(model.disc, {})
    key = (model.plane, StraightPencil.key(model.params))
    pencil = per_disc.get(key)
    if pencil is None:
        if len(per_disc) > 32:  # a stability map visits many parameter points
            per_disc.clear()
        pencil = per_disc[key] = StraightPencil(model)
    return pencil


def straight_is_static(params: Params) -> bool:
    """Whether theta = 0 solves Eq. (31a) for every v: alpha = 0 or pi (mod 2 pi).

    Then gravity acts along the straight pipe, the follower term
    v^2 sin(theta(1) - theta) and the springs vanish with theta, and the
    residual is zero (to the 1e-16 of sin(pi) at alpha = pi).
    """
    return abs(math.sin(params.alpha)) < 1e-12


def _analyse(
    model: PipeModel,
    q: np.ndarray,
    res: Resolution,
    method: str,
    matrices: tuple[np.ndarray, np.ndarray, np.ndarray] | None = None,
) -> _Eig:
    K, C, M = linearized_matrices(model, q) if matrices is None else matrices
    lam, X, used = _eigen(K, C, M, method)
    W, share = _weights(res, X)
    mu_h = model.params.hysteretic_damping
    if mu_h > 0.0:
        Kb = model.hysteretic_stiffness(q)
        lam, X = hysteretic_roots(
            K, C, M, Kb, mu_h, lam, X, relevant=share >= RELEVANT_SHARE, method=used
        )
        W, share = _weights(res, X)
    return _Eig(
        v=model.params.v,
        q=np.asarray(q, dtype=float),
        lam=lam,
        X=X,
        share=share,
        weights=W,
        resolved=share >= RESOLVED_SHARE,
        method=used,
    )


#: Classification inherited from a spectrum with eigenvectors only within
#: this distance in v of it (:func:`_analyse_inherited`).  2.0 against 1.0 on
#: 56 straight-branch cases (alpha 0 and pi, the variants): the same events
#: (to 2.4e-11), 12 % fewer spectra with eigenvectors.
INHERIT_SPAN = 2.0
#: ... only from eigenvalues whose share is this far from RESOLVED_SHARE ...
INHERIT_MARGIN = 0.2
#: ... and only when every eigenvalue's nearest old one is closer than this
#: fraction of the distance to the nearest old one classified otherwise.
INHERIT_MATCH = 0.25


def _analyse_inherited(
    model: PipeModel,
    q: np.ndarray,
    res: Resolution,
    method: str,
    matrices: tuple[np.ndarray, np.ndarray, np.ndarray],
    ref: _Eig,
) -> _Eig:
    """:func:`_analyse` with eigenvalues only, the classification taken from a nearby spectrum.

    Each eigenvalue takes the share and canonical weights of the nearest
    eigenvalue of ``ref`` (a spectrum of the same straight pencil at a v at
    most :data:`INHERIT_SPAN` from the one whose eigenvectors ``ref``'s
    classification came from).  That needs, for every eigenvalue, a nearest
    old one whose share is at least :data:`INHERIT_MARGIN` from
    :data:`RESOLVED_SHARE`, and no old eigenvalue of the other class within
    1 / :data:`INHERIT_MATCH` times that distance -- except for heavily damped
    roots (-Re lambda >= :data:`HYSTERETIC_HEAVY` |lambda|), which are never
    unstable and must lie below the largest real part of the light resolved
    roots, so that their class changes neither an event nor ``max_real``
    (measured: in the clusters near -1/mu the eigenvectors, and so the
    shares, of the full solve are arbitrary mixes); otherwise (and with
    hysteretic damping, whose roots are continued along their eigenvectors)
    the spectrum is solved with its eigenvectors as in :func:`_analyse`.
    The dense eigensolver then skips the eigenvectors (40 % of its work).
    """
    origin = ref.v if ref.origin_v is None else ref.origin_v
    if model.params.hysteretic_damping > 0.0 or abs(model.params.v - origin) > INHERIT_SPAN:
        return _analyse(model, q, res, method, matrices)
    K, C, M = matrices
    lam, _, used = _eigen(K, C, M, method, vectors=False)
    if lam.size == ref.lam.size:
        D = np.abs(lam[:, None] - ref.lam[None, :])
        j = np.argmin(D, axis=1)
        rows = np.arange(lam.size)
        d1 = D[rows, j]
        cls = ref.resolved[j]
        other = np.where(ref.resolved[None, :] != cls[:, None], D, np.inf).min(axis=1)
        sure = np.abs(ref.share[j] - RESOLVED_SHARE) >= INHERIT_MARGIN
        # Heavily damped roots (the crowded Kelvin-Voigt roots near -1/mu,
        # whose eigenvectors are arbitrary mixes of a nearly degenerate
        # cluster) need not be sure: they are never unstable, and they may not
        # reach the largest real part of the light resolved roots (max_real).
        heavy = -lam.real >= HYSTERETIC_HEAVY * np.abs(lam)
        light_res = cls & ~heavy
        top = lam.real[light_res].max() if light_res.any() else -np.inf
        ok = heavy | (sure & (d1 <= INHERIT_MATCH * other))
        if np.all(ok) and np.all(lam.real[heavy] < top):
            return _Eig(
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
    return _analyse(model, q, res, method, matrices)


def _canonical_labels(e: _Eig, idx: np.ndarray) -> np.ndarray:
    """Mode numbers (1-based) of eigenvalues idx by optimal assignment to canonical modes.

    Two slots per canonical mode (a conjugate pair, or two real roots of one
    mode); the cost is minus the share of the eigenvector on that mode.
    """
    if idx.size == 0:
        return np.zeros(0, dtype=int)
    W = e.weights[:, idx].T  # (k, n_can)
    cost = -np.repeat(W, 2, axis=1)
    rows, cols = assignment(cost)
    labels = np.empty(idx.size, dtype=int)
    labels[rows] = cols // 2 + 1
    return labels


def _order(lam: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Sort by mode number, then upper half-plane first."""
    return np.lexsort((-lam.imag, labels))


def _eig_dict(lam: complex, mode: int) -> dict:
    """One eigenvalue in both conventions (JSON): lambda and Omega = -i lambda."""
    return {
        "mode": mode,
        "re": float(lam.real),
        "im": float(lam.imag),
        "Omega_re": float(lam.imag),
        "Omega_im": float(-lam.real),
    }

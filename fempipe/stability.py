"""Linear stability of the static states: spectra, critical velocities, events.

Writing theta = theta^s(xi) + theta^d(xi, tau) in Eq. (20) and keeping the
terms linear in theta^d gives Eq. (31b), discretised as Eq. (32):

    M^d q_ddot + C^d q_dot + K^d q = 0,

with M^d, C^d, K^d of Eqs. (33a)-(33c) (SPEC section 3.2).  They are the
Jacobians of the residual of Eq. (20) with respect to q'', q' and q at the
static state, so they are taken from :meth:`fempipe.operators.PipeModel.jacobians`
and never written a second time.  With theta^d ∝ e^{lambda tau} the quadratic
eigenproblem is solved in first-order form

    [[0, I], [-K, -C]] z = lambda [[I, 0], [0, M]] z,   z = (q, lambda q),

and every eigenvalue is reported in two conventions: lambda (Re lambda > 0
unstable) and the paper's Omega = -i lambda (theta^d ∝ e^{i Omega tau},
Im Omega < 0 unstable, Re Omega = Im lambda the frequency).

Resolved modes
--------------
A discretisation with n unknowns has 2n eigenvalues, but only its lowest
modes approximate the continuum.  The rule used here (:func:`resolution`):

1. The *canonical modes* of a discretisation are those of the straight,
   unloaded pipe (v = gamma = mu = 0): K phi = omega^2 M(0) phi, the
   clamped-free Euler-Bernoulli beam, whose exact frequencies beta_r^2
   (cos beta cosh beta = -1) are known.  Canonical mode r is *resolved* when
   the discretisation reproduces omega_r within ``RESOLUTION_TOL`` = 5 %
   (and so are all lower ones).  P3:16 resolves 27 modes, P3:256 423,
   modal N resolves N - 1: the N-th sine mode is always 8-9 % off
   because the sine basis misses theta''(0) != 0 (see SPEC section 2).
2. An eigenvector of the actual problem (any static state, any v) is expanded
   in the canonical modes (an M(0)-orthonormal basis).  The eigenvalue is
   *resolved* when at least half of the eigenvector's squared M(0)-norm (the
   kinetic energy of the displacement it causes) lies on resolved canonical
   modes.

Only resolved eigenvalues are reported and used for stability decisions.
The unresolved ones are the top of the discrete spectrum, where |lambda| is
1e5-1e11 and the eigensolver's round-off alone gives Re lambda up to 1e-7
(QZ, P3:64) or 0.5 (shift-invert, P3:256) for an exactly conservative
problem (v = mu = 0); for mu > 0 they also include the slow Kelvin-Voigt
roots near -1/mu of modes the mesh cannot represent.  A resolved eigenvalue is unstable when
Re lambda > ``STABILITY_TOL`` max(1, |lambda|) = 1e-8 max(1, |lambda|):
round-off on resolved modes was measured below 2e-10 (P1:128 ... P3:64 at
v = mu = 0, an exactly conservative case).

Mode numbers
------------
At one state, each resolved eigenvalue gets the number of the canonical mode
its eigenvector is made of (an optimal assignment, two eigenvalues per mode:
a conjugate pair or two real roots).  Along a path in v, mode numbers are
carried by continuity instead: each tracked eigenvalue is matched to the
nearest eigenvalue at the next point (optimal assignment on the distance to
a linear prediction), and the step is halved when the match is not clearly
better than the next candidate.

Stability events
----------------
:func:`stability_analysis` follows a static branch in v by pseudo-arclength
continuation (:func:`fempipe.static.continuation`), computes the spectrum at
every point, and locates to 1e-10 in v (Brent's method, recomputing the
static state at every trial v) every crossing of a tracked eigenvalue through
Re lambda = 0: flutter (a complex pair to the right), divergence (a real root
through zero), restabilisation (back to the left).  Folds of the static
branch come from the continuation (bisection to 1e-10 in arclength; v at a
fold agrees with the Moore-Spence extended system to 1e-15); a real root
passes through zero there, which is reported as the fold itself.  Branch
points (pitchforks at alpha = 0, pi) are followed with
:func:`fempipe.static.switch_branch` and the new branches analysed the same
way.  v_cr is the first velocity along the primary branch (the gravity-loaded
state continued in v) at which it is not stable.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
import weakref
from collections.abc import Callable, Sequence
from concurrent.futures import Executor, ProcessPoolExecutor
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp
import scipy.sparse.linalg as spla
from scipy.optimize import brentq, linear_sum_assignment, minimize_scalar

from .operators import PipeModel
from .params import Params
from .static import (
    Branch,
    NewtonError,
    continuation,
    solve_path,
    solve_static,
    switch_branch,
)
from .static import sagged_state as gravity_loaded_state  # noqa: F401  (public name kept)

__all__ = [
    "RESOLUTION_TOL",
    "STABILITY_TOL",
    "Resolution",
    "Spectrum",
    "ModeShape",
    "RootLocus",
    "StabilityEvent",
    "BranchStability",
    "StabilityResult",
    "StabilityMap",
    "cantilever_frequencies",
    "resolution",
    "linearized_matrices",
    "gravity_loaded_state",
    "spectrum",
    "growth_rate",
    "linearly_stable",
    "mode_shape",
    "root_locus",
    "root_loci",
    "stability_analysis",
    "critical_velocity",
    "stability_map",
    "run_tasks",
]

log = logging.getLogger(__name__)

#: Relative error of the clamped-free beam frequency up to which a
#: discretisation is said to resolve a canonical mode.
RESOLUTION_TOL = 0.05
#: Share of an eigenvector's squared M(0)-norm that must lie on resolved
#: canonical modes for its eigenvalue to be resolved.
RESOLVED_SHARE = 0.5
#: Re(lambda) <= STABILITY_TOL * max(1, |lambda|) counts as not unstable.
STABILITY_TOL = 1e-8
#: Brent tolerance on v for every located event (the task asks for 1e-8).
EVENT_XTOL = 1e-10
#: An eigenvalue with |Im| <= IMAG_TOL * max(1, |lambda|) at a crossing is real.
IMAG_TOL = 1e-7
#: Mode numbers up to which tracking ambiguities are refined (labels of higher
#: modes, heavily damped for mu > 0, may swap without affecting any event).
LABEL_MODES = 8
#: Largest state dimension solved by QZ; above, dense shift-invert.
QZ_MAX_N = 200


# ---------------------------------------------------------------------------
# Resolution of a discretisation
# ---------------------------------------------------------------------------


@contextlib.contextmanager
def _blas_threads(n: int):
    """One BLAS thread for the dense eigenproblems.

    They are small (2n = 96 for P3:16), where a multi-threaded BLAS spends
    more time synchronising than computing (measured: 32 ms per spectrum with
    2 OpenBLAS threads, 7 ms with one), and LAPACK's nonsymmetric QR
    iterations parallelise poorly even at n = 768 (P3:256: 5 s with one
    thread, 18 s with two on a busy 2-core machine).  threadpoolctl is
    optional; without it nothing changes.
    """
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # pragma: no cover - optional dependency
        yield
        return
    with threadpool_limits(1):
        yield


def _small_blas(fn):
    """Run ``fn(model, ...)`` under :func:`_blas_threads` (model.n)."""

    @functools.wraps(fn)
    def wrapper(model, *args, **kwargs):
        with _blas_threads(model.n):
            return fn(model, *args, **kwargs)

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
    time integrators, so the physics is written once.

    Returns
    -------
    K, C, M : ndarray, shape (n, n)
        Stiffness (bending, gravity, follower: not symmetric for v > 0),
        damping (Coriolis 2 v sqrt(beta) and Kelvin-Voigt mu), mass (SPD).
    """
    return model.jacobians(np.asarray(q, dtype=float))


def _eigen(K, C, M, method: str = "auto") -> tuple[np.ndarray, np.ndarray, str]:
    """All eigenvalues and theta-parts of the eigenvectors of (lambda^2 M + lambda C + K) x = 0.

    ``qz``: the generalised Schur decomposition of the first-order pencil
    (backward stable; used up to n = 200).  ``shift-invert``: the standard
    eigenproblem of (A - sigma B)^{-1} B with a real shift, for larger n: the
    low modes, the ones that matter, are its largest eigenvalues and come out
    with full relative accuracy, and it is 5-20 times faster than QZ at
    n = 768.  Both keep exact conjugate pairs (real arithmetic).
    """
    n = K.shape[0]
    if method == "auto":
        method = "qz" if n <= QZ_MAX_N else "shift-invert"
    if method == "qz":
        Z, I = np.zeros((n, n)), np.eye(n)
        A = np.block([[Z, I], [-K, -C]])
        B = np.block([[I, Z], [Z, M]])
        lam, V = sla.eig(A, B)
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
            nu, V = sla.eig(T)
            with np.errstate(divide="ignore", invalid="ignore"):
                lam = sigma + 1.0 / nu
            break
        else:  # pragma: no cover - four singular shifts in a row
            raise np.linalg.LinAlgError("shift-invert: the quadratic pencil is singular")
    else:
        raise ValueError(f"method must be 'auto', 'qz' or 'shift-invert', got {method!r}")
    ok = np.isfinite(lam)
    lam, X = lam[ok], V[:n, ok]
    X = X / np.linalg.norm(X, axis=0)
    return lam, X, method


@dataclass
class _Eig:
    """All eigenvalues of one state with their resolved-share classification."""

    v: float
    q: np.ndarray
    lam: np.ndarray
    X: np.ndarray
    share: np.ndarray
    weights: np.ndarray  # (n_canonical, m) squared canonical coefficients, normalised
    resolved: np.ndarray
    method: str
    s: float = 0.0  # position along a path (arclength proxy)
    fold: bool = False

    @property
    def unstable(self) -> np.ndarray:
        return self.resolved & (self.lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(self.lam)))

    @property
    def max_real(self) -> float:
        r = self.lam.real[self.resolved]
        return float(r.max()) if r.size else -math.inf


def _analyse(model: PipeModel, q: np.ndarray, res: Resolution, method: str) -> _Eig:
    K, C, M = linearized_matrices(model, q)
    lam, X, used = _eigen(K, C, M, method)
    c = res.basis.T @ (res.mass @ X)
    W = np.abs(c) ** 2
    W = W / W.sum(axis=0)
    share = W[: res.n_resolved].sum(axis=0)
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


def _canonical_labels(e: _Eig, idx: np.ndarray) -> np.ndarray:
    """Mode numbers (1-based) of eigenvalues idx by optimal assignment to canonical modes.

    Two slots per canonical mode (a conjugate pair, or two real roots of one
    mode); the cost is minus the share of the eigenvector on that mode.
    """
    if idx.size == 0:
        return np.zeros(0, dtype=int)
    W = e.weights[:, idx].T  # (k, n_can)
    cost = -np.repeat(W, 2, axis=1)
    rows, cols = linear_sum_assignment(cost)
    labels = np.empty(idx.size, dtype=int)
    labels[rows] = cols // 2 + 1
    return labels


def _order(lam: np.ndarray, labels: np.ndarray) -> np.ndarray:
    """Sort by mode number, then upper half-plane first."""
    return np.lexsort((-lam.imag, labels))


# ---------------------------------------------------------------------------
# One spectrum
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Spectrum:
    """The resolved spectrum of Eq. (32) about one static state.

    Attributes
    ----------
    params : Params
    q : ndarray, shape (n,)
        The static state theta^s.
    lam : ndarray of complex, shape (m,)
        Resolved eigenvalues lambda (theta^d ∝ e^{lambda tau}), sorted by mode
        number, upper half-plane first.
    mode : ndarray of int, shape (m,)
        Mode numbers (1-based; the canonical mode each eigenvector is made of).
    vectors : ndarray of complex, shape (n, m)
        theta-parts of the eigenvectors (unit Euclidean norm).
    share : ndarray, shape (m,)
        Share of each eigenvector on resolved canonical modes (>= 1/2).
    n_computed : int
        All eigenvalues computed (2 n).
    n_resolved_modes : int
        Canonical modes the discretisation resolves.
    max_real_unresolved : float
        Largest Re lambda among the discarded eigenvalues (diagnostic).
    static_residual : float
        Norm of the static residual at q (the linearisation assumes a state).
    method : str
        ``"qz"`` or ``"shift-invert"``.
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
                _eig_dict(lam, int(m)) for lam, m in zip(self.lam, self.mode, strict=True)
            ],
            "n_computed": self.n_computed,
            "n_resolved_modes": self.n_resolved_modes,
            "max_real_unresolved": self.max_real_unresolved,
            "static_residual": self.static_residual,
            "method": self.method,
        }


def _eig_dict(lam: complex, mode: int) -> dict:
    return {
        "mode": mode,
        "re": float(lam.real),
        "im": float(lam.imag),
        "Omega_re": float(lam.imag),
        "Omega_im": float(-lam.real),
    }


@_small_blas
def spectrum(
    model: PipeModel,
    q: np.ndarray | None = None,
    *,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
) -> Spectrum:
    """Resolved eigenvalues of the linearised problem, Eq. (32), about a static state.

    Parameters
    ----------
    model : PipeModel
    q : ndarray, shape (n,), optional
        The static state; default :func:`gravity_loaded_state`.
    method : {'auto', 'qz', 'shift-invert'}
        Dense eigensolver (see :func:`_eigen`).
    tolerance : float
        :data:`RESOLUTION_TOL`, the canonical-frequency error of a resolved mode.

    Returns
    -------
    Spectrum

    Raises
    ------
    ValueError
        If the discretisation resolves no mode at all.
    """
    res = resolution(model.disc, tolerance)
    if res.n_resolved == 0:
        raise ValueError(
            f"discretisation {model.disc.name} resolves no mode within {tolerance:.0%} "
            "of the clamped-free beam frequencies; refine it"
        )
    if q is None:
        q = gravity_loaded_state(model).q
    e = _analyse(model, q, res, method)
    tracker, _ = _reference_tracker(model, e, res, method)
    keep = e.resolved[tracker.first_idx]
    idx, labels = tracker.first_idx[keep], tracker.labels[keep]
    o = _order(e.lam[idx], labels)
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


# ---------------------------------------------------------------------------
# The stability criterion
# ---------------------------------------------------------------------------


def growth_rate(model: PipeModel, q: np.ndarray, *, tolerance: float = RESOLUTION_TOL) -> float:
    """Largest Re lambda of the resolved eigenvalues of Eq. (32) at the static state q.

    The quantity :attr:`Spectrum.max_real` reports (-inf if no eigenvalue is
    resolved).  Its sign alone is not the stability decision: an exactly
    conservative problem (v = mu = 0) has Re lambda = 0 to round-off; use
    :func:`linearly_stable`.
    """
    res = resolution(model.disc, tolerance)
    return _analyse(model, np.asarray(q, dtype=float), res, "auto").max_real


def linearly_stable(
    model: PipeModel,
    q: np.ndarray,
    *,
    tolerance: float = RESOLUTION_TOL,
    sparse: bool | None = None,
) -> bool | None:
    """Whether the static state q is linearly stable: the criterion of :func:`spectrum`.

    Stable when no resolved eigenvalue of Eq. (32) has
    Re lambda > ``STABILITY_TOL`` max(1, |lambda|) (the module docstring,
    "Resolved modes"); the same decision as ``spectrum(model, q).stable``,
    :func:`critical_velocity` and :func:`stability_analysis`.

    For finite elements with more than ``QZ_MAX_N`` unknowns only the
    eigenvalues of the lowest ``SPARSE_MODES`` modes are computed, by
    shift-invert Arnoldi at lambda = 0 on the first-order pencil: the inverse
    needs one sparse LU of K^d (banded plus the rank-one tip coupling of the
    follower force) and products with C^d and M^d, which are applied without
    forming them in O(n) (:meth:`fempipe.operators.PipeModel.inertia`,
    ``coriolis``, ``kelvin_voigt``).  Their resolution is tested on the lowest
    canonical modes (:func:`_low_canonical_modes`).  The modes above are
    bending-dominated and damped (Kelvin-Voigt Re lambda ~ -mu omega^2 / 2;
    the Coriolis force at the free end) and never decide; the tests check the
    decision against the dense criterion on stable, fluttering, diverging and
    buckled states.  Where K^d is singular (a fold or a branch point itself)
    the dense criterion is used.

    Parameters
    ----------
    model : PipeModel
    q : ndarray, shape (n,)
        A static state of ``model``.
    tolerance : float
        :data:`RESOLUTION_TOL`.
    sparse : bool, optional
        Force (True) or forbid (False) the sparse path; default: finite
        elements with n > ``QZ_MAX_N``.

    Returns
    -------
    bool or None
        None when the discretisation resolves no mode at all.
    """
    disc = model.disc
    if sparse is None:
        sparse = bool(disc.sparse) and disc.n > QZ_MAX_N
    if sparse:
        decision = _sparse_stable(model, np.asarray(q, dtype=float), tolerance)
        if decision is not _DENSE:
            return decision
    res = resolution(disc, tolerance)
    if res.n_resolved == 0:
        return None
    with _blas_threads(disc.n):
        e = _analyse(model, np.asarray(q, dtype=float), res, "auto")
    return not bool(e.unstable.any())


#: Modes whose eigenvalues the sparse criterion computes (24 eigenvalues:
#: canonical frequencies up to ~1300).
SPARSE_MODES = 12
#: Canonical modes computed for the sparse resolution test.
SPARSE_CANONICAL = 40
_DENSE = object()  # sentinel: the sparse path cannot decide, use the dense one
_LOW_CANONICAL_CACHE: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _mass_operator(model: PipeModel, q: np.ndarray) -> spla.LinearOperator:
    """x -> M^d(q) x in O(n): the inertia term of Eq. (20) with theta_ddot = Phi x."""
    n = model.n
    return spla.LinearOperator(
        (n, n), matvec=lambda x: model.inertia(model.fields(q, qddot=np.ravel(x))), dtype=float
    )


def _low_canonical_modes(disc, tolerance: float):
    """The lowest canonical modes (K phi = omega^2 M(0) phi) by sparse shift-invert at 0.

    Returns (basis (n, k) M(0)-orthonormal, number of leading modes within
    ``tolerance`` of the exact cantilever frequencies).  O(n) per Lanczos step:
    K is banded, M(0) is applied by :func:`_mass_operator`.
    """
    per_disc = _LOW_CANONICAL_CACHE.setdefault(disc, {})
    if tolerance in per_disc:
        return per_disc[tolerance]
    model0 = PipeModel(disc, Params(alpha=0.0, beta=0.0, gamma=0.0, mu=0.0, v=0.0))
    K = sp.csc_matrix(disc.K)
    lu = spla.splu(K)
    k = min(SPARSE_CANONICAL, disc.n - 2)
    opinv = spla.LinearOperator(K.shape, matvec=lambda x: lu.solve(np.ravel(x)), dtype=float)
    w2, basis = spla.eigsh(
        K, k=k, M=_mass_operator(model0, np.zeros(disc.n)), sigma=0.0, OPinv=opinv
    )
    o = np.argsort(w2)
    w2, basis = w2[o], basis[:, o]
    err = np.abs(np.sqrt(np.maximum(w2, 0.0)) / cantilever_frequencies(k) - 1.0)
    bad = np.flatnonzero(err > tolerance)
    out = (basis, int(bad[0]) if bad.size else k, model0)
    per_disc[tolerance] = out
    return out


def _sparse_stable(model: PipeModel, q: np.ndarray, tolerance: float):
    """:func:`linearly_stable` on the lowest modes (True/False/None, or _DENSE)."""
    n = model.n
    basis, n_low, model0 = _low_canonical_modes(model.disc, tolerance)
    if n_low == 0:
        return None
    try:
        lu = spla.splu(sp.csc_matrix(model.static_jacobian(q)))
    except RuntimeError:  # K^d exactly singular: a fold or a branch point
        return _DENSE
    mu = model.params.mu

    def op(z):
        # (A)^{-1} B z for A = [[0, I], [-K, -C]], B = diag(I, M): eigenvalue 1/lambda.
        x, y = z[:n], z[n:]
        fl = model.fields(q, qdot=x, qddot=y)
        rhs = model.inertia(fl) + model.coriolis(fl) + mu * np.asarray(model.disc.K @ x)
        return np.concatenate([-lu.solve(rhs), x])

    T = spla.LinearOperator((2 * n, 2 * n), matvec=lambda z: op(np.ravel(z)), dtype=float)
    # Kelvin-Voigt damping makes the modes with omega > 2 / mu overdamped, and
    # their roots accumulate between -2 / mu and -1 / mu: asking Arnoldi for
    # eigenvalues beyond |lambda| ~ 1 / mu would have it resolve that cluster
    # (measured: 58000 iterations at P3:300, mu = 5e-3).  Only the modes with
    # omega < 0.5 / mu are computed then; above, Re lambda < -mu omega^2 / 2
    # < -1 / (8 mu).
    omega = cantilever_frequencies(SPARSE_MODES)
    limit = 0.5 / mu if mu > 0.0 else math.inf
    k = min(2 * max(2, int(np.count_nonzero(omega < limit))), 2 * n - 2)
    nu, Z = spla.eigs(T, k=k, which="LM", ncv=min(2 * n, 2 * k + 1))
    lam = 1.0 / nu
    X = Z[:n]
    M0 = _mass_operator(model0, np.zeros(n))
    M0X = np.column_stack([M0 @ X[:, j].real + 1j * (M0 @ X[:, j].imag) for j in range(k)])
    total = np.real(np.einsum("ij,ij->j", X.conj(), M0X))
    low = np.abs(basis[:, :n_low].T @ M0X) ** 2
    resolved = low.sum(axis=0) >= RESOLVED_SHARE * total
    unstable = resolved & (lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(lam)))
    return not bool(unstable.any())


# ---------------------------------------------------------------------------
# Mode shapes
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class ModeShape:
    """A mode shape about a static state, in theta and in the global frame.

    The perturbation is ``Re(a e^{lambda tau})`` times the complex fields
    below, normalised so that max |theta^d| = 1 and theta^d is real and
    positive where it is largest.

    Attributes
    ----------
    xi : ndarray, shape (m,)
    theta : ndarray of complex, shape (m,)
        theta^d(xi).
    X_g, Z_g : ndarray of complex, shape (m,)
        Displacement of the centreline in the global frame (Eq. (28)
        linearised): dX_g = -int sin(theta^s + alpha) theta^d,
        dZ_g = int cos(theta^s + alpha) theta^d.
    X_static, Z_static : ndarray, shape (m,)
        The static centreline.
    lam : complex
    mode : int
    """

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
    """Shape of the resolved eigenvalue ``spec.lam[index]`` in theta and in the global frame.

    The global-frame displacement is the derivative of the centreline of
    :func:`fempipe.kinematics.shape` in the direction of the mode, obtained by
    complex-step differentiation of that same function (exact to round-off,
    no second copy of Eq. (28)).
    """
    from .kinematics import shape

    if not -spec.lam.size <= index < spec.lam.size:
        raise ValueError(f"index must be in [0, {spec.lam.size}), got {index}")
    x = spec.vectors[:, index]
    alpha = spec.params.alpha
    base = shape(disc, spec.q, alpha, points_per_cell)
    theta = disc.evaluate(x, base.xi)
    k = int(np.argmax(np.abs(theta)))
    scale = np.abs(theta[k]) / theta[k] if theta[k] != 0 else 1.0
    x = x * scale / np.abs(theta[k])
    h = 1e-30  # complex step: Im f(q + i h d) / h = f'(q) d exactly
    parts = []
    for d in (x.real, x.imag):
        s = shape(disc, spec.q + 1j * h * d, alpha, points_per_cell)
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


# ---------------------------------------------------------------------------
# Tracking eigenvalues along a path
# ---------------------------------------------------------------------------


class _Tracker:
    """Carries mode numbers along a sequence of states by continuity.

    Tracked eigenvalue j is, at every state, one index into that state's
    :class:`_Eig`; ``labels[j]`` is its mode number, given at the first state
    (``first_idx``) and inherited by continuity afterwards.
    """

    def __init__(self, labels: np.ndarray, first_idx: np.ndarray) -> None:
        self.labels = np.asarray(labels, dtype=int)
        self.first_idx = np.asarray(first_idx, dtype=int)

    @classmethod
    def canonical(cls, first: _Eig) -> _Tracker:
        """Every resolved eigenvalue of ``first``, numbered by canonical assignment."""
        idx = np.flatnonzero(first.resolved)
        labels = _canonical_labels(first, idx)
        o = _order(first.lam[idx], labels)
        return cls(labels[o], idx[o])

    def match(self, new: _Eig, pred: np.ndarray):
        """Indices in ``new`` of the tracked eigenvalues, and an ambiguity flag per eigenvalue."""
        D = np.abs(pred[:, None] - new.lam[None, :])
        rows, cols = linear_sum_assignment(D)
        idx = np.empty(pred.size, dtype=int)
        idx[rows] = cols
        d1 = D[np.arange(pred.size), idx]
        # Distance to the nearest other candidate that is not the same mode's
        # partner (swapping a conjugate pair or the two roots of one mode is harmless).
        owner = np.full(new.lam.size, -1)
        owner[idx] = self.labels
        other = owner[None, :] != self.labels[:, None]
        D2 = np.where(other, D, np.inf)
        d2 = D2.min(axis=1)
        relevant = (self.labels <= LABEL_MODES) | (new.lam[idx].real > -1.0)
        ambiguous = relevant & (d1 > 0.35 * d2)
        return idx, ambiguous


def _predict(samples: list[tuple[_Eig, np.ndarray]], s: float) -> np.ndarray:
    """Linear prediction of the tracked eigenvalues at position s."""
    e1, i1 = samples[-1]
    lam1 = e1.lam[i1]
    if len(samples) < 2:
        return lam1
    e0, i0 = samples[-2]
    lam0 = e0.lam[i0]
    if e1.s == e0.s:
        return lam1
    return lam1 + (s - e1.s) / (e1.s - e0.s) * (lam1 - lam0)


def _l2(model: PipeModel, dq: np.ndarray) -> float:
    th = model.disc.Phi @ dq
    return float(np.sqrt(model.w @ th**2))


class _Path:
    """Spectra along a sequence of static states, with tracking and refinement.

    ``static_between(a, b, v)`` returns the static state at v between samples
    a and b (both on the same monotone piece in v), or None.
    """

    def __init__(
        self,
        model: PipeModel,
        res: Resolution,
        method: str,
        max_depth: int = 6,
    ) -> None:
        self.model = model
        self.res = res
        self.method = method
        self.max_depth = max_depth
        self.samples: list[tuple[_Eig, np.ndarray]] = []
        self.tracker: _Tracker | None = None
        self.n_spectra = 0

    def analyse(self, q: np.ndarray, v: float) -> _Eig:
        self.n_spectra += 1
        return _analyse(
            self.model.with_params(replace(self.model.params, v=v)), q, self.res, self.method
        )

    def static_between(self, a: _Eig, b: _Eig, v: float) -> np.ndarray | None:
        if a.v == b.v:
            return None
        t = (v - a.v) / (b.v - a.v)
        m = self.model.with_params(replace(self.model.params, v=v))
        guess = a.q + t * (b.q - a.q)
        # An exact guess (the straight pipe at alpha = 0, pi) is kept as it is:
        # at a branch point the Jacobian is singular and a Newton step from an
        # exact solution would fail.
        p = m.params
        if np.linalg.norm(m.static_residual(guess)) <= 1e-13 * (1.0 + p.gamma + p.v**2):
            return guess
        try:
            return solve_static(m, q0=guess).q
        except NewtonError:
            return None

    def add(self, e: _Eig, depth: int = 0) -> None:
        """Append the next state, halving the step while tracking is ambiguous."""
        if self.tracker is None:
            self.tracker = _Tracker.canonical(e)
            self.samples.append((e, self.tracker.first_idx))
            return
        prev = self.samples[-1]
        pred = _predict(self.samples, e.s)
        idx, amb = self.tracker.match(e, pred)
        if amb.any() and depth < self.max_depth and not e.fold and not prev[0].fold:
            a = prev[0]
            vm = 0.5 * (a.v + e.v)
            qm = self.static_between(a, e, vm)
            if qm is not None:
                mid = self.analyse(qm, vm)
                mid.s = 0.5 * (a.s + e.s)
                self.add(mid, depth + 1)
                self.add(e, depth + 1)
                return
        self.samples.append((e, idx))

    # -- views ------------------------------------------------------------
    @property
    def labels(self) -> np.ndarray:
        return self.tracker.labels

    def tracked(self) -> np.ndarray:
        """Tracked eigenvalues, shape (n_samples, k)."""
        return np.array([e.lam[i] for e, i in self.samples])

    def tracked_resolved(self) -> np.ndarray:
        return np.array([e.resolved[i] for e, i in self.samples])

    def start_labelled(self, e: _Eig, tracker: _Tracker) -> None:
        """Start at ``e`` with mode numbers given by ``tracker`` (indices into e)."""
        self.tracker = tracker
        self.samples = [(e, tracker.first_idx)]


#: Largest arclength step of the reference path from v = 0 (mode numbers);
#: the tracker halves it wherever the match is ambiguous.
REFERENCE_STEP = 1.0


def _reference_tracker(model: PipeModel, e: _Eig, res: Resolution, method: str):
    """Mode numbers of the resolved eigenvalues of ``e``, carried by continuity from v = 0.

    The static branch through e is followed back to v = 0 by pseudo-arclength
    continuation (steps up to :data:`REFERENCE_STEP`, folds passed); the
    eigenvalues resolved there are numbered by canonical assignment and
    tracked forward to e.  A branch that does not reach v = 0 is numbered at
    the end of the backward continuation instead.  Returns the tracker
    (indices into e) and the number of spectra solved.
    """
    if e.v == 0.0:
        return _Tracker.canonical(e), 0
    m = model.with_params(replace(model.params, v=e.v))
    back = continuation(
        m, "v", stop=0.0, q0=e.q, ds=REFERENCE_STEP, ds_max=REFERENCE_STEP, detect=False
    )
    if back.end_reason != "stop":
        log.info(
            "reference path: the branch through v=%.6g ends at v=%.6g (%s); mode numbers "
            "assigned there",
            e.v,
            back.points[-1].value,
            back.end_reason,
        )
    points = back.points[::-1][:-1]  # v = 0 first; the last point is e itself
    path = _Path(model, res, method)
    s, prev = 0.0, None
    for pt in points:
        if prev is not None:
            s += abs(pt.value - prev[1]) + _l2(model, pt.q - prev[0])
        prev = (pt.q, pt.value)
        x = path.analyse(pt.q, pt.value)
        x.s = s
        path.add(x)
    s += abs(e.v - prev[1]) + _l2(model, e.q - prev[0]) if prev is not None else 0.0
    target = replace(e, s=s)
    path.add(target)
    last, idx = path.samples[-1]
    if last is not target:  # pragma: no cover - add() always appends its argument last
        raise RuntimeError("reference path: the target state is not the last sample")
    return _complete(e, _Tracker(path.labels, idx)), path.n_spectra


def _complete(e: _Eig, tracker: _Tracker) -> _Tracker:
    """Add the resolved eigenvalues of e the tracker lacks, numbered on the free canonical slots.

    An eigenvalue can be resolved at e and not where the numbering started;
    it gets the canonical mode its eigenvector is made of among the slots (two
    per mode) the tracked eigenvalues leave free.
    """
    tracked = set(tracker.first_idx.tolist())
    extra = np.array([i for i in np.flatnonzero(e.resolved) if i not in tracked], dtype=int)
    if extra.size == 0:
        return tracker
    n_can = e.weights.shape[0]
    used = np.bincount(tracker.labels - 1, minlength=n_can)[:n_can]
    free = np.maximum(0, 2 - used)
    slots = np.repeat(np.arange(n_can), free)
    cost = -e.weights[:, extra].T[:, slots]
    rows, cols = linear_sum_assignment(cost)
    labels = np.zeros(extra.size, dtype=int)
    labels[rows] = slots[cols] + 1
    return _Tracker(
        np.concatenate([tracker.labels, labels]), np.concatenate([tracker.first_idx, extra])
    )


# ---------------------------------------------------------------------------
# Root loci (Fig. 5)
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class RootLocus:
    """Eigenvalues against v with mode numbers carried by continuity (Fig. 5).

    Attributes
    ----------
    params : Params
        The fixed parameters (v is the first value).
    v : ndarray, shape (m,)
    lam : ndarray of complex, shape (m, k)
        Tracked eigenvalues; column j belongs to mode ``modes[j]``.
    modes : ndarray of int, shape (k,)
    resolved : ndarray of bool, shape (m, k)
    max_real : ndarray, shape (m,)
        Largest Re lambda of all resolved eigenvalues at each v.
    stable : ndarray of bool, shape (m,)
    theta_tip : ndarray, shape (m,)
        Static tip rotation (which branch).
    n_spectra : int
        Spectra computed, including the points inserted for tracking.
    """

    params: Params
    v: np.ndarray
    lam: np.ndarray
    modes: np.ndarray
    resolved: np.ndarray
    max_real: np.ndarray
    stable: np.ndarray
    theta_tip: np.ndarray
    n_spectra: int

    @property
    def Omega(self) -> np.ndarray:
        return -1j * self.lam

    def to_dict(self) -> dict:
        p = self.params.to_dict()
        p.pop("v", None)
        points = []
        for i, v in enumerate(self.v):
            eig = [
                _eig_dict(self.lam[i, j], int(self.modes[j]))
                for j in range(self.modes.size)
                if self.resolved[i, j]
            ]
            points.append(
                {
                    "v": float(v),
                    "stable": bool(self.stable[i]),
                    "max_real": float(self.max_real[i]),
                    "theta_tip": float(self.theta_tip[i]),
                    "eigenvalues": eig,
                }
            )
        return {"params": p, "modes": self.modes.tolist(), "points": points}


@_small_blas
def root_locus(
    model: PipeModel,
    values: Sequence[float],
    *,
    q0: np.ndarray | None = None,
    n_modes: int | None = 6,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
    callback: Callable[[int, float], None] | None = None,
) -> RootLocus:
    """Spectra along the static branch at the flow velocities ``values`` (Fig. 5).

    Parameters
    ----------
    model : PipeModel
        Parameters other than v are taken from ``model.params``.
    values : sequence of float
        Flow velocities, in the order the branch is followed.
    q0 : ndarray, optional
        Static state at ``values[0]`` (default: :func:`gravity_loaded_state`).
    n_modes : int or None
        Report modes 1..n_modes (None: every resolved mode); every mode that
        is unstable at some v is reported too, whatever its number.  Every
        resolved eigenvalue is tracked.
    callback : callable, optional
        ``callback(i, v)`` after each point (progress).

    Returns
    -------
    RootLocus
    """
    values = [float(x) for x in values]
    if not values:
        raise ValueError("values must contain at least one flow velocity")
    if n_modes is not None and int(n_modes) < 1:
        raise ValueError(f"n_modes must be >= 1 or None, got {n_modes}")
    res = resolution(model.disc, tolerance)
    if res.n_resolved == 0:
        raise ValueError(f"discretisation {model.disc.name} resolves no mode; refine it")
    m0 = model.with_params(replace(model.params, v=values[0]))
    if q0 is None:
        q0 = gravity_loaded_state(m0).q
    states = solve_path(m0, values, q0=q0)
    path = _Path(model, res, method)
    keep = []  # sample index of each requested value
    s = 0.0
    for i, sol in enumerate(states):
        if i:
            s += abs(values[i] - values[i - 1]) + _l2(model, sol.q - states[i - 1].q)
        e = path.analyse(sol.q, values[i])
        e.s = s
        if i == 0:
            tracker, n_ref = _reference_tracker(model, e, res, method)
            path.n_spectra += n_ref
            path.start_labelled(e, tracker)
        else:
            path.add(e)
        keep.append(len(path.samples) - 1)
        if callback:
            callback(i, values[i])
    lam = path.tracked()[keep]
    resolved = path.tracked_resolved()[keep]
    labels = path.labels
    # Modes 1..n_modes, and every mode that is unstable at some point whatever
    # its number (the eigenvalue that decides ``stable`` is always listed).
    unstable = resolved & (lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(lam)))
    cols = np.ones(labels.size, dtype=bool) if n_modes is None else labels <= int(n_modes)
    cols = np.flatnonzero(cols | unstable.any(axis=0))
    cols = cols[np.argsort(labels[cols], kind="stable")]
    max_real = np.array([path.samples[k][0].max_real for k in keep])
    stable = np.array([not path.samples[k][0].unstable.any() for k in keep])
    tips = np.array([float(model.disc.tip @ st.q) for st in states])
    return RootLocus(
        params=m0.params,
        v=np.array(values),
        lam=lam[:, cols],
        modes=labels[cols].copy(),
        resolved=resolved[:, cols],
        max_real=max_real,
        stable=stable,
        theta_tip=tips,
        n_spectra=path.n_spectra,
    )


# ---------------------------------------------------------------------------
# Stability events along branches
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class StabilityEvent:
    """A change of stability, or a fold, on a static branch.

    Attributes
    ----------
    v : float
        Flow velocity, located to 1e-10 (Brent) for crossings; folds to the
        continuation's 1e-10 in arclength.
    type : {'flutter', 'divergence', 'restabilization', 'mode_restabilization', 'fold'}
        As v increases: a complex pair crosses to Re lambda > 0 (flutter), a
        real root does (divergence), an eigenvalue crosses back and the
        branch is stable above the event (restabilization), an eigenvalue
        crosses back while another one stays unstable, so the branch is not
        stable above the event (mode_restabilization: a per-mode event, the
        system does not restabilise); or the branch turns back in v (fold).
        ``stable_before`` and ``stable_after`` say what the whole system does.
    branch : str
        Branch name (``"primary"``, ``"B1+"``, ...).
    frequency : float
        Im lambda = Re Omega at the crossing (0 for real roots and folds).
    mode : int or None
        Number of the crossing mode (carried by continuity along the branch).
    eigenvalue : complex
        lambda at the crossing.
    at_start : bool
        The instability was already present at the start of the branch's
        v-range (the event is listed at that v).
    stable_before, stable_after : bool
        Stability of the branch just below / above the event in v (for a fold:
        on the branch piece arriving at / leaving the fold, in branch order).
    """

    v: float
    type: str
    branch: str
    frequency: float
    mode: int | None
    eigenvalue: complex = 0j
    at_start: bool = False
    stable_before: bool = True
    stable_after: bool = True

    def to_dict(self) -> dict:
        """The contract of ``fempipe critical --json``: v, type, branch, frequency, mode,
        stable_before, stable_after (the whole system just below and above the event)."""
        return {
            "v": self.v,
            "type": self.type,
            "branch": self.branch,
            "frequency": self.frequency,
            "mode": self.mode,
            "stable_before": self.stable_before,
            "stable_after": self.stable_after,
        }

    def details(self) -> dict:
        d = self.to_dict()
        d.update(
            {
                "eigenvalue": [float(self.eigenvalue.real), float(self.eigenvalue.imag)],
                "at_start": self.at_start,
            }
        )
        return d


@dataclass(frozen=True)
class BranchStability:
    """One static branch and its stability along it (arclength order).

    Attributes
    ----------
    name : str
    parent : str or None
        Branch it bifurcates from.
    born_at : float or None
        v of the branch point it starts from.
    v, theta_tip, max_real : ndarray, shape (m,)
        At every sample (continuation points plus inserted ones).
    n_unstable : ndarray of int, shape (m,)
        Resolved eigenvalues with Re lambda > 0 (a complex pair counts 2).
    events : tuple of StabilityEvent
    folds, bifurcations : tuple of float
        v of the folds and branch points located by the continuation.
    end_reason : str
        Why the continuation stopped (see :class:`fempipe.static.Branch`).
    """

    name: str
    parent: str | None
    born_at: float | None
    v: np.ndarray
    theta_tip: np.ndarray
    max_real: np.ndarray
    n_unstable: np.ndarray
    events: tuple
    folds: tuple
    bifurcations: tuple
    end_reason: str

    def to_dict(self, samples: bool = False) -> dict:
        d = {
            "name": self.name,
            "parent": self.parent,
            "born_at": self.born_at,
            "v_min": float(self.v.min()),
            "v_max": float(self.v.max()),
            "folds": list(self.folds),
            "bifurcations": list(self.bifurcations),
            "end_reason": self.end_reason,
            "events": [e.details() for e in self.events],
        }
        if samples:
            d["samples"] = {
                "v": self.v.tolist(),
                "theta_tip": self.theta_tip.tolist(),
                "max_real": self.max_real.tolist(),
                "n_unstable": self.n_unstable.tolist(),
            }
        return d


@dataclass(frozen=True)
class StabilityResult:
    """Stability of the static branches of one parameter point over a v-range.

    Attributes
    ----------
    params : Params
        (v is the start of the range.)
    discretization : dict
    v_range : (float, float)
    v_cr : float or None
        First v at which the primary branch is not stable (the start of the
        range if it is unstable there); None if stable throughout.
    critical : StabilityEvent or None
        The event that defines v_cr.
    v_flutter : float or None
        First flutter on the primary branch (Fig. 6 plots this; it equals v_cr
        except where divergence or a fold comes first, e.g. alpha = pi).
    events : tuple of StabilityEvent
        All branches, by branch then v.
    branches : tuple of BranchStability
    n_spectra : int
        Eigenproblems solved (diagnostic).
    """

    params: Params
    discretization: dict
    v_range: tuple[float, float]
    v_cr: float | None
    critical: StabilityEvent | None
    v_flutter: float | None
    events: tuple
    branches: tuple
    n_spectra: int

    def to_dict(self, samples: bool = False) -> dict:
        p = self.params.to_dict()
        p.pop("v", None)
        return {
            "v_cr": self.v_cr,
            "events": [e.to_dict() for e in self.events],
            "critical": None if self.critical is None else self.critical.details(),
            "v_flutter": self.v_flutter,
            "v_range": list(self.v_range),
            "params": p,
            "discretization": self.discretization,
            "branches": [b.to_dict(samples) for b in self.branches],
            "n_spectra": self.n_spectra,
        }


def _unstable_count(e: _Eig) -> int:
    return int(e.unstable.sum())


def _state_sign(lam: complex) -> int:
    """+1 unstable, -1 stable, 0 marginal (|Re| within round-off)."""
    tol = STABILITY_TOL * max(1.0, abs(lam))
    if lam.real > tol:
        return 1
    if lam.real < -tol:
        return -1
    return 0


class _BranchAnalysis:
    """Spectra, tracking and events along one continuation branch.

    Three passes: (1) a spectrum at every continuation point (folds inserted,
    tracking refined where ambiguous); (2) a peak check: where a tracked
    Re lambda has an extremum towards zero between three samples, it is
    maximised and, if it crosses, the extremum becomes a sample; (3) every
    sign change of a tracked Re lambda between neighbouring samples is
    located by Brent's method.
    """

    def __init__(
        self,
        model: PipeModel,
        res: Resolution,
        branch: _Pieces,
        name: str,
        v_range: tuple[float, float],
        method: str,
        stop_at_first: bool = False,
        callback: Callable[[str, float], None] | None = None,
        parent: _BranchAnalysis | None = None,
    ) -> None:
        self.model = model
        self.res = res
        self.method = method
        self.branch = branch
        self.name = name
        self.v_lo, self.v_hi = v_range
        self.path = _Path(model, res, method)
        self.parent = parent
        self.stop_at_first = stop_at_first
        self.callback = callback
        # (position s, event, unstable count before, after) in branch order
        self.events: list[tuple[float, StabilityEvent, int, int]] = []

    # -- pass 1: samples ----------------------------------------------------
    def run(self) -> None:
        s, prev = 0.0, None
        for q, v, is_fold in self.branch.iter_points():
            if prev is not None:
                s += abs(v - prev[1]) + _l2(self.model, q - prev[0])
            prev = (q, v)
            e = self.path.analyse(q, v)
            e.s, e.fold = s, is_fold
            if self.path.tracker is None:
                self._number(e)
            else:
                self.path.add(e)
            if self.callback:
                self.callback(self.name, v)
            if self.stop_at_first and _unstable_count(e) > 0:
                break
        self._peaks()
        samples = self.path.samples
        for k in range(1, len(samples)):
            self._segment(k)
            if samples[k][0].fold:
                self._fold_event(k)
        self._start_events()
        self.events.sort(key=lambda x: x[0])

    def _number(self, first: _Eig) -> None:
        """Mode numbers at the branch's first state (the package docstring, "Mode numbers").

        Carried from v = 0 along the branch (:func:`_reference_tracker`); on a
        branch born at a branch point, from the parent branch's sample nearest
        the first state.
        """
        if self.parent is None:
            tracker, n = _reference_tracker(self.model, first, self.res, self.method)
        else:
            tracker, n = self.parent.carry_to(first)
        self.path.n_spectra += n
        self.path.start_labelled(first, tracker)

    def carry_to(self, e: _Eig) -> tuple[_Tracker, int]:
        """Mode numbers of e (a state near this branch) by continuity from the nearest sample."""
        dist = [abs(x.v - e.v) + _l2(self.model, x.q - e.q) for x, _ in self.path.samples]
        k = int(np.argmin(dist))
        ref, idx = self.path.samples[k]
        path = _Path(self.model, self.res, self.method)
        path.start_labelled(ref, _Tracker(self.path.labels, idx))
        target = replace(e, s=ref.s + dist[k])
        path.add(target)
        return _complete(e, _Tracker(path.labels, path.samples[-1][1])), path.n_spectra

    def _retrack(self, eigs: list[_Eig]) -> None:
        self.path.samples = [(eigs[0], self.path.tracker.first_idx)]
        for e in eigs[1:]:
            self.path.add(e, depth=self.path.max_depth)

    # -- pass 2: extrema of Re lambda between samples ----------------------
    def _peaks(self, max_inserts: int = 20) -> None:
        inserted = 0
        k = 2
        while k < len(self.path.samples) and inserted < max_inserts:
            e = self._peak(k)
            if e is None:
                k += 1
                continue
            eigs = [x for x, _ in self.path.samples]
            eigs.insert(k - 1 if e.s < eigs[k - 1].s else k, e)
            self._retrack(eigs)
            inserted += 1

    def _peak(self, k: int) -> _Eig | None:
        """A sample where a tracked Re lambda touches zero between samples k-2 and k, or None."""
        (a, ia), (m, im), (b, ib) = self.path.samples[k - 2 : k + 1]
        if m.fold or a.fold or b.fold or not (a.v < m.v < b.v or a.v > m.v > b.v):
            return None
        x = np.array([a.v, m.v, b.v])
        for j in range(self.path.labels.size):
            lams = (a.lam[ia[j]], m.lam[im[j]], b.lam[ib[j]])
            states = [_state_sign(lam) for lam in lams]
            signs = [s > 0 for s in states]
            if len(set(signs)) != 1:
                continue  # a crossing: located in pass 3
            unstable = signs[0]
            if not unstable and -1 not in states:
                continue  # on the imaginary axis to round-off (undamped): nothing to refine
            r = np.array([lam.real for lam in lams])
            c = np.polyfit(x, r, 2)
            if c[0] == 0 or (c[0] < 0) == unstable:
                continue  # the extremum points away from zero
            vx = -c[1] / (2 * c[0])
            if not x.min() < vx < x.max():
                continue
            ext, spread = np.polyval(c, vx), abs(r[1] - r[0]) + abs(r[2] - r[1])
            if (not unstable and ext < -0.5 * spread) or (unstable and ext > 0.5 * spread):
                continue
            sgn = -1.0 if unstable else 1.0
            lo, hi = (a, b) if a.v < b.v else (b, a)
            ilo, ihi = (ia[j], ib[j]) if a.v < b.v else (ib[j], ia[j])

            def g(v: float, lo=lo, hi=hi, ilo=ilo, ihi=ihi, sgn=sgn) -> float:
                e, kk = self._eig_at(lo, hi, ilo, ihi, v)
                return -sgn * e.lam[kk].real

            opt = minimize_scalar(g, bounds=(lo.v, hi.v), method="bounded", options={"xatol": 1e-7})
            e, kk = self._eig_at(lo, hi, ilo, ihi, float(opt.x))
            if (_state_sign(e.lam[kk]) > 0) != unstable:
                e.s = lo.s + (hi.s - lo.s) * (float(opt.x) - lo.v) / (hi.v - lo.v)
                log.info("branch %s: narrow window of Re lambda > 0 near v=%.6g", self.name, opt.x)
                return e
        return None

    # -- pass 3: events -----------------------------------------------------
    def _eig_at(self, a: _Eig, b: _Eig, ia: int, ib: int, v: float) -> tuple[_Eig, int]:
        """The tracked eigenvalue at v between samples a and b (nearest the linear prediction)."""
        q = self.path.static_between(a, b, v)
        if q is None:
            raise NewtonError(
                f"static state not found at v={v:.10g} while locating a stability event on "
                f"branch {self.name}",
                params=replace(self.model.params, v=v),
                iterations=0,
                residual=float("nan"),
            )
        e = self.path.analyse(q, v)
        pred = a.lam[ia] + (v - a.v) / (b.v - a.v) * (b.lam[ib] - a.lam[ia])
        cand = np.flatnonzero(e.resolved) if e.resolved.any() else np.arange(e.lam.size)
        return e, int(cand[np.argmin(np.abs(e.lam[cand] - pred))])

    def _locate(self, a: _Eig, b: _Eig, ia: int, ib: int) -> tuple[float, complex]:
        """Brent on Re lambda of one tracked eigenvalue between samples a and b."""
        shift = 0.0
        # A marginal end (|Re| within round-off: an undamped problem) means the
        # onset is a collision, Re ~ sqrt(v - v_c): locating Re = tol instead
        # of 0 moves v by ~tol^2, far below the 1e-10 asked of Brent.
        for lam in (a.lam[ia], b.lam[ib]):
            if _state_sign(lam) == 0:
                shift = STABILITY_TOL * max(1.0, abs(lam))
        fa, fb = a.lam[ia].real - shift, b.lam[ib].real - shift
        if fa == 0.0 or fb == 0.0 or np.sign(fa) == np.sign(fb):
            e, i = (a, ia) if abs(fa) <= abs(fb) else (b, ib)
            return e.v, complex(e.lam[i])
        found: dict[float, complex] = {}

        def f(v: float) -> float:
            if v == a.v:
                return fa
            if v == b.v:
                return fb
            e, k = self._eig_at(a, b, ia, ib, v)
            found[v] = e.lam[k]
            return float(e.lam[k].real - shift)

        v0 = brentq(f, a.v, b.v, xtol=EVENT_XTOL, rtol=4 * np.finfo(float).eps)
        lam0 = found.get(v0)
        if lam0 is None:
            lam0 = a.lam[ia] if abs(v0 - a.v) <= abs(v0 - b.v) else b.lam[ib]
        return float(v0), complex(lam0)

    def _segment(self, k: int) -> None:
        """Crossings of tracked eigenvalues between samples k-1 and k."""
        (a, ia), (b, ib) = self.path.samples[k - 1], self.path.samples[k]
        labels = self.path.labels
        ca, cb = _unstable_count(a), _unstable_count(b)
        crossings = []
        for j in range(labels.size):
            la, lb = a.lam[ia[j]], b.lam[ib[j]]
            if (_state_sign(la) > 0) == (_state_sign(lb) > 0):
                continue
            real_a = abs(la.imag) <= IMAG_TOL * max(1.0, abs(la))
            real_b = abs(lb.imag) <= IMAG_TOL * max(1.0, abs(lb))
            if not real_a and not real_b and la.imag < 0 and lb.imag < 0:
                continue  # the lower member of a crossing pair: counted with its partner
            if (a.fold or b.fold) and (real_a or real_b):
                continue  # a real root through zero at a fold: the fold event itself
            if a.v == b.v:
                continue
            v0, lam0 = self._locate(a, b, ia[j], ib[j])
            real = abs(lam0.imag) <= IMAG_TOL * max(1.0, abs(lam0))
            # Unstable on the side of larger v?
            up = (_state_sign(lb) > 0) == (b.v > a.v)
            s0 = a.s + (b.s - a.s) * (v0 - a.v) / (b.v - a.v)
            crossings.append((float(v0), complex(lam0), j, up, real, s0))
        # Whole-system stability on either side of each crossing: the unstable
        # count at the lower-v sample, changed by each crossing in v order (a
        # complex pair counts two, a real root one).
        count = ca if b.v > a.v else cb
        for v0, lam0, j, up, real, s0 in sorted(crossings):
            after = max(0, count + (1 if real else 2) * (1 if up else -1))
            if up:
                typ = "divergence" if real else "flutter"
            else:
                typ = "restabilization" if after == 0 else "mode_restabilization"
            ev = StabilityEvent(
                v=v0,
                type=typ,
                branch=self.name,
                frequency=0.0 if real else float(abs(lam0.imag)),
                mode=int(labels[j]),
                eigenvalue=complex(lam0.real, abs(lam0.imag)),
                stable_before=bool(count == 0),
                stable_after=bool(after == 0),
            )
            self.events.append((s0, ev, ca, cb))
            count = after

    def _fold_event(self, k: int) -> None:
        samples = self.path.samples
        f, i_f = samples[k]
        before = _unstable_count(samples[k - 1][0])
        after = _unstable_count(samples[k + 1][0]) if k + 1 < len(samples) else before
        j = int(np.argmin(np.abs(f.lam[i_f])))
        ev = StabilityEvent(
            v=float(f.v),
            type="fold",
            branch=self.name,
            frequency=0.0,
            mode=int(self.path.labels[j]),
            eigenvalue=complex(f.lam[i_f][j]),
            stable_before=bool(before == 0),
            stable_after=bool(after == 0),
        )
        self.events.append((f.s, ev, before, after))

    def _start_events(self) -> None:
        """Instabilities present at the branch end with the smaller v (listed at that v)."""
        samples = self.path.samples
        first, last = samples[0], samples[-1]
        end, idx = first if first[0].v <= last[0].v else last
        n_u = _unstable_count(end)
        for j, label in enumerate(self.path.labels):
            lam = end.lam[idx[j]]
            if not end.resolved[idx[j]] or _state_sign(lam) <= 0:
                continue
            real = abs(lam.imag) <= IMAG_TOL * max(1.0, abs(lam))
            if not real and lam.imag < 0:
                continue
            ev = StabilityEvent(
                v=float(end.v),
                type="divergence" if real else "flutter",
                branch=self.name,
                frequency=0.0 if real else float(lam.imag),
                mode=int(label),
                eigenvalue=complex(lam),
                at_start=True,
                stable_before=False,
                stable_after=False,
            )
            self.events.append((end.s, ev, n_u, n_u))

    # -- results -----------------------------------------------------------
    def first_loss(self) -> StabilityEvent | None:
        """The first event in branch order after which the branch is not stable."""
        start_unstable = _unstable_count(self.path.samples[0][0]) > 0
        for _, ev, before, after in self.events:
            if ev.at_start:
                if start_unstable:
                    return ev
                continue
            if before == 0 and after > 0:
                return ev
        return None

    def refined_bifurcation(self, value: float) -> float:
        """A branch point's v from the located real-root crossing, if there is one.

        The continuation locates branch points by bisection on the sign of a
        determinant, which stops where the corrector fails near the singular
        point (measured: 7e-8 off in v at alpha = pi); the real eigenvalue
        through zero located by Brent is exact to 1e-10.
        """
        near = [
            ev.v
            for _, ev, _, _ in self.events
            if ev.frequency == 0.0 and ev.type != "fold" and abs(ev.v - value) < 1e-5
        ]
        return float(min(near, key=lambda x: abs(x - value))) if near else float(value)

    def finish(self, parent: str | None, born_at: float | None) -> BranchStability:
        samples = [e for e, _ in self.path.samples]
        lo, hi = self.v_lo - 1e-12, self.v_hi + 1e-12
        events = [ev for _, ev, _, _ in self.events if lo <= ev.v <= hi]
        return BranchStability(
            name=self.name,
            parent=parent,
            born_at=born_at,
            v=np.array([e.v for e in samples]),
            theta_tip=np.array([float(self.model.disc.tip @ e.q) for e in samples]),
            max_real=np.array([e.max_real for e in samples]),
            n_unstable=np.array([_unstable_count(e) for e in samples]),
            events=tuple(sorted(events, key=lambda ev: ev.v)),
            folds=tuple(float(f.value) for f in self.branch.folds),
            bifurcations=tuple(self.refined_bifurcation(b.value) for b in self.branch.bifurcations),
            end_reason=self.branch.end_reason,
        )


class _Pieces:
    """A static branch continued in v piece by piece, seen as one branch.

    With ``chunk`` set, the continuation advances ``chunk`` in v at a time and
    only as far as the analysis asks (``stop_at_first``: no continuation
    beyond the first loss of stability); otherwise in one piece.  Fold and
    branch-point indices are renumbered to the concatenated point list.
    """

    def __init__(self, branch: Branch | None = None) -> None:
        self.points: list = []
        self.special: list = []
        self.end_reason = "stop"
        self._next = None
        if branch is not None:
            self._add(branch)

    @classmethod
    def follow(
        cls,
        model: PipeModel,
        v_range: tuple[float, float],
        ds_max: float,
        q0: np.ndarray | None,
        max_steps: int,
        chunk: float | None = None,
    ) -> _Pieces:
        lo, hi = v_range
        m = model.with_params(replace(model.params, v=lo))
        q = gravity_loaded_state(m).q if q0 is None else solve_static(m, q0=q0).q
        self = cls()
        kw = {"ds": min(0.05, ds_max), "ds_max": ds_max, "max_steps": max_steps}

        def advance(piece_start, tangent):
            v_a, q_a = piece_start
            stop = hi if chunk is None else min(hi, v_a + chunk)
            ma = model.with_params(replace(model.params, v=v_a))
            return continuation(ma, "v", stop=stop, q0=q_a, tangent=tangent, **kw)

        self._next = lambda: advance((lo, q), None)
        self._hi = hi
        self._advance = advance
        return self

    def _add(self, branch: Branch) -> None:
        skip = 1 if self.points else 0
        offset = len(self.points) - skip
        self.points.extend(branch.points[skip:])
        self.special.extend(replace(s, index=s.index + offset) for s in branch.special)
        self.end_reason = branch.end_reason

    def more(self) -> bool:
        """Continue one more piece; False when the branch is finished."""
        if self._next is None:
            return False
        piece = self._next()
        self._add(piece)
        last = self.points[-1]
        if piece.end_reason != "stop" or last.value >= self._hi:
            self._next = None
        else:
            self._next = lambda: self._advance((last.value, last.q), last.tangent)
        return True

    @property
    def folds(self) -> list:
        return [s for s in self.special if s.kind == "fold"]

    @property
    def bifurcations(self) -> list:
        return [s for s in self.special if s.kind == "bifurcation"]

    def iter_points(self):
        """(q, v, is_fold) in arclength order, continuing lazily."""
        i = 0
        while True:
            while i < len(self.points):
                # The folds located in segment [i - 1, i] come before point i.
                for f in self.special:
                    if f.kind == "fold" and f.index == i - 1:
                        yield f.q, f.value, True
                p = self.points[i]
                yield p.q, p.value, False
                i += 1
            if not self.more():
                return


@_small_blas
def stability_analysis(
    model: PipeModel,
    v_max: float = 10.0,
    v_min: float = 0.0,
    *,
    follow_bifurcations: bool = True,
    max_depth: int = 1,
    q0: np.ndarray | None = None,
    ds_max: float = 0.1,
    max_steps: int = 2000,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
    stop_at_first: bool = False,
    callback: Callable[[str, float], None] | None = None,
) -> StabilityResult:
    """Every stability event and fold of the static branches for v_min <= v <= v_max.

    Parameters
    ----------
    model : PipeModel
        alpha, beta, gamma, mu from ``model.params`` (its v is ignored).
    v_max, v_min : float
        The flow range, 0 <= v_min < v_max.
    follow_bifurcations : bool
        Follow the branches born at branch points (pitchforks at alpha = 0, pi)
        with :func:`fempipe.static.switch_branch` and analyse them too.
    max_depth : int
        Generations of branches to follow (1: those born on the primary branch).
    q0 : ndarray, optional
        Initial guess of the primary state at v_min (default: gravity loading).
    ds_max : float
        Largest continuation step (arclength in (theta L2, v)); spectra are
        computed at every point, so it bounds the sampling of the eigenvalue
        paths; tracking inserts points where it is not clear and a peak check
        catches a real part that touches zero between samples.
    stop_at_first : bool
        Stop analysing the primary branch after the first loss of stability
        (enough for v_cr; events beyond it are not listed).
    callback : callable, optional
        ``callback(branch_name, v)`` after every sample (progress).

    Returns
    -------
    StabilityResult

    Raises
    ------
    NewtonError
        If the static state cannot be followed (naming v and the residual).
    """
    v_min, v_max = float(v_min), float(v_max)
    if not (math.isfinite(v_min) and math.isfinite(v_max)) or v_min < 0 or v_max <= v_min:
        raise ValueError(f"need 0 <= v_min < v_max, got v_min={v_min}, v_max={v_max}")
    if ds_max <= 0:
        raise ValueError(f"ds_max must be > 0, got {ds_max}")
    res = resolution(model.disc, tolerance)
    if res.n_resolved == 0:
        raise ValueError(f"discretisation {model.disc.name} resolves no mode; refine it")
    # Piecewise continuation when only v_cr is wanted: nothing beyond it is computed.
    chunk = 1.0 if stop_at_first else None
    primary = _Pieces.follow(model, (v_min, v_max), ds_max, q0, max_steps, chunk)
    ana = _BranchAnalysis(
        model, res, primary, "primary", (v_min, v_max), method, stop_at_first, callback
    )
    ana.run()
    results = [ana.finish(None, None)]
    n_spectra = ana.path.n_spectra
    first = ana.first_loss()
    v_flutter = next((ev.v for _, ev, _, _ in ana.events if ev.type == "flutter"), None)
    queue = [(primary, "primary", 1, ana)] if follow_bifurcations and not stop_at_first else []
    while queue:
        br, name, depth, parent_ana = queue.pop(0)
        for k, bp in enumerate(br.bifurcations, start=1):
            if not v_min <= bp.value <= v_max:
                continue
            try:
                kids = switch_branch(
                    model.with_params(replace(model.params, v=bp.value)),
                    bp,
                    "v",
                    v_max,
                    ds_max=ds_max,
                    max_steps=max_steps,
                )
            except (NewtonError, np.linalg.LinAlgError) as exc:
                log.warning("branch switching at v=%.8g on %s failed: %s", bp.value, name, exc)
                continue
            for sign, kid in zip("+-", kids, strict=True):
                kname = f"B{k}{sign}" if name == "primary" else f"{name}.B{k}{sign}"
                ka = _BranchAnalysis(
                    model,
                    res,
                    _Pieces(kid),
                    kname,
                    (v_min, v_max),
                    method,
                    False,
                    callback,
                    parent=parent_ana,
                )
                ka.run()
                results.append(ka.finish(name, parent_ana.refined_bifurcation(bp.value)))
                n_spectra += ka.path.n_spectra
                if depth < max_depth:
                    queue.append((kid, kname, depth + 1, ka))
    events = tuple(ev for b in results for ev in b.events)
    return StabilityResult(
        params=replace(model.params, v=v_min),
        discretization=model.disc.to_dict(),
        v_range=(v_min, v_max),
        v_cr=None if first is None else float(first.v),
        critical=first,
        v_flutter=v_flutter,
        events=events,
        branches=tuple(results),
        n_spectra=n_spectra,
    )


def critical_velocity(
    model: PipeModel,
    v_max: float = 10.0,
    v_min: float = 0.0,
    **kwargs,
) -> StabilityResult:
    """v_cr: the first loss of stability of the primary branch (no branch switching).

    A shortcut for :func:`stability_analysis` with ``follow_bifurcations=False``
    and ``stop_at_first=True``; its ``events`` stop at the critical one.
    """
    kwargs.setdefault("follow_bifurcations", False)
    kwargs.setdefault("stop_at_first", True)
    return stability_analysis(model, v_max, v_min, **kwargs)


# ---------------------------------------------------------------------------
# Parallel sweeps
# ---------------------------------------------------------------------------


def _limit_threads() -> None:
    """Worker initializer: one BLAS thread per process (the matrices are small)."""
    try:
        from threadpoolctl import threadpool_limits

        threadpool_limits(1)
    except ImportError:  # pragma: no cover - optional
        pass


def run_tasks(
    fn: Callable,
    tasks: Sequence[tuple],
    *,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
) -> list:
    """Run ``fn(*task)`` for every task, in parallel if asked; results in task order.

    Parameters
    ----------
    fn : callable
        A module-level function (it is pickled for process pools).
    tasks : sequence of tuple
    workers : int, optional
        Without ``executor``: > 1 starts a local ``ProcessPoolExecutor`` with
        that many processes (one BLAS thread each); None or 1 runs serially.
    executor : concurrent.futures.Executor, optional
        Any executor (a process pool, Dask's ``Client.get_executor()``); it is
        not shut down.
    callback : callable, optional
        ``callback(done, total, result)`` as each task finishes (progress).

    Returns
    -------
    list
        One entry per task: its return value, or the exception it raised (a
        failed point does not lose the others).
    """
    tasks = list(tasks)
    total = len(tasks)
    out: list = [None] * total
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    own = None
    if executor is None and workers is not None and int(workers) > 1 and total > 1:
        own = ProcessPoolExecutor(max_workers=int(workers), initializer=_limit_threads)
        executor = own
    try:
        if executor is None:
            for i, t in enumerate(tasks):
                try:
                    out[i] = fn(*t)
                except (NewtonError, ValueError, np.linalg.LinAlgError, RuntimeError) as exc:
                    out[i] = exc
                if callback:
                    callback(i + 1, total, out[i])
            return out
        from concurrent.futures import as_completed

        futures = {executor.submit(fn, *t): i for i, t in enumerate(tasks)}
        done = 0
        for fut in as_completed(futures):
            i = futures[fut]
            try:
                out[i] = fut.result()
            except Exception as exc:  # noqa: BLE001 - recorded per point
                out[i] = exc
            done += 1
            if callback:
                callback(done, total, out[i])
        return out
    finally:
        if own is not None:
            own.shutdown(cancel_futures=True)


def _map_point(disc, params: Params, v_max: float, options: dict) -> dict:
    model = PipeModel(disc, params)
    res = critical_velocity(model, v_max, **options)
    c = res.critical
    if c is not None and c.at_start:
        # Unstable from the start (the straight column at alpha = pi): follow the
        # branch to the end for its first flutter (what Fig. 6 shows there).
        full = stability_analysis(
            model, v_max, **{**options, "stop_at_first": False, "follow_bifurcations": False}
        )
        res = replace(res, v_flutter=full.v_flutter, n_spectra=res.n_spectra + full.n_spectra)
    return {
        "v_cr": res.v_cr,
        "type": None if c is None else c.type,
        "frequency": None if c is None else c.frequency,
        "mode": None if c is None else c.mode,
        "v_flutter": res.v_flutter,
        "n_spectra": res.n_spectra,
    }


@dataclass(frozen=True)
class StabilityMap:
    """v_cr against alpha for several (beta, gamma) curves (Fig. 6).

    Attributes
    ----------
    alphas : ndarray, shape (n_alpha,)
    curves : tuple of (beta, gamma)
    base : Params
        mu and the defaults.
    v_max : float
        Upper end of the searched range (v_cr is None if stable up to it).
    points : list of list of dict
        ``points[c][a]``: v_cr, type, frequency, mode, v_flutter (or error).
    """

    alphas: np.ndarray
    curves: tuple
    base: Params
    v_max: float
    discretization: dict
    points: list

    def array(self, key: str = "v_cr") -> np.ndarray:
        """``key`` as an array, shape (n_curves, n_alpha); NaN where missing."""
        out = np.full((len(self.curves), self.alphas.size), np.nan)
        for c, row in enumerate(self.points):
            for a, pt in enumerate(row):
                x = pt.get(key)
                if isinstance(x, (int, float)) and x is not None:
                    out[c, a] = x
        return out

    def rows(self) -> list[dict]:
        """Flat rows (one per curve and alpha) for CSV."""
        rows = []
        for (beta, gamma), row in zip(self.curves, self.points, strict=True):
            for alpha, pt in zip(self.alphas, row, strict=True):
                rows.append(
                    {
                        "alpha": float(alpha),
                        "beta": beta,
                        "gamma": gamma,
                        "v_cr": pt.get("v_cr"),
                        "type": pt.get("type"),
                        "frequency": pt.get("frequency"),
                        "mode": pt.get("mode"),
                        "v_flutter": pt.get("v_flutter"),
                        "error": pt.get("error"),
                    }
                )
        return rows

    def to_dict(self) -> dict:
        return {
            "alphas": self.alphas.tolist(),
            "curves": [{"beta": b, "gamma": g} for b, g in self.curves],
            "mu": self.base.mu,
            "v_max": self.v_max,
            "discretization": self.discretization,
            "points": self.rows(),
        }


def stability_map(
    disc,
    alphas: Sequence[float],
    curves: Sequence[tuple[float, float]],
    *,
    mu: float = 5e-3,
    v_max: float = 10.0,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
    **options,
) -> StabilityMap:
    """v_cr(alpha) for each (beta, gamma) in ``curves``, in parallel (Fig. 6).

    Each point is an independent :func:`critical_velocity` (gravity loading,
    continuation in v, first loss of stability); ``options`` are passed on
    (``ds_max`` defaults to 0.2 here: Brent locates v_cr to 1e-10 whatever the
    sampling, and the tracking and peak checks refine where needed).
    A point that fails is recorded with its error and does not stop the others.
    """
    alphas = np.asarray([float(a) for a in alphas])
    curves = tuple((float(b), float(g)) for b, g in curves)
    # v_cr only: continuation steps of 0.2 (measured: the 37-point curve of
    # Fig. 6 is identical to 3e-11 with 0.1, in 60 % of the time).
    options.setdefault("ds_max", 0.2)
    if alphas.size == 0 or not curves:
        raise ValueError("need at least one alpha and one (beta, gamma) curve")
    tasks = []
    for beta, gamma in curves:
        for a in alphas:
            tasks.append(
                (disc, Params(alpha=a, beta=beta, gamma=gamma, mu=mu, v=0.0), v_max, options)
            )
    out = run_tasks(_map_point, tasks, workers=workers, executor=executor, callback=callback)
    points = []
    for c in range(len(curves)):
        row = []
        for a in range(alphas.size):
            r = out[c * alphas.size + a]
            row.append(r if isinstance(r, dict) else {"v_cr": None, "error": str(r)})
        points.append(row)
    return StabilityMap(
        alphas=alphas,
        curves=curves,
        base=Params(alpha=0.0, beta=curves[0][0], gamma=curves[0][1], mu=mu),
        v_max=float(v_max),
        discretization=disc.to_dict(),
        points=points,
    )


def _locus_task(disc, params: Params, values, options: dict) -> RootLocus:
    return root_locus(PipeModel(disc, params), values, **options)


def root_loci(
    disc,
    params: Sequence[Params],
    values: Sequence[float],
    *,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
    **options,
) -> list:
    """:func:`root_locus` for several parameter points (e.g. the four alphas of Fig. 5), in parallel.

    Returns a list of RootLocus (or the exception of a failed point).
    """
    tasks = [(disc, p, list(values), options) for p in params]
    return run_tasks(_locus_task, tasks, workers=workers, executor=executor, callback=callback)

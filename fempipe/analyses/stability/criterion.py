"""The stability criterion of a static state: :func:`linearly_stable`, :func:`growth_rate`.

Dense on every resolved eigenvalue, or for large meshes on the lowest modes by sparse
shift-invert Arnoldi (docs/theory/stability.md, "Linear stability").
"""

from __future__ import annotations

import math
import weakref

import numpy as np
import scipy.sparse as sp
import scipy.sparse.linalg as spla

from fempipe.core.parallel import single_blas, single_blas_thread
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

from .canonical import RESOLUTION_TOL, RESOLVED_SHARE, cantilever_frequencies, resolution
from .classified import STABILITY_TOL, classify_spectrum
from .eigensolvers import QZ_MAX_N
from .hysteretic import RELEVANT_SHARE, ConjugateHalves, match_roots, relevant_roots


@single_blas
def growth_rate(model: PipeModel, q: np.ndarray, *, tolerance: float = RESOLUTION_TOL) -> float:
    """Largest resolved Re lambda of Eq. (32) at q (the decision is :func:`linearly_stable`)."""
    res = resolution(model.disc, tolerance)
    return classify_spectrum(model, np.asarray(q, dtype=float), res, "auto").max_real


def linearly_stable(
    model: PipeModel,
    q: np.ndarray,
    *,
    tolerance: float = RESOLUTION_TOL,
    sparse: bool | None = None,
) -> bool | None:
    """Whether the static state q is linearly stable: no resolved eigenvalue of Eq. (32) with
    Re lambda > ``STABILITY_TOL`` max(1, |lambda|) (docs/theory/stability.md).

    Parameters
    ----------
    model : PipeModel
    q : ndarray, shape (n,)
    tolerance : float
        :data:`RESOLUTION_TOL`.
    sparse : bool, optional
        Only the lowest ``SPARSE_MODES`` modes by shift-invert Arnoldi; default: finite
        elements with n > ``QZ_MAX_N``.

    Returns
    -------
    bool or None
        None when the discretization resolves no mode.
    """
    disc = model.disc
    if sparse is None:
        sparse = bool(disc.sparse) and disc.n > QZ_MAX_N
    # The sparse path applies the planar operators without forming them; the
    # out-of-plane problem is formed densely (fempipe.model.out_of_plane.model).
    if sparse and model.plane == "in":
        decision = _sparse_stable(model, np.asarray(q, dtype=float), tolerance)
        if decision is not _DENSE:
            return decision
    res = resolution(disc, tolerance)
    if res.n_resolved == 0:
        return None
    with single_blas_thread():
        e = classify_spectrum(model, np.asarray(q, dtype=float), res, "auto")
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
    """(M(0)-orthonormal basis, number of resolved leading modes, model) of the lowest
    canonical modes K phi = omega^2 M(0) phi, by sparse shift-invert at 0."""
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
    per_disc[tolerance] = out = (basis, int(bad[0]) if bad.size else k, model0)
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

    def op_parts(z):
        # M y + C x for real z: every rate term of the model.
        return model.rate_terms(q, z[:n], z[n:])

    def op(z):
        # (A)^{-1} B z for A = [[0, I], [-K, -C]], B = diag(I, M): eigenvalue 1/lambda.
        return np.concatenate([-lu.solve(op_parts(z)), z[:n]])

    T = spla.LinearOperator((2 * n, 2 * n), matvec=lambda z: op(np.ravel(z)), dtype=float)
    # Kelvin-Voigt roots of the modes with omega > 2 / mu cluster between -2 / mu and
    # -1 / mu, which Arnoldi would have to resolve: only omega < 0.5 / mu is computed
    # (above, Re lambda < -mu omega^2 / 2 < -1 / (8 mu)).
    omega = cantilever_frequencies(SPARSE_MODES)
    mu = model.params.mu
    limit = 0.5 / mu if mu > 0.0 else math.inf
    k = min(2 * max(2, int(np.count_nonzero(omega < limit))), 2 * n - 2)
    nu, Z = spla.eigs(T, k=k, which="LM", ncv=min(2 * n, 2 * k + 1))
    lam = 1.0 / nu
    X = Z[:n]
    M0 = _mass_operator(model0, np.zeros(n))

    def energies(X):
        # Squared M(0)-norm of each column, and its part on the resolved canonical modes.
        M0X = np.column_stack([M0 @ X[:, j].real + 1j * (M0 @ X[:, j].imag) for j in range(k)])
        total = np.real(np.einsum("ij,ij->j", X.conj(), M0X))
        return (np.abs(basis[:, :n_low].T @ M0X) ** 2).sum(axis=0), total

    low, total = energies(X)
    mu_h = model.params.hysteretic_damping
    if mu_h > 0.0:
        relevant = low >= RELEVANT_SHARE * total
        roots = _sparse_hysteretic(model, q, op_parts, lam, X, relevant, mu_h, k)
        if roots is _DENSE:
            return _DENSE
        lam, X = roots
        low, total = energies(X)
    resolved = low >= RESOLVED_SHARE * total
    unstable = resolved & (lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(lam)))
    return not bool(unstable.any())


def _sparse_hysteretic(model: PipeModel, q, op_parts, lam0, X0, relevant, mu_h: float, k: int):
    """The lowest roots with hysteretic damping (one step of mu_h), or _DENSE if ambiguous."""
    n = model.n
    try:
        Kc = sp.csc_matrix(model.static_jacobian(q)) + 1j * mu_h * sp.csc_matrix(model.disc.K)
        lu = spla.splu(sp.csc_matrix(Kc))
    except RuntimeError:
        return _DENSE

    def op(z):
        rhs = op_parts(z.real) + 1j * op_parts(z.imag)
        return np.concatenate([-lu.solve(rhs), z[:n]])

    T = spla.LinearOperator((2 * n, 2 * n), matvec=lambda z: op(np.ravel(z)), dtype=complex)
    nu, Z = spla.eigs(T, k=k, which="LM", ncv=min(2 * n, 2 * k + 1))
    lam, X = 1.0 / nu, Z[:n]
    halves = ConjugateHalves.of(lam0)
    targets, Xt = halves.targets(lam0, X0)
    if targets.size > lam.size:
        return _DENSE
    idx, ambiguous = match_roots(targets, Xt, lam, X, relevant_roots(targets, relevant[halves.pos]))
    if ambiguous.any():
        return _DENSE
    return halves.assemble(lam0, X0, lam[idx], X[:, idx], lam[idx].imag <= 0.0)

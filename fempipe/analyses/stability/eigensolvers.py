"""Dense eigensolvers of the quadratic eigenproblem of Eq. (32).

(lambda^2 M + lambda C + K) x = 0 in first-order form
(:mod:`fempipe.core.companion`): QZ on the pencil, or a shift-inverted
standard eigenproblem for larger n (:func:`quadratic_eigen`).
"""

from __future__ import annotations

import numpy as np
import scipy.linalg as sla

from fempipe.core.companion import first_order_pencil

#: Largest state dimension solved by QZ; above, dense shift-invert.
QZ_MAX_N = 200

#: geev's workspace size per (order, vectors), queried once.
_GEEV_LWORK: dict = {}


def _dense_eig(T: np.ndarray, rows: int, vectors: bool) -> tuple[np.ndarray, np.ndarray | None]:
    """LAPACK geev as scipy.linalg.eig calls it (same bits); eigenvectors' first ``rows`` rows."""
    if T.dtype != np.float64:
        out = sla.eig(T, right=vectors)
        return (out[0], out[1][:rows]) if vectors else (out, None)
    if not np.isfinite(T).all():
        raise ValueError("array must not contain infs or NaNs")
    geev, geev_lwork = sla.get_lapack_funcs(("geev", "geev_lwork"), (T,))
    key = (T.shape[0], bool(vectors))
    lwork = _GEEV_LWORK.get(key)
    if lwork is None:
        # scipy's own (private) workspace query, the one scipy.linalg.eig makes:
        # the same lwork gives geev the same blocking, hence the same bits.
        # scipy has no public equivalent; it is outside this package.
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


def quadratic_eigen(
    K, C, M, method: str = "auto", vectors: bool = True
) -> tuple[np.ndarray, np.ndarray | None, str]:
    """All eigenvalues and theta-parts of the eigenvectors of (lambda^2 M + lambda C + K) x = 0.

    ``qz``: the generalized Schur decomposition of the first-order pencil (backward stable);
    ``shift-invert``: (A - sigma B)^{-1} B with a real shift, the low modes its largest
    eigenvalues.  Both keep exact conjugate pairs.

    Parameters
    ----------
    K, C, M : ndarray, shape (n, n)
        K^d, C^d, M^d of Eqs. (33a)-(33c) (K complex with hysteretic damping).
    method : {'auto', 'qz', 'shift-invert'}
        ``auto``: QZ up to n = :data:`QZ_MAX_N`, shift-invert above.
    vectors : bool
        Whether to compute the eigenvectors (X None otherwise).

    Returns
    -------
    lam : ndarray of complex, shape (m,)
        The finite eigenvalues (m <= 2n).
    X : ndarray of complex, shape (n, m), or None
        Their theta-parts, unit Euclidean norm.
    method : str
        The method used.
    """
    n = K.shape[0]
    if method == "auto":
        method = "qz" if n <= QZ_MAX_N else "shift-invert"
    if method == "qz":
        A, B = first_order_pencil(K, C, M)
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

"""Hopf criticality of the flutter events: the first Lyapunov coefficient l1.

A flutter event of ``fempipe critical`` is a Hopf bifurcation of the static
state: one complex pair lambda(v) = mu(v) +- i omega(v) of the linearisation of
Eq. (20) (Eqs. (31b)-(33)) crosses the imaginary axis at v = v_cr.  Whether the
periodic orbit born there is stable (supercritical, l1 < 0: a small limit
cycle grows like sqrt(v - v_cr) on the unstable side) or unstable
(subcritical, l1 > 0: an unstable cycle surrounds the still stable
equilibrium on the stable side, and the motion jumps to a large cycle at
v_cr) is decided by the sign of the first Lyapunov coefficient of the normal
form on the centre manifold.

First-order form
----------------
With x = (q, p = q') the weak form of Eq. (20), R(q, q', q'') = 0 (linear in
q'', :class:`fempipe.model.operators.PipeModel`), is

    x' = F(x; v),   F(q, p) = (p, a(q, p)),   a = -M(q)^{-1} R(q, p, 0).

Its Jacobian is analytic: differentiating R(q, p, a(q, p)) = 0,

    D_x F = [[0, I], [-M^{-1} R_q(q, p, a), -M^{-1} R_q'(q, p, a)]],

with R_q, R_q' and M = R_q'' of :meth:`PipeModel.jacobians` evaluated at the
acceleration a (off the equilibrium the derivative of M(q) a matters).  At the
equilibrium x0 = (q0, 0) this is the first-order form of the pencil
lambda^2 M + lambda C + K of the stability code, A = D_x F(x0).

Kuznetsov's formula
-------------------
With A q = i omega q, A^T p = -i omega p, <p, q> = p^H q = 1, and the
multilinear forms B(x, y) = D^2 F(x0)[x, y], C(x, y, z) = D^3 F(x0)[x, y, z]
(Kuznetsov, Elements of Applied Bifurcation Theory, 3rd ed., Eq. (3.20) and
its n-dimensional form, Eq. (5.39)):

    c1 = 1/2 [ <p, C(q, q, qbar)> - 2 <p, B(q, A^{-1} B(q, qbar))>
               + <p, B(qbar, (2 i omega I - A)^{-1} B(q, q))> ],
    l1 = Re(c1) / omega.

On the centre manifold x = x0 + z q + zbar qbar + O(|z|^2) the flow is
z' = lambda(v) z + c1 |z|^2 z + O(|z|^4), so a periodic orbit has
|z|^2 = rho^2 = -mu(v) / (omega l1), and to leading order

    rho^2 = -Re(lambda'(v_cr)) (v - v_cr) / (omega l1),
    x(tau) - x0 = 2 rho Re(q e^{i omega tau}) + O(rho^2).

It exists on the side of v_cr where Re(lambda') (v - v_cr) / l1 < 0.  (The
shorter rho^2 = -Re(lambda') (v - v_cr) / l1 measures lambda in the time
omega tau of Kuznetsov's topological normal form; here tau is the time of
Eq. (19).)

Normalisation
-------------
l1 scales with |q|^2, so its value depends on how q is normalised; its sign
does not.  Here the theta-part q_theta of q has unit L2 norm,
``\\int_0^1 |theta_q(xi)|^2 dxi = 1`` (the discretisation's Gram matrix), so
that l1 and rho converge with the discretisation and rho is the amplitude of
the theta field: theta(xi, tau) ~ theta0 + 2 rho Re(theta_q(xi) e^{i omega tau}).
A tip quantity s(q) oscillates with (max - min)/2 = 2 rho |ds . q_theta| +
O(rho^3) (the second harmonic shifts max and min alike), which gives the
amplitude coefficients c in ``(max - min)/2 ~ c sqrt(|v - v_cr|)``.

Derivatives
-----------
B and C are differences of the analytic Jacobian J(x) = D_x F(x), never of F:

    DJ[u] = (J(x0 + h u) - J(x0 - h u)) / (2 h),
    D2J[u, u] = (J(x0 + h u) - 2 J(x0) + J(x0 - h u)) / h^2,

for u = Re q, Im q.  Since B is symmetric and bilinear,
B(q, y) = B(y, q) = (DJ[Re q] + i DJ[Im q]) y and B(qbar, y) = (DJ[Re q] -
i DJ[Im q]) y; C(q, q, qbar) = D2J[q, qbar] q = (D2J[Re q, Re q] +
D2J[Im q, Im q]) q (the mixed terms cancel).  Four Jacobians (plus A) give
every term; two on the straight pipe at alpha = 0 or pi, where the mirror
symmetry makes J even about x0 = 0, J(x0 - h u) = J(x0 + h u), and B = 0.
The errors are O(h^2) (truncation) and O(eps |J| / h^2)
(rounding of the second difference).  For the pipe the constant bending part
of J (~h_mesh^-4 after M^{-1}) is not differenced (:func:`pipe_derivatives`);
what rounding remains comes from the acceleration off the equilibrium (a sum
of O(gamma, v^2) forces that cancel at x0) and grows with the mesh.  So the
step is not fixed: l1 is computed on the ladder h = 1e-5 4^k, k = 0..4
(q of unit size), and the flattest three consecutive values are taken (the
middle one), their spread being the uncertainty, plus a rounding level 1e-10
of the size of the terms of c1.  The middle three steps are computed first,
and taken with their spread as the uncertainty when they agree to
:data:`FLAT_ENOUGH` of l1; otherwise the two ends are added.  Measured at the paper's Hopf point at
alpha = 0: l1 flat to 2e-6 relative for 1e-5 <= h <= 1e-3 on P3:4 to P3:32.
A fixed ``step`` h uses h and 2 h, the uncertainty being their difference / 3
(Richardson).  An l1 within 10 times its uncertainty of zero is called
``"degenerate"`` (a Bautin point, or a cancellation this computation cannot
resolve): neither criticality is claimed.

Transversality
--------------
lambda'(v) = <p, (dA/dv) q>, with dA/dv the derivative along the static
branch: (J(x0 + h x_v; v + h) - J(x0 - h x_v; v - h)) / (2 h), where
x_v = (q_v, 0) and q_v = -R_q^{-1} R_v the branch's tangent.

Hysteretic damping
------------------
Hysteretic damping (``Params.hysteretic_damping``) is a frequency-domain
model with no equation of motion in time, hence no normal form:
:func:`first_lyapunov_coefficient` refuses it (ValueError) and
:func:`decorate_events` reports the reason instead of a value.
"""

from __future__ import annotations

import copy
import math
from collections.abc import Callable
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla
import scipy.sparse as sp

from fempipe.model.operators import PipeModel

from .linear import single_blas, straight_is_static

__all__ = [
    "DEGENERATE_FACTOR",
    "STEP_LADDER",
    "FLAT_ENOUGH",
    "HopfCoefficient",
    "HopfNormalForm",
    "lyapunov_coefficient",
    "pipe_jacobian",
    "pipe_derivatives",
    "jacobian_differences",
    "first_lyapunov_coefficient",
    "event_states",
    "normal_forms",
    "decorate_events",
    "EVENT_KEYS",
]

#: |l1| <= DEGENERATE_FACTOR * uncertainty: "degenerate", no criticality claimed.
DEGENERATE_FACTOR = 10.0
#: Difference steps tried for B and C (q of unit size; module docstring).
STEP_LADDER = (1e-5, 4e-5, 1.6e-4, 6.4e-4, 2.56e-3)
#: The ends of the ladder are added only when the middle three steps spread by
#: more than this fraction of l1 (measured flat to ~2e-6 from P3:4 to P3:32).
FLAT_ENOUGH = 1e-5
#: Relative rounding level of the terms of c1 added to the uncertainty.
ROUNDING_LEVEL = 1e-10


@dataclass(frozen=True)
class HopfCoefficient:
    """The normal-form coefficient of a Hopf point of a generic x' = F(x).

    Attributes
    ----------
    l1 : float
        First Lyapunov coefficient Re(c1) / omega.
    uncertainty : float
        Spread of l1 over the steps used, plus the rounding level (module docstring).
    c1 : complex
        Cubic coefficient of z' = lambda z + c1 |z|^2 z.
    eigenvalue : complex
        The critical eigenvalue of A (Im > 0).
    omega : float
        Im of it.
    q, p : ndarray of complex, shape (N,)
        Right and adjoint eigenvectors, p^H q = 1, q normalised by ``norm``.
    step : float
        The difference step h of ``l1``.
    l1_2h : float
        l1 computed with the next larger step (diagnostic).
    terms : tuple of complex
        <p, C(q,q,qbar)>, -2 <p, B(q, A^-1 B(q,qbar))>, <p, B(qbar, (2iw-A)^-1 B(q,q))>.
    ladder : tuple of (float, float)
        (h, l1(h)) for every step tried: the plateau.
    """

    l1: float
    uncertainty: float
    c1: complex
    eigenvalue: complex
    omega: float
    q: np.ndarray = field(repr=False)
    p: np.ndarray = field(repr=False)
    step: float = math.nan
    l1_2h: float = math.nan
    terms: tuple = ()
    ladder: tuple = ()

    @property
    def criticality(self) -> str:
        """'supercritical' (l1 < 0), 'subcritical' (l1 > 0) or 'degenerate'."""
        if not abs(self.l1) > DEGENERATE_FACTOR * self.uncertainty:
            return "degenerate"
        return "supercritical" if self.l1 < 0 else "subcritical"


def _critical_pair(A: np.ndarray, omega: float | None) -> tuple[complex, np.ndarray, np.ndarray]:
    """The eigenvalue of A nearest i omega (default: the Im > 0 one nearest the
    imaginary axis, relative to its size), with right and left eigenvectors."""
    lam, vl, vr = sla.eig(A, left=True, right=True)
    upper = np.flatnonzero(lam.imag > 0)
    if upper.size == 0:
        raise ValueError("the Jacobian has no complex eigenvalue: not a Hopf point")
    if omega is None:
        k = upper[np.argmin(np.abs(lam[upper].real) / np.abs(lam[upper]))]
    else:
        k = upper[np.argmin(np.abs(lam[upper] - 1j * omega))]
    return complex(lam[k]), vr[:, k], vl[:, k]


def jacobian_differences(
    jacobian: Callable[[np.ndarray], np.ndarray], x0: np.ndarray, A: np.ndarray
) -> Callable[[np.ndarray, float], tuple[np.ndarray, np.ndarray]]:
    """``(u, h) -> (DJ[u], D2J[u, u])``: central differences of the Jacobian about x0.

    ``DJ[u] = (J(x0 + h u) - J(x0 - h u)) / (2 h)`` and
    ``D2J[u, u] = (J(x0 + h u) - 2 A + J(x0 - h u)) / h^2`` with A = J(x0):
    errors O(h^2) and O(eps |J| / h^2).
    """

    def deriv(u: np.ndarray, h: float) -> tuple[np.ndarray, np.ndarray]:
        Jp, Jm = jacobian(x0 + h * u), jacobian(x0 - h * u)
        return (Jp - Jm) / (2.0 * h), (Jp - 2.0 * A + Jm) / (h * h)

    return deriv


def lyapunov_coefficient(
    jacobian: Callable[[np.ndarray], np.ndarray],
    x0: np.ndarray,
    *,
    omega: float | None = None,
    norm: np.ndarray | None = None,
    step: float | None = None,
    derivatives: Callable[[np.ndarray, float], tuple[np.ndarray, np.ndarray]] | None = None,
) -> HopfCoefficient:
    """First Lyapunov coefficient of x' = F(x) at the equilibrium x0 (Kuznetsov, Eq. (3.20)).

    Parameters
    ----------
    jacobian : callable
        ``jacobian(x) -> ndarray (N, N)``, the analytic D_x F at any x (the
        multilinear forms B, C are its differences, module docstring).
    x0 : ndarray, shape (N,)
        The equilibrium, F(x0) = 0, where A = jacobian(x0) has a pair +- i omega.
    omega : float, optional
        Frequency of the critical pair (the eigenvalue nearest i omega is
        taken); default the pair nearest the imaginary axis.
    norm : ndarray, shape (N, N), optional
        Hermitian positive semi-definite G with q^H G q = 1 fixing the scale
        of q (and so of l1); default the identity.
    step : float, optional
        A fixed difference step h for q of that unit size, > 0; default the
        ladder :data:`STEP_LADDER` (module docstring).
    derivatives : callable, optional
        ``(u, h) -> (DJ[u], D2J[u, u])`` for real u; default
        :func:`jacobian_differences`.  A problem-specific form can avoid the
        rounding of large constant parts of J (the pipe's, :func:`pipe_derivatives`).

    Returns
    -------
    HopfCoefficient
    """
    x0 = np.asarray(x0, dtype=float)
    A = np.asarray(jacobian(x0), dtype=float)
    if derivatives is None:
        derivatives = jacobian_differences(jacobian, x0, A)
    lam, q, pl = _critical_pair(A, omega)
    G = np.eye(x0.size) if norm is None else np.asarray(norm)
    s = float(np.real(np.conj(q) @ (G @ q)))
    if not s > 0:
        raise ValueError("norm: the critical eigenvector has zero norm in G")
    q = q / math.sqrt(s)
    # Fix the phase (any is valid): the largest component real.
    k = int(np.argmax(np.abs(q)))
    q = q * (abs(q[k]) / q[k])
    p = pl / np.conj(np.conj(pl) @ q)  # p^H q = 1
    w = float(lam.imag)
    if step is None:
        # The middle three steps first; the ends of the ladder only where those
        # are not flat (the plateau moves with the mesh's rounding level).
        ladder = STEP_LADDER
        found = {h: _c1(derivatives, A, q, p, w, h) for h in ladder[1:-1]}
        l1m = [found[h][0].real / w for h in ladder[1:-1]]
        flat = max(abs(l1m[0] - l1m[1]), abs(l1m[1] - l1m[2]))
        if flat > FLAT_ENOUGH * max(abs(l1m[1]), 1e-300):
            found.update({h: _c1(derivatives, A, q, p, w, h) for h in (ladder[0], ladder[-1])})
        ladder = tuple(h for h in ladder if h in found)
        runs = [found[h] for h in ladder]
    else:
        if not step > 0:
            raise ValueError(f"step must be > 0, got {step}")
        ladder = (step, 2.0 * step)
        runs = [_c1(derivatives, A, q, p, w, h) for h in ladder]
    l1s = [c.real / w for c, _ in runs]
    if len(ladder) == 2:
        k, mid = 0, 0
        spread = abs(l1s[0] - l1s[1]) / 3.0  # Richardson: the O(h^2) error at h
    else:
        # The flattest three consecutive steps: the middle one, their spread.
        spreads = [
            max(abs(l1s[i] - l1s[i + 1]), abs(l1s[i + 1] - l1s[i + 2]))
            for i in range(len(ladder) - 2)
        ]
        k = int(np.argmin(spreads))
        mid, spread = k + 1, spreads[k]
    c1, terms = runs[mid]
    l1 = l1s[mid]
    size = sum(abs(t) for t in terms) / (2.0 * w)
    unc = spread + ROUNDING_LEVEL * size
    step = ladder[mid]
    l1_2h = l1s[mid + 1] if mid + 1 < len(l1s) else math.nan
    return HopfCoefficient(
        l1=float(l1),
        uncertainty=float(unc),
        c1=complex(c1),
        eigenvalue=lam,
        omega=w,
        q=q,
        p=p,
        step=float(step),
        l1_2h=float(l1_2h),
        terms=terms,
        ladder=tuple(zip(ladder, l1s, strict=True)),
    )


def _c1(derivatives, A, q, p, w, h) -> tuple[complex, tuple]:
    """c1 of the module docstring with difference step h."""
    DJr, D2r = derivatives(q.real, h)
    DJi, D2i = derivatives(q.imag, h)
    D2 = D2r + D2i  # D2J[q, qbar]
    Bq = DJr + 1j * DJi  # B(q, .)
    Bqbar = DJr - 1j * DJi  # B(qbar, .)
    n = A.shape[0]
    b11 = (Bq @ np.conj(q)).real  # B(q, qbar), real
    b20 = Bq @ q  # B(q, q)
    t1 = np.conj(p) @ (D2 @ q)
    t2 = -2.0 * (np.conj(p) @ (Bq @ np.linalg.solve(A, b11)))
    t3 = np.conj(p) @ (Bqbar @ np.linalg.solve(2j * w * np.eye(n) - A, b20))
    return 0.5 * (t1 + t2 + t3), (complex(t1), complex(t2), complex(t3))


# ---------------------------------------------------------------------------
# The pipe
# ---------------------------------------------------------------------------


def pipe_jacobian(model: PipeModel, x: np.ndarray) -> np.ndarray:
    """D_x F of the first-order form of Eq. (20) at x = (q, q'), shape (2n, 2n).

    ``[[0, I], [-M^{-1} R_q, -M^{-1} R_q']]`` with the analytic Jacobians of
    :meth:`PipeModel.jacobians` at (q, q', a), a = -M^{-1} R(q, q', 0) the
    acceleration (module docstring).
    """
    n = model.n
    q, qd = x[:n], x[n:]
    M = model.mass_matrix(q)
    cf = sla.cho_factor(M)
    a = -sla.cho_solve(cf, model.residual(q, qd, None))
    Jq, Jqd, _ = model.jacobians(q, qd, a)
    out = np.zeros((2 * n, 2 * n))
    out[:n, n:] = np.eye(n)
    out[n:] = -sla.cho_solve(cf, np.hstack([Jq, Jqd]))
    return out


def _dense(A) -> np.ndarray:
    return A.toarray() if sp.issparse(A) else np.asarray(A)


def _without_bending(model: PipeModel) -> PipeModel:
    """The model with the bending matrix K set to zero (a shallow copy).

    Its residual is R - K q - mu K q' and its Jacobians lack the constant K
    and mu K, the largest entries of the finite-element Jacobian (~h^-2):
    differenced, they would only add their rounding.
    """
    disc = copy.copy(model.disc)
    K = model.disc.K
    disc.K = sp.csr_matrix(K.shape) if sp.issparse(K) else np.zeros(K.shape)
    # A new model, not with_params: that would share the caches of the model's
    # matrices (a dense copy of K among them).
    return PipeModel(disc, model.params)


def _mirror_even(model: PipeModel, x0: np.ndarray) -> bool:
    """Whether J is even about x0: the straight pipe x0 = 0 at alpha = 0 or pi.

    The mirror symmetry (theta, alpha) -> (-theta, -alpha) of Eq. (20) maps
    alpha = 0 and pi onto themselves, so there F is odd, F(-x) = -F(x) (every
    term: gravity along the pipe, follower, Coriolis, inertia, the end mass,
    external damping, springs tied to points of the axis), and its Jacobian
    is even, J(-x) = J(x).  At alpha = pi the odd part of gravity is off by
    sin(pi) ~ 1e-16.  A subclass of PipeModel may add terms that are not odd:
    it takes the general path.
    """
    return type(model) is PipeModel and straight_is_static(model.params) and not np.any(x0)


def pipe_derivatives(
    model: PipeModel, x0: np.ndarray, mirror: bool | None = None
) -> Callable[[np.ndarray, float, float], tuple[np.ndarray, np.ndarray]]:
    """``(u, h, dv=0) -> (DJ[u], D2J[u, u])`` of :func:`pipe_jacobian` about x0, without
    differencing the bending matrix.

    The lower block of J is ``-N (Kc + X(x))`` with N = M(q)^{-1},
    Kc = [K, mu K] constant and X(x) the rest of ``[R_q, R_q']`` (a model
    without bending, :func:`_without_bending`, at the full model's
    acceleration).  With Y = N0 (Kc + X(x0)) formed once and differences of
    M and X only (the identities dN = -N dM N and
    d^2N = 2 N dM N dM N - N d^2M N):

        DJ = N0 (DM Y - DX),
        D2J = N0 (D2M Y - D2X - 2 DM N0 (DM Y - DX)).

    The rounding is then eps |M|, eps |X| over h^2 instead of eps |K| / h^2.
    ``dv`` moves v by ``h dv`` along with x (the derivative along the
    static branch, for lambda'(v)).

    On the straight pipe at alpha = 0 or pi (``mirror``; default: detected,
    :func:`_mirror_even`) J is even about x0 = 0, so J(x0 - h u) = J(x0 + h u):
    DJ = 0 (B = 0) and D2J = 2 (J(x0 + h u) - J(x0)) / h^2 take one
    evaluation instead of two (not for ``dv``, which moves v as well).
    """
    n = model.n
    bare = _without_bending(model)
    Kd = _dense(model.disc.K)
    Kc = np.hstack([Kd, model.params.mu * Kd])
    v0 = model.params.v

    def parts(x: np.ndarray, dv: float) -> tuple[np.ndarray, np.ndarray]:
        full, m = model, bare
        if dv:
            full = model.with_params(replace(model.params, v=v0 + dv))
            m = _without_bending(full)
        q, qd = x[:n], x[n:]
        M = full.mass_matrix(q)
        a = -sla.cho_solve(sla.cho_factor(M), full.residual(q, qd, None))
        Jq, Jqd, _ = m.jacobians(q, qd, a)
        return M, np.hstack([Jq, Jqd])

    M0, X0 = parts(x0, 0.0)
    # The split must be exact: the full model's Jacobians are Kc + X.
    Jq, Jqd, _ = model.jacobians(x0[:n], x0[n:], np.zeros(n))
    scale = np.abs(Kc).max() + np.abs(X0).max()
    if np.abs(np.hstack([Jq, Jqd]) - Kc - X0).max() > 1e-12 * scale:
        raise RuntimeError("the model without bending does not split the Jacobian as K + X")
    cf = sla.cho_factor(M0)
    Y = sla.cho_solve(cf, Kc + X0)
    even = _mirror_even(model, x0) if mirror is None else bool(mirror)

    def deriv(u: np.ndarray, h: float, dv: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
        Mp, Xp = parts(x0 + h * u, h * dv)
        Mm, Xm = (Mp, Xp) if even and not dv else parts(x0 - h * u, -h * dv)
        DM, DX = (Mp - Mm) / (2.0 * h), (Xp - Xm) / (2.0 * h)
        D2M, D2X = (Mp - 2.0 * M0 + Mm) / (h * h), (Xp - 2.0 * X0 + Xm) / (h * h)
        W = DM @ Y - DX
        lower1 = sla.cho_solve(cf, W)
        lower2 = sla.cho_solve(cf, D2M @ Y - D2X - 2.0 * DM @ lower1)
        DJ, D2J = np.zeros((2 * n, 2 * n)), np.zeros((2 * n, 2 * n))
        DJ[n:], D2J[n:] = lower1, lower2
        return DJ, D2J

    return deriv


@dataclass(frozen=True)
class HopfNormalForm:
    """The Hopf normal form of the pipe at a flutter point (module docstring).

    Attributes
    ----------
    v : float
        Flow velocity of the Hopf point.
    l1 : float
        First Lyapunov coefficient, q_theta of unit L2 norm.
    uncertainty : float
        Numerical uncertainty of l1 (module docstring).
    criticality : {'supercritical', 'subcritical', 'degenerate'}
    omega : float
        Im lambda at v.
    eigenvalue : complex
        The critical eigenvalue at v (Re ~ 0 to the event's accuracy).
    eigenvalue_derivative : complex
        lambda'(v) along the static branch.
    transversality : float
        Re lambda'(v).
    rho2_slope : float
        rho^2 / (v - v_cr) = -Re(lambda') / (omega l1): positive where the
        cycles exist above v_cr (module docstring).
    side : {'above', 'below'} or None
        Side of v_cr where the cycles exist (None if degenerate or not transversal).
    amplitude_coefficients : dict
        c of ``(max - min)/2 ~ c sqrt(|v - v_cr|)`` for theta_tip and eta_tip
        (``{}`` when ``side`` is None).
    q_static : ndarray, shape (n,)
        The equilibrium.
    eigenvector : ndarray of complex, shape (2n,)
        q of the normal form (x - x0 ~ 2 rho Re(q e^{i omega tau})).
    coefficient : HopfCoefficient
        The generic result (step diagnostics).
    """

    v: float
    l1: float
    uncertainty: float
    criticality: str
    omega: float
    eigenvalue: complex
    eigenvalue_derivative: complex
    transversality: float
    rho2_slope: float
    side: str | None
    amplitude_coefficients: dict
    q_static: np.ndarray = field(repr=False)
    eigenvector: np.ndarray = field(repr=False)
    coefficient: HopfCoefficient = field(repr=False)
    eta_gradient: np.ndarray = field(repr=False, default=None)

    def rho(self, v: float) -> float:
        """Predicted normal-form amplitude rho at v (nan on the side without cycles)."""
        r2 = self.rho2_slope * (v - self.v)
        return math.sqrt(r2) if r2 >= 0 else math.nan

    def initial_state(
        self, v: float, phase: float | None = None
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """(q, q', T) on the predicted cycle at v: x0 + 2 rho Re(q e^{i phase}), T = 2 pi / omega.

        A starting guess for shooting (:func:`fempipe.analyses.limit_cycle.shoot`),
        also of unstable cycles a transient never reaches.  The default phase
        puts the state where eta_tip crosses its static value upwards, the
        Poincare section of :mod:`fempipe.analyses.limit_cycle` (at another phase the
        section could be nearly tangent to the orbit).
        """
        n = self.q_static.size
        if phase is None:
            # eta_tip - eta0 ~ 2 rho Re(g e^{i phase}), g = d eta_tip . q_theta: zero
            # and rising where g e^{i phase} = -i |g|.
            g = complex(self.eta_gradient @ self.eigenvector[:n])
            phase = float(np.angle(-1j * np.conj(g))) if g != 0 else 0.0
        x = 2.0 * self.rho(v) * np.real(self.eigenvector * np.exp(1j * phase))
        return self.q_static + x[:n], x[n:], 2.0 * math.pi / self.omega

    def to_dict(self) -> dict:
        return {
            "first_lyapunov_coefficient": self.l1,
            "first_lyapunov_uncertainty": self.uncertainty,
            "criticality": self.criticality,
            "transversality": self.transversality,
            "cycle_side": self.side,
            "theta_tip_amplitude_coefficient": self.amplitude_coefficients.get("theta_tip"),
            "eta_tip_amplitude_coefficient": self.amplitude_coefficients.get("eta_tip"),
        }


@single_blas
def first_lyapunov_coefficient(
    model: PipeModel,
    q_static: np.ndarray,
    *,
    omega: float | None = None,
    step: float | None = None,
) -> HopfNormalForm:
    """The Hopf normal form of Eq. (20) at the static state q_static, v = model.params.v.

    Parameters
    ----------
    model : PipeModel
        With v at the Hopf point (a flutter event's v).
    q_static : ndarray, shape (n,)
        The static state there (Eq. (31a)).
    omega : float, optional
        Frequency of the crossing pair (the event's ``frequency``); default
        the pair nearest the imaginary axis.
    step : float, optional
        A fixed difference step h, > 0; default the ladder (module docstring).

    Returns
    -------
    HopfNormalForm

    Raises
    ------
    ValueError
        With hysteretic damping (no equation of motion in time), or if the
        state has no complex pair.
    """
    if model.params.hysteretic_damping > 0.0:
        raise ValueError(
            "hysteretic_damping must be 0: hysteretic damping is a frequency-domain model "
            "with no equation of motion, hence no Hopf normal form"
        )
    n, disc = model.n, model.disc
    q0 = np.asarray(q_static, dtype=float)
    x0 = np.concatenate([q0, np.zeros(n)])
    G = np.zeros((2 * n, 2 * n))
    G[:n, :n] = _dense(disc.gram)
    deriv = pipe_derivatives(model, x0)
    hc = lyapunov_coefficient(
        lambda x: pipe_jacobian(model, x), x0, omega=omega, norm=G, step=step, derivatives=deriv
    )
    q, p, w = hc.q, hc.p, hc.omega
    # lambda'(v) = p^H (dA/dv) q along the branch, tangent q_v = -R_q^{-1} R_v.
    v = model.params.v
    rv = model.static_parameter_derivative(q0, "v")
    # R_v = 0 (the straight pipe at alpha = 0, pi stays static at every v):
    # q_v = 0 without assembling and solving R_q.
    qv = -np.linalg.solve(_dense(model.static_jacobian(q0)), rv) if rv.any() else np.zeros(n)
    xv = np.concatenate([qv, np.zeros(n)])
    hv = 1e-4 * max(1.0, abs(v))
    s = max(1.0, float(np.linalg.norm(xv)))  # a step of unit size in (x, v)
    dA = deriv(xv / s, hv, 1.0 / s)[0] * s
    dlam = complex(np.conj(p) @ (dA @ q))
    crit = hc.criticality
    slope = -dlam.real / (w * hc.l1) if hc.l1 != 0.0 else math.inf
    side, coef = None, {}
    # d(theta_tip)/dq and d(eta_tip)/dq = int phi_j cos theta.
    grads = {
        "theta_tip": np.asarray(disc.tip, dtype=float),
        "eta_tip": np.asarray(disc.Phi.T @ (disc.quad.w * np.cos(disc.Phi @ q0))),
    }
    if crit != "degenerate" and dlam.real != 0.0 and math.isfinite(slope):
        side = "above" if slope > 0 else "below"
        r = math.sqrt(abs(slope))
        coef = {k: float(2.0 * abs(g @ q[:n]) * r) for k, g in grads.items()}
    return HopfNormalForm(
        v=float(v),
        l1=hc.l1,
        uncertainty=hc.uncertainty,
        criticality=crit,
        omega=w,
        eigenvalue=hc.eigenvalue,
        eigenvalue_derivative=dlam,
        transversality=float(dlam.real),
        rho2_slope=float(slope),
        side=side,
        amplitude_coefficients=coef,
        q_static=q0,
        eigenvector=q,
        coefficient=hc,
        eta_gradient=grads["eta_tip"],
    )


# ---------------------------------------------------------------------------
# The flutter events of a stability analysis
# ---------------------------------------------------------------------------

#: Keys added to every flutter event of ``fempipe critical --json``.
EVENT_KEYS = (
    "first_lyapunov_coefficient",
    "first_lyapunov_uncertainty",
    "criticality",
    "transversality",
    "cycle_side",
    "theta_tip_amplitude_coefficient",
    "eta_tip_amplitude_coefficient",
    "hopf_note",
)
#: The eigenvalue at the reconstructed state must be within this (relative to
#: max(1, |lambda|)) of the event's to accept the state as the event's.
STATE_MATCH_TOL = 1e-6
#: Largest step in v of the static path to the flutter points.
PATH_STEP = 1.0


def _key(ev) -> tuple:
    return (ev.branch, ev.type, float(ev.v), ev.mode)


def event_states(model: PipeModel, result) -> dict:
    """Static states at the flutter events of a :class:`~fempipe.analyses.stability.StabilityResult`.

    The primary branch is followed again from its start (``result.v_range[0]``,
    gravity loading, :func:`fempipe.analyses.statics.solve_path`, which passes folds by
    continuation) through every flutter v in steps of at most
    :data:`PATH_STEP`.  Events of other branches, and instabilities present at
    the start of the range (no crossing), get a reason instead.
    :func:`normal_forms` accepts a state only if its critical eigenvalue is
    the event's to :data:`STATE_MATCH_TOL` (a Newton step onto another branch
    would not pass).

    Returns
    -------
    dict
        ``{(branch, type, v, mode): ndarray q or str reason}`` for the flutter events.
    """
    from fempipe.analyses.statics import NewtonError, solve_path

    out: dict = {}
    flutter = [ev for ev in result.events if ev.type == "flutter"]
    primary = sorted(
        (ev for ev in flutter if ev.branch == "primary" and not ev.at_start), key=lambda e: e.v
    )
    for ev in flutter:
        if ev.at_start:
            out[_key(ev)] = "an instability present at the start of the range, not a crossing"
        elif ev.branch != "primary":
            out[_key(ev)] = f"the static state of branch {ev.branch} is not reconstructed"
    if not primary:
        return out
    v_lo = float(result.v_range[0])
    targets = sorted({float(ev.v) for ev in primary})
    values, states = [v_lo], {}
    for vt in targets:
        k = max(1, math.ceil((vt - values[-1]) / PATH_STEP))
        values.extend(np.linspace(values[-1], vt, k + 1)[1:].tolist())
        values[-1] = vt
    try:
        sols = solve_path(model.with_params(replace(model.params, v=v_lo)), values)
    except NewtonError as exc:
        for ev in primary:
            out[_key(ev)] = f"the static state was not found on the way to v = {ev.v:.10g} ({exc})"
        return out
    for v, sol in zip(values, sols, strict=True):
        states[v] = sol.q
    for ev in primary:
        out[_key(ev)] = states[float(ev.v)]
    return out


def _x0(q: np.ndarray) -> np.ndarray:
    return np.concatenate([q, np.zeros_like(q)])


@single_blas
def normal_forms(model: PipeModel, result) -> dict:
    """The Hopf normal form of every flutter event of ``result`` (a StabilityResult).

    Returns
    -------
    dict
        ``{(branch, type, v, mode): HopfNormalForm or str reason}``.
    """
    if model.params.hysteretic_damping > 0.0:
        reason = "hysteretic damping is a frequency-domain model without an equation of motion"
        return {_key(ev): reason for ev in result.events if ev.type == "flutter"}
    out = {}
    if straight_is_static(model.params):
        # The straight pipe is a static state at every v (alpha = 0 or pi); when
        # it carries the event's eigenvalue no path needs to be followed.
        straight = {
            _key(ev): np.zeros(model.n)
            for ev in result.events
            if ev.type == "flutter" and ev.branch == "primary" and not ev.at_start
        }
        for key, q in straight.items():
            nf = _normal_form(model, result, key, q)
            if not isinstance(nf, str):
                out[key] = nf
    states = None
    for ev in result.events:
        key = _key(ev)
        if ev.type != "flutter" or key in out:
            continue
        if states is None:
            states = event_states(model, result)
        q = states[key]
        out[key] = q if isinstance(q, str) else _normal_form(model, result, key, q)
    return out


def _normal_form(model: PipeModel, result, key: tuple, q: np.ndarray) -> HopfNormalForm | str:
    """The normal form at the event ``key`` from the static state q, or why there is none."""
    m = model.with_params(replace(model.params, v=key[2]))
    ev = next(e for e in result.events if _key(e) == key)
    try:
        nf = first_lyapunov_coefficient(m, q, omega=float(ev.frequency))
    except (ValueError, np.linalg.LinAlgError) as exc:
        return f"no normal form: {exc}"
    # The state is the event's if its critical eigenvalue is the event's.
    target = complex(ev.eigenvalue)
    err = abs(nf.eigenvalue - target) / max(1.0, abs(target))
    if err <= STATE_MATCH_TOL:
        return nf
    return (
        f"the static state reconstructed at v = {ev.v:.10g} does not hold the event's "
        f"eigenvalue (relative distance {err:.2g})"
    )


def decorate_events(result_dict: dict, model: PipeModel, result) -> dict:
    """Add :data:`EVENT_KEYS` to every flutter event of ``fempipe critical --json``.

    In ``events``, ``critical`` (when a flutter) and ``branches[*].events``;
    ``hopf_note`` is null, or why the other keys are null (hysteretic
    damping, a state not reconstructed).  ``result_dict`` is modified and returned.
    """
    forms = normal_forms(model, result)

    def decorate(d: dict | None) -> None:
        if d is None or d.get("type") != "flutter":
            return
        if d.get("plane", "in") != "in":
            d.update(dict.fromkeys(EVENT_KEYS))
            d["hopf_note"] = (
                "a flutter out of the plane: its normal form needs the three-dimensional "
                "nonlinear model"
            )
            return
        key = (d["branch"], d["type"], float(d["v"]), d["mode"])
        nf = forms.get(key, "no normal form computed for this event")
        if isinstance(nf, str):
            d.update(dict.fromkeys(EVENT_KEYS))
            d["hopf_note"] = nf
        else:
            d.update(nf.to_dict())
            d["hopf_note"] = None

    for d in result_dict.get("events", []):
        decorate(d)
    decorate(result_dict.get("critical"))
    for key in ("critical_in_plane", "critical_out_of_plane"):
        decorate(result_dict.get(key))
    for b in result_dict.get("branches", []) + result_dict.get("branches_out_of_plane", []):
        for d in b.get("events", []):
            decorate(d)
    return result_dict

"""The first Lyapunov coefficient of a generic x' = F(x) at a Hopf point.

Kuznetsov's formula with the multilinear forms B and C taken as differences
of the analytic Jacobian, on a ladder of steps (docs/theory/stability.md, "Kuznetsov's
formula" and "Derivatives").  Nothing here knows the pipe.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import scipy.linalg as sla

#: |l1| <= DEGENERATE_FACTOR * uncertainty: "degenerate", no criticality claimed.
DEGENERATE_FACTOR = 10.0
#: Difference steps tried for B and C (q of unit size; docs/theory/stability.md, "Derivatives").
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
    l1, uncertainty : float
        First Lyapunov coefficient Re(c1) / omega; its spread over the steps plus rounding.
    c1 : complex
        Cubic coefficient of z' = lambda z + c1 |z|^2 z.
    eigenvalue, omega : complex, float
        The critical eigenvalue of A (Im > 0) and its Im.
    q, p : ndarray of complex, shape (N,)
        Right and adjoint eigenvectors, p^H q = 1, q normalized by ``norm``.
    step, l1_2h : float
        The difference step h of ``l1``; l1 with the next larger step.
    terms : tuple of complex
        <p, C(q,q,qbar)>, -2 <p, B(q, A^-1 B(q,qbar))>, <p, B(qbar, (2iw-A)^-1 B(q,q))>.
    ladder : tuple of (float, float)
        (h, l1(h)) for every step tried.
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
        ``jacobian(x) -> ndarray (N, N)``, the analytic D_x F.
    x0 : ndarray, shape (N,)
        The equilibrium, where A = jacobian(x0) has a pair +- i omega.
    omega : float, optional
        Frequency of the critical pair; default the pair nearest the imaginary axis.
    norm : ndarray, shape (N, N), optional
        Hermitian positive semi-definite G with q^H G q = 1; default the identity.
    step : float, optional
        A fixed difference step h > 0; default the ladder :data:`STEP_LADDER`.
    derivatives : callable, optional
        ``(u, h) -> (DJ[u], D2J[u, u])``; default :func:`jacobian_differences`.

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
    size = sum(abs(t) for t in terms) / (2.0 * w)
    l1_2h = l1s[mid + 1] if mid + 1 < len(l1s) else math.nan
    return HopfCoefficient(
        l1=float(l1s[mid]),
        uncertainty=float(spread + ROUNDING_LEVEL * size),
        c1=complex(c1),
        eigenvalue=lam,
        omega=w,
        q=q,
        p=p,
        step=float(ladder[mid]),
        l1_2h=float(l1_2h),
        terms=terms,
        ladder=tuple(zip(ladder, l1s, strict=True)),
    )


def _c1(derivatives, A, q, p, w, h) -> tuple[complex, tuple]:
    """c1 of Kuznetsov's formula (docs/theory/stability.md) with difference step h."""
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

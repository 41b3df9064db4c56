"""An independent solver of the static problem, for checking the weak form.

Eq. (31a) in strong form with an end mass and springs (point forces where theta'' jumps), a
BVP with theta(1) and the spring points r(xi_j) as parameters, carrying X_g, Z_g as states;
solved by scipy's ``solve_bvp`` on pieces cut at the springs.  It shares no code with
fempipe's discretizations.  Derivation: docs/theory/independent.md.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["BVPSolution", "solve_static_bvp"]


@dataclass(frozen=True)
class BVPSolution:
    """The BVP solution: ``sol(xi)`` gives (theta, theta', X_g, Z_g)."""

    alpha: float
    theta_tip: float
    X_tip: float
    Z_tip: float
    n_nodes: int
    sol: object

    @property
    def eta_tip(self) -> float:
        """Lateral tip displacement in the local frame: (X, Z) rotated back by alpha."""
        return -np.sin(self.alpha) * self.X_tip + np.cos(self.alpha) * self.Z_tip

    @property
    def varsigma_tip(self) -> float:
        """Axial tip displacement in the local frame: (X, Z) rotated back by alpha, minus 1."""
        return np.cos(self.alpha) * self.X_tip + np.sin(self.alpha) * self.Z_tip - 1.0


class _Pieces:
    """``sol(xi)`` of a solution on pieces [b_k, b_(k+1)] mapped onto s in [0, 1]."""

    def __init__(self, sol, breaks: np.ndarray) -> None:
        self._sol = sol
        self._b = breaks

    def __call__(self, xi):
        xi = np.asarray(xi, dtype=float)
        flat = np.atleast_1d(xi)
        b = self._b
        k = np.clip(np.searchsorted(b, flat, side="right") - 1, 0, b.size - 2)
        s = (flat - b[k]) / (b[k + 1] - b[k])
        Y = self._sol(s)  # (4K, m)
        out = np.stack([Y[4 * kk : 4 * kk + 4, i] for i, kk in enumerate(k)], axis=1)
        return out[:, 0] if xi.ndim == 0 else out


def solve_static_bvp(
    alpha: float,
    gamma: float,
    v: float,
    guess=None,
    tol: float = 1e-10,
    *,
    end_mass: float = 0.0,
    springs=(),
) -> BVPSolution:
    """Solve Eq. (31a) by collocation (scipy ``solve_bvp``); RuntimeError if it fails.

    Parameters
    ----------
    alpha, gamma, v : float
        Inclination, gravity parameter, flow velocity.
    guess : callable, optional
        ``guess(xi) -> theta`` selecting the branch (default: the straight pipe).
    tol : float
        Collocation tolerance.
    end_mass : float
        Gamma = M_e / ((m+M) L) at xi = 1.
    springs : sequence of (kappa, xi_s)
        Linear springs tying r(xi_s) to (xi_s, 0).
    """
    from scipy.integrate import solve_bvp

    springs = [(float(k), float(x)) for k, x in springs]
    breaks = np.unique(np.r_[0.0, [x for _, x in springs if x < 1.0], 1.0])
    K = breaks.size - 1
    h = np.diff(breaks)
    # Index of the piece that ends at each spring's position.
    ends_at = [int(np.searchsorted(breaks, x)) - 1 for _, x in springs]
    ca, sa = np.cos(alpha), np.sin(alpha)
    lever = 1.0 + end_mass

    def rhs(s, y, p):
        out = np.empty_like(y)
        for k in range(K):
            xi = breaks[k] + h[k] * s
            th = y[4 * k]
            f = gamma * (lever - xi) * np.sin(th + alpha) + v**2 * np.sin(p[0] - th)
            for j, (kappa, xj) in enumerate(springs):
                if xj >= breaks[k + 1]:  # the piece lies before the spring
                    X, Z = p[1 + 2 * j], p[2 + 2 * j]
                    r1, r2 = ca * X + sa * Z, -sa * X + ca * Z  # the pipe's frame
                    f = f + kappa * (-np.sin(th) * (r1 - xj) + np.cos(th) * r2)
            out[4 * k] = h[k] * y[4 * k + 1]
            out[4 * k + 1] = h[k] * f
            out[4 * k + 2] = h[k] * np.cos(th + alpha)
            out[4 * k + 3] = h[k] * np.sin(th + alpha)
        return out

    def bc(ya, yb, p):
        last = 4 * (K - 1)
        res = [ya[0], yb[last + 1], yb[last] - p[0], ya[2], ya[3]]
        for k in range(K - 1):
            res.extend(yb[4 * k + i] - ya[4 * (k + 1) + i] for i in range(4))
        for j, k in enumerate(ends_at):
            res.extend([yb[4 * k + 2] - p[1 + 2 * j], yb[4 * k + 3] - p[2 + 2 * j]])
        return np.array(res)

    s = np.linspace(0.0, 1.0, 401 if K == 1 else 201)
    y0 = np.empty((4 * K, s.size))
    for k in range(K):
        x = breaks[k] + h[k] * s
        xf = np.linspace(0.0, x[-1], 401)  # the positions integrate from the clamp
        th_f = np.zeros_like(xf) if guess is None else np.asarray(guess(xf), dtype=float)
        th = np.interp(x, xf, th_f)
        c, sn = np.cos(th_f + alpha), np.sin(th_f + alpha)
        dx = np.diff(xf)
        X = np.concatenate([[0.0], np.cumsum(0.5 * dx * (c[1:] + c[:-1]))])
        Z = np.concatenate([[0.0], np.cumsum(0.5 * dx * (sn[1:] + sn[:-1]))])
        y0[4 * k] = th
        y0[4 * k + 1] = np.gradient(th, x)
        y0[4 * k + 2] = np.interp(x, xf, X)
        y0[4 * k + 3] = np.interp(x, xf, Z)
    p0 = [y0[4 * (K - 1), -1]]
    for k in ends_at:
        p0 += [y0[4 * k + 2, -1], y0[4 * k + 3, -1]]
    res = solve_bvp(rhs, bc, s, y0, p=p0, tol=tol, bc_tol=1e-12, max_nodes=500_000)
    if res.status != 0:
        raise RuntimeError(
            f"solve_bvp failed at alpha={alpha:.6g}, gamma={gamma:.6g}, v={v:.6g}: {res.message}"
        )
    yb = res.sol(1.0)
    last = 4 * (K - 1)
    sol = res.sol if K == 1 else _Pieces(res.sol, breaks)
    return BVPSolution(
        alpha=float(alpha),
        theta_tip=float(res.p[0]),
        X_tip=float(yb[last + 2]),
        Z_tip=float(yb[last + 3]),
        n_nodes=int(res.x.size),
        sol=sol,
    )

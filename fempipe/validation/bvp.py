"""An independent solver of the static problem, for checking the weak form.

Eq. (31a) in strong form is the two-point boundary-value problem

    theta'' = gamma (1 - xi) sin(theta + alpha) + v^2 sin(theta(1) - theta),
    theta(0) = 0,  theta'(1) = 0,

with theta(1) an unknown parameter p and the extra condition theta(1) = p.
:func:`solve_static_bvp` integrates it with scipy's collocation solver
``solve_bvp`` (4th-order Lobatto IIIA, adaptive mesh), carrying the global
coordinates X_g' = cos(theta + alpha), Z_g' = sin(theta + alpha) as two more
states so that the tip position is part of the solution.  It shares no code
with fempipe's discretisations, quadrature or residual: agreement to the BVP
tolerance checks the weak form, the integration operators and Newton at once.
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


def solve_static_bvp(
    alpha: float,
    gamma: float,
    v: float,
    guess=None,
    tol: float = 1e-10,
) -> BVPSolution:
    """Solve Eq. (31a) by collocation (scipy ``solve_bvp``).

    Parameters
    ----------
    alpha, gamma, v : float
        Inclination (rad), gravity parameter, flow velocity.
    guess : callable, optional
        ``guess(xi) -> theta`` selecting the branch (the problem has several
        equilibria for large gamma); default the straight pipe.
    tol : float
        Collocation residual tolerance of ``solve_bvp``.

    Raises
    ------
    RuntimeError
        If ``solve_bvp`` does not converge, with its message.
    """
    from scipy.integrate import solve_bvp

    def rhs(x, y, p):
        th = y[0]
        return np.vstack(
            [
                y[1],
                gamma * (1.0 - x) * np.sin(th + alpha) + v**2 * np.sin(p[0] - th),
                np.cos(th + alpha),
                np.sin(th + alpha),
            ]
        )

    def bc(ya, yb, p):
        return np.array([ya[0], yb[1], yb[0] - p[0], ya[2], ya[3]])

    x = np.linspace(0.0, 1.0, 401)
    th0 = np.zeros_like(x) if guess is None else np.asarray(guess(x), dtype=float)
    dth0 = np.gradient(th0, x)
    # Cumulative trapezoid for the initial positions.
    c, s = np.cos(th0 + alpha), np.sin(th0 + alpha)
    dx = np.diff(x)
    X0 = np.concatenate([[0.0], np.cumsum(0.5 * dx * (c[1:] + c[:-1]))])
    Z0 = np.concatenate([[0.0], np.cumsum(0.5 * dx * (s[1:] + s[:-1]))])
    y0 = np.vstack([th0, dth0, X0, Z0])
    res = solve_bvp(rhs, bc, x, y0, p=[th0[-1]], tol=tol, bc_tol=1e-12, max_nodes=500_000)
    if res.status != 0:
        raise RuntimeError(
            f"solve_bvp failed at alpha={alpha:.6g}, gamma={gamma:.6g}, v={v:.6g}: {res.message}"
        )
    yb = res.sol(1.0)
    return BVPSolution(
        alpha=float(alpha),
        theta_tip=float(res.p[0]),
        X_tip=float(yb[2]),
        Z_tip=float(yb[3]),
        n_nodes=int(res.x.size),
        sol=res.sol,
    )

"""Centerline geometry from the rotation angle (Eqs. (5), (27), (28)).

The displacements and global coordinates are integrals of theta, evaluated
with the discretization's own integration operator so that they inherit its
accuracy: exact integrals of the interpolant at cell edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .discretization import Discretization
from .quadrature import lagrange_integrals

__all__ = ["Shape", "shape", "tip_values", "tip_velocity"]


@dataclass(frozen=True)
class Shape:
    """A deformed centerline, dimensionless (divide by nothing, multiply by L for m).

    Attributes
    ----------
    xi : ndarray, shape (m,)
        Material coordinate, from 0 (clamp) to 1 (free end).
    theta : ndarray, shape (m,)
        Rotation angle, rad.
    varsigma, eta : ndarray, shape (m,)
        Axial and lateral displacement in the local frame, Eq. (5).
    X_g, Z_g : ndarray, shape (m,)
        Global coordinates, X_g along gravity (down), Eq. (28).
    """

    xi: np.ndarray
    theta: np.ndarray
    varsigma: np.ndarray
    eta: np.ndarray
    X_g: np.ndarray
    Z_g: np.ndarray


def _edge_points(disc: Discretization, points_per_cell: int) -> np.ndarray:
    """Points at which shapes are sampled: every cell edge plus interior points."""
    edges = disc.quad.edges
    if points_per_cell <= 1:
        return edges
    s = np.arange(points_per_cell) / points_per_cell
    inner = (edges[:-1, None] + np.diff(edges)[:, None] * s[None, :]).ravel()
    return np.append(inner, 1.0)


def shape(disc: Discretization, q: np.ndarray, alpha: float, points_per_cell: int = 4) -> Shape:
    """Centerline of the state q.

    Parameters
    ----------
    disc : Discretization
    q : ndarray, shape (n,)
    alpha : float
        Inclination, rad (Eq. (28)).
    points_per_cell : int
        Samples per quadrature cell; the integrals are exact at cell edges and
        at the sampled interior points they use the same Gauss interpolation.

    Returns
    -------
    Shape
    """
    xi = _edge_points(disc, points_per_cell)
    quad = disc.quad
    theta_q = disc.Phi @ np.asarray(q)
    f = np.stack(
        [np.cos(theta_q), np.sin(theta_q), np.cos(theta_q + alpha), np.sin(theta_q + alpha)],
        axis=1,
    )
    # Integrals at the sample points: edges exactly; interior points by the
    # same cell-wise Gauss interpolation as the integration operator.
    cells = np.clip(np.searchsorted(quad.edges, xi, side="right") - 1, 0, quad.n_cells - 1)
    start = quad.at_edges(f)[cells]
    a, h = quad.edges[cells], quad.h[cells]
    s = (xi - a) / h
    fc = f.reshape(quad.n_cells, quad.n_gauss, 4)[cells]  # (m, n_g, 4)
    lag = lagrange_integrals(quad.ref_points, s)  # (m, n_g)
    integ = start + np.einsum("mk,mkc->mc", lag, fc) * h[:, None]
    return Shape(
        xi=xi,
        theta=disc.evaluate(q, xi),
        varsigma=integ[:, 0] - xi,
        eta=integ[:, 1],
        X_g=integ[:, 2],
        Z_g=integ[:, 3],
    )


def tip_values(disc: Discretization, q: np.ndarray, alpha: float) -> dict:
    """Tip rotation and positions: theta_tip, varsigma_tip, eta_tip, X_tip, Z_tip.

    The displacements (Eq. (5)) and global coordinates (Eq. (28)) at xi = 1
    are the integrals of cos theta, sin theta over [0, 1], summed exactly on
    the interpolated integrands by the discretization's Gauss rule.  The one
    place the package computes the tip's geometry.

    Parameters
    ----------
    disc : Discretization
    q : ndarray, shape (n,) or (m, n)
        One state or m states.
    alpha : float
        Inclination, rad.

    Returns
    -------
    dict
        Floats for one state, arrays of shape (m,) for m states.
    """
    q = np.asarray(q)
    th = disc.Phi @ q.T  # (n_q,) or (n_q, m)
    w = disc.quad.w
    out = {
        "theta_tip": disc.tip @ q.T,
        "varsigma_tip": w @ np.cos(th) - 1.0,
        "eta_tip": w @ np.sin(th),
        "X_tip": w @ np.cos(th + alpha),
        "Z_tip": w @ np.sin(th + alpha),
    }
    if q.ndim == 1:
        return {k: float(val) for k, val in out.items()}
    return {k: np.asarray(val) for k, val in out.items()}


def tip_velocity(disc: Discretization, q: np.ndarray, qdot: np.ndarray, alpha: float) -> dict:
    """Tip velocities, d/dtau of varsigma_tip, eta_tip, X_tip, Z_tip (Eq. (27)).

    Parameters
    ----------
    disc : Discretization
    q, qdot : ndarray, shape (n,) or (m, n)
        One state or m states.
    alpha : float

    Returns
    -------
    dict
        Floats for one state, arrays of shape (m,) for m states.
    """
    q, qdot = np.asarray(q), np.asarray(qdot)
    th = disc.Phi @ q.T
    thd = disc.Phi @ qdot.T
    w = disc.quad.w
    out = {
        "varsigma_tip": -(w @ (thd * np.sin(th))),
        "eta_tip": w @ (thd * np.cos(th)),
        "X_tip": -(w @ (thd * np.sin(th + alpha))),
        "Z_tip": w @ (thd * np.cos(th + alpha)),
    }
    if q.ndim == 1:
        return {k: float(val) for k, val in out.items()}
    return {k: np.asarray(val) for k, val in out.items()}

"""Centerline geometry from the rotation angle (Eqs. (5), (27), (28)).

Displacements and global coordinates are integrals of theta by the discretization's own
integration operator: exact integrals of the interpolant at cell edges.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fempipe.model.discretization import Discretization
from fempipe.model.quadrature import lagrange_integrals

__all__ = ["Shape", "compute_shape", "compute_tip", "tip_velocity"]


@dataclass(frozen=True)
class Shape:
    """A dimensionless centerline, shape (m,) each: ``xi``, ``theta``, ``varsigma``, ``eta`` (axial
    and lateral displacement, Eq. (5)), ``X_g``, ``Z_g`` (X_g along gravity, Eq. (28))."""

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


def compute_shape(
    disc: Discretization, q: np.ndarray, alpha: float, points_per_cell: int = 4
) -> Shape:
    """Centerline of the state q.

    Parameters
    ----------
    disc : Discretization
    q : ndarray, shape (n,)
    alpha : float
        Inclination, rad (Eq. (28)).
    points_per_cell : int
        Samples per quadrature cell (exact at cell edges, Gauss interpolation inside).
    """
    xi = _edge_points(disc, points_per_cell)
    quad = disc.quad
    theta_q = disc.Phi @ np.asarray(q)
    f = np.stack(
        [np.cos(theta_q), np.sin(theta_q), np.cos(theta_q + alpha), np.sin(theta_q + alpha)], axis=1
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


def compute_tip(disc: Discretization, q: np.ndarray, alpha: float) -> dict:
    """Tip rotation and positions: theta_tip, varsigma_tip, eta_tip, X_tip, Z_tip.

    Eqs. (5) and (28) at xi = 1, the one place the package computes the tip's geometry:
    integrals of cos theta, sin theta over [0, 1] by the discretization's Gauss rule.

    Parameters
    ----------
    disc : Discretization
    q : ndarray, shape (n,) or (m, n)
    alpha : float
        Inclination, rad.

    Returns
    -------
    dict
        Floats for one state, arrays (m,) for m states.
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
    """Tip velocities, d/dtau of varsigma_tip, eta_tip, X_tip, Z_tip (Eq. (27)); shapes as in
    :func:`compute_tip`, ``qdot`` shaped like ``q``."""
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

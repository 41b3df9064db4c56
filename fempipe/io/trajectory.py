"""The moving pipe as a ParaView time series (``NAME.pvd`` and one VTU per time in ``NAME/``),
and the tip's time series (tip.csv).  Format: docs/cli/options.md, "VTK files".
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from fempipe.io import SHAPE_FIELDS, screen_points
from fempipe.io.meshes import write_series
from fempipe.model.discretization import Discretization
from fempipe.model.kinematics import Shape, compute_shape, compute_tip, tip_velocity
from fempipe.model.quadrature import lagrange_integrals

__all__ = [
    "TIP_COLUMNS",
    "CenterlineSampler",
    "frame_data",
    "read_trajectory",
    "tip_rows",
    "write_trajectory",
]


class CenterlineSampler:
    """The centerlines of many states of one discretization at the same sample points.

    The point-only work is done once; each state is then
    :func:`fempipe.model.kinematics.compute_shape` bit for bit (checked on the first state,
    else every state falls back to it).
    """

    def __init__(self, disc: Discretization, alpha: float, points_per_cell: int = 4) -> None:
        self.disc, self.alpha, self.points_per_cell = disc, float(alpha), points_per_cell
        quad = disc.quad
        self.xi = compute_shape(disc, np.zeros(disc.n), alpha, points_per_cell).xi
        self._cells = np.clip(
            np.searchsorted(quad.edges, self.xi, side="right") - 1, 0, quad.n_cells - 1
        )
        a, self._h = quad.edges[self._cells], quad.h[self._cells]
        self._lag = lagrange_integrals(quad.ref_points, (self.xi - a) / self._h)
        self._basis = disc.basis_values(self.xi)
        self._checked = False

    def _fast_shape(self, q: np.ndarray):
        disc, quad, alpha, xi = self.disc, self.disc.quad, self.alpha, self.xi
        theta_q = disc.Phi @ q
        f = np.stack(
            [np.cos(theta_q), np.sin(theta_q), np.cos(theta_q + alpha), np.sin(theta_q + alpha)],
            axis=1,
        )
        start = quad.at_edges(f)[self._cells]
        fc = f.reshape(quad.n_cells, quad.n_gauss, 4)[self._cells]
        integ = start + np.einsum("mk,mkc->mc", self._lag, fc) * self._h[:, None]
        return Shape(
            xi=xi,
            theta=self._basis @ q,
            varsigma=integ[:, 0] - xi,
            eta=integ[:, 1],
            X_g=integ[:, 2],
            Z_g=integ[:, 3],
        )

    def _check(self, q: np.ndarray, qdot: np.ndarray | None) -> None:
        """Compare the fast path with ``shape`` and ``disc.evaluate`` on one state, bitwise."""
        self._checked = True
        ref, fast = (
            compute_shape(self.disc, q, self.alpha, self.points_per_cell),
            self._fast_shape(q),
        )
        same = all(
            np.array_equal(getattr(ref, f), getattr(fast, f)) for f in ("xi", *_SHAPE_ARRAYS)
        )
        if qdot is not None:
            same = same and np.array_equal(self.disc.evaluate(qdot, self.xi), self._basis @ qdot)
        if not same:
            self._basis = None

    def shape(self, q: np.ndarray, qdot: np.ndarray | None = None):
        """:class:`~fempipe.model.kinematics.Shape` of the state q (as ``compute_shape(disc, q, alpha)``)."""
        q = np.asarray(q)
        if not self._checked:
            self._check(q, None if qdot is None else np.asarray(qdot))
        if self._basis is None:
            return compute_shape(self.disc, q, self.alpha, self.points_per_cell)
        return self._fast_shape(q)

    def evaluate(self, q: np.ndarray) -> np.ndarray:
        """theta(xi) (or theta_dot for a velocity) at the sample points, as ``disc.evaluate``."""
        if self._basis is None:
            return self.disc.evaluate(q, self.xi)
        return self._basis @ np.asarray(q)


_SHAPE_ARRAYS = ("theta", "varsigma", "eta", "X_g", "Z_g")


def frame_data(
    disc: Discretization,
    q: np.ndarray,
    qdot: np.ndarray,
    alpha: float,
    points_per_cell: int = 4,
    sampler: CenterlineSampler | None = None,
):
    """Points (m, 3) and point data of one frame; ``sampler`` reused over the frames."""
    if sampler is None:
        s = compute_shape(disc, q, alpha, points_per_cell=points_per_cell)
        theta_dot = disc.evaluate(qdot, s.xi)
    else:
        s = sampler.shape(q, qdot)
        theta_dot = sampler.evaluate(qdot)
    xi = s.xi
    # Centerline velocity r_dot(xi) = \int_0^xi theta_dot (-sin(theta+alpha), cos(theta+alpha))
    # in the global frame (X_g, Z_g): integrate at the quadrature points and
    # interpolate linearly to the sample points (post-processing only).
    quad = disc.quad
    th = disc.Phi @ np.asarray(q)
    thd = disc.Phi @ np.asarray(qdot)
    f = np.stack([-thd * np.sin(th + alpha), thd * np.cos(th + alpha)], axis=1)
    edges = quad.at_edges(f)
    vel_X = np.interp(xi, quad.edges, edges[:, 0])
    vel_Z = np.interp(xi, quad.edges, edges[:, 1])

    points = screen_points(s.X_g, s.Z_g)
    data = {f: np.asarray(getattr(s, f), dtype=float) for f in SHAPE_FIELDS}
    data["theta_dot"] = theta_dot
    data["velocity"] = np.stack([vel_Z, -vel_X, np.zeros_like(xi)], axis=1)
    return points, data


def write_trajectory(
    path: str | os.PathLike,
    disc: Discretization,
    t: Sequence[float],
    q: np.ndarray,
    qdot: np.ndarray,
    alpha: float,
    points_per_cell: int = 4,
    params=None,
) -> Path:
    """Write a trajectory ``t``, ``q``, ``qdot`` (shape (m, n)) as ``path`` (.pvd) plus one VTU
    per time in ``path``'s stem directory; ``params``: field data (v, alpha, beta, gamma, mu)."""
    q = np.atleast_2d(np.asarray(q, dtype=float))
    qdot = np.atleast_2d(np.asarray(qdot, dtype=float))
    t = np.asarray(t, dtype=float)
    if not (q.shape == qdot.shape and q.shape[0] == t.size):
        raise ValueError("t, q and qdot must describe the same number of frames")
    field = {}
    if params is not None:
        field = {k: float(getattr(params, k)) for k in ("v", "alpha", "beta", "gamma", "mu")}
    sampler = CenterlineSampler(disc, alpha, points_per_cell)

    def frames():
        for k in range(t.size):
            pts, data = frame_data(disc, q[k], qdot[k], alpha, points_per_cell, sampler)
            yield pts, data, {"time": float(t[k])} | field

    return write_series(path, t, frames(), sampler.xi.size)


def read_trajectory(path: str | os.PathLike) -> tuple[np.ndarray, list]:
    """Read a .pvd series back with meshio: (times, list of meshio.Mesh)."""
    import xml.etree.ElementTree as ET

    import meshio

    path = Path(path)
    root = ET.parse(path).getroot()
    times, meshes = [], []
    for ds in root.iter("DataSet"):
        times.append(float(ds.get("timestep")))
        meshes.append(meshio.read(path.parent / ds.get("file")))
    return np.asarray(times), meshes


#: Columns of tip.csv (units: :data:`fempipe.io.CSV_UNITS`; rates per unit tau).
TIP_COLUMNS = (
    "tau",
    "theta_tip",
    "eta_tip",
    "X_tip",
    "Z_tip",
    "theta_tip_rate",
    "eta_tip_rate",
    "X_tip_rate",
    "Z_tip_rate",
)


def tip_rows(disc, t, q, qdot, alpha: float, output_dt: float | None = None) -> list[dict]:
    """Rows :data:`TIP_COLUMNS` of the tip's time series, Eq. (28), at the steps ``t`` or, with
    ``output_dt``, on a uniform grid (cubic Hermite interpolants through (q, qdot))."""
    t, q, qdot = np.asarray(t, float), np.asarray(q, float), np.asarray(qdot, float)
    if output_dt is not None:
        from scipy.interpolate import CubicHermiteSpline  # scipy: not for the CLI's start-up

        keep = np.concatenate([[True], np.diff(t) > 0])  # no zero-length steps
        spline = CubicHermiteSpline(t[keep], q[keep], qdot[keep], axis=0)
        n = int(np.floor((t[-1] - t[0]) / output_dt * (1 + 1e-12))) + 1
        t = t[0] + output_dt * np.arange(n)
        q, qdot = spline(t), spline.derivative()(t)
    pos = compute_tip(disc, q, alpha)
    vel = tip_velocity(disc, q, qdot, alpha)
    cols = {"tau": t, **{k: pos[k] for k in TIP_COLUMNS[1:5]}}
    cols["theta_tip_rate"] = np.asarray(disc.tip @ qdot.T)
    cols |= {f"{k}_rate": vel[k] for k in ("eta_tip", "X_tip", "Z_tip")}
    return [{k: float(cols[k][i]) for k in TIP_COLUMNS} for i in range(t.size)]

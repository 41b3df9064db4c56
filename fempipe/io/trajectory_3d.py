"""The pipe moving in three dimensions as a ParaView time series (``trajectory.pvd``).

The files of :mod:`fempipe.io.trajectory` in its VTK frame extended by z = Y_g (out of the
plane of the static state), so a planar and a 3-D run overlap: the centerline at the cell
edges and quadrature points, point data ``xi``, ``X_g``, ``Z_g``, ``Y_g``, ``tangent``.
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from fempipe.io.meshes import write_series
from fempipe.model.three_d.chart import tangent
from fempipe.model.three_d.model import PipeModel3D

__all__ = ["frame_points_3d", "write_trajectory_3d"]


def frame_points_3d(model: PipeModel3D, U: np.ndarray) -> tuple[np.ndarray, dict]:
    """(points (m, 3) in the VTK frame, point data) of the centerline of U.

    The points are the cell edges and the quadrature points, where the
    integration operators give r = \\int_0^xi t exactly for the interpolated tangent.
    """
    a = model.params.alpha
    quad = model.quad
    t_q = model.fields(U).t[:, :, 0]
    xi = np.concatenate([quad.edges, quad.x])
    order = np.argsort(xi, kind="stable")
    xi = xi[order]
    r = np.concatenate([quad.at_edges(t_q), quad.cumulative(t_q)])[order]  # pipe frame
    X = np.cos(a) * r[:, 0] - np.sin(a) * r[:, 1]
    Z = np.sin(a) * r[:, 0] + np.cos(a) * r[:, 1]
    Y = r[:, 2]
    nt = model.n_theta
    u = np.stack([model.disc.evaluate(U[c * nt : (c + 1) * nt], xi) for c in range(3)], axis=1)
    tp = tangent(u[:, :, None])[:, :, 0]
    tX = np.cos(a) * tp[:, 0] - np.sin(a) * tp[:, 1]
    tZ = np.sin(a) * tp[:, 0] + np.cos(a) * tp[:, 1]
    points = np.column_stack([Z, -X, Y])
    data = {"xi": xi, "X_g": X, "Z_g": Z, "Y_g": Y, "tangent": np.column_stack([tZ, -tX, tp[:, 2]])}
    return points, data


def write_trajectory_3d(
    path: str | os.PathLike, model: PipeModel3D, t: np.ndarray, U: np.ndarray
) -> Path:
    """Write ``path`` (.pvd) and one VTU per time in ``path``'s stem directory, all or none."""
    t = np.asarray(t, dtype=float)
    U = np.atleast_2d(np.asarray(U, dtype=float))
    if U.shape[0] != t.size:
        raise ValueError("t and U must describe the same number of frames")
    p = model.params
    field = {k: float(getattr(p, k)) for k in ("v", "alpha", "beta", "gamma", "mu")}
    frames = ((*frame_points_3d(model, U[k]), {"time": float(t[k])} | field) for k in range(t.size))
    return write_series(path, t, frames, model.quad.edges.size + model.quad.x.size)

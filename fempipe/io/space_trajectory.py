"""The pipe moving in three dimensions as a ParaView time series (``trajectory.pvd``).

The files of :mod:`fempipe.io.trajectory`, in the same VTK frame extended to
3-D: x = Z_g (horizontal, in the plane of the static state), y = -X_g
(gravity down the screen), z = Y_g (out of that plane), so a planar run and
a 3-D run opened together overlap.  Each VTU holds the centerline at the
cell edges and quadrature points as ``line`` cells, the point data ``xi``, ``X_g``, ``Z_g``,
``Y_g`` and ``tangent`` (3 components, in the same frame), and the field
data ``time`` and the parameters.
"""

from __future__ import annotations

import os
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from fempipe.core.files import write_text
from fempipe.io.meshes import write_vtu_frames
from fempipe.model.space import SpaceModel
from fempipe.model.space_chart import tangent

__all__ = ["space_frame_points", "write_space_trajectory"]


def space_frame_points(model: SpaceModel, U: np.ndarray) -> tuple[np.ndarray, dict]:
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
    data = {
        "xi": xi,
        "X_g": X,
        "Z_g": Z,
        "Y_g": Y,
        "tangent": np.column_stack([tZ, -tX, tp[:, 2]]),
    }
    return points, data


def write_space_trajectory(
    path: str | os.PathLike, model: SpaceModel, t: np.ndarray, U: np.ndarray
) -> Path:
    """Write ``path`` (.pvd) and one VTU per time in ``path``'s stem directory, all or none."""
    path = Path(path)
    if path.suffix != ".pvd":
        raise ValueError(f"trajectory path must end in .pvd, got {path.name!r}")
    t = np.asarray(t, dtype=float)
    U = np.atleast_2d(np.asarray(U, dtype=float))
    if U.shape[0] != t.size:
        raise ValueError("t and U must describe the same number of frames")
    p = model.params
    field = {k: float(getattr(p, k)) for k in ("v", "alpha", "beta", "gamma", "mu")}
    m = model.quad.edges.size + model.quad.x.size
    cells = np.stack([np.arange(m - 1), np.arange(1, m)], axis=1)
    names = [f"frame_{k:05d}.vtu" for k in range(t.size)]
    frames_dir = path.with_suffix("")

    def frames():
        for k in range(t.size):
            pts, data = space_frame_points(model, U[k])
            yield pts, data, {"time": float(t[k])} | field

    write_vtu_frames(frames_dir, names, frames(), cells)
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    for tk, name in zip(t, names, strict=True):
        f = f"{frames_dir.name}/{name}"
        lines.append(
            f'    <DataSet timestep="{float(tk)!r}" group="" part="0" file={quoteattr(f)}/>'
        )
    lines += ["  </Collection>", "</VTKFile>"]
    write_text(path, "\n".join(lines) + "\n")
    return path

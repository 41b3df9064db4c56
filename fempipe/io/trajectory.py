"""The moving pipe as a time series of meshio files that ParaView opens.

Format: a ParaView collection ``NAME.pvd`` (a small XML list of
``(timestep, file)``) plus one VTU file per output time in ``NAME/``, written
by meshio.  Each VTU holds the centerline in the package's one VTK frame
(:mod:`fempipe.io`: x = Z_g horizontal, y = -X_g so that gravity points
down the screen, z = 0) as ``line`` cells, as point data ``xi``, ``theta``
(rad), ``varsigma``, ``eta``, ``X_g``, ``Z_g`` (the arrays of
``shapes.vtu``), ``theta_dot`` (rad per unit tau) and ``velocity`` (the
centerline velocity r_dot in the same frame, 3 components), and as field
data ``time`` (tau), ``v`` and the parameters.

Why not XDMF: tried and measured with meshio 5.3.5.  ``meshio.xdmf.TimeSeriesWriter``
needs h5py (not a dependency of fempipe), writes line cells as a ``Polyline``
topology without ``NodesPerElement`` (which ParaView's XDMF reader needs to
split a polyline into segments), and in our test the written series did not
read back (the writer put the HDF5 heavy data in the current working
directory, not beside the .xdmf file that refers to it, so the reader could
not find it).  VTU
stores line cells and point data and reads back with plain meshio; the PVD
wrapper gives ParaView the time values.

Every file is written to a temporary name and moved into place
(:func:`fempipe.io.atomic_path`); the ``.pvd`` index is written last, so a
reader never sees an index pointing at missing frames.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from fempipe.model.discretization import Discretization

__all__ = ["frame_data", "write_trajectory", "read_trajectory"]


def frame_data(
    disc: Discretization, q: np.ndarray, qdot: np.ndarray, alpha: float, points_per_cell: int = 4
):
    """Points (m, 3) and point data of one frame (see module docstring)."""
    from fempipe.model.kinematics import shape

    s = shape(disc, q, alpha, points_per_cell=points_per_cell)
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
    from fempipe.io import SHAPE_FIELDS, screen_points

    points = screen_points(s.X_g, s.Z_g)
    data = {f: np.asarray(getattr(s, f), dtype=float) for f in SHAPE_FIELDS}
    data["theta_dot"] = disc.evaluate(qdot, xi)
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
    """Write a trajectory as ``path`` (.pvd) plus one VTU per time in ``path``'s stem directory.

    Parameters
    ----------
    path : path-like
        The collection file, ending in ``.pvd``.
    disc : Discretization
    t : sequence of float, shape (m,)
    q, qdot : ndarray, shape (m, n)
    alpha : float
    params : Params, optional
        Written as field data (v, alpha, beta, gamma, mu) beside ``time``.

    Returns
    -------
    Path of the .pvd file.
    """
    from fempipe.core.files import write_text
    from fempipe.io.meshes import write_vtu

    path = Path(path)
    if path.suffix != ".pvd":
        raise ValueError(f"trajectory path must end in .pvd, got {path.name!r}")
    q = np.atleast_2d(np.asarray(q, dtype=float))
    qdot = np.atleast_2d(np.asarray(qdot, dtype=float))
    t = np.asarray(t, dtype=float)
    if not (q.shape == qdot.shape and q.shape[0] == t.size):
        raise ValueError("t, q and qdot must describe the same number of frames")
    field = {}
    if params is not None:
        field = {k: float(getattr(params, k)) for k in ("v", "alpha", "beta", "gamma", "mu")}
    frames_dir = path.with_suffix("")
    frames_dir.mkdir(parents=True, exist_ok=True)
    entries = []
    for k in range(t.size):
        pts, data = frame_data(disc, q[k], qdot[k], alpha, points_per_cell)
        m = pts.shape[0]
        cells = np.stack([np.arange(m - 1), np.arange(1, m)], axis=1)
        name = f"frame_{k:05d}.vtu"
        write_vtu(frames_dir / name, pts, cells, data, {"time": float(t[k])} | field)
        entries.append((float(t[k]), f"{frames_dir.name}/{name}"))
    lines = ['<?xml version="1.0"?>']
    lines.append('<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">')
    lines.append("  <Collection>")
    for tk, f in entries:
        lines.append(f'    <DataSet timestep="{tk!r}" group="" part="0" file={quoteattr(f)}/>')
    lines.append("  </Collection>")
    lines.append("</VTKFile>")
    write_text(path, "\n".join(lines) + "\n")
    return path


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

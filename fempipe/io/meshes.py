"""Deformed centerlines as VTU files (meshio), in the VTK frame of :mod:`fempipe.io`.

Gravity along -y: a centerline point is ``(x, y, z) = (Z_g, -X_g, 0)``
(Eq. (28)), the frame of every figure and of :mod:`fempipe.io.trajectory`.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from fempipe.core.files import atomic_path

__all__ = [
    "SHAPE_FIELDS",
    "screen_points",
    "write_vtu",
    "read_field_data",
    "write_shapes",
    "read_shapes",
]


#: Point-data fields of a shape file, in order (all dimensionless; theta in rad).
SHAPE_FIELDS = ("xi", "theta", "varsigma", "eta", "X_g", "Z_g")


def screen_points(X_g, Z_g, scale: float = 1.0) -> np.ndarray:
    """Centerline points in the VTK frame (module docstring): ``(Z_g, -X_g, 0) * scale``."""
    X, Z = np.asarray(X_g, dtype=float), np.asarray(Z_g, dtype=float)
    return np.column_stack([Z, -X, np.zeros(X.size)]) * float(scale)


def write_vtu(
    path: str | os.PathLike,
    points: np.ndarray,
    lines: np.ndarray,
    point_data: Mapping[str, np.ndarray],
    field_data: Mapping[str, float | Sequence[float]] | None = None,
) -> Path:
    """Write line cells with point data and field data as a VTU file, atomically.

    meshio writes the points, cells and point data; the field data (numbers
    or lists of numbers, e.g. ``{"time": 1.5, "v": 4.0, "alpha": 0.0}``) go
    into a ``<FieldData>`` block of the grid, which VTK's XML readers (and
    ParaView) show as field data.  NaN values are written as ``nan``.
    """
    import meshio

    mesh = meshio.Mesh(points, [("line", np.asarray(lines))], point_data=dict(point_data))
    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu")
        if field_data:
            arrays = []
            for name, value in field_data.items():
                vals = np.atleast_1d(np.asarray(value, dtype=float))
                text = " ".join(repr(float(x)) for x in vals)
                arrays.append(
                    f'<DataArray type="Float64" Name="{name}" NumberOfTuples="{vals.size}" '
                    f'format="ascii">{text}</DataArray>'
                )
            xml = tmp.read_text(encoding="utf-8")
            block = "<FieldData>\n" + "\n".join(arrays) + "\n</FieldData>\n"
            xml = xml.replace("<UnstructuredGrid>\n", "<UnstructuredGrid>\n" + block, 1)
            tmp.write_text(xml, encoding="utf-8")
    return Path(path)


def read_field_data(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The field data of a VTU file written by :func:`write_vtu` (name -> array)."""
    import xml.etree.ElementTree as ET

    root = ET.parse(path).getroot()
    out = {}
    for fd in root.iter("FieldData"):
        for arr in fd.iter("DataArray"):
            out[arr.get("Name")] = np.array([float(x) for x in (arr.text or "").split()])
    return out


def write_shapes(
    path: str | os.PathLike,
    shapes: Sequence,
    values: Sequence[float],
    parameter: str = "v",
    length: float | None = None,
    params: Mapping[str, float] | None = None,
) -> Path:
    """Write deformed centerlines to one VTU file, atomically.

    Each shape becomes a polyline of ``line`` cells in the VTK frame of the
    module docstring (gravity along -y); all shapes share one file and are
    told apart by the point data ``shape_index`` and ``parameter``.

    Parameters
    ----------
    path : path-like
        Destination, normally ending in ``.vtu``.
    shapes : sequence of Shape
        :class:`fempipe.model.kinematics.Shape` (or objects with the attributes in
        :data:`SHAPE_FIELDS`), dimensionless.
    values : sequence of float
        The continuation value of each shape (e.g. v), same length.
    parameter : str
        Name of ``values`` in the point data.
    length : float, optional
        Pipe length in m: points are then in metres (the point data stay
        dimensionless, with ``X_g_m``, ``Z_g_m`` added).
    params : mapping, optional
        The fixed parameters (alpha, beta, gamma, mu, v, ...), written as field
        data beside ``time`` = 0 and ``{parameter}_values`` (one per shape).

    Returns
    -------
    Path
    """
    if len(shapes) != len(values):
        raise ValueError(f"got {len(shapes)} shapes but {len(values)} values")
    if not shapes:
        raise ValueError("no shapes to write")
    scale = 1.0 if length is None else float(length)
    pts, lines, data = [], [], {f: [] for f in SHAPE_FIELDS}
    index, value = [], []
    offset = 0
    for i, (s, val) in enumerate(zip(shapes, values, strict=True)):
        m = np.asarray(s.X_g).size
        pts.append(screen_points(s.X_g, s.Z_g, scale))
        lines.append(offset + np.column_stack([np.arange(m - 1), np.arange(1, m)]))
        for f in SHAPE_FIELDS:
            data[f].append(np.asarray(getattr(s, f), dtype=float))
        index.append(np.full(m, i, dtype=float))
        value.append(np.full(m, float(val)))
        offset += m
    point_data = {f: np.concatenate(data[f]) for f in SHAPE_FIELDS}
    point_data["shape_index"] = np.concatenate(index)
    point_data[parameter] = np.concatenate(value)
    if length is not None:
        point_data["X_g_m"] = point_data["X_g"] * scale
        point_data["Z_g_m"] = point_data["Z_g"] * scale
    field = {"time": 0.0}
    field.update({k: float(x) for k, x in (params or {}).items() if k != parameter})
    field[f"{parameter}_values"] = [float(x) for x in values]
    if length is not None:
        field["length_m"] = scale
    return write_vtu(path, np.concatenate(pts), np.concatenate(lines), point_data, field)


def read_shapes(path: str | os.PathLike) -> list[dict[str, np.ndarray]]:
    """Read a file written by :func:`write_shapes` back, one dict per shape.

    Each dict holds the point data of one shape (``xi``, ``theta``, ...,
    the continuation value) and ``points``, shape (m, 3).
    """
    import meshio

    mesh = meshio.read(path)
    idx = np.asarray(mesh.point_data["shape_index"]).astype(int)
    out = []
    for i in np.unique(idx):
        sel = idx == i
        d = {k: np.asarray(a)[sel] for k, a in mesh.point_data.items() if k != "shape_index"}
        d["points"] = np.asarray(mesh.points)[sel]
        out.append(d)
    return out

"""Deformed centerlines as VTU files (meshio) and ParaView time series (:func:`write_series`).

The VTK frame of :mod:`fempipe.io`: gravity along -y, a centerline point at
``(x, y, z) = (Z_g, -X_g, 0)`` (Eq. (28)).
"""

from __future__ import annotations

import base64
import contextlib
import os
import re
import zlib
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from fempipe.core.files import write_text

__all__ = [
    "SHAPE_FIELDS",
    "screen_points",
    "write_vtu",
    "write_vtu_frames",
    "read_field_data",
    "write_shapes",
    "read_shapes",
    "write_series",
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
    """Write line cells with point data (meshio) and field data (numbers or lists, e.g.
    ``{"time": 1.5}``, a ``<FieldData>`` block that ParaView shows) as a VTU file, atomically."""
    return write_text(path, _with_field_data(_meshio_xml(points, lines, point_data), field_data))


def _meshio_xml(points: np.ndarray, lines: np.ndarray, point_data: Mapping) -> str:
    """The VTU text meshio writes for line cells and point data (binary, zlib)."""
    import tempfile

    import meshio

    mesh = meshio.Mesh(points, [("line", np.asarray(lines))], point_data=dict(point_data))
    # meshio writes to a file name only: a private temporary file, read back.
    with tempfile.TemporaryDirectory(prefix="fempipe-vtu-") as tmp:
        name = Path(tmp) / "mesh.vtu"
        meshio.write(name, mesh, file_format="vtu")
        return name.read_text(encoding="utf-8")


def _with_field_data(xml: str, field_data: Mapping | None) -> str:
    """``xml`` with a ``<FieldData>`` block of ``field_data`` at the top of the grid."""
    if not field_data:
        return xml
    arrays = []
    for name, value in field_data.items():
        vals = np.atleast_1d(np.asarray(value, dtype=float))
        text = " ".join(repr(float(x)) for x in vals)
        arrays.append(
            f'<DataArray type="Float64" Name="{name}" NumberOfTuples="{vals.size}" '
            f'format="ascii">{text}</DataArray>'
        )
    block = "<FieldData>\n" + "\n".join(arrays) + "\n</FieldData>\n"
    return xml.replace("<UnstructuredGrid>\n", "<UnstructuredGrid>\n" + block, 1)


#: meshio's compressed binary arrays: blocks of this many bytes, each zlib-compressed.
_BLOCK = 32768
_PAYLOAD = re.compile(
    r'(<DataArray[^>]*Name="([^"]*)"[^>]*format="binary"[^>]*>\s*)([A-Za-z0-9+/=]+)'
)


def _zlib_base64(data: np.ndarray) -> str:
    """One binary DataArray as meshio 5 writes it: UInt32 header and zlib blocks, base64."""
    raw = np.ascontiguousarray(data).tobytes()
    blocks = [zlib.compress(raw[i : i + _BLOCK]) for i in range(0, len(raw), _BLOCK)]
    last = len(raw) - (len(blocks) - 1) * _BLOCK
    header = np.array([len(blocks), _BLOCK, last] + [len(b) for b in blocks], dtype=np.uint32)
    return base64.b64encode(header.tobytes()).decode() + base64.b64encode(b"".join(blocks)).decode()


class _VTUTemplate:
    """meshio's VTU text of one frame with the arrays' places open for frames of its layout
    (meshio's XML tree is most of a small frame's cost); ``valid``: reproduces meshio's text."""

    def __init__(self, xml: str, points: np.ndarray, point_data: Mapping) -> None:
        self.pieces: list[str] = []
        self.names: list[str] = []
        self.layout = _layout(points, point_data)
        pos = 0
        for m in _PAYLOAD.finditer(xml):
            self.pieces.append(xml[pos : m.end(1)])
            self.names.append(m.group(2))
            pos = m.end(3)
        self.pieces.append(xml[pos:])
        self.constant = {}
        arrays = {"Points": points, **point_data}
        for m in _PAYLOAD.finditer(xml):
            if m.group(2) not in arrays:  # the cells: the same in every frame
                self.constant[m.group(2)] = m.group(3)
        self.valid = (
            len(set(self.names)) == len(self.names) and self.fill(points, point_data) == xml
        )

    def fill(self, points: np.ndarray, point_data: Mapping) -> str:
        """The file's text for these arrays (the cells' arrays kept from the template)."""
        arrays = {"Points": points, **point_data}
        out = [self.pieces[0]]
        for name, piece in zip(self.names, self.pieces[1:], strict=True):
            payload = self.constant.get(name)
            out.append(payload if payload is not None else _zlib_base64(arrays[name]))
            out.append(piece)
        return "".join(out)


def _layout(points: np.ndarray, point_data: Mapping) -> tuple:
    """Names, shapes and types of a frame's arrays (the template fits frames of one layout)."""
    arrays = {"Points": points, **point_data}
    return tuple((k, np.shape(a), np.asarray(a).dtype.str) for k, a in arrays.items())


def write_vtu_frames(
    directory: str | os.PathLike,
    names: Sequence[str],
    frames: Iterable[tuple[np.ndarray, Mapping, Mapping | None]],
    lines: np.ndarray,
) -> list[Path]:
    """Write one VTU file per name and frame ``(points, point_data, field_data)`` of the line
    cells ``lines`` into ``directory``, as :func:`write_vtu` would, all or none.

    Frames after the first fill its text (:class:`_VTUTemplate`), meshio where that differs.
    """
    lines = np.asarray(lines)
    template = None
    with _all_or_none(directory) as tmp:
        for name, (points, point_data, field_data) in zip(names, frames, strict=True):
            points = np.asarray(points, dtype=float)
            if template is not None and template.layout == _layout(points, point_data):
                xml = template.fill(points, point_data)
            else:
                xml = _meshio_xml(points, lines, point_data)
                if template is None:
                    template = _VTUTemplate(xml, points, point_data)
                    if not template.valid:
                        template.layout = None  # never used: meshio writes every frame
            with open(tmp / name, "w", encoding="utf-8") as f:
                f.write(_with_field_data(xml, field_data))
    return [Path(directory) / name for name in names]


@contextlib.contextmanager
def _all_or_none(directory: str | os.PathLike) -> Iterator[Path]:
    """A private directory beside ``directory``, moved into it on success, removed on failure."""
    import shutil
    import tempfile

    directory = Path(directory)
    directory.parent.mkdir(parents=True, exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix=f".{directory.name}.", dir=directory.parent))
    try:
        yield tmp
        # mkdtemp makes the directory private (0700): the usual permissions.
        mask = os.umask(0)
        os.umask(mask)
        os.chmod(tmp, 0o777 & ~mask)
        if not directory.exists():
            os.replace(tmp, directory)
            return
        for f in sorted(tmp.iterdir()):
            os.replace(f, directory / f.name)
        tmp.rmdir()
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise


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
    """Write deformed centerlines to one VTU file, atomically (polylines in the VTK frame,
    told apart by the point data ``shape_index`` and ``parameter``).

    Parameters
    ----------
    path : path-like
    shapes : sequence of Shape
        :class:`fempipe.model.kinematics.Shape` (the attributes :data:`SHAPE_FIELDS`).
    values : sequence of float
        The continuation value of each shape.
    parameter : str
        Name of ``values`` in the point data.
    length : float, optional
        Pipe length in m: points in metres, ``X_g_m``, ``Z_g_m`` added.
    params : mapping, optional
        Fixed parameters, field data beside ``time`` = 0 and ``{parameter}_values``.
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
    """A file of :func:`write_shapes`, one dict per shape: its point data and ``points``."""
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


def write_series(path: str | os.PathLike, t, frames: Iterable, n_points: int) -> Path:
    """A ParaView time series: one VTU per time ``t`` and frame ``(points, point_data,
    field_data)`` in ``path``'s stem directory, all or none, then the index ``path`` (.pvd)."""
    path = Path(path)
    if path.suffix != ".pvd":
        raise ValueError(f"trajectory path must end in .pvd, got {path.name!r}")
    frames_dir = path.with_suffix("")
    names = [f"frame_{k:05d}.vtu" for k in range(len(t))]
    cells = np.stack([np.arange(n_points - 1), np.arange(1, n_points)], axis=1)
    write_vtu_frames(frames_dir, names, frames, cells)
    lines = [
        '<?xml version="1.0"?>',
        '<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">',
        "  <Collection>",
    ]
    for tk, name in zip(t, names, strict=True):
        f = quoteattr(f"{frames_dir.name}/{name}")
        lines.append(f'    <DataSet timestep="{float(tk)!r}" group="" part="0" file={f}/>')
    lines += ["  </Collection>", "</VTKFile>"]
    write_text(path, "\n".join(lines) + "\n")
    return path

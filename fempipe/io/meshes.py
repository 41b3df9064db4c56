"""Deformed centerlines as VTU files (meshio), in the VTK frame of :mod:`fempipe.io`.

Gravity along -y: a centerline point is ``(x, y, z) = (Z_g, -X_g, 0)``
(Eq. (28)), the frame of every figure and of :mod:`fempipe.io.trajectory`.
"""

from __future__ import annotations

import base64
import contextlib
import os
import re
import zlib
from collections.abc import Iterable, Iterator, Mapping, Sequence
from pathlib import Path

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
    """One binary DataArray as meshio 5 writes it: a UInt32 header (blocks, block
    size, last block size, compressed sizes) and the zlib blocks, each base64."""
    raw = np.ascontiguousarray(data).tobytes()
    blocks = [zlib.compress(raw[i : i + _BLOCK]) for i in range(0, len(raw), _BLOCK)]
    last = len(raw) - (len(blocks) - 1) * _BLOCK
    header = np.array([len(blocks), _BLOCK, last] + [len(b) for b in blocks], dtype=np.uint32)
    return base64.b64encode(header.tobytes()).decode() + base64.b64encode(b"".join(blocks)).decode()


class _VTUTemplate:
    """The text of meshio's VTU file for one mesh, with the arrays' places kept open.

    The frames of a trajectory share their cells and the names, shapes and
    types of their arrays; only the numbers change.  meshio builds an XML tree
    for every file (most of the cost of a small frame); this fills the text
    meshio wrote for the first frame with each frame's arrays, encoded as
    meshio encodes them.  ``valid`` says whether that reproduces meshio's text
    of the first frame exactly.
    """

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
    """Write many VTU files of the same line cells into ``directory``, as
    :func:`write_vtu` writes each, all or none.

    Parameters
    ----------
    directory : path-like
        Created if missing.
    names : sequence of str
        The file names, one per frame.
    frames : iterable of (points, point_data, field_data)
        One per name, the arguments of :func:`write_vtu`.
    lines : ndarray
        The line cells, shared by every frame.

    Returns
    -------
    list of Path

    Notes
    -----
    The first frame is written by meshio; the others by filling its text with
    their arrays (:class:`_VTUTemplate`), byte for byte the file meshio would
    write (checked on the first frame: otherwise, or for a frame whose arrays
    differ in name, shape or type, meshio writes it).  The files are written
    into a new hidden directory beside ``directory`` and moved into it once
    all are written (:func:`_all_or_none`), so a failure leaves none of them;
    a file per file atomic write (a temporary name, then a rename) cost twice
    as much for the 400 small frames of a trajectory.
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
    """Yield a new private directory beside ``directory``; on success move its files
    into ``directory`` (the whole directory, if ``directory`` does not exist yet),
    on an exception remove it.  The files of a failed write never appear."""
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

"""Writing results to files, atomically.

Every writer here writes to a temporary file in the destination directory
and moves it into place with :func:`os.replace`, so a reader (or a crashed
run) never sees a half-written file: the destination either keeps its old
content or gets the complete new one.

Formats
-------
* JSON (:func:`write_json`): numpy scalars and arrays are converted, NaN/inf
  become ``null`` (strict JSON).
* CSV (:func:`write_csv`, read back with :func:`read_csv`): one row per
  result and a header line whose every cell is ``name [unit]`` (below).
* Shapes (:func:`write_shapes`): deformed centrelines as a meshio VTU file
  (VTK XML unstructured grid): line cells, the centreline in the screen
  frame as points, theta, varsigma, eta, X_g, Z_g, xi and the continuation
  value as point data, the parameters as field data.  VTU was chosen by
  trying: it stores line cells and point data and reads back with plain
  meshio (and opens in ParaView); meshio's XDMF writer needs h5py, which is
  not a dependency.

The VTK frame
-------------
Every VTU file of the package (these shapes and the frames of
:mod:`fempipe.io.trajectory`) uses one frame, the one of every figure:
gravity along -y.  A centreline point is ``(x, y, z) = (Z_g, -X_g, 0)``
(Eq. (28): X_g along gravity, Z_g horizontal), so shapes and trajectories
opened together in ParaView overlap.  Every file has the point arrays
:data:`SHAPE_FIELDS` (and ``theta_dot`` where the state has a velocity) and
the time, v and the parameters as field data (:func:`write_vtu`; meshio's
writer drops field data, so it is added to the XML here).

CSV headers and units
---------------------
Each header cell is the column's name (the JSON key it comes from) and its
unit in square brackets, separated by one space: ``theta_tip [rad]``,
``X_tip [L]``, ``tau [T]``, ``U [m/s]``.  The unit of every column is stated
once, in :data:`CSV_UNITS`; writing a column that is not there is an error.
The error estimate of a column (``--error-estimate``), ``X_tip_error``, has
the unit of the column: ``X_tip_error [L]``.  The units are

* ``[L]``: a length divided by the pipe length L (Eq. (19));
* ``[T]``: a time divided by the time scale T = L^2 sqrt((m + M)/EI)
  (Eq. (19)), i.e. the dimensionless time tau; ``[1/T]``, ``[L/T]`` and
  ``[rad/T]`` are rates per unit tau (eigenvalues lambda, Omega and their
  frequencies; tip velocities);
* ``[rad]``: an angle;
* ``[1]``: any other dimensionless number (v, beta, gamma, mu, a residual
  norm);
* ``[m]``, ``[mm]``, ``[m/s]``: SI values (present with an SI pipe);
* ``[-]``: not a quantity: a flag (True/False), a count, an index, a mode
  number or a label (text).

:func:`read_csv` returns the columns by their bare names, so a script reads a
file in one line: ``fempipe.io.read_csv("out/static.csv")["X_tip"]``.
"""

from __future__ import annotations

import contextlib
import csv
import io as _io
import json
import math
import os
import re
import tempfile
from collections.abc import Iterator, Mapping, Sequence
from pathlib import Path

import numpy as np

__all__ = [
    "atomic_path",
    "to_jsonable",
    "json_dumps",
    "write_json",
    "write_csv",
    "read_csv",
    "csv_header",
    "CSV_UNITS",
    "ERROR_SUFFIX",
    "write_text",
    "write_figure",
    "write_shapes",
    "write_vtu",
    "read_shapes",
    "read_field_data",
    "screen_points",
    "SHAPE_FIELDS",
]

#: Point-data fields of a shape file, in order (all dimensionless; theta in rad).
SHAPE_FIELDS = ("xi", "theta", "varsigma", "eta", "X_g", "Z_g")


def screen_points(X_g, Z_g, scale: float = 1.0) -> np.ndarray:
    """Centreline points in the VTK frame (module docstring): ``(Z_g, -X_g, 0) * scale``."""
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


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; move it onto ``path`` on success.

    The temporary file keeps the destination's suffix (some writers choose the
    format from it).  On an exception it is removed and ``path`` is untouched.

    Examples
    --------
    >>> with atomic_path("out/fig.png") as tmp:   # doctest: +SKIP
    ...     fig.savefig(tmp)
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        # mkstemp makes the file private (0600); give it the usual permissions.
        os.chmod(tmp_path, 0o666 & ~_umask())
        os.replace(tmp_path, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def to_jsonable(obj):
    """Recursively convert numpy types, tuples, paths and non-finite floats for strict JSON.

    Mappings become dicts with string keys, tuples and arrays become lists,
    numpy scalars become Python scalars, NaN and +-inf become ``None`` (JSON
    has no such numbers), :class:`~pathlib.Path` becomes ``str`` and an
    object with ``to_dict()`` becomes that dict.  The one JSON sanitiser of
    the package: result files, ``--json`` output and the validation report.
    """
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        return x if math.isfinite(x) else None
    if isinstance(obj, np.generic):  # other numpy scalars (str_, complex, ...)
        return to_jsonable(obj.item())
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "to_dict"):
        return to_jsonable(obj.to_dict())
    return obj


def json_dumps(obj, indent: int | None = 2) -> str:
    """``json.dumps`` of :func:`to_jsonable` (strict: no NaN literals)."""
    return json.dumps(to_jsonable(obj), indent=indent, allow_nan=False)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path: str | os.PathLike, obj) -> Path:
    """Write ``obj`` as indented strict JSON, atomically."""
    return write_text(path, json_dumps(obj) + "\n")


#: The unit of every CSV column (module docstring, "CSV headers and units").
CSV_UNITS: Mapping[str, str] = {
    # flow, parameters and continuation values
    "v": "1",
    "alpha": "rad",
    "beta": "1",
    "gamma": "1",
    "mu": "1",
    "U": "m/s",
    # tip of a static state (fempipe static)
    "theta_tip": "rad",
    "eta_tip": "L",
    "X_tip": "L",
    "Z_tip": "L",
    "varsigma_tip": "L",
    "tip_drop": "L",
    "X_tip_m": "m",
    "Z_tip_m": "m",
    "eta_tip_m": "m",
    "varsigma_tip_m": "m",
    "tip_drop_mm": "mm",
    "newton_iterations": "-",
    "gravity_loading_iterations": "-",
    "residual_norm": "1",
    "includes_gravity_loading": "-",
    "stable": "-",
    # stability in three dimensions: the verdict or value of each plane (in the
    # plane of the static state or out of it), and which plane
    "stable_in_plane": "-",
    "stable_out_of_plane": "-",
    "plane": "-",
    # eigenvalues (fempipe spectrum): lambda and Omega = -i lambda per unit tau
    "mode": "-",
    "lambda_re": "1/T",
    "lambda_im": "1/T",
    "Omega_re": "1/T",
    "Omega_im": "1/T",
    "eigenvalue_index": "-",
    "pair_member": "-",
    "system_stable": "-",
    # stability events (fempipe critical) and the stability map
    "type": "-",
    "branch": "-",
    "frequency": "1/T",
    "stable_before": "-",
    "stable_after": "-",
    "at_start": "-",
    "eigenvalue_re": "1/T",
    "eigenvalue_im": "1/T",
    "v_cr": "1",
    "v_flutter": "1",
    "U_cr": "m/s",
    "v_cr_in_plane": "1",
    "v_cr_out_of_plane": "1",
    "frequency_in_plane": "1/T",
    "frequency_out_of_plane": "1/T",
    "type_in_plane": "-",
    "type_out_of_plane": "-",
    "mode_in_plane": "-",
    "mode_out_of_plane": "-",
    "v_flutter_in_plane": "1",
    "v_flutter_out_of_plane": "1",
    "first_plane": "-",
    "U_cr_in_plane": "m/s",
    "U_cr_out_of_plane": "m/s",
    "error": "-",
    # the tip's time series (fempipe simulate)
    "tau": "T",
    "theta_tip_rate": "rad/T",
    "eta_tip_rate": "L/T",
    "X_tip_rate": "L/T",
    "Z_tip_rate": "L/T",
    # convergence studies (fempipe convergence): one row per member of a family,
    # the value of the quantity under its own name and its distance to the
    # reference as <quantity>_error
    "family": "-",
    "n": "-",
    "dofs": "-",
    "lc_amplitude": "L",
    "lc_period": "T",
    "theta_tip_error": "rad",
    "X_tip_error": "L",
    "Z_tip_error": "L",
    "eta_tip_error": "L",
    "v_cr_error": "1",
    "frequency_error": "1/T",
    "eigenvalue_error": "1/T",
    "lc_amplitude_error": "L",
    "lc_period_error": "T",
    # comparisons of a user's values (fempipe compare): one row per data row and
    # quantity; user, fempipe, difference, error_estimate and refined are in the
    # unit of the row's quantity, stated in its column "unit", so their header
    # carries "-"
    "row": "-",
    "label": "-",
    "quantity": "-",
    "unit": "-",
    "user": "-",
    "fempipe": "-",
    "difference": "-",
    "relative_difference": "1",
    "error_estimate": "-",
    "resolved": "-",
    "refined": "-",
    "v_min": "1",
    "v_max": "1",
    "U_min": "m/s",
    "U_max": "m/s",
    "failure": "-",
    "note": "-",
}

_HEADER_CELL = re.compile(r"(?P<name>[^\s\[\]]+) \[(?P<unit>[^\[\]]+)\]")
_INTEGER = re.compile(r"[+-]?[0-9]+")


#: The suffix of the column of an error estimate (``fempipe COMMAND --error-estimate``):
#: ``X_tip_error`` has the unit of ``X_tip``.
ERROR_SUFFIX = "_error"


def csv_header(name: str) -> str:
    """The header cell of column ``name``: ``"name [unit]"`` with the unit of :data:`CSV_UNITS`.

    The error estimate ``<name>_error`` of a column (:data:`ERROR_SUFFIX`)
    has the unit of ``<name>``.

    Raises
    ------
    ValueError
        If ``name`` has no unit in :data:`CSV_UNITS`.
    """
    unit = CSV_UNITS.get(name)
    if unit is None and name.endswith(ERROR_SUFFIX):
        # The error estimate of a column has the unit of the column.
        unit = CSV_UNITS.get(name.removesuffix(ERROR_SUFFIX))
    if unit is None:
        raise ValueError(f"CSV column {name!r} has no unit: add it to fempipe.io.CSV_UNITS")
    return f"{name} [{unit}]"


def write_csv(
    path: str | os.PathLike,
    rows: Sequence[Mapping],
    columns: Sequence[str] | None = None,
) -> Path:
    """Write a list of flat dicts as CSV with a header, atomically.

    The header cells are :func:`csv_header` of the keys (``theta_tip [rad]``);
    floats are written with all their digits (``repr``), ``None`` as an
    empty cell.

    Parameters
    ----------
    rows : sequence of mapping
        One dict per row; missing keys give empty cells.
    columns : sequence of str, optional
        Column order (default: keys in order of first appearance).

    Raises
    ------
    ValueError
        If a column has no unit in :data:`CSV_UNITS` (nothing is written).
    """
    if columns is None:
        columns = []
        for row in rows:
            columns.extend(k for k in row if k not in columns)
    header = [csv_header(k) for k in columns]
    buf = _io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow([_csv_cell(row.get(k)) for k in columns])
    return write_text(path, buf.getvalue())


def read_csv(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The columns of a CSV file written by :func:`write_csv`, by bare name.

    Each header cell must be ``name [unit]`` (module docstring); the unit is
    dropped, so ``read_csv(path)["X_tip"]`` is the column ``X_tip [L]``.  A
    column of ``True``/``False`` becomes a bool array, one of integers an int
    array, one of numbers a float array (an empty cell is NaN) and any other
    a str array.

    Raises
    ------
    ValueError
        If a header cell has no unit or a name appears twice.

    Examples
    --------
    >>> tip = read_csv("out/tip.csv")   # doctest: +SKIP
    >>> tip["tau"], tip["X_tip"]        # doctest: +SKIP
    """
    with open(path, newline="", encoding="utf-8") as f:
        table = list(csv.reader(f))
    if not table:
        raise ValueError(f"{path}: empty file, no header")
    names = []
    for cell in table[0]:
        m = _HEADER_CELL.fullmatch(cell)
        if m is None:
            raise ValueError(f"{path}: header cell {cell!r} is not 'name [unit]'")
        if m["name"] in names:
            raise ValueError(f"{path}: column {m['name']!r} appears twice")
        names.append(m["name"])
    body = table[1:]
    for i, row in enumerate(body, start=2):
        if len(row) != len(names):
            raise ValueError(f"{path}, line {i}: {len(row)} cells, the header has {len(names)}")
    return {name: _csv_column([row[j] for row in body]) for j, name in enumerate(names)}


def _csv_column(cells: list[str]) -> np.ndarray:
    if cells and all(c in ("True", "False") for c in cells):
        return np.array([c == "True" for c in cells], dtype=bool)
    if cells and all(_INTEGER.fullmatch(c) for c in cells):
        return np.array([int(c) for c in cells], dtype=int)
    try:
        return np.array([float(c) if c else math.nan for c in cells], dtype=float)
    except ValueError:
        return np.array(cells, dtype=str)


def _csv_cell(x):
    if x is None:
        return ""
    if isinstance(x, (float, np.floating)):
        return repr(float(x))  # round-trip precision
    return x


def write_figure(path: str | os.PathLike, fig, **savefig_kwargs) -> Path:
    """``fig.savefig`` atomically; the format follows the suffix of ``path``."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_kwargs)
    return Path(path)


def write_shapes(
    path: str | os.PathLike,
    shapes: Sequence,
    values: Sequence[float],
    parameter: str = "v",
    length: float | None = None,
    params: Mapping[str, float] | None = None,
) -> Path:
    """Write deformed centrelines to one VTU file, atomically.

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

"""Writing results to files, atomically (temporary file, then :func:`os.replace`): JSON, CSV,
VTU shapes, trajectories, figures; re-exports every public name (``fempipe.io.write_csv``).

VTU frame: gravity along -y, a centerline point is ``(x, y, z) = (Z_g, -X_g, 0)`` (Eq. (28)).
CSV header cells are ``name [unit]`` (:data:`CSV_UNITS`): ``[L]``, ``[T]`` (tau), ``[1/T]``,
``[L/T]``, ``[rad/T]`` scaled by L and T, ``[rad]``, ``[1]`` dimensionless, ``[m]``, ``[mm]``,
``[m/s]`` SI, ``[-]`` no quantity (a flag, a count, a label).  Formats, frame and units in full:
docs/cli/options.md, "Files and units" and "VTK files".
"""

from __future__ import annotations

from fempipe.core.files import atomic_path, json_dumps, to_jsonable, write_json, write_text
from fempipe.io.figures import write_figure, write_gif
from fempipe.io.meshes import (
    SHAPE_FIELDS,
    read_field_data,
    read_shapes,
    screen_points,
    write_shapes,
    write_vtu,
)
from fempipe.io.tables import CSV_UNITS, ERROR_SUFFIX, csv_header, read_csv, write_csv

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
    "write_gif",
    "write_shapes",
    "write_vtu",
    "read_shapes",
    "read_field_data",
    "screen_points",
    "SHAPE_FIELDS",
]

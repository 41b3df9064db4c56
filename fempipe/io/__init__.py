"""Writing results to files, atomically: JSON, CSV tables, VTU shapes, trajectories, figures.

Every writer writes to a temporary file in the destination directory and moves it into place
with :func:`os.replace`, so a reader (or a crashed run) never sees a half-written file.  The
writers live in :mod:`fempipe.core.files` (atomic files, strict JSON), :mod:`fempipe.io.tables`
(CSV), :mod:`fempipe.io.meshes` (VTU shapes), :mod:`fempipe.io.figures` (figures, animated
GIFs) and :mod:`fempipe.io.trajectory` (ParaView time series); this package re-exports every
public name, so ``fempipe.io.write_csv`` is the spelling to use.

Every VTU file uses the frame of every figure, gravity along -y: a centerline point is
``(x, y, z) = (Z_g, -X_g, 0)`` (Eq. (28)).  Every CSV header cell is ``name [unit]``, the unit
of each column stated once in :data:`CSV_UNITS` (an error estimate ``Q_error`` has Q's):
``[L]`` a length over L, ``[T]`` a time over T (that is, tau), ``[1/T]``, ``[L/T]`` and
``[rad/T]`` rates per unit tau, ``[rad]`` an angle, ``[1]`` any other dimensionless number,
``[m]``, ``[mm]`` and ``[m/s]`` SI values, ``[-]`` no quantity (a flag, a count, an index, a
mode number or a label).  :func:`read_csv` returns the columns by their bare names.

Formats, frame and units in full: docs/cli/options.md, "Files and units" and "VTK files".
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

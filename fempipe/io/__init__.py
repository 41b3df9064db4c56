"""Writing results to files, atomically.

Every writer here writes to a temporary file in the destination directory
and moves it into place with :func:`os.replace`, so a reader (or a crashed
run) never sees a half-written file: the destination either keeps its old
content or gets the complete new one.

The writers live in :mod:`fempipe.core.files` (atomic files and strict
JSON, used by the analyses' resumable stores too), :mod:`fempipe.io.tables`
(CSV), :mod:`fempipe.io.meshes` (VTU shapes), :mod:`fempipe.io.figures` (figures, animated GIFs) and
:mod:`fempipe.io.trajectory` (ParaView time series); this package re-exports
every public name, so ``fempipe.io.write_csv`` is the spelling to use.

Formats
-------
* JSON (:func:`write_json`): numpy scalars and arrays are converted, NaN/inf
  become ``null`` (strict JSON).
* CSV (:func:`write_csv`, read back with :func:`read_csv`): one row per
  result and a header line whose every cell is ``name [unit]`` (below).
* Shapes (:func:`write_shapes`): deformed centerlines as a meshio VTU file
  (VTK XML unstructured grid): line cells, the centerline in the screen
  frame as points, theta, varsigma, eta, X_g, Z_g, xi and the continuation
  value as point data, the parameters as field data.  VTU was chosen by
  trying: it stores line cells and point data and reads back with plain
  meshio (and opens in ParaView); meshio's XDMF writer needs h5py, which is
  not a dependency.

The VTK frame
-------------
Every VTU file of the package (these shapes and the frames of
:mod:`fempipe.io.trajectory`) uses one frame, the one of every figure:
gravity along -y.  A centerline point is ``(x, y, z) = (Z_g, -X_g, 0)``
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

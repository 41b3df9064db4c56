"""CSV tables: one row per result, a header cell ``name [unit]`` per column.

The units (``[L]``, ``[T]``, ``[rad]``, ``[1]``, ``[-]``, ...): :mod:`fempipe.io`; the unit of
every column is stated once, in :data:`CSV_UNITS`.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from fempipe.core.files import write_text

__all__ = ["CSV_UNITS", "ERROR_SUFFIX", "csv_header", "write_csv", "read_csv"]


def _units(text: str) -> dict[str, str]:
    """``"name unit name unit ..."`` as a dict."""
    words = text.split()
    return dict(zip(words[::2], words[1::2], strict=True))


#: The unit of every CSV column (the package docstring of :mod:`fempipe.io`; docs/cli/options.md).
#: Per command: static (tip values), spectrum (lambda, Omega = -i lambda per unit tau),
#: parametric (one row per chart, region, plane and sigma), critical and stability-map (the
#: verdict or value of each plane), simulate (tau and the tip's rates), convergence (one row
#: per member, ``<quantity>_error`` its distance to the reference), compare (user, fempipe,
#: difference, error_estimate, refined in the unit of the row's column "unit": "-").
CSV_UNITS: Mapping[str, str] = _units(
    """
    v 1  alpha rad  beta 1  gamma 1  mu 1  U m/s
    theta_tip rad  eta_tip L  X_tip L  Z_tip L  Y_tip L  varsigma_tip L  tip_drop L
    X_tip_m m  Z_tip_m m  eta_tip_m m  varsigma_tip_m m  tip_drop_mm mm
    newton_iterations -  gravity_loading_iterations -  residual_norm 1
    includes_gravity_loading -  stable -  stable_in_plane -  stable_out_of_plane -  plane -
    mode -  lambda_re 1/T  lambda_im 1/T  Omega_re 1/T  Omega_im 1/T  eigenvalue_index -
    pair_member -  system_stable -
    discretization -  kind -  order -  sigma_threshold 1  omega_threshold 1/T  sigma 1
    omega_lo 1/T  omega_hi 1/T
    type -  branch -  frequency 1/T  stable_before -  stable_after -  at_start -
    eigenvalue_re 1/T  eigenvalue_im 1/T  v_cr 1  v_flutter 1  U_cr m/s  v_cr_in_plane 1
    v_cr_out_of_plane 1  frequency_in_plane 1/T  frequency_out_of_plane 1/T
    type_in_plane -  type_out_of_plane -  mode_in_plane -  mode_out_of_plane -
    v_flutter_in_plane 1  v_flutter_out_of_plane 1  first_plane -  U_cr_in_plane m/s
    U_cr_out_of_plane m/s  error -
    tau T  theta_tip_rate rad/T  eta_tip_rate L/T  X_tip_rate L/T  Z_tip_rate L/T
    family -  n -  dofs -  lc_amplitude L  lc_period T  theta_tip_error rad  X_tip_error L
    Z_tip_error L  eta_tip_error L  v_cr_error 1  frequency_error 1/T  eigenvalue_error 1/T
    lc_amplitude_error L  lc_period_error T
    row -  label -  quantity -  fempipe_quantity -  unit -  user -  fempipe -  difference -
    relative_difference 1  error_estimate -  resolved -  verdict -  refined -  v_min 1
    v_max 1  U_min m/s  U_max m/s  omega_min 1/T  omega_max 1/T  sigma_max 1  failure -  note -
    """
)

_HEADER_CELL = re.compile(r"(?P<name>[^\s\[\]]+) \[(?P<unit>[^\[\]]+)\]")
_INTEGER = re.compile(r"[+-]?[0-9]+")


#: The suffix of the column of an error estimate (``fempipe COMMAND --error-estimate``):
#: ``X_tip_error`` has the unit of ``X_tip``.
ERROR_SUFFIX = "_error"


def csv_header(name: str) -> str:
    """``"name [unit]"`` with the unit of :data:`CSV_UNITS` (``<name>_error``: ``<name>``'s)."""
    unit = CSV_UNITS.get(name)
    if unit is None and name.endswith(ERROR_SUFFIX):
        unit = CSV_UNITS.get(name.removesuffix(ERROR_SUFFIX))
    if unit is None:
        raise ValueError(f"CSV column {name!r} has no unit: add it to fempipe.io.CSV_UNITS")
    return f"{name} [{unit}]"


def write_csv(
    path: str | os.PathLike, rows: Sequence[Mapping], columns: Sequence[str] | None = None
) -> Path:
    """Write flat dicts as CSV, atomically: header cells :func:`csv_header`, floats with all
    their digits, ``None`` and missing keys empty; ``columns`` default: keys in order of first
    appearance.  ValueError (nothing written) if a column has no unit."""
    if columns is None:
        columns = []
        for row in rows:
            columns.extend(k for k in row if k not in columns)
    header = [csv_header(k) for k in columns]
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    for row in rows:
        w.writerow([_csv_cell(row.get(k)) for k in columns])
    return write_text(path, buf.getvalue())


def read_csv(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """The columns of a CSV file of :func:`write_csv` by bare name (``read_csv(p)["X_tip"]`` is
    ``X_tip [L]``): bool, int, float (empty NaN) or str arrays.  ValueError if a header cell
    has no unit or a name appears twice."""
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
    """One column of :func:`read_csv`: bool, int, float (empty is NaN) or str, the first that fits."""
    if cells and all(c in ("True", "False") for c in cells):
        return np.array([c == "True" for c in cells], dtype=bool)
    if cells and all(_INTEGER.fullmatch(c) for c in cells):
        return np.array([int(c) for c in cells], dtype=int)
    try:
        return np.array([float(c) if c else math.nan for c in cells], dtype=float)
    except ValueError:
        return np.array(cells, dtype=str)


def _csv_cell(x):
    """One cell of :func:`write_csv`: ``None`` empty, floats with all their digits."""
    if x is None:
        return ""
    if isinstance(x, (float, np.floating)):
        return repr(float(x))  # round-trip precision
    return x

"""Cases files: a user's results, one case per CSV row, read and checked (:func:`read_cases`).

The format (columns :data:`COLUMNS`; ``#`` comments): docs/cli/commands.md, "fempipe compare".
Every value is checked against :mod:`fempipe.io.ranges` first; the first bad one raises
:class:`~fempipe.core.errors.ParamError` ``FILE: row N (line L), column C: message``.
"""

from __future__ import annotations

import csv
import functools
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path

from fempipe.core.errors import ParamError
from fempipe.io import ranges
from fempipe.io.tables import CSV_UNITS
from fempipe.model.params import Params, PipeSI
from fempipe.studies.convergence import PARAMETRIC_QUANTITIES, Quantity

__all__ = [
    "COLUMNS",
    "DEFAULT_SIGMA_MAX",
    "DEFAULT_V_MAX",
    "Case",
    "fempipe_quantity",
    "read_cases",
]

#: Default end of the flow range of v_cr and frequency (above every v_cr of Fig. 6).
DEFAULT_V_MAX = 15.0
#: Default sigma_max, as ``fempipe convergence --sigma-max``.
DEFAULT_SIGMA_MAX = 0.5

_PLANAR = ("v_cr", "frequency")
_CRITICAL = _PLANAR + (
    "v_cr_in_plane",
    "v_cr_out_of_plane",
    "frequency_in_plane",
    "frequency_out_of_plane",
)
_QUANTITIES = ("v_cr", "frequency", "theta_tip", "X_tip", "Z_tip", "eta_tip")
_QUANTITIES += ("lc_amplitude", "lc_period") + _CRITICAL[2:] + PARAMETRIC_QUANTITIES
#: The band the parametric thresholds are searched in (dimensionless, also in an SI file).
_BAND = ("omega_min", "omega_max", "sigma_max")
_DIMLESS = ("beta", "gamma", "mu", "v", "v_min", "v_max")
_SI = ("length", "EI", "m", "M", "g", "a", "U", "U_min", "U_max")
_SI_REQUIRED = ("length", "EI", "m", "M")
#: SI column -> PipeSI field.
_SI_FIELD = {"length": "L", "EI": "EI", "m": "m", "M": "M", "g": "g", "a": "a"}

#: Every column and its unit (a bracketed unit in the header must be this one).
COLUMNS: dict[str, str] = {
    "label": "-",
    "alpha": "rad",
    "alpha_deg": "deg",
    **dict.fromkeys(_DIMLESS, "1"),
    "length": "m",
    "EI": "N m^2",
    "m": "kg/m",
    "M": "kg/m",
    "g": "m/s^2",
    "a": "s",
    **dict.fromkeys(("U", "U_min", "U_max"), "m/s"),
    **{b: CSV_UNITS[b] for b in _BAND},
    **{q: CSV_UNITS[q] for q in _QUANTITIES},
}

_HEADER_CELL = re.compile(r"(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?")


def fempipe_quantity(name: str, planar: bool) -> str:
    """The quantity fempipe computes for the column ``name``: with ``planar``, ``v_cr`` and
    ``frequency`` are the in-plane ones (``v_cr_in_plane``)."""
    return f"{name}_in_plane" if planar and name in _PLANAR else name


@dataclass(frozen=True)
class Case:
    """One data row, checked: ``row`` and ``line`` from 1, ``values`` (quantity -> the user's
    value), ``params`` at the row's flow ``v``, ``defaults`` (parameter not given -> value),
    ``omega_range`` and ``sigma_max`` the band of the parametric thresholds (None without)."""

    row: int
    line: int
    values: dict
    params: Params
    v: float | None
    v_range: tuple[float, float] | None
    defaults: dict = field(default_factory=dict)
    pipe: PipeSI | None = None
    U: float | None = None
    U_range: tuple[float, float] | None = None
    label: str | None = None
    omega_range: tuple[float, float] | None = None
    sigma_max: float | None = None

    def quantity(self, name: str, shoot_rtol: float = 1e-9, planar: bool = False) -> Quantity:
        """The :class:`~fempipe.studies.convergence.Quantity` of column ``name`` for this row."""
        if name in _CRITICAL:
            lo, hi = self.v_range
            planar = planar and name in _PLANAR
            return Quantity(
                name, replace(self.params, v=lo), v_max=hi, shoot_rtol=shoot_rtol, planar=planar
            )
        if name in PARAMETRIC_QUANTITIES:
            return Quantity(
                name, self.params, omega_band=self.omega_range, sigma_max=self.sigma_max
            )
        return Quantity(name, self.params, shoot_rtol=shoot_rtol)

    def to_dict(self, quantity: str | None = None) -> dict:
        """The row's parameters, flat; with ``quantity`` only the flow it uses (the others None)."""
        p = self.params
        out = {"alpha": p.alpha, "beta": p.beta, "gamma": p.gamma, "mu": p.mu, "v": self.v}
        out["v_min"], out["v_max"] = self.v_range or (None, None)
        if self.pipe is not None:
            out["U"] = self.U
            out["U_min"], out["U_max"] = self.U_range or (None, None)
            out["pipe_SI"] = self.pipe.to_dict()
        if self.omega_range is not None:
            out["omega_min"], out["omega_max"] = self.omega_range
            out["sigma_max"] = self.sigma_max
        defaults = dict(self.defaults)
        if quantity is not None:
            unused = ("v", "U") if quantity in _CRITICAL else ("v_min", "v_max", "U_min", "U_max")
            if quantity not in PARAMETRIC_QUANTITIES:
                unused += _BAND
            for key in unused:
                if key in out:
                    out[key] = None
                defaults.pop(key, None)
        out["defaults"] = defaults
        return out


def _columns(column: str) -> str:
    return f"{'columns' if ', ' in column else 'column'} {column}"


def _error(path: str, where: str | None, column: str | None, message: str) -> ParamError:
    """``ParamError(column, "FILE: where, column C: message")``."""
    parts = [p for p in (where, None if column is None else _columns(column)) if p]
    text = f"{path}: {', '.join(parts)}: {message}" if parts else f"{path}: {message}"
    return ParamError(column or "file", text)


def _read_lines(path: str) -> list[tuple[int, list[str]]]:
    """``(line number, cells)`` of the header and data lines (comments and blanks skipped)."""
    err = functools.partial(_error, path, None, None)
    try:
        text = Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise err("no such file") from None
    except IsADirectoryError:
        raise err("is a directory, not a CSV file") from None
    except UnicodeDecodeError as exc:
        raise err(f"not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise err(f"cannot read: {exc.strerror or exc}") from None
    out = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            cells = next(csv.reader([line], strict=True))
        except csv.Error as exc:
            if not out:
                raise _error(path, "header", None, f"line {number} is not CSV ({exc})") from None
            raise _error(
                path, f"row {len(out)} (line {number})", None, f"not CSV ({exc})"
            ) from None
        out.append((number, [c.strip() for c in cells]))
    if not out:
        raise err("no header line: the file is empty or holds only comments")
    return out


def _norm_unit(unit: str) -> str:
    return re.sub(r"[\s*·^]", "", unit).replace("²", "2")


def _parse_header(cells: list[str], path: str) -> list[str]:
    err = functools.partial(_error, path, "header")
    names: list[str] = []
    for i, cell in enumerate(cells, start=1):
        m = _HEADER_CELL.fullmatch(cell)
        if m is None or not m["name"].strip():
            raise err(f"{i}", f"{cell!r} is not a column name (write name or 'name [unit]')")
        name, unit = m["name"].strip(), m["unit"]
        if name not in COLUMNS:
            raise err(
                name,
                "unknown column; the columns are the quantities "
                f"{', '.join(_QUANTITIES)}; the parameters alpha (rad) or alpha_deg, beta, "
                "gamma, mu, v (or the SI pipe length, EI, m, M, g, a, U); the flow range v_min, "
                "v_max (U_min, U_max); the band omega_min, omega_max, sigma_max of the "
                "thresholds; label",
            )
        if name in names:
            raise err(name, "appears twice")
        if unit is not None and _norm_unit(unit) != _norm_unit(COLUMNS[name]):
            hint = ""
            if name == "alpha":
                hint = " (for degrees name the column alpha_deg)"
            elif COLUMNS[name] == "L":
                hint = " (lengths are divided by the pipe length L)"
            raise err(name, f"unit [{unit}] is not the unit of {name}, [{COLUMNS[name]}]{hint}")
        names.append(name)
    present = set(names)
    if not present & set(_QUANTITIES):
        raise err(None, f"no quantity column; give one or more of {', '.join(_QUANTITIES)}")
    if {"alpha", "alpha_deg"} <= present:
        raise err("alpha, alpha_deg", "give the inclination once (rad or degrees)")
    dimless = [n for n in names if n in _DIMLESS]
    si = [n for n in names if n in _SI]
    if dimless and si:
        raise err(
            f"{dimless[0]}, {si[0]}",
            "mixes dimensionless columns (beta, gamma, mu, v, v_min, v_max) with the SI pipe "
            "(length, EI, m, M, g, a, U, U_min, U_max); a file is one or the other",
        )
    missing = [n for n in _SI_REQUIRED if n not in present]
    if si and missing:
        raise err(
            ", ".join(missing),
            f"missing; the SI pipe needs the columns {', '.join(_SI_REQUIRED)} together",
        )
    return names


#: ``err(column, message)``: the ParamError naming the row, its line and the column.
_CellError = Callable[[str | None, str], ParamError]


def _parse_row(names, cells, row: int, line: int, v_max_default: float, path: str) -> Case:
    """One data row checked into a :class:`Case`."""
    err: _CellError = functools.partial(_error, path, f"row {row} (line {line})")
    if len(cells) != len(names):
        raise err(None, f"{len(cells)} cells, the header has {len(names)}")
    values, nums, label = _row_cells(names, cells, err)
    defaults: dict[str, float] = {}
    alpha = _inclination(nums, defaults, err)
    if any(n in _SI for n in names):
        pipe, base, flow, flow_cols = _si_pipe(nums, alpha, defaults, err)
    else:
        pipe = None
        base, flow, flow_cols = _dimensionless(nums, alpha, defaults, err)
    v, v_range, U_range = _flows(
        values, names, nums, flow, flow_cols, pipe, v_max_default, defaults, err
    )
    omega_range, sigma_max = _band(values, names, nums, defaults, err)
    return Case(
        row=row,
        line=line,
        values=values,
        params=base.with_flow(0.0 if v is None else v),
        v=v,
        v_range=v_range,
        defaults=defaults,
        pipe=pipe,
        U=nums.get("U") if pipe is not None else None,
        U_range=U_range,
        label=label,
        omega_range=omega_range,
        sigma_max=sigma_max,
    )


def _row_cells(names, cells, err: _CellError) -> tuple[dict, dict, str | None]:
    """``(values, nums, label)``: the quantities given, the other numbers, the label."""
    values: dict[str, float] = {}
    nums: dict[str, float] = {}
    raw = dict(zip(names, cells, strict=True))
    for name, text in raw.items():
        if name == "label" or text == "":
            continue
        if name == "alpha":
            try:
                nums[name] = ranges.parse_alpha(text)
            except ValueError:
                raise err(
                    name,
                    f"{text!r} is not an angle: radians (1.0472), degrees (60deg) or a multiple "
                    "of pi (pi/3)",
                ) from None
            continue
        try:
            x = float(text)
        except ValueError:
            x = math.nan
        if not math.isfinite(x):
            raise err(name, f"{text!r} is not a (finite) number")
        (values if name in _QUANTITIES else nums)[name] = x
    if not values:
        raise err(
            ", ".join(n for n in names if n in _QUANTITIES),
            "no value: every quantity cell of the row is empty (give one or delete the row)",
        )
    return values, nums, raw.get("label") or None


def _inclination(nums: dict, defaults: dict, err: _CellError) -> float:
    """alpha in rad from ``alpha`` or ``alpha_deg`` (0, recorded in ``defaults``, if neither)."""
    if "alpha_deg" in nums:
        deg = nums["alpha_deg"]
        if abs(deg) > 360.0:
            raise err(
                "alpha_deg", f"alpha_deg = {deg:g} is outside -360 <= alpha_deg <= 360 (degrees)"
            )
        return math.radians(deg)
    if "alpha" in nums:
        alpha = nums["alpha"]
        if abs(alpha) > ranges.ALPHA_MAX:
            raise err(
                "alpha", f"alpha = {alpha:g} is outside -2pi <= alpha <= 2pi (an angle, in rad)"
            )
        return alpha
    defaults["alpha"] = 0.0
    return 0.0


def _si_pipe(nums: dict, alpha: float, defaults: dict, err: _CellError) -> tuple:
    """``(pipe, params at v = 0, flows as v, flow columns)`` of an SI row."""
    for col in _SI_REQUIRED:
        if col not in nums:
            raise err(col, "empty: the SI pipe needs length, EI, m, M in every row")
    kw = {f: nums[c] for c, f in _SI_FIELD.items() if c in nums}
    if "g" not in nums:
        kw["g"] = defaults["g"] = ranges.DEFAULT_G
    if "a" not in nums:
        defaults["a"] = 0.0
    column = {f: c for c, f in _SI_FIELD.items()} | {"gamma": "length, EI, m, M, g", "mu": "a"}
    try:
        pipe = PipeSI(alpha=alpha, **kw)
        base = ranges.check_pipe(pipe.params(0.0))
    except ParamError as exc:
        raise err(column.get(exc.field, exc.field), str(exc)) from None
    flow_cols = {"v": "U", "v_min": "U_min", "v_max": "U_max"}
    flow = {}
    for key, col in flow_cols.items():
        if col in nums:
            try:
                flow[key] = ranges.v_of_U(pipe, nums[col])
            except ParamError as exc:
                raise err(col, str(exc)) from None
    return pipe, base, flow, flow_cols


def _dimensionless(nums: dict, alpha: float, defaults: dict, err: _CellError) -> tuple:
    """``(params at v = 0, flows, flow columns)`` of a dimensionless row."""
    flow = {}
    for name in _DIMLESS:
        if name in nums:
            try:
                x = ranges.check_param(name if name in ("beta", "gamma", "mu") else "v", nums[name])
            except ParamError as exc:
                raise err(name, str(exc)) from None
            if name.startswith("v"):
                flow[name] = x
        elif name in ("beta", "gamma", "mu"):
            defaults[name] = getattr(ranges, f"DEFAULT_{name.upper()}")
    groups = {k: nums.get(k, defaults.get(k)) for k in ("beta", "gamma", "mu")}
    return Params(alpha=alpha, **groups), flow, {k: k for k in ("v", "v_min", "v_max")}


def _flows(values, names, nums, flow, flow_cols, pipe, v_max_default, defaults, err) -> tuple:
    """``(v, v_range, U_range)``: the row's v and the flow range of the critical quantities."""
    v = flow.get("v")
    needs_v = [q for q in values if q not in _CRITICAL]
    if needs_v and v is None:
        col = flow_cols["v"]
        if col in names:
            raise err(col, f"empty, but {needs_v[0]} is at the row's flow velocity {col}")
        raise err(
            needs_v[0],
            f"needs the flow velocity of the case: add a column {col}"
            + (" (m/s)" if pipe is not None else " (or U in m/s with the SI pipe)"),
        )
    critical = [q for q in values if q in _CRITICAL]
    if not critical:
        return v, None, None
    lo, hi = flow.get("v_min", 0.0), flow.get("v_max", v_max_default)
    for key, val in (("v_min", lo), ("v_max", hi)):
        if key not in flow:
            defaults[flow_cols[key]] = pipe.U_of_v(val) if pipe is not None else val
    if not hi > lo:
        raise err(
            f"{flow_cols['v_min']}, {flow_cols['v_max']}",
            f"the flow range of {', '.join(critical)} needs v_min < v_max, got v_min = {lo:g}, "
            f"v_max = {hi:g}",
        )
    if pipe is None:
        return v, (lo, hi), None
    return v, (lo, hi), (nums.get("U_min", pipe.U_of_v(lo)), nums.get("U_max", pipe.U_of_v(hi)))


def _band(values, names, nums, defaults, err: _CellError) -> tuple:
    """``(omega_range, sigma_max)`` of the row's parametric thresholds (None, None without)."""
    for col in _BAND:
        if col in nums:
            try:
                ranges.check_pulsation(col, nums[col])
            except ParamError as exc:
                raise err(col, str(exc)) from None
    thresholds = [q for q in values if q in PARAMETRIC_QUANTITIES]
    if not thresholds:
        return None, None
    for col in ("omega_min", "omega_max"):
        if col not in nums:
            need = f"{thresholds[0]} is searched in the band omega_min < omega < omega_max [1/T]"
            if col in names:
                raise err(col, f"empty, but {need}")
            raise err(thresholds[0], f"{need}: add the columns omega_min, omega_max (e.g. 20, 40)")
    lo, hi = nums["omega_min"], nums["omega_max"]
    if not hi > lo:
        raise err(
            "omega_min, omega_max",
            f"the band of {', '.join(thresholds)} needs omega_min < omega_max, got omega_min = "
            f"{lo:g}, omega_max = {hi:g}",
        )
    if "sigma_max" not in nums:
        defaults["sigma_max"] = DEFAULT_SIGMA_MAX
    return (lo, hi), nums.get("sigma_max", DEFAULT_SIGMA_MAX)


def read_cases(path, v_max: float = DEFAULT_V_MAX) -> list[Case]:
    """The :class:`Case` of every row of the CSV file ``path``, all checked first (ParamError);
    ``v_max``: end of a critical quantity's flow range where a row gives none."""
    path = str(path)
    lines = _read_lines(path)
    (header_line, header), rows = lines[0], lines[1:]
    names = _parse_header(header, path)
    if not rows:
        raise _error(path, None, None, f"no data rows below the header (line {header_line})")
    return [
        _parse_row(names, cells, row, line, v_max, path)
        for row, (line, cells) in enumerate(rows, start=1)
    ]

"""``fempipe compare``'s input file read and checked: one :class:`Case` per data row.

The file's format is in :mod:`fempipe.cli.compare`'s docstring (the columns:
:data:`COLUMNS`).  Every value is checked before anything is computed, against
the ranges of the command-line options (:mod:`fempipe.cli.parsing`); the first
bad cell raises :class:`~fempipe.cli.parsing.CLIError` with the one-line
message ``FILE: row N (line L), column C: message`` (``FILE: header, column
C: ...`` for the header, ``FILE: message`` for the file).
"""

from __future__ import annotations

import csv
import functools
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from fempipe.cli import parsing
from fempipe.cli.parsing import CLIError
from fempipe.core.errors import ParamError
from fempipe.model.params import Params, PipeSI

__all__ = ["COLUMNS", "DEFAULT_V_MAX", "Case", "fempipe_quantity", "read_cases"]

#: Default end of the flow range of v_cr and frequency (above every v_cr of
#: the paper's Fig. 6, about 10 at beta = 0.5).
DEFAULT_V_MAX = 15.0

_QUANTITIES = ("v_cr", "frequency", "theta_tip", "X_tip", "Z_tip", "eta_tip")
_QUANTITIES += ("lc_amplitude", "lc_period")
_QUANTITIES += (
    "v_cr_in_plane",
    "v_cr_out_of_plane",
    "frequency_in_plane",
    "frequency_out_of_plane",
)
_CRITICAL = ("v_cr", "frequency")
_CRITICAL += ("v_cr_in_plane", "v_cr_out_of_plane", "frequency_in_plane", "frequency_out_of_plane")
#: With ``--planar`` the user's v_cr and frequency are the planar model's (module docstring).
_PLANAR = ("v_cr", "frequency")


def fempipe_quantity(name: str, planar: bool) -> str:
    """The name of the quantity fempipe computes for the user's column ``name``: ``v_cr`` and
    ``frequency`` are the first loss of stability in either plane, or with ``--planar`` the
    in-plane ones (``v_cr_in_plane``), as :meth:`Case.quantity` computes them."""
    return f"{name}_in_plane" if planar and name in _PLANAR else name


_DIMLESS = ("beta", "gamma", "mu", "v", "v_min", "v_max")
_SI = ("length", "EI", "m", "M", "g", "a", "U", "U_min", "U_max")
_SI_REQUIRED = ("length", "EI", "m", "M")
#: SI column -> PipeSI field.
_SI_FIELD = {"length": "L", "EI": "EI", "m": "m", "M": "M", "g": "g", "a": "a"}


def _quantity_units() -> dict[str, str]:
    from fempipe.io import CSV_UNITS

    return {q: CSV_UNITS[q] for q in _QUANTITIES}


#: Every column of the input file and its unit (a bracketed unit in the
#: header must be this one; spaces, ``*``, ``·`` and ``^`` are ignored).
COLUMNS: dict[str, str] = {
    "label": "-",
    "alpha": "rad",
    "alpha_deg": "deg",
    "beta": "1",
    "gamma": "1",
    "mu": "1",
    "v": "1",
    "v_min": "1",
    "v_max": "1",
    "length": "m",
    "EI": "N m^2",
    "m": "kg/m",
    "M": "kg/m",
    "g": "m/s^2",
    "a": "s",
    "U": "m/s",
    "U_min": "m/s",
    "U_max": "m/s",
    **_quantity_units(),
}

_HEADER_CELL = re.compile(r"(?P<name>[^\[\]]*?)\s*(?:\[(?P<unit>[^\[\]]*)\])?")


@dataclass(frozen=True)
class Case:
    """One data row of the input file, checked.

    Attributes
    ----------
    row : int
        Data row number, from 1.
    line : int
        Line of the file, from 1.
    values : dict
        quantity -> the user's value (in the file's column order).
    params : Params
        alpha, beta, gamma, mu and the row's flow v (0 if not given).
    v : float or None
        The row's flow velocity (None if not given).
    v_range : tuple of float or None
        ``(v_min, v_max)`` of v_cr and frequency (None if neither is given).
    defaults : dict
        Parameters not given and the value taken.
    pipe : PipeSI or None
        The SI pipe of an SI file.
    U, U_range
        The flow in m/s of an SI file.
    label : str or None
    """

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

    def quantity(self, name: str, shoot_rtol: float = 1e-9, planar: bool = False):
        """The :class:`~fempipe.studies.convergence.Quantity` of column ``name`` for this row:
        ``v_cr`` and ``frequency`` those of the first loss of stability, in either plane, or
        with ``planar`` of the paper's planar model (``v_cr_in_plane``)."""
        from dataclasses import replace

        from fempipe.studies.convergence import Quantity

        if name in _CRITICAL:
            lo, hi = self.v_range
            return Quantity(
                name,
                replace(self.params, v=lo),
                v_max=hi,
                shoot_rtol=shoot_rtol,
                planar=planar and name in _PLANAR,
            )
        return Quantity(name, self.params, shoot_rtol=shoot_rtol)

    def to_dict(self, quantity: str | None = None) -> dict:
        """The parameters of the row, flat (the keys of an output row after the comparison).

        With ``quantity``, only the flow that quantity uses is given: ``v``
        (``U``) for a static tip value or a limit cycle, ``v_min``, ``v_max``
        (``U_min``, ``U_max``) for v_cr and frequency; the other keys are
        None, and ``defaults`` lists only what the quantity uses.
        """
        p = self.params
        out = {"alpha": p.alpha, "beta": p.beta, "gamma": p.gamma, "mu": p.mu, "v": self.v}
        out["v_min"], out["v_max"] = self.v_range if self.v_range else (None, None)
        if self.pipe is not None:
            out["U"] = self.U
            out["U_min"], out["U_max"] = self.U_range if self.U_range else (None, None)
            out["pipe_SI"] = self.pipe.to_dict()
        defaults = dict(self.defaults)
        if quantity is not None:
            unused = ("v", "U") if quantity in _CRITICAL else ("v_min", "v_max", "U_min", "U_max")
            for key in unused:
                if key in out:
                    out[key] = None
                defaults.pop(key, None)
        out["defaults"] = defaults
        return out


class _Where:
    """Builds the one-line messages ``FILE: row N (line L), column C: ...``."""

    def __init__(self, path: str) -> None:
        self.path = path

    def file(self, message: str) -> CLIError:
        return CLIError(self.path, message)

    def header(self, column: str | None, message: str) -> CLIError:
        if column is None:
            where = "header"
        else:
            where = f"header, {'columns' if ', ' in column else 'column'} {column}"
        return CLIError(self.path, f"{where}: {message}")

    def cell(self, row: int, line: int, column: str | None, message: str) -> CLIError:
        where = f"row {row} (line {line})"
        if column is not None:
            where += f", {'columns' if ', ' in column else 'column'} {column}"
        return CLIError(self.path, f"{where}: {message}")


def _norm_unit(unit: str) -> str:
    return re.sub(r"[\s*·^]", "", unit).replace("²", "2")


def _read_lines(path: str, where: _Where) -> list[tuple[int, list[str]]]:
    """``(line number, cells)`` of the header and data lines (comments and blanks skipped)."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise where.file("no such file") from None
    except IsADirectoryError:
        raise where.file("is a directory, not a CSV file") from None
    except UnicodeDecodeError as exc:
        raise where.file(f"not a UTF-8 text file ({exc.reason} at byte {exc.start})") from None
    except OSError as exc:
        raise where.file(f"cannot read: {exc.strerror or exc}") from None
    out = []
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        try:
            cells = next(csv.reader([line], strict=True))
        except csv.Error as exc:
            if not out:
                raise where.header(None, f"line {number} is not CSV ({exc})") from None
            raise where.cell(len(out), number, None, f"not CSV ({exc})") from None
        out.append((number, [c.strip() for c in cells]))
    if not out:
        raise where.file("no header line: the file is empty or holds only comments")
    return out


def _parse_header(cells: list[str], where: _Where) -> list[str]:
    names: list[str] = []
    for i, cell in enumerate(cells, start=1):
        m = _HEADER_CELL.fullmatch(cell)
        if m is None or not m["name"].strip():
            raise where.header(
                f"{i}", f"{cell!r} is not a column name (write name or 'name [unit]')"
            )
        name = m["name"].strip()
        if name not in COLUMNS:
            raise where.header(
                name,
                "unknown column; the columns are the quantities "
                f"{', '.join(_QUANTITIES)}; the parameters alpha (rad) or alpha_deg, beta, "
                "gamma, mu, v (or the SI pipe length, EI, m, M, g, a, U); the flow range v_min, "
                "v_max (U_min, U_max); label",
            )
        if name in names:
            raise where.header(name, "appears twice")
        unit = m["unit"]
        if unit is not None and _norm_unit(unit) != _norm_unit(COLUMNS[name]):
            hint = ""
            if name == "alpha":
                hint = " (for degrees name the column alpha_deg)"
            elif COLUMNS[name] == "L":
                hint = " (lengths are divided by the pipe length L)"
            raise where.header(
                name, f"unit [{unit}] is not the unit of {name}, [{COLUMNS[name]}]{hint}"
            )
        names.append(name)
    present = set(names)
    if not present & set(_QUANTITIES):
        raise where.header(
            None, f"no quantity column; give one or more of {', '.join(_QUANTITIES)}"
        )
    if {"alpha", "alpha_deg"} <= present:
        raise where.header("alpha, alpha_deg", "give the inclination once (rad or degrees)")
    dimless = [n for n in names if n in _DIMLESS]
    si = [n for n in names if n in _SI]
    if dimless and si:
        raise where.header(
            f"{dimless[0]}, {si[0]}",
            "mixes dimensionless columns (beta, gamma, mu, v, v_min, v_max) with the SI pipe "
            "(length, EI, m, M, g, a, U, U_min, U_max); a file is one or the other",
        )
    if si:
        missing = [n for n in _SI_REQUIRED if n not in present]
        if missing:
            raise where.header(
                ", ".join(missing),
                f"missing; the SI pipe needs the columns {', '.join(_SI_REQUIRED)} together",
            )
    return names


def _number(text: str) -> float:
    x = float(text)  # ValueError for text
    if not math.isfinite(x):
        raise ValueError
    return x


def _strip_option(message: str, option: str) -> str:
    return message[len(option) + 2 :] if message.startswith(option + ": ") else message


def _check_group(name: str, x: float) -> float:
    """A dimensionless group in the range of its command-line option (ValueError)."""
    if name == "beta":
        return parsing.check_param("beta", x, 1.0, "a mass ratio")
    if name == "gamma":
        return parsing.check_param("gamma", x, parsing.GAMMA_MAX, parsing.WHY_GAMMA)
    if name == "mu":
        return parsing.check_param("mu", x, parsing.MU_MAX, parsing.WHY_MU)
    try:
        return parsing.check_v(x, name)
    except ValueError as exc:
        raise ValueError(_strip_option(str(exc), name)) from None


#: ``err(column, message)``: the CLIError naming the row, its line and the column.
_CellError = Callable[[str | None, str], CLIError]


def _parse_row(
    names: list[str], cells: list[str], row: int, line: int, v_max_default: float, where: _Where
) -> Case:
    """One data row checked into a :class:`Case` (CLIError naming the row and column)."""
    err: _CellError = functools.partial(where.cell, row, line)
    if len(cells) != len(names):
        raise err(None, f"{len(cells)} cells, the header has {len(names)}")
    values, nums, label = _row_cells(names, cells, err)
    defaults: dict[str, float] = {}
    alpha = _inclination(nums, defaults, err)
    si = any(n in _SI for n in names)
    if si:
        pipe, base, flow, flow_cols = _si_pipe(nums, alpha, defaults, err)
        U = nums.get("U")
    else:
        pipe = U = None
        base, flow, flow_cols = _dimensionless(nums, alpha, defaults, err)
    v, v_range, U_range = _flow_of_quantities(
        values, names, nums, flow, flow_cols, pipe, v_max_default, defaults, err
    )
    params = base.with_flow(0.0 if v is None else v)
    return Case(
        row=row,
        line=line,
        values=values,
        params=params,
        v=v,
        v_range=v_range,
        defaults=defaults,
        pipe=pipe,
        U=U,
        U_range=U_range,
        label=label,
    )


def _row_cells(
    names: list[str], cells: list[str], err: _CellError
) -> tuple[dict, dict, str | None]:
    """``(values, nums, label)``: the quantities given, the other numbers, the label."""
    raw = dict(zip(names, cells, strict=True))
    values: dict[str, float] = {}
    nums: dict[str, float] = {}
    label = raw.get("label") or None
    for name, text in raw.items():
        if name == "label" or text == "":
            continue
        if name == "alpha":
            try:
                nums[name] = parsing.parse_alpha(text)
            except ValueError:
                raise err(
                    name,
                    f"{text!r} is not an angle: radians (1.0472), degrees (60deg) or a multiple "
                    "of pi (pi/3)",
                ) from None
            continue
        try:
            x = _number(text)
        except ValueError:
            raise err(name, f"{text!r} is not a (finite) number") from None
        (values if name in _QUANTITIES else nums)[name] = x
    if not values:
        raise err(
            ", ".join(n for n in names if n in _QUANTITIES),
            "no value: every quantity cell of the row is empty (give one or delete the row)",
        )
    return values, nums, label


def _inclination(nums: dict, defaults: dict, err: _CellError) -> float:
    """alpha in rad from ``alpha`` or ``alpha_deg`` (0, recorded in ``defaults``, if neither)."""
    if "alpha_deg" in nums:
        if abs(nums["alpha_deg"]) > 360.0:
            raise err(
                "alpha_deg",
                f"alpha_deg = {nums['alpha_deg']:g} is outside -360 <= alpha_deg <= 360 (degrees)",
            )
        return math.radians(nums["alpha_deg"])
    if "alpha" in nums:
        alpha = nums["alpha"]
        if abs(alpha) > parsing.ALPHA_MAX:
            raise err(
                "alpha", f"alpha = {alpha:g} is outside -2pi <= alpha <= 2pi (an angle, in rad)"
            )
        return alpha
    defaults["alpha"] = 0.0
    return 0.0


def _si_pipe(nums: dict, alpha: float, defaults: dict, err: _CellError) -> tuple:
    """``(pipe, params at v = 0, flow, flow columns)`` of an SI row; ``flow`` the given
    flows (``v``, ``v_min``, ``v_max``) converted to v."""
    for col in _SI_REQUIRED:
        if col not in nums:
            raise err(col, "empty: the SI pipe needs length, EI, m, M in every row")
    kw = {_SI_FIELD[c]: nums[c] for c in _SI_FIELD if c in nums}
    if "g" not in nums:
        kw["g"] = defaults["g"] = parsing.DEFAULT_G
    if "a" not in nums:
        defaults["a"] = 0.0
    try:
        pipe = PipeSI(alpha=alpha, **kw)
    except ParamError as exc:
        col = {f: c for c, f in _SI_FIELD.items()}.get(exc.field, exc.field)
        raise err(col, str(exc)) from None
    base = pipe.params(0.0)
    if base.gamma > parsing.GAMMA_MAX:
        raise err(
            "length, EI, m, M, g",
            f"the pipe has gamma = (m+M) g L^3/EI = {base.gamma:g}, outside 0 <= gamma <= "
            f"{parsing.GAMMA_MAX:g} ({parsing.WHY_GAMMA})",
        )
    if base.mu > parsing.MU_MAX:
        raise err(
            "a",
            f"the pipe has mu = sqrt(EI/(m+M)) a/L^2 = {base.mu:g}, outside 0 <= mu <= "
            f"{parsing.MU_MAX:g} ({parsing.WHY_MU})",
        )
    flow_cols = {"v": "U", "v_min": "U_min", "v_max": "U_max"}
    flow = {k: _v_of_U(pipe, nums, c, err) for k, c in flow_cols.items() if c in nums}
    return pipe, base, flow, flow_cols


def _v_of_U(pipe: PipeSI, nums: dict, col: str, err: _CellError) -> float:
    """The dimensionless v of the SI flow in column ``col``, in the range of ``--U``."""
    try:
        v = pipe.v_of_U(nums[col])
    except ParamError as exc:
        raise err(col, str(exc)) from None
    if v > parsing.V_MAX:
        raise err(
            col,
            f"U = {nums[col]:g} m/s is outside 0 <= U <= "
            f"{pipe.U_of_v(parsing.V_MAX):.6g} m/s, the U of v = {parsing.V_MAX:g} for "
            f"this pipe ({parsing.WHY_V})",
        )
    return v


def _dimensionless(nums: dict, alpha: float, defaults: dict, err: _CellError) -> tuple:
    """``(params at v = 0, flow, flow columns)`` of a dimensionless row."""
    for name in ("beta", "gamma", "mu"):
        if name in nums:
            try:
                _check_group(name, nums[name])
            except ValueError as exc:
                raise err(name, str(exc)) from None
        else:
            defaults[name] = getattr(parsing, f"DEFAULT_{name.upper()}")
    base = Params(
        alpha=alpha,
        beta=nums.get("beta", parsing.DEFAULT_BETA),
        gamma=nums.get("gamma", parsing.DEFAULT_GAMMA),
        mu=nums.get("mu", parsing.DEFAULT_MU),
    )
    flow = {}
    for name in ("v", "v_min", "v_max"):
        if name in nums:
            try:
                flow[name] = _check_group(name, nums[name])
            except ValueError as exc:
                raise err(name, str(exc)) from None
    flow_cols = {"v": "v", "v_min": "v_min", "v_max": "v_max"}
    return base, flow, flow_cols


def _flow_of_quantities(
    values: dict,
    names: list[str],
    nums: dict,
    flow: dict,
    flow_cols: dict,
    pipe: PipeSI | None,
    v_max_default: float,
    defaults: dict,
    err: _CellError,
) -> tuple:
    """``(v, v_range, U_range)``: the flow of each quantity (the row's v for the static
    tip values and the limit cycle, the range of v_cr and frequency)."""
    si = pipe is not None
    v = flow.get("v")
    needs_v = [q for q in values if q not in _CRITICAL]
    if needs_v and v is None:
        col = flow_cols["v"]
        if col in names:
            raise err(col, f"empty, but {needs_v[0]} is at the row's flow velocity {col}")
        raise err(
            needs_v[0],
            f"needs the flow velocity of the case: add a column {col}"
            + (" (m/s)" if si else " (or U in m/s with the SI pipe)"),
        )
    v_range = U_range = None
    if any(q in _CRITICAL for q in values):
        lo = flow.get("v_min", 0.0)
        hi = flow.get("v_max", v_max_default)
        for key, val in (("v_min", lo), ("v_max", hi)):
            if key not in flow:
                defaults[flow_cols[key]] = pipe.U_of_v(val) if si else val
        if not hi > lo:
            cols = f"{flow_cols['v_min']}, {flow_cols['v_max']}"
            raise err(
                cols,
                f"the flow range of {', '.join(q for q in values if q in _CRITICAL)} needs "
                f"v_min < v_max, got v_min = {lo:g}, v_max = {hi:g}",
            )
        v_range = (lo, hi)
        if si:
            # As given, else converted: U = v sqrt(EI/M)/L.
            U_range = (nums.get("U_min", pipe.U_of_v(lo)), nums.get("U_max", pipe.U_of_v(hi)))
    return v, v_range, U_range


def read_cases(path: str, v_max: float = DEFAULT_V_MAX) -> list[Case]:
    """Read and check the whole input file (module docstring) before anything is computed.

    Parameters
    ----------
    path : str
        The CSV file.
    v_max : float
        End of the flow range of v_cr and frequency where a row gives none.

    Returns
    -------
    list of Case

    Raises
    ------
    CLIError
        At the first bad cell: ``FILE: row N (line L), column C: message``
        (``FILE: header, column C: ...``, ``FILE: message`` for the file).
    """
    where = _Where(str(path))
    lines = _read_lines(str(path), where)
    header_line, header = lines[0]
    names = _parse_header(header, where)
    if len(lines) == 1:
        raise where.file(f"no data rows below the header (line {header_line})")
    return [
        _parse_row(names, cells, row, line, v_max, where)
        for row, (line, cells) in enumerate(lines[1:], start=1)
    ]

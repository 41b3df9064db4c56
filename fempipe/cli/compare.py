"""``fempipe compare FILE.csv``: a user's results checked against fempipe, with its error estimate.

The file holds the user's own numbers (from a modal code, another FE code, an
experiment), one case per row; for each row and each quantity given, fempipe
computes the same quantity (:class:`fempipe.studies.convergence.Quantity`, exactly
as ``fempipe convergence`` does) on the chosen discretisation (``--fe``,
default P3:16, or ``--modal N``) and again on the refined one (elements
halved, twice the modes plus one for an odd N), and reports the user's value, fempipe's, the
difference user - fempipe, the relative difference (over |fempipe|),
fempipe's error estimate (the Grid Convergence Index of one refinement,
:mod:`fempipe.studies.error_estimate`) and whether the difference is *resolved*
(|difference| > error estimate: fempipe's discretisation error cannot explain
it).  See :mod:`fempipe.studies.compare`.

Input file
----------
CSV with a header line; lines starting with ``#`` and blank lines are
skipped (comments: say where the numbers come from); ``row`` N in the output
and in messages counts the data rows from 1.  A header cell is a column name,
optionally with its unit in brackets as in fempipe's own CSV files
(``v_cr [1]``, ``alpha [rad]``, ``X_tip [L]``); a unit that is not the
column's is refused (``alpha [deg]``: name the column ``alpha_deg``).
Columns (:data:`COLUMNS`):

* the quantities, one or more: ``v_cr``, ``frequency`` (Im lambda of the
  critical event, per unit tau), ``theta_tip`` (rad), ``X_tip``, ``Z_tip``,
  ``eta_tip`` (static tip values, divided by L), ``lc_amplitude`` (of
  eta(1), L), ``lc_period`` (T); an empty cell: not given for that row.
  ``v_cr`` and ``frequency`` are compared, as they always were, with the
  critical velocity of the paper's planar model, the motion in the plane of
  the static state (what a planar code computes; the same numbers as
  ``v_cr_in_plane``, ``frequency_in_plane``); ``v_cr_out_of_plane`` and
  ``frequency_out_of_plane`` are those of the motion out of that plane
  (:mod:`fempipe.model.out_of_plane`): the round pipe first loses stability at the
  smaller of ``v_cr_in_plane`` and ``v_cr_out_of_plane``, which is
  ``fempipe critical``'s and ``fempipe convergence``'s ``v_cr`` (README,
  "Out of the plane");
* the inclination ``alpha`` in rad (also ``pi/3``, ``60deg`` as for
  ``--alpha``) or ``alpha_deg`` in degrees, default 0;
* dimensionless groups ``beta``, ``gamma``, ``mu`` (Eq. (19)) and the flow
  ``v``; missing columns or empty cells of beta, gamma, mu take the paper's
  case 0.142, 18.9, 5e-3 like the options of every other command, and the
  output lists each value so taken (``defaults``);
* or the SI pipe: ``length`` (m), ``EI`` (N m^2), ``m``, ``M`` (kg/m), ``g``
  (m/s^2, default 9.81), ``a`` (s, default 0) and the flow ``U`` (m/s),
  converted by :class:`fempipe.model.params.PipeSI` as the SI options are; a file
  is either dimensionless or SI (``alpha``/``alpha_deg`` belong to both);
* the flow range of the critical quantities (``v_cr``, ``frequency`` and
  their ``_in_plane``, ``_out_of_plane`` forms): ``v_min`` (default 0),
  ``v_max`` (default ``--v-max``, 15) or, SI, ``U_min``, ``U_max`` in m/s;
  ``v``/``U`` is then not needed.  The static tip values and the limit
  cycle are at the row's ``v`` (or ``U``), which they require;
* ``label``: free text, carried into the output.

Every value is checked before anything is computed, against the ranges of
the command-line options (:mod:`fempipe.cli.parsing`); the first bad cell
ends the command with one line ``fempipe compare: error: FILE: row N (line
L), column C: message`` (``FILE: header, column C: ...`` for the header)
and exit code 2, and no file is written.

Output
------
``--json`` prints ``{"file", "rows": [{"row", "quantity", "user",
"fempipe", "difference", "relative_difference", "error_estimate",
"resolved", "unit", "refined", "failure", "note", "alpha", "beta",
"gamma", "mu", "v", "v_min", "v_max", "defaults", ...}], "discretization",
"error_estimate": {"method", "discretization", "refined", "formula",
"floor", "floors", "resolved", ...}, "summary", "cpu_time"}`` (with the SI
pipe also ``U``, ``U_min``, ``U_max``, ``pipe_SI`` per row).  ``--out DIR``
writes compare.json, compare.csv (one line per row and quantity; ``user``,
``fempipe``, ``difference``, ``error_estimate`` and ``refined`` are in the
unit of the line's quantity, named in its column ``unit``, so their header
says ``[-]``) and compare.png (user against fempipe per quantity, the line
y = x, and the differences with fempipe's error estimate as error bars).

Exit codes: 0 when every comparison was computed (resolved or not), 1 when
some computation failed (Newton, no v_cr in the flow range, no limit cycle:
its row is in the table and the files with the failure's message and no
fempipe value; the others are complete), 2 for bad input.
"""

from __future__ import annotations

import argparse
import csv
import math
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

from fempipe.cli import common, parsing, reporting
from fempipe.cli.parsing import CLIError
from fempipe.model.params import Params, PipeSI

__all__ = ["COLUMNS", "DEFAULT_V_MAX", "Case", "add_arguments", "read_cases", "run"]

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
#: The user's v_cr and frequency are the planar model's (module docstring).
_PLANAR = ("v_cr", "frequency")
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


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "file",
        metavar="FILE.csv",
        help="the user's values: one case per row; columns: quantities (v_cr, frequency "
        "(in the plane, the paper's planar model), theta_tip, X_tip, Z_tip, eta_tip, "
        "lc_amplitude, lc_period, v_cr_in_plane, v_cr_out_of_plane, frequency_in_plane, "
        "frequency_out_of_plane), parameters (alpha or "
        "alpha_deg, beta, gamma, mu, v; or length, EI, m, M, g, a, U in SI), the flow range "
        "v_min, v_max (or U_min, U_max) of v_cr and frequency, label; '# ...' lines are "
        "comments (see README, 'fempipe compare')",
    )
    common.add_discretization_arguments(parser)
    g = parser.add_argument_group("comparison")
    g.add_argument(
        "--v-max",
        metavar="V",
        type=parsing.number_type("--v-max", 0.0, parsing.V_MAX, strict_low=True),
        default=str(DEFAULT_V_MAX),
        help=f"end of the flow range of v_cr and frequency where a row has no v_max (or U_max) "
        f"cell (default {DEFAULT_V_MAX:g}; dimensionless v, also for an SI file)",
    )
    common.add_shoot_rtol_argument(
        g, "integration tolerance of the limit cycle's shooting (lc_amplitude, lc_period)"
    )
    common.add_workers_argument(g, "processes computing the comparisons in parallel (default 1)")
    common.add_output_arguments(parser)


# ---------------------------------------------------------------------------
# Reading and checking the file
# ---------------------------------------------------------------------------


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

    def quantity(self, name: str, shoot_rtol: float = 1e-9):
        """The :class:`~fempipe.studies.convergence.Quantity` of column ``name`` for this row."""
        from dataclasses import replace

        from fempipe.studies.convergence import Quantity

        if name in _CRITICAL:
            lo, hi = self.v_range
            return Quantity(
                name,
                replace(self.params, v=lo),
                v_max=hi,
                shoot_rtol=shoot_rtol,
                planar=name in _PLANAR,
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
        return parsing._check_param("beta", x, 1.0, "a mass ratio")
    if name == "gamma":
        return parsing._check_param("gamma", x, parsing.GAMMA_MAX, parsing._WHY_GAMMA)
    if name == "mu":
        return parsing._check_param("mu", x, parsing.MU_MAX, parsing._WHY_MU)
    try:
        return parsing._check_v(x, name)
    except ValueError as exc:
        raise ValueError(_strip_option(str(exc), name)) from None


def _parse_row(
    names: list[str], cells: list[str], row: int, line: int, v_max_default: float, where: _Where
) -> Case:
    """One data row checked into a :class:`Case` (CLIError naming the row and column)."""
    from fempipe.core.errors import ParamError

    def err(column: str | None, message: str) -> CLIError:
        return where.cell(row, line, column, message)

    if len(cells) != len(names):
        raise err(None, f"{len(cells)} cells, the header has {len(names)}")
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

    # inclination
    defaults: dict[str, float] = {}
    if "alpha_deg" in nums:
        if abs(nums["alpha_deg"]) > 360.0:
            raise err(
                "alpha_deg",
                f"alpha_deg = {nums['alpha_deg']:g} is outside -360 <= alpha_deg <= 360 (degrees)",
            )
        alpha = math.radians(nums["alpha_deg"])
    elif "alpha" in nums:
        alpha = nums["alpha"]
        if abs(alpha) > parsing.ALPHA_MAX:
            raise err(
                "alpha", f"alpha = {alpha:g} is outside -2pi <= alpha <= 2pi (an angle, in rad)"
            )
    else:
        alpha = 0.0
        defaults["alpha"] = 0.0

    pipe = None
    U = U_range = None
    si = any(n in _SI for n in names)
    if si:
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
                f"{parsing.GAMMA_MAX:g} ({parsing._WHY_GAMMA})",
            )
        if base.mu > parsing.MU_MAX:
            raise err(
                "a",
                f"the pipe has mu = sqrt(EI/(m+M)) a/L^2 = {base.mu:g}, outside 0 <= mu <= "
                f"{parsing.MU_MAX:g} ({parsing._WHY_MU})",
            )

        def to_v(col: str) -> float:
            try:
                v = pipe.v_of_U(nums[col])
            except ParamError as exc:
                raise err(col, str(exc)) from None
            if v > parsing.V_MAX:
                raise err(
                    col,
                    f"U = {nums[col]:g} m/s is outside 0 <= U <= "
                    f"{pipe.U_of_v(parsing.V_MAX):.6g} m/s, the U of v = {parsing.V_MAX:g} for "
                    f"this pipe ({parsing._WHY_V})",
                )
            return v

        flow_cols = {"v": "U", "v_min": "U_min", "v_max": "U_max"}
        flow = {k: to_v(c) for k, c in flow_cols.items() if c in nums}
        U = nums.get("U")
    else:
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

    # the flow of each quantity
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
    v_range = None
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


# ---------------------------------------------------------------------------
# The command
# ---------------------------------------------------------------------------


def run(args: argparse.Namespace) -> int:
    import time

    from fempipe.io import CSV_UNITS
    from fempipe.studies.compare import compare_values, estimate_description

    t0 = time.process_time()
    setup = common.setup_from_args(args, need_flow=False)  # the discretisation
    disc = setup.disc
    cases = read_cases(args.file, v_max=args.v_max)
    items = [(case, name) for case in cases for name in case.values]
    parsing.check_count(
        args.file, len(items), parsing.MAX_VALUES, parsing.allow_large(args), "comparisons"
    )
    pairs = [(case.quantity(name, args.shoot_rtol), case.values[name]) for case, name in items]
    output = reporting.Output(args.out) if args.out is not None else None
    with reporting.progress(args, len(pairs), "compare") as bar:
        comparisons = compare_values(
            pairs, disc, workers=args.workers, callback=lambda done, total: bar.update()
        )
    rows = []
    for (case, name), comp in zip(items, comparisons, strict=True):
        d = comp.to_dict()
        row = {"row": case.row, "line": case.line}
        if case.label is not None:
            row["label"] = case.label
        row |= {k: d[k] for k in ("quantity", "user", "fempipe", "difference")}
        row |= {k: d[k] for k in ("relative_difference", "error_estimate", "resolved")}
        row |= {"unit": CSV_UNITS[name], "refined": d["refined"]}
        row |= {"failure": d["failure"], "note": d["note"]}
        row |= case.to_dict(name)
        row["cpu_time"] = d["cpu_time"]
        rows.append(row)
    quantities = list(dict.fromkeys(name for _, name in items))
    failed = [r for r in rows if r["failure"] is not None]
    result = {
        "file": str(args.file),
        "rows": rows,
        "discretization": {"name": disc.name, **disc.to_dict()},
        "error_estimate": estimate_description(disc, quantities, args.shoot_rtol),
        "summary": {
            "comparisons": len(rows),
            "resolved": sum(r["resolved"] is True for r in rows),
            "not_resolved": sum(r["resolved"] is False for r in rows),
            "no_estimate": sum(r["resolved"] is None and r["failure"] is None for r in rows),
            "failed": len(failed),
        },
        "cpu_time": reporting.cpu_seconds(t0),
    }
    reporting.deliver(
        args, result, output, write=lambda out: _write(out, result), text=lambda: _print(result)
    )
    if failed:
        rows_failed = ", ".join(f"{r['row']} {r['quantity']}" for r in failed)
        print(
            f"fempipe compare: {len(failed)} of {len(rows)} comparisons failed (row {rows_failed});"
            " they are in the table with their message",
            file=sys.stderr,
        )
        return 1
    return 0


#: The columns of compare.csv, in order (those present).
CSV_COLUMNS = (
    "row",
    "label",
    "quantity",
    "unit",
    "user",
    "fempipe",
    "difference",
    "relative_difference",
    "error_estimate",
    "resolved",
    "refined",
    "alpha",
    "beta",
    "gamma",
    "mu",
    "v",
    "v_min",
    "v_max",
    "U",
    "U_min",
    "U_max",
    "failure",
    "note",
)


def _write(output: reporting.Output, result: dict) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from fempipe.plotting.compare import plot_comparison

    present = {k for r in result["rows"] for k in r}
    columns = [c for c in CSV_COLUMNS if c in present]
    fig = plot_comparison(result["rows"], caption=_caption(result))
    try:
        output.json("compare.json", result)
        output.csv("compare.csv", result["rows"], columns)
        output.figure("compare.png", fig, dpi=150)
    finally:
        plt.close(fig)


def _ranges(numbers: list[int]) -> str:
    """``[1, 2, 3, 5]`` -> ``"1-3, 5"``."""
    out, start, prev = [], None, None
    for n in sorted(set(numbers)):
        if start is None:
            start = prev = n
        elif n == prev + 1:
            prev = n
        else:
            out.append(f"{start}" if start == prev else f"{start}-{prev}")
            start = prev = n
    if start is not None:
        out.append(f"{start}" if start == prev else f"{start}-{prev}")
    return ", ".join(out)


def _common(rows: list[dict], key: str, fmt: str = "{:.6g}") -> str | None:
    vals = {r.get(key) for r in rows}
    if len(vals) == 1 and None not in vals:
        return fmt.format(vals.pop())
    return None


def _caption(result: dict) -> str:
    """The parameters every row shares, the discretisation and the estimate."""
    rows = result["rows"]
    est = result["error_estimate"]
    parts = []
    alpha = _common(rows, "alpha", "{:.6g}")
    if alpha is not None:
        parts.append(f"α = {math.degrees(float(alpha)):.4g}°")
    for key, sym in (("beta", "β"), ("gamma", "γ"), ("mu", "μ")):
        val = _common(rows, key)
        parts.append(f"{sym} = {val}" if val is not None else f"{sym} per row")
    if _common(rows, "alpha") is None:
        parts.insert(0, "α per row")
    disc = result["discretization"]["name"]
    text = (
        f"{', '.join(parts)} (rows: compare.csv). fempipe on {disc}; error bars: its error "
        f"estimate, {est['formula']} with {est['refined']}; filled: resolved "
        "(|user − fempipe| > estimate)."
    )
    failed = [r for r in rows if r["fempipe"] is None]
    if failed:
        text += " Not drawn (failed): " + ", ".join(
            f"row {r['row']} {r['quantity']}" for r in failed
        )
    return text


def _fmt(x, spec: str = "{:.10g}") -> str:
    return "-" if x is None else spec.format(x)


def _print(result: dict) -> None:
    rows = result["rows"]
    est = result["error_estimate"]
    n = len(rows)
    print(
        f"fempipe compare {result['file']}: {n} comparison{'s' if n != 1 else ''} on "
        f"{est['discretization']}; error estimate {est['formula']} from {est['refined']}"
    )
    wq = max([12] + [len(r["quantity"]) for r in rows])
    print(
        f"{'row':>4} {'quantity':<{wq}} {'user':>15} {'fempipe':>17} {'difference':>11} "
        f"{'rel. diff.':>11} {'error est.':>10} {'resolved':>8}"
    )
    for r in rows:
        rel = (
            "-" if r["relative_difference"] is None else f"{100 * r['relative_difference']:+.3g} %"
        )
        resolved = {True: "yes", False: "no", None: "-"}[r["resolved"]]
        print(
            f"{r['row']:>4} {r['quantity']:<{wq}} {_fmt(r['user']):>15} "
            f"{_fmt(r['fempipe']):>17} "
            f"{_fmt(r['difference'], '{:+.3e}'):>11} {rel:>11} "
            f"{_fmt(r['error_estimate'], '{:.1e}'):>10} {resolved:>8}"
        )
        if r["failure"] is not None:
            print(f"       failed: {r['failure']}")
        elif r["note"]:
            print(f"       {r['note']}")
    defaults: dict[tuple[str, float], list[int]] = {}
    for r in rows:
        for k, val in r["defaults"].items():
            defaults.setdefault((k, val), []).append(r["row"])
    for (k, val), where in defaults.items():
        why = {
            "alpha": "the default inclination",
            "g": "the default gravity, m/s^2",
            "a": "no Kelvin-Voigt damping, s",
            "v_min": "the start of the flow range",
            "U_min": "the start of the flow range, m/s",
            "v_max": "--v-max",
            "U_max": "--v-max, in m/s",
        }.get(k, "the paper's case")
        print(f"not given in row {_ranges(where)}: {k} = {val:.6g} ({why})")
    s = result["summary"]
    print(
        f"{s['resolved']} resolved, {s['not_resolved']} not resolved (within fempipe's error "
        f"estimate), {s['no_estimate']} without an estimate, {s['failed']} failed"
    )

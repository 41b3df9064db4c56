"""The one option parser shared by every ``fempipe`` subcommand.

Every subcommand that solves the pipe takes the same physical parameters,
discretisation, flow values and output options; they are declared here once
so that the spellings (``--alpha 90deg``, ``--fe P3:16``, ``--v 0:6:13``,
``--U 0,0.5,1``) and the error messages are the same everywhere.

Physical parameters come either dimensionless (``--alpha --beta --gamma
--mu``, with ``--v`` for the flow) or in SI units (``--length --EI --m --M``,
all four together, plus optional ``--g --a``, with ``--U`` in m/s for the
flow), Eq. (19) of Chen, Hu, Dai & Wang (2020).

Bad input is refused before any computation, with one line naming the
option: a single option is checked by its argparse ``type=`` callable, what
depends on several options (the SI pipe, ``--U``, the work limits) by
:func:`setup_from_args`, which raises :class:`CLIError`.  The dispatcher
(:func:`fempipe.cli.main`) prints ``fempipe <cmd>: error: --option: message``
on stderr and exits with code 2.

Accepted ranges
---------------
The default discretisation P3:16 has 48 unknowns, its nodes 1/48 apart.  The
narrowest features of a state are the layer at the clamp where gravity takes
over from bending, of width ~ 1/sqrt(gamma), and the bending waves of the
follower force v^2 sin(theta(1) - theta) of Eq. (20), of length ~ 1/v.  They
are resolved while they are no narrower than about one node spacing, so the
command line accepts

* ``0 <= v <= 50`` (:data:`V_MAX`; ``--U`` up to the U of v = 50),
* ``0 <= gamma <= 2500`` (:data:`GAMMA_MAX` = 50^2),
* ``0 <= mu <= 10`` (:data:`MU_MAX`): without flow, mode r of the cantilever
  has the damping ratio mu lambda_r^2 / 2 (lambda_1 = 1.875), so from
  mu = 0.57 on every mode is overdamped; 10 leaves ample room,
* ``-2 pi <= alpha <= 2 pi`` (:data:`ALPHA_MAX`; alpha is an angle).

At the ends P3:16 is still close to P3:64: 6e-5 in the static tip X_tip at
gamma = 2500 (alpha = pi/2; 4e-8 at gamma = 100) and 3 % in the first
eigenvalue at v = 50 (alpha = 0; 8e-7 at v = 10); refine ``--fe`` for accuracy
there.  The ranges are far beyond the paper's figures (v <= 12, gamma <= 100)
and beyond what a soft plug-flow pipe is: v = 50 is U = 30 m/s in
Texier & Dorbolo's pipe.

Work limits
-----------
More than :data:`MAX_VALUES` values in a list (``--v``, ``--U``, ``--values``,
``--alphas``, ``--betas``, ``--gammas``, and their products in
``stability-map`` and ``bifurcation``), more than :data:`MAX_DOFS` unknowns
(``--fe Pk:n`` has n k, ``--modal N`` has N) or ``--t-max`` above
:data:`T_MAX` need ``--allow-large``: a typing slip must not start hours of
work.

Typical use in a subcommand module::

    def add_arguments(parser):
        common.add_physical_arguments(parser)
        common.add_flow_arguments(parser, default="0:10:11")
        common.add_discretization_arguments(parser)
        common.add_output_arguments(parser)

    def run(args):
        setup = common.setup_from_args(args)   # raises CLIError on bad input
        model = PipeModel(setup.disc, setup.params)   # setup.v: the flow values
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from fempipe.discretization import _FE_RE, DEFAULT_FE, parse_discretization
from fempipe.errors import ParamError
from fempipe.params import PAPER_CASE, Params, PipeSI

__all__ = [
    "CLIError",
    "ArgumentParser",
    "Output",
    "Setup",
    "ValueList",
    "add_physical_arguments",
    "add_discretization_arguments",
    "add_flow_arguments",
    "add_output_arguments",
    "number_type",
    "option_type",
    "parse_alpha",
    "parse_alpha_list",
    "parse_values",
    "parse_float",
    "setup_from_args",
    "progress",
    "workers_type",
]

#: Defaults of the dimensionless options: the paper's reference case.
DEFAULT_BETA = PAPER_CASE["beta"]
DEFAULT_GAMMA = PAPER_CASE["gamma"]
DEFAULT_MU = PAPER_CASE["mu"]
DEFAULT_G = 9.81

#: Accepted ranges (module docstring, "Accepted ranges").
V_MAX = 50.0
GAMMA_MAX = V_MAX**2
MU_MAX = 10.0
ALPHA_MAX = 2 * math.pi
#: Work limits lifted by ``--allow-large`` (module docstring, "Work limits").
MAX_VALUES = 1000
MAX_DOFS = 1000
T_MAX = 1e4

_WHY_V = "the default mesh P3:16 resolves bending waves of length 1/v down to v = 50"
_WHY_GAMMA = "the default mesh P3:16 resolves the clamp layer 1/sqrt(gamma) down to gamma = 2500"
_WHY_MU = "every mode is overdamped from mu = 0.57 on"

#: SI option -> PipeSI field.
_SI_OPTIONS = {"--length": "L", "--EI": "EI", "--m": "m", "--M": "M", "--g": "g", "--a": "a"}
_SI_REQUIRED = ("--length", "--EI", "--m", "--M")
#: Params / PipeSI field -> the option that sets it, to name it in errors.
_DIMLESS_OPTION = {"alpha": "--alpha", "beta": "--beta", "gamma": "--gamma", "mu": "--mu"}
_SI_FIELD_OPTION = {field: opt for opt, field in _SI_OPTIONS.items()} | {"alpha": "--alpha"}


class CLIError(ValueError):
    """Bad command-line input; ``str()`` is the one-line message naming the option.

    Parameters
    ----------
    option : str
        The offending option, e.g. ``"--alpha"``.
    message : str
        What is wrong and what is allowed.
    """

    def __init__(self, option: str, message: str) -> None:
        message = " ".join(str(message).split())  # one line, always
        if message.startswith(option):
            message = message[len(option) :].lstrip(" :")
        super().__init__(f"{option}: {message}")
        self.option = option
        self.message = message


class ArgumentParser(argparse.ArgumentParser):
    """argparse with one-line errors: ``prog: error: message`` and exit code 2.

    The standard parser prints the whole usage block before the error; the
    project's rule is one line naming the option (``--help`` still shows usage).
    """

    def error(self, message: str):  # noqa: D102 - argparse API
        message = " ".join(message.split())
        # A type= callable's error reads "argument --v: ..."; print "--v: ...",
        # like CLIError.
        message = re.sub(r"^argument (-[-\w]+)(?:/-[-\w]+)?: ", r"\1: ", message)
        self.exit(2, f"{self.prog}: error: {message}\n")


def option_type(option: str, parse: Callable[[str], object]) -> Callable[[str], object]:
    """An argparse ``type=`` callable: ``parse(text)``, its ValueError a one-line usage error."""

    def convert(text: str):
        try:
            return parse(text)
        except ValueError as exc:
            raise argparse.ArgumentTypeError(CLIError(option, str(exc)).message) from None

    convert.__name__ = option.lstrip("-")
    return convert


# ---------------------------------------------------------------------------
# Value parsers (pure functions; ValueError names the option)
# ---------------------------------------------------------------------------

_NUMBER = r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_PI_RE = re.compile(rf"^([+-]?)\s*({_NUMBER})?\s*\*?\s*(?:pi|π)\s*(?:/\s*({_NUMBER}))?$")
_DEG_RE = re.compile(rf"^([+-]?\s*{_NUMBER})\s*(?:deg|degrees?|°)$")
_RAD_RE = re.compile(rf"^([+-]?\s*{_NUMBER})\s*(?:rad)?$")


def parse_alpha(text: str) -> float:
    """Parse an inclination alpha in rad, degrees or multiples of pi.

    Accepted forms: ``1.5708`` or ``1.5708rad`` (radians), ``90deg``,
    ``-45°`` (degrees), ``pi``, ``pi/2``, ``0.5pi``, ``-pi/4``, ``3pi/4``,
    ``3*pi/4`` (multiples of pi).

    Returns
    -------
    float
        alpha in radians.

    Raises
    ------
    ValueError
        Naming ``--alpha`` and the accepted forms.
    """
    s = str(text).strip().lower()
    value: float | None = None
    if m := _PI_RE.match(s):
        sign = -1.0 if m.group(1) == "-" else 1.0
        num = float(m.group(2)) if m.group(2) else 1.0
        den = float(m.group(3)) if m.group(3) else 1.0
        if den != 0.0:
            value = sign * num * math.pi / den
    elif m := _DEG_RE.match(s):
        value = math.radians(float(m.group(1).replace(" ", "")))
    elif m := _RAD_RE.match(s):
        value = float(m.group(1).replace(" ", ""))
    if value is None or not math.isfinite(value):
        raise ValueError(
            f"--alpha expects radians (1.5708), degrees (90deg) or a multiple of pi "
            f"(pi/2, 0.5pi, -pi/4, 3pi/4), got {text!r}"
        )
    return value


def parse_float(text: str, option: str) -> float:
    """A finite float, or ValueError naming ``option``."""
    try:
        value = float(str(text).strip())
    except ValueError:
        raise ValueError(f"{option} expects a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{option} must be finite, got {text!r}")
    return value


@dataclass(frozen=True)
class ValueList:
    """A list option as given (``0,2,4`` or ``start:stop:count``), not yet expanded.

    Its length and extremes are known without building the list, so that a
    count past :data:`MAX_VALUES` is refused before any memory is spent.

    Attributes
    ----------
    option : str
        The option, for messages.
    text : str
        The text as given.
    count : int
        Number of values.
    low, high : float
        Smallest and largest value.
    """

    option: str
    text: str
    count: int
    low: float
    high: float

    def values(self, allow_large: bool = False) -> list[float]:
        """The values; CLIError naming ``--allow-large`` past :data:`MAX_VALUES`."""
        check_count(self.option, self.count, MAX_VALUES, allow_large, "values")
        return parse_values(self.text, self.option)


def check_count(option: str, count: float, limit: float, allow_large: bool, what: str) -> None:
    """CLIError naming ``option``, ``--allow-large`` and ``limit`` if ``count > limit``."""
    if count > limit and not allow_large:
        raise CLIError(
            option,
            f"{_amount(count)} {what} is more than the limit {_amount(limit)}; "
            "give --allow-large to run it anyway",
        )


def _amount(x: float) -> str:
    return str(int(x)) if float(x).is_integer() and abs(x) < 1e15 else f"{x:g}"


def _split_values(text: str, option: str) -> tuple[list[float] | None, float, float, int]:
    """``(items, start, stop, count)``: items for ``0,2,4``, None for a range."""
    s = str(text).strip()
    forms = "a list 0,2,4 or start:stop:count such as 0:6:13"
    if ":" in s:
        parts = s.split(":")
        if len(parts) != 3:
            raise ValueError(f"{option} expects {forms}, got {text!r}")
        try:
            start, stop = float(parts[0]), float(parts[1])
            count = int(parts[2])
        except ValueError:
            raise ValueError(f"{option} expects {forms} (count an integer), got {text!r}") from None
        if not (math.isfinite(start) and math.isfinite(stop)):
            raise ValueError(f"{option} range ends must be finite, got {text!r}")
        if count < 1:
            raise ValueError(f"{option} count must be >= 1, got {count}")
        if count == 1 and start != stop:
            raise ValueError(f"{option} count 1 needs start == stop, got {text!r}")
        return None, start, stop, count
    out = []
    for item in s.split(","):
        if not item.strip():
            raise ValueError(f"{option} expects {forms}; empty item in {text!r}")
        try:
            value = float(item)
        except ValueError:
            raise ValueError(
                f"{option} expects {forms}; {item.strip()!r} is not a number"
            ) from None
        if not math.isfinite(value):
            raise ValueError(f"{option} values must be finite, got {item.strip()!r}")
        out.append(value)
    return out, out[0], out[-1], len(out)


def parse_values(text: str, option: str) -> list[float]:
    """Parse a list of values: ``0,2,4``, ``3`` or ``start:stop:count``.

    ``start:stop:count`` gives ``count`` equally spaced values including both
    ends (``0:6:13`` is 0, 0.5, ..., 6), like ``numpy.linspace``.

    Raises
    ------
    ValueError
        Naming ``option`` and the allowed forms.
    """
    items, start, stop, count = _split_values(text, option)
    if items is not None:
        return items
    if count == 1:
        return [start]
    step = (stop - start) / (count - 1)
    # start + i*step, with the end hit exactly (no round-off past stop).
    return [start + i * step for i in range(count - 1)] + [stop]


def value_list(text: str, option: str) -> ValueList:
    """Check the form of a list option without expanding it (ValueError naming it)."""
    items, start, stop, count = _split_values(text, option)
    ends = items if items is not None else [start, stop]
    return ValueList(option, str(text), count, min(ends), max(ends))


def _check_v(x: float, option: str = "--v") -> float:
    """A dimensionless flow velocity in [0, :data:`V_MAX`] (ValueError naming ``option``)."""
    try:
        Params(v=x)
    except ParamError as exc:
        raise ValueError(f"{option}: {exc}") from None
    if x > V_MAX:
        raise ValueError(f"{option}: v = {x:g} is outside 0 <= v <= {V_MAX:g} ({_WHY_V})")
    return x


def check_gamma(x: float, option: str = "--gamma") -> float:
    """A gravity parameter in [0, :data:`GAMMA_MAX`] (ValueError naming ``option``)."""
    try:
        return _check_param("gamma", x, GAMMA_MAX, _WHY_GAMMA)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None


def _v_list(text: str) -> ValueList:
    values = value_list(text, "--v")
    _check_v(values.low)
    _check_v(values.high)
    return values


def _alpha(text: str) -> float:
    alpha = parse_alpha(text)
    if abs(alpha) > ALPHA_MAX:
        raise ValueError(
            f"--alpha {text!r} is outside -2pi <= alpha <= 2pi (alpha is an angle; "
            f"take it modulo 2pi)"
        )
    return alpha


def _check_param(field: str, x: float, high: float, why: str) -> float:
    """``x`` as dimensionless ``field``: Params' own check, then ``<= high`` (ValueError)."""
    try:
        Params(**{field: x})
    except ParamError as exc:
        raise ValueError(str(exc)) from None
    if x > high:
        raise ValueError(f"{field} = {x:g} is outside 0 <= {field} <= {high:g} ({why})")
    return x


def _param(field: str, high: float, why: str) -> Callable[[str], float]:
    """Parser of ``--field``: a finite number, checked by :func:`_check_param`."""
    option = f"--{field}"
    return lambda text: _check_param(field, parse_float(text, option), high, why)


def number_type(
    option: str,
    low: float | None = None,
    high: float | None = None,
    strict_low: bool = False,
) -> Callable[[str], float]:
    """argparse ``type=``: a finite number, ``> low`` (strict) or ``>= low``, ``<= high``."""

    def parse(text: str) -> float:
        x = parse_float(text, option)
        below = low is not None and (x < low or (strict_low and x == low))
        if below or (high is not None and x > high):
            lo = "" if low is None else f"{low:g} {'<' if strict_low else '<='} "
            hi = "" if high is None else f" <= {high:g}"
            raise ValueError(f"must satisfy {lo}{option}{hi}, got {x:g}")
        return x

    return option_type(option, parse)


def _workers(text: str) -> int:
    try:
        n = int(str(text))
    except ValueError:
        raise ValueError(f"expects an integer >= 1, got {text!r}") from None
    if n < 1:
        raise ValueError(f"expects an integer >= 1, got {n}")
    return n


#: argparse ``type=`` of ``--workers``: a whole number of local processes >= 1.
workers_type = option_type("--workers", _workers)


# ---------------------------------------------------------------------------
# Option groups
# ---------------------------------------------------------------------------


def add_physical_arguments(parser: argparse.ArgumentParser) -> None:
    """Dimensionless ``--alpha --beta --gamma --mu`` or SI ``--length --EI --m --M --g --a``.

    Each value is checked on its own by its ``type=``; the SI pipe as a whole
    by :func:`setup_from_args`.
    """
    g = parser.add_argument_group(
        "physical parameters",
        f"dimensionless (Eq. (19)); defaults are the paper's case beta={DEFAULT_BETA:g}, "
        f"gamma={DEFAULT_GAMMA:g}, mu={DEFAULT_MU:g}, alpha=0. Give SI values instead to have "
        "beta, gamma, mu computed. Accepted: gamma <= 2500 and v <= 50, where the clamp layer "
        "(width 1/sqrt(gamma)) and the bending waves of the flow (length 1/v) are as narrow as "
        "the node spacing 1/48 of the default mesh P3:16; mu <= 10 (every mode is overdamped "
        "from mu = 0.57 on).",
    )
    g.add_argument(
        "--alpha",
        metavar="A",
        type=option_type("--alpha", _alpha),
        default=None,
        help="inclination from the downward vertical, -2pi..2pi: radians (1.5708), degrees "
        "(90deg) or a multiple of pi (pi/2, 0.5pi, 3pi/4); negative values as --alpha=-pi/4 "
        "(default 0; pi stands up)",
    )
    g.add_argument(
        "--beta",
        metavar="B",
        type=option_type("--beta", _param("beta", 1.0, "a mass ratio")),
        default=None,
        help="mass ratio M/(m+M) in [0, 1]",
    )
    g.add_argument(
        "--gamma",
        metavar="G",
        type=option_type("--gamma", _param("gamma", GAMMA_MAX, _WHY_GAMMA)),
        default=None,
        help=f"gravity (m+M) g L^3/EI, 0..{GAMMA_MAX:g} (a standing pipe is --alpha pi, not "
        "gamma < 0)",
    )
    g.add_argument(
        "--mu",
        metavar="MU",
        type=option_type("--mu", _param("mu", MU_MAX, _WHY_MU)),
        default=None,
        help=f"Kelvin-Voigt damping, 0..{MU_MAX:g}",
    )
    si = parser.add_argument_group(
        "SI pipe (instead of --beta --gamma --mu)",
        "--length --EI --m --M are required together; the flow is then given by --U in m/s. "
        "The pipe's gamma and mu must lie in the ranges above.",
    )
    for opt, metavar, text in (
        ("--length", "L", "pipe length, m"),
        ("--EI", "EI", "bending stiffness, N m^2"),
        ("--m", "m", "pipe mass per length, kg/m"),
        ("--M", "M", "fluid mass per length, kg/m"),
        ("--g", "g", f"gravity, m/s^2 (default {DEFAULT_G:g})"),
        ("--a", "a", "Kelvin-Voigt retardation time, s (default 0)"),
    ):
        si.add_argument(opt, metavar=metavar, type=number_type(opt), default=None, help=text)


def add_flow_arguments(parser: argparse.ArgumentParser, default: str | None = "0:10:11") -> None:
    """``--v`` (dimensionless) or ``--U`` (m/s, with an SI pipe): lists or ranges.

    Parameters
    ----------
    default : str or None
        Default for ``--v`` (used when neither is given); None makes the flow
        optional (``Setup.v`` is then empty).
    """
    g = parser.add_argument_group("flow velocity")
    ex = g.add_mutually_exclusive_group()
    d = f" (default {default})" if default is not None else ""
    ex.add_argument(
        "--v",
        metavar="LIST",
        type=option_type("--v", _v_list),
        default=None,
        help=f"dimensionless flow velocities, 0..{V_MAX:g}: 0,2,4 or start:stop:count like "
        f"0:6:13{d}",
    )
    ex.add_argument(
        "--U",
        metavar="LIST",
        type=option_type("--U", lambda text: value_list(text, "--U")),
        default=None,
        help="flow velocities in m/s (needs the SI pipe; up to the U of v = "
        f"{V_MAX:g}): 0,0.5,1 or 0:3:7",
    )
    parser.set_defaults(_flow_default=default)


def add_discretization_arguments(parser: argparse.ArgumentParser) -> None:
    """``--fe Pk:n`` (default :data:`~fempipe.discretization.DEFAULT_FE`) or ``--modal N``,
    and ``--allow-large``."""
    g = parser.add_argument_group("discretisation and work limits")
    ex = g.add_mutually_exclusive_group()
    ex.add_argument(
        "--fe",
        metavar="Pk:n",
        type=option_type("--fe", _fe_size),
        default=None,
        help=f"Lagrange elements of degree k (1..10) on n uniform elements (default {DEFAULT_FE})",
    )
    ex.add_argument(
        "--modal",
        metavar="N",
        type=option_type("--modal", _modal_size),
        default=None,
        help="the paper's N sine modes sin((2r-1) pi xi/2) instead of finite elements",
    )
    g.add_argument(
        "--allow-large",
        action="store_true",
        help=f"accept more than {MAX_DOFS} unknowns (n k of Pk:n, N of --modal), lists of more "
        f"than {MAX_VALUES} values (or points of a map or sweep) and --t-max above {T_MAX:g}",
    )


def _fe_size(text: str) -> tuple[str, int]:
    """``(text, unknowns)`` of ``--fe Pk:n``, checked without building the mesh."""
    m = _FE_RE.match(str(text).strip())
    if not m or not 1 <= int(m.group(1)) <= 10 or int(m.group(2)) < 1:
        parse_discretization(fe=text)  # raises, with the library's message
        raise AssertionError(text)
    return str(text), int(m.group(1)) * int(m.group(2))


def _modal_size(text: str) -> tuple[str, int]:
    """``(text, unknowns)`` of ``--modal N``."""
    try:
        n = int(str(text))
    except ValueError:
        n = 0
    if n < 1:
        parse_discretization(modal=text)  # raises, with the library's message
        raise AssertionError(text)
    return str(text), n


def add_output_arguments(parser: argparse.ArgumentParser, out_help: str | None = None) -> None:
    """``--json``, ``--out DIR`` and ``--quiet`` / ``--progress``.

    Parameters
    ----------
    out_help : str, optional
        Help of ``--out`` (default: "write result files into DIR").
    """
    g = parser.add_argument_group("output")
    g.add_argument(
        "--json",
        action="store_true",
        help="print machine-readable JSON on stdout (and nothing else there)",
    )
    g.add_argument(
        "--out", metavar="DIR", default=None, help=out_help or "write result files into DIR"
    )
    ex = g.add_mutually_exclusive_group()
    ex.add_argument(
        "--progress",
        dest="progress",
        action="store_true",
        default=None,
        help="show a progress bar on stderr (default: when stderr is a terminal)",
    )
    ex.add_argument(
        "--quiet", dest="progress", action="store_false", help="no progress bar, no log output"
    )


# ---------------------------------------------------------------------------
# From parsed arguments to a validated problem
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Setup:
    """The validated problem behind a command line.

    Attributes
    ----------
    params : Params
        Dimensionless parameters; ``params.v`` is the first flow value (0 if none).
    pipe : PipeSI or None
        The SI pipe when SI input was given.
    v : list of float
        Dimensionless flow velocities (empty if the command has no flow list).
    disc : FiniteElement or Modal
    U : list of float or None
        The flow velocities in m/s as given by ``--U`` (or converted from ``--v``
        when the pipe is SI), else None.
    """

    params: Params
    pipe: PipeSI | None
    v: list[float]
    disc: object
    U: list[float] | None = None

    def to_dict(self) -> dict:
        """``params`` (with the ``pipe`` in SI when given) and ``discretization``."""
        p = self.params.to_dict()
        p.pop("v", None)
        out: dict = {"params": p, "discretization": self.disc.to_dict()}
        if self.pipe is not None:
            out["params"]["pipe_SI"] = self.pipe.to_dict()
            out["params"]["time_scale_s"] = self.pipe.time_scale
            out["params"]["velocity_scale_m_per_s"] = self.pipe.velocity_scale
        return out


def _given(args: argparse.Namespace, dest: str):
    return getattr(args, dest, None)


def allow_large(args: argparse.Namespace) -> bool:
    """Whether ``--allow-large`` was given."""
    return bool(getattr(args, "allow_large", False))


def setup_from_args(args: argparse.Namespace, need_flow: bool = True) -> Setup:
    """Turn parsed options into the validated :class:`Setup`.

    Parameters
    ----------
    args : argparse.Namespace
        From a parser with :func:`add_physical_arguments`,
        :func:`add_discretization_arguments` and optionally
        :func:`add_flow_arguments`.
    need_flow : bool
        If False a missing flow list is allowed even without a default.

    Returns
    -------
    Setup

    Raises
    ------
    CLIError
        Naming the offending option; the dispatcher prints it and exits 2.
    """
    alpha = _given(args, "alpha")
    alpha = 0.0 if alpha is None else alpha
    large = allow_large(args)

    # --- SI pipe or dimensionless groups ------------------------------
    si_given = [opt for opt in _SI_OPTIONS if _given(args, opt[2:]) is not None]
    pipe: PipeSI | None = None
    if si_given:
        missing = [opt for opt in _SI_REQUIRED if _given(args, opt[2:]) is None]
        if missing:
            raise CLIError(
                missing[0],
                f"the SI pipe needs {' '.join(_SI_REQUIRED)} together; missing {' '.join(missing)}",
            )
        for opt in ("--beta", "--gamma", "--mu"):
            if _given(args, opt[2:]) is not None:
                raise CLIError(
                    opt,
                    f"cannot be combined with the SI pipe ({si_given[0]}): "
                    "beta, gamma, mu follow from --length --EI --m --M --g --a",
                )
        kw = {f: _given(args, opt[2:]) for opt, f in _SI_OPTIONS.items()}
        kw = {f: x for f, x in kw.items() if x is not None}
        kw.setdefault("g", DEFAULT_G)
        try:
            pipe = PipeSI(alpha=alpha, **kw)
        except ParamError as exc:
            raise CLIError(_SI_FIELD_OPTION[exc.field], str(exc)) from None
        base = pipe.params(0.0)
        si = "--length --EI --m --M --g"
        if base.gamma > GAMMA_MAX:
            raise CLIError(
                si,
                f"the SI pipe has gamma = (m+M) g L^3/EI = {base.gamma:g}, outside "
                f"0 <= gamma <= {GAMMA_MAX:g} ({_WHY_GAMMA})",
            )
        if base.mu > MU_MAX:
            raise CLIError(
                "--a",
                f"the SI pipe has mu = sqrt(EI/(m+M)) a/L^2 = {base.mu:g}, outside "
                f"0 <= mu <= {MU_MAX:g} ({_WHY_MU})",
            )
    else:
        vals = {"alpha": alpha, "beta": DEFAULT_BETA, "gamma": DEFAULT_GAMMA, "mu": DEFAULT_MU}
        for name in ("beta", "gamma", "mu"):
            if _given(args, name) is not None:
                vals[name] = _given(args, name)
        try:
            base = Params(**vals)
        except ParamError as exc:
            raise CLIError(_DIMLESS_OPTION[exc.field], str(exc)) from None

    # --- flow ---------------------------------------------------------
    v_list: list[float] = []
    U_list: list[float] | None = None
    if _given(args, "U") is not None:
        if pipe is None:
            raise CLIError(
                "--U",
                "needs the SI pipe (--length --EI --m --M); use --v for dimensionless flow",
            )
        U_spec: ValueList = args.U
        U_max = pipe.U_of_v(V_MAX)
        for U in (U_spec.low, U_spec.high):
            try:
                v = pipe.v_of_U(U)
            except ParamError as exc:
                raise CLIError("--U", str(exc)) from None
            if v > V_MAX:
                raise CLIError(
                    "--U",
                    f"U = {U:g} m/s is outside 0 <= U <= {U_max:.6g} m/s, the U of "
                    f"v = {V_MAX:g} for this pipe ({_WHY_V})",
                )
        U_list = U_spec.values(large)
        v_list = [pipe.v_of_U(U) for U in U_list]
    else:
        spec = _given(args, "v")
        if spec is None and getattr(args, "_flow_default", None) is not None:
            spec = _v_list(args._flow_default)
        if spec is not None:
            v_list = spec.values(large)
        elif need_flow and hasattr(args, "_flow_default"):
            raise CLIError("--v", "give the flow velocities (--v or --U)")
        if pipe is not None and v_list:
            U_list = [pipe.U_of_v(v) for v in v_list]
    params = replace(base, v=v_list[0]) if v_list else base

    # --- discretisation -----------------------------------------------
    fe, modal = _given(args, "fe"), _given(args, "modal")
    option, (text, unknowns) = (
        ("--modal", modal) if modal is not None else ("--fe", fe or (None, 0))
    )
    check_count(option, unknowns, MAX_DOFS, large, "unknowns")
    try:
        disc = parse_discretization(
            fe=None if fe is None else fe[0], modal=None if modal is None else modal[0]
        )
    except ValueError as exc:
        raise CLIError(option, str(exc)) from None

    return Setup(params=params, pipe=pipe, v=v_list, disc=disc, U=U_list)


# ---------------------------------------------------------------------------
# Progress and output files
# ---------------------------------------------------------------------------


def progress(args: argparse.Namespace, total: int | None, desc: str):
    """A tqdm bar on stderr if ``--progress`` (or a terminal without ``--quiet``).

    Use as a context manager; call ``bar.update()`` from the library's
    progress callback.  A disabled bar does nothing.
    """
    from tqdm import tqdm

    show = getattr(args, "progress", None)
    if show is None:
        show = sys.stderr.isatty()
    return tqdm(
        total=total,
        desc=desc,
        file=sys.stderr,
        leave=False,
        dynamic_ncols=True,
        disable=not show,
    )


class Output:
    """The result files of one command in ``--out DIR``, recorded as they are written.

    Every file goes through one of the methods, which write atomically
    (:mod:`fempipe.io`) and record the path, so the "wrote ..." lines of
    :meth:`report` are exactly the files written.

    Parameters
    ----------
    directory : path-like
        The ``--out`` directory.
    """

    def __init__(self, directory) -> None:
        self.directory = Path(directory)
        self.written: list[Path] = []

    def path(self, name: str) -> Path:
        """The destination of ``name``; call :meth:`record` once it is written."""
        return self.directory / name

    def record(self, path) -> Path:
        """Record a path written by another writer (e.g. a GIF, a point store)."""
        path = Path(path)
        self.written.append(path)
        return path

    def json(self, name: str, obj) -> Path:
        from fempipe.io import write_json

        return self.record(write_json(self.path(name), obj))

    def csv(self, name: str, rows, columns=None) -> Path:
        from fempipe.io import write_csv

        return self.record(write_csv(self.path(name), rows, columns))

    def figure(self, name: str, fig, **savefig_kwargs) -> Path:
        from fempipe.io import write_figure

        return self.record(write_figure(self.path(name), fig, **savefig_kwargs))

    def report(self, args: argparse.Namespace) -> None:
        """``wrote PATH`` on stderr for each file, unless ``--json`` or ``--quiet``."""
        if getattr(args, "json", False) or getattr(args, "progress", None) is False:
            return
        for path in self.written:
            print(f"wrote {path}", file=sys.stderr)


def describe(result: dict, keys: Sequence[str] = ("alpha", "beta", "gamma", "mu")) -> tuple:
    """``(discretisation label, "alpha = ..., beta = ...")`` for a table heading.

    ``result`` is a subcommand's JSON dict with ``params`` and ``discretization``.
    """
    p, d = result["params"], result["discretization"]
    disc = f"P{d['degree']}:{d['n_elements']}" if d["kind"] == "fe" else f"modal:{d['n_modes']}"
    head = ", ".join(f"{k} = {p[k]:.6g}" for k in keys if k in p)
    return disc, head


def parse_alpha_list(text: str, option: str, allow_large: bool = False) -> list[float]:
    """A list of inclinations: ``0,pi/4,pi/2`` or ``start:stop:count`` in any
    :func:`parse_alpha` spelling (``0deg:180deg:7``); CLIError naming ``option``
    (also past :data:`MAX_VALUES` values without ``allow_large``)."""
    text = str(text)
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError(f"{option} expects start:stop:count, got {text!r}")
            start, stop = _alpha(parts[0]), _alpha(parts[1])
            spec = value_list(f"{start!r}:{stop!r}:{parts[2]}", option)
            return spec.values(allow_large)
        items = text.split(",")
        if any(not s.strip() for s in items):
            raise ValueError(f"{option} has an empty item in {text!r}")
        check_count(option, len(items), MAX_VALUES, allow_large, "values")
        return [_alpha(s) for s in items]
    except ValueError as exc:
        if isinstance(exc, CLIError):
            raise
        raise CLIError(option, str(exc).replace("--alpha ", f"{option} ")) from None

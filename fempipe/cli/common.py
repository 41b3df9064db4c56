"""The one option parser shared by every ``fempipe`` subcommand.

Every subcommand that solves the pipe takes the same physical parameters,
discretisation, flow values and output options; they are declared here once
so that the spellings (``--alpha 90deg``, ``--fe P3:16``, ``--v 0:6:13``,
``--U 0,0.5,1``) and the error messages are the same everywhere.

Physical parameters come either dimensionless (``--alpha --beta --gamma
--mu``, with ``--v`` for the flow) or in SI units (``--length --EI --m --M``,
all four together, plus optional ``--g --a``, with ``--U`` in m/s for the
flow), Eq. (19) of Chen, Hu, Dai & Wang (2020).

Bad input raises :class:`CLIError` naming the option; the dispatcher
(:func:`fempipe.cli.main`) prints it as one line
``fempipe <cmd>: error: --option: message`` on stderr and exits with code 2.

Typical use in a subcommand module::

    def add_arguments(parser):
        common.add_physical_arguments(parser)
        common.add_flow_arguments(parser, default="0:10:11")
        common.add_discretization_arguments(parser)
        common.add_output_arguments(parser)

    def run(args):
        setup = common.setup_from_args(args)   # raises CLIError on bad input
        params, pipe, v_values, disc = setup   # unpacks like a 4-tuple
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Iterator, Sequence
from dataclasses import dataclass, replace

from fempipe.discretization import DEFAULT_FE, parse_discretization
from fempipe.params import Params, PipeSI

__all__ = [
    "CLIError",
    "ArgumentParser",
    "Setup",
    "add_physical_arguments",
    "add_discretization_arguments",
    "add_flow_arguments",
    "add_output_arguments",
    "parse_alpha",
    "parse_values",
    "parse_float",
    "setup_from_args",
    "progress",
]

#: The paper's reference case (a silicone-rubber pipe of Paidoussis & Semler),
#: Section 5: the defaults of the dimensionless options.
DEFAULT_BETA = 0.142
DEFAULT_GAMMA = 18.9
DEFAULT_MU = 5e-3
DEFAULT_G = 9.81

#: SI option -> PipeSI field.
_SI_OPTIONS = {"--length": "L", "--EI": "EI", "--m": "m", "--M": "M", "--g": "g", "--a": "a"}
_SI_REQUIRED = ("--length", "--EI", "--m", "--M")
#: Params / PipeSI field -> the option that sets it, to name it in errors.
_DIMLESS_OPTION = {"alpha": "--alpha", "beta": "--beta", "gamma": "--gamma", "mu": "--mu"}
_SI_FIELD_OPTION = {field: opt for opt, field in _SI_OPTIONS.items()}


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
        self.exit(2, f"{self.prog}: error: {' '.join(message.split())}\n")


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


def parse_values(text: str, option: str) -> list[float]:
    """Parse a list of values: ``0,2,4``, ``3`` or ``start:stop:count``.

    ``start:stop:count`` gives ``count`` equally spaced values including both
    ends (``0:6:13`` is 0, 0.5, ..., 6), like ``numpy.linspace``.

    Raises
    ------
    ValueError
        Naming ``option`` and the allowed forms.
    """
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
        if count == 1:
            if start != stop:
                raise ValueError(f"{option} count 1 needs start == stop, got {text!r}")
            return [start]
        step = (stop - start) / (count - 1)
        # start + i*step, with the end hit exactly (no round-off past stop).
        return [start + i * step for i in range(count - 1)] + [stop]
    items = s.split(",")
    out = []
    for item in items:
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
    return out


# ---------------------------------------------------------------------------
# Option groups
# ---------------------------------------------------------------------------


def add_physical_arguments(parser: argparse.ArgumentParser) -> None:
    """Dimensionless ``--alpha --beta --gamma --mu`` or SI ``--length --EI --m --M --g --a``.

    Values are kept as text and parsed by :func:`setup_from_args`, so every
    error is reported the same way (one line naming the option).
    """
    g = parser.add_argument_group(
        "physical parameters",
        "dimensionless (Eq. (19)); defaults are the paper's case beta=0.142, gamma=18.9, "
        "mu=5e-3, alpha=0. Give SI values instead to have beta, gamma, mu computed.",
    )
    g.add_argument(
        "--alpha",
        metavar="A",
        default=None,
        help="inclination from the downward vertical: radians (1.5708), degrees (90deg) or a "
        "multiple of pi (pi/2, 0.5pi, 3pi/4); negative values as --alpha=-pi/4 (default 0)",
    )
    g.add_argument("--beta", metavar="B", default=None, help="mass ratio M/(m+M) in [0, 1]")
    g.add_argument("--gamma", metavar="G", default=None, help="gravity (m+M) g L^3/EI >= 0")
    g.add_argument("--mu", metavar="MU", default=None, help="Kelvin-Voigt damping >= 0")
    si = parser.add_argument_group(
        "SI pipe (instead of --beta --gamma --mu)",
        "--length --EI --m --M are required together; the flow is then given by --U in m/s",
    )
    si.add_argument("--length", metavar="L", default=None, help="pipe length, m")
    si.add_argument("--EI", metavar="EI", default=None, help="bending stiffness, N m^2")
    si.add_argument("--m", metavar="m", default=None, help="pipe mass per length, kg/m")
    si.add_argument("--M", metavar="M", default=None, help="fluid mass per length, kg/m")
    si.add_argument("--g", metavar="g", default=None, help="gravity, m/s^2 (default 9.81)")
    si.add_argument(
        "--a", metavar="a", default=None, help="Kelvin-Voigt retardation time, s (default 0)"
    )


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
        default=None,
        help=f"dimensionless flow velocities: 0,2,4 or start:stop:count like 0:6:13{d}",
    )
    ex.add_argument(
        "--U",
        metavar="LIST",
        default=None,
        help="flow velocities in m/s (needs the SI pipe): 0,0.5,1 or 0:3:7",
    )
    parser.set_defaults(_flow_default=default)


def add_discretization_arguments(parser: argparse.ArgumentParser) -> None:
    """``--fe Pk:n`` (default :data:`~fempipe.discretization.DEFAULT_FE`) or ``--modal N``."""
    g = parser.add_argument_group("discretisation")
    ex = g.add_mutually_exclusive_group()
    ex.add_argument(
        "--fe",
        metavar="Pk:n",
        default=None,
        help=f"Lagrange elements of degree k on n uniform elements (default {DEFAULT_FE})",
    )
    ex.add_argument(
        "--modal",
        metavar="N",
        default=None,
        help="the paper's N sine modes sin((2r-1) pi xi/2) instead of finite elements",
    )


def add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """``--json``, ``--out DIR`` and ``--quiet`` / ``--progress``."""
    g = parser.add_argument_group("output")
    g.add_argument(
        "--json",
        action="store_true",
        help="print machine-readable JSON on stdout (and nothing else there)",
    )
    g.add_argument("--out", metavar="DIR", default=None, help="write result files into DIR")
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

    Unpacks like ``params, pipe, v, disc = setup``.

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

    def __iter__(self) -> Iterator:
        return iter((self.params, self.pipe, self.v, self.disc))

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


def _given(args: argparse.Namespace, dest: str) -> str | None:
    return getattr(args, dest, None)


def setup_from_args(args: argparse.Namespace, need_flow: bool = True) -> Setup:
    """Turn parsed options into validated (Params, PipeSI | None, v list, disc).

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
    # --- alpha --------------------------------------------------------
    alpha = 0.0
    if _given(args, "alpha") is not None:
        try:
            alpha = parse_alpha(args.alpha)
        except ValueError as exc:
            raise CLIError("--alpha", str(exc)) from None

    # --- SI pipe or dimensionless groups ------------------------------
    si_given = [opt for opt, f in _SI_OPTIONS.items() if _given(args, opt[2:]) is not None]
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
        kw = {}
        for opt, field in _SI_OPTIONS.items():
            text = _given(args, opt[2:])
            if text is not None:
                try:
                    kw[field] = parse_float(text, opt)
                except ValueError as exc:
                    raise CLIError(opt, str(exc)) from None
        kw.setdefault("g", DEFAULT_G)
        try:
            pipe = PipeSI(alpha=alpha, **kw)
        except ValueError as exc:
            raise CLIError(_option_for(exc, _SI_FIELD_OPTION, "--length"), str(exc)) from None
        base = pipe.params(0.0)
    else:
        vals = {"alpha": alpha, "beta": DEFAULT_BETA, "gamma": DEFAULT_GAMMA, "mu": DEFAULT_MU}
        for name in ("beta", "gamma", "mu"):
            text = _given(args, name)
            if text is not None:
                try:
                    vals[name] = parse_float(text, f"--{name}")
                except ValueError as exc:
                    raise CLIError(f"--{name}", str(exc)) from None
        try:
            base = Params(**vals)
        except ValueError as exc:
            raise CLIError(_option_for(exc, _DIMLESS_OPTION, "--alpha"), str(exc)) from None

    # --- flow ---------------------------------------------------------
    v_list: list[float] = []
    U_list: list[float] | None = None
    if _given(args, "U") is not None:
        if pipe is None:
            raise CLIError(
                "--U",
                "needs the SI pipe (--length --EI --m --M); use --v for dimensionless flow",
            )
        try:
            U_list = parse_values(args.U, "--U")
            v_list = [pipe.v_of_U(U) for U in U_list]
        except ValueError as exc:
            raise CLIError("--U", str(exc)) from None
    else:
        text = _given(args, "v")
        if text is None:
            text = getattr(args, "_flow_default", None)
        if text is not None:
            try:
                v_list = parse_values(text, "--v")
            except ValueError as exc:
                raise CLIError("--v", str(exc)) from None
        elif need_flow and hasattr(args, "_flow_default"):
            raise CLIError("--v", "give the flow velocities (--v or --U)")
        if pipe is not None and v_list:
            try:
                U_list = [pipe.U_of_v(v) for v in v_list]
            except ValueError as exc:
                raise CLIError("--v", str(exc)) from None
    for v in v_list:
        try:
            replace(base, v=v)
        except ValueError as exc:
            opt = "--U" if _given(args, "U") is not None else "--v"
            raise CLIError(opt, str(exc)) from None
    params = replace(base, v=v_list[0]) if v_list else base

    # --- discretisation -----------------------------------------------
    fe, modal = _given(args, "fe"), _given(args, "modal")
    try:
        disc = parse_discretization(fe=fe, modal=modal)
    except ValueError as exc:
        raise CLIError("--modal" if modal is not None else "--fe", str(exc)) from None

    return Setup(params=params, pipe=pipe, v=v_list, disc=disc, U=U_list)


def _option_for(exc: ValueError, table: dict[str, str], fallback: str) -> str:
    """The option whose field name starts the validation message ("gamma must ...")."""
    first = str(exc).split(" ", 1)[0]
    return table.get(first, fallback)


# ---------------------------------------------------------------------------
# Progress
# ---------------------------------------------------------------------------


class _NoBar:
    def update(self, n: int = 1) -> None:
        pass

    def set_postfix_str(self, s: str) -> None:
        pass

    def close(self) -> None:
        pass

    def __enter__(self) -> _NoBar:
        return self

    def __exit__(self, *exc) -> None:
        pass


def progress(args: argparse.Namespace, total: int, desc: str):
    """A tqdm bar on stderr if ``--progress`` (or a terminal without ``--quiet``), else a no-op.

    Use as a context manager; call ``bar.update()`` from the library's
    progress callback.
    """
    show = getattr(args, "progress", None)
    if show is None:
        show = sys.stderr.isatty()
    if not show:
        return _NoBar()
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, file=sys.stderr, leave=False, dynamic_ncols=True)


def values_text(values: Sequence[float]) -> str:
    """Short human rendering of a value list for messages."""
    return ", ".join(f"{x:g}" for x in values)


def describe(result: dict, keys: Sequence[str] = ("alpha", "beta", "gamma", "mu")) -> tuple:
    """``(discretisation label, "alpha = ..., beta = ...")`` for a table heading.

    ``result`` is a subcommand's JSON dict with ``params`` and ``discretization``.
    """
    p, d = result["params"], result["discretization"]
    disc = f"P{d['degree']}:{d['n_elements']}" if d["kind"] == "fe" else f"modal:{d['n_modes']}"
    head = ", ".join(f"{k} = {p[k]:.6g}" for k in keys if k in p)
    return disc, head


def parse_workers(text) -> int:
    """``--workers N``: a whole number of local processes >= 1 (CLIError otherwise)."""
    try:
        n = int(str(text))
    except ValueError:
        raise CLIError("--workers", f"expects an integer >= 1, got {text!r}") from None
    if n < 1:
        raise CLIError("--workers", f"expects an integer >= 1, got {n}")
    return n


def parse_alpha_list(text: str, option: str) -> list[float]:
    """A list of inclinations: ``0,pi/4,pi/2`` or ``start:stop:count`` in any
    :func:`parse_alpha` spelling (``0deg:180deg:7``); CLIError naming ``option``."""
    text = str(text)
    try:
        if ":" in text:
            parts = text.split(":")
            if len(parts) != 3:
                raise ValueError(f"{option} expects start:stop:count, got {text!r}")
            start, stop = parse_alpha(parts[0]), parse_alpha(parts[1])
            return parse_values(f"{start!r}:{stop!r}:{parts[2]}", option)
        items = text.split(",")
        if any(not s.strip() for s in items):
            raise ValueError(f"{option} has an empty item in {text!r}")
        return [parse_alpha(s) for s in items]
    except ValueError as exc:
        raise CLIError(option, str(exc).replace("--alpha ", f"{option} ")) from None

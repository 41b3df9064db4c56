"""Parsers of option values, the accepted ranges and the work limits of ``fempipe``.

Each parser checks one option: it is an argparse ``type=`` callable (made by
:func:`option_type`, so that its error is the one-line usage error naming the
option) or a pure function raising ValueError naming the option.  What depends
on several options is checked by :func:`fempipe.cli.common.setup_from_args`,
which raises :class:`CLIError`.

Accepted ranges
---------------
The default discretization P3:16 has 48 unknowns, its nodes 1/48 apart.  The
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
"""

from __future__ import annotations

import argparse
import math
import re
from collections.abc import Callable
from dataclasses import dataclass

from fempipe.core.errors import ParamError
from fempipe.model.params import PAPER_CASE, Params, PipeSI

__all__ = [
    "ALPHA_MAX",
    "CLIError",
    "DEFAULT_BETA",
    "DEFAULT_G",
    "DEFAULT_GAMMA",
    "DEFAULT_MU",
    "GAMMA_MAX",
    "MAX_DOFS",
    "MAX_VALUES",
    "MU_MAX",
    "T_MAX",
    "V_MAX",
    "WHY_GAMMA",
    "WHY_MU",
    "WHY_V",
    "ValueList",
    "U_list_type",
    "allow_large",
    "alpha_type",
    "beta_type",
    "check_count",
    "check_U",
    "check_gamma",
    "check_param",
    "check_si_groups",
    "check_v",
    "fe_type",
    "gamma_type",
    "modal_type",
    "mu_type",
    "number_type",
    "option_type",
    "parse_alpha",
    "parse_alpha_list",
    "parse_float",
    "parse_values",
    "v_list_type",
    "value_list",
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

#: Why each range ends where it does (the end of the messages of a value outside it).
WHY_V = "the default mesh P3:16 resolves bending waves of length 1/v down to v = 50"
WHY_GAMMA = "the default mesh P3:16 resolves the clamp layer 1/sqrt(gamma) down to gamma = 2500"
WHY_MU = "every mode is overdamped from mu = 0.57 on"


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


def check_v(x: float, option: str = "--v") -> float:
    """A dimensionless flow velocity in [0, :data:`V_MAX`] (ValueError naming ``option``)."""
    try:
        Params(v=x)
    except ParamError as exc:
        raise ValueError(f"{option}: {exc}") from None
    if x > V_MAX:
        raise ValueError(f"{option}: v = {x:g} is outside 0 <= v <= {V_MAX:g} ({WHY_V})")
    return x


def check_gamma(x: float, option: str = "--gamma") -> float:
    """A gravity parameter in [0, :data:`GAMMA_MAX`] (ValueError naming ``option``)."""
    try:
        return check_param("gamma", x, GAMMA_MAX, WHY_GAMMA)
    except ValueError as exc:
        raise ValueError(f"{option}: {exc}") from None


def _v_list(text: str) -> ValueList:
    values = value_list(text, "--v")
    check_v(values.low)
    check_v(values.high)
    return values


def _alpha(text: str) -> float:
    alpha = parse_alpha(text)
    if abs(alpha) > ALPHA_MAX:
        raise ValueError(
            f"--alpha {text!r} is outside -2pi <= alpha <= 2pi (alpha is an angle; "
            f"take it modulo 2pi)"
        )
    return alpha


def check_param(field: str, x: float, high: float, why: str) -> float:
    """``x`` as dimensionless ``field``: Params' own check, then ``<= high`` (ValueError)."""
    try:
        Params(**{field: x})
    except ParamError as exc:
        raise ValueError(str(exc)) from None
    if x > high:
        raise ValueError(f"{field} = {x:g} is outside 0 <= {field} <= {high:g} ({why})")
    return x


def _param(field: str, high: float, why: str) -> Callable[[str], float]:
    """Parser of ``--field``: a finite number, checked by :func:`check_param`."""
    option = f"--{field}"
    return lambda text: check_param(field, parse_float(text, option), high, why)


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


def positive_int(text: str) -> int:
    """An integer >= 1 (``--workers``, ``--mode``)."""
    try:
        n = int(str(text))
    except ValueError:
        raise ValueError(f"expects an integer >= 1, got {text!r}") from None
    if n < 1:
        raise ValueError(f"expects an integer >= 1, got {n}")
    return n


# argparse ``type=`` callables of the options shared by the subcommands.
workers_type = option_type("--workers", positive_int)
alpha_type = option_type("--alpha", _alpha)
beta_type = option_type("--beta", _param("beta", 1.0, "a mass ratio"))
gamma_type = option_type("--gamma", _param("gamma", GAMMA_MAX, WHY_GAMMA))
mu_type = option_type("--mu", _param("mu", MU_MAX, WHY_MU))
v_list_type = option_type("--v", _v_list)
U_list_type = option_type("--U", lambda text: value_list(text, "--U"))


def check_si_groups(params: Params) -> None:
    """CLIError if the SI pipe's gamma or mu (Eq. (19)) is outside the accepted range."""
    if params.gamma > GAMMA_MAX:
        raise CLIError(
            "--length --EI --m --M --g",
            f"the SI pipe has gamma = (m+M) g L^3/EI = {params.gamma:g}, outside "
            f"0 <= gamma <= {GAMMA_MAX:g} ({WHY_GAMMA})",
        )
    if params.mu > MU_MAX:
        raise CLIError(
            "--a",
            f"the SI pipe has mu = sqrt(EI/(m+M)) a/L^2 = {params.mu:g}, outside "
            f"0 <= mu <= {MU_MAX:g} ({WHY_MU})",
        )


def check_U(pipe: PipeSI, spec: ValueList) -> None:
    """CLIError unless every U of ``spec`` gives 0 <= v <= :data:`V_MAX` for ``pipe``."""
    for U in (spec.low, spec.high):
        try:
            v = pipe.v_of_U(U)
        except ParamError as exc:
            raise CLIError("--U", str(exc)) from None
        if v > V_MAX:
            raise CLIError(
                "--U",
                f"U = {U:g} m/s is outside 0 <= U <= {pipe.U_of_v(V_MAX):.6g} m/s, the U of "
                f"v = {V_MAX:g} for this pipe ({WHY_V})",
            )


def _fe_size(text: str) -> tuple[str, int]:
    """``(text, unknowns)`` of ``--fe Pk:n``, checked without building the mesh."""
    from fempipe.model.discretization import parse_fe_spec

    degree, n_el = parse_fe_spec(text)  # ValueError with the library's message
    return str(text), degree * n_el


def _modal_size(text: str) -> tuple[str, int]:
    """``(text, unknowns)`` of ``--modal N``."""
    from fempipe.model.discretization import parse_discretization

    try:
        n = int(str(text))
    except ValueError:
        n = 0
    if n < 1:
        parse_discretization(modal=text)  # raises, with the library's message
        raise AssertionError(text)
    return str(text), n


fe_type = option_type("--fe", _fe_size)
modal_type = option_type("--modal", _modal_size)


def allow_large(args: argparse.Namespace) -> bool:
    """Whether ``--allow-large`` was given."""
    return bool(getattr(args, "allow_large", False))


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


#: Ranges of the variant options.  Gamma_e <= 100: a tip mass a hundred times
#: the pipe's is a pendulum on a massless spring, far outside the model's
#: purpose; sigma <= 100 and kappa <= 1e5 (a spring that stiff pins the pipe:
#: its first frequency is then within 1e-3 of the pinned one); mu_h <= 1 (loss
#: factors of real materials are below 0.3).
END_MASS_MAX = 100.0
EXTERNAL_DAMPING_MAX = 100.0
HYSTERETIC_MAX = 1.0
SPRING_MAX = 1e5


def _spring(text: str) -> tuple[float, float]:
    """``KAPPA@XI_S`` of ``--spring``."""
    kappa_text, sep, xi_text = str(text).partition("@")
    if not sep:
        raise ValueError(f"expects KAPPA@XI_S, e.g. 50@0.5, got {text!r}")
    kappa = parse_float(kappa_text, "--spring")
    xi_s = parse_float(xi_text, "--spring")
    if not 0.0 <= kappa <= SPRING_MAX:
        raise ValueError(f"stiffness kappa = {kappa:g} is outside 0 <= kappa <= {SPRING_MAX:g}")
    if not 0.0 < xi_s <= 1.0:
        raise ValueError(f"position xi_s = {xi_s:g} is outside 0 < xi_s <= 1")
    return (kappa, xi_s)


spring_type = option_type("--spring", _spring)

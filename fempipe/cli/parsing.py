"""Parsers of option values, the work limits of ``fempipe`` and :class:`CLIError`.

The accepted ranges are those of :mod:`fempipe.io.ranges`; more than :data:`MAX_VALUES` values,
:data:`MAX_DOFS` unknowns or ``--t-max`` above :data:`T_MAX` need ``--allow-large``, so that a
typing slip does not start hours of work (docs/cli/options.md, "Work limits").
"""

from __future__ import annotations

import argparse
import math
from collections.abc import Callable
from dataclasses import dataclass

from fempipe.core.errors import ParamError
from fempipe.io import ranges
from fempipe.io.ranges import check_alpha, check_v, parse_alpha, parse_float
from fempipe.model.params import PipeSI

__all__ = [
    "MAX_DOFS",
    "MAX_VALUES",
    "T_MAX",
    "CLIError",
    "ValueList",
    "allow_large",
    "check_U",
    "check_count",
    "number_type",
    "option_type",
    "parse_band",
    "parse_alpha_list",
    "parse_names",
    "parse_values",
    "positive_int",
    "value_list",
]

MAX_VALUES = 1000
MAX_DOFS = 1000
T_MAX = 1e4
#: Ranges of the variants of the pipe: an end mass a hundred times the pipe's is a pendulum
#: on a massless spring; a spring of 1e5 pins the pipe; loss factors of materials are < 0.3.
END_MASS_MAX = 100.0
EXTERNAL_DAMPING_MAX = 100.0
HYSTERETIC_MAX = 1.0
SPRING_MAX = 1e5


class CLIError(ValueError):
    """Bad command-line input; ``str()`` is the one-line message ``option: message``."""

    def __init__(self, option: str, message: str) -> None:
        message = " ".join(str(message).split())
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


@dataclass(frozen=True)
class ValueList:
    """A list option as given (``0,2,4`` or ``start:stop:count``), count known before expansion."""

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


def _split_values(text: str, option: str, number=None) -> tuple[list | None, float, float, int]:
    """``(items, start, stop, count)``: items for ``0,2,4``, None for a range."""
    s = str(text).strip()
    forms = "a list 0,2,4 or start:stop:count such as 0:6:13"

    def finite(item: str) -> float:
        try:
            value = float(item)
        except ValueError:
            raise ValueError(
                f"{option} expects {forms}; {item.strip()!r} is not a number"
            ) from None
        if not math.isfinite(value):
            raise ValueError(f"{option} values must be finite, got {item.strip()!r}")
        return value

    number = number or finite
    if ":" in s:
        parts = s.split(":")
        if len(parts) != 3:
            raise ValueError(f"{option} expects {forms}, got {text!r}")
        try:
            count = int(parts[2])
        except ValueError:
            raise ValueError(f"{option} expects {forms} (count an integer), got {text!r}") from None
        start, stop = number(parts[0]), number(parts[1])
        if count < 1:
            raise ValueError(f"{option} count must be >= 1, got {count}")
        if count == 1 and start != stop:
            raise ValueError(f"{option} count 1 needs start == stop, got {text!r}")
        return None, start, stop, count
    items = s.split(",")
    if any(not item.strip() for item in items):
        raise ValueError(f"{option} expects {forms}; empty item in {text!r}")
    out = [number(item) for item in items]
    return out, out[0], out[-1], len(out)


def _expand(items: list | None, start: float, stop: float, count: int) -> list[float]:
    """The values of :func:`_split_values`: a range like ``numpy.linspace``, stop hit exactly."""
    if items is not None:
        return items
    if count == 1:
        return [start]
    step = (stop - start) / (count - 1)
    return [start + i * step for i in range(count - 1)] + [stop]


def parse_values(text: str, option: str) -> list[float]:
    """``0,2,4``, ``3`` or ``start:stop:count`` (``count`` values from start to stop, both
    included); ValueError naming ``option``."""
    return _expand(*_split_values(text, option))


def value_list(text: str, option: str) -> ValueList:
    """The form of a list option checked without expanding it (ValueError naming it)."""
    items, start, stop, count = _split_values(text, option)
    ends = items if items is not None else [start, stop]
    return ValueList(option, str(text), count, min(ends), max(ends))


def number_type(
    option: str, low: float | None = None, high: float | None = None, strict_low: bool = False
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


def parse_band(text: str) -> tuple[float, float]:
    """``A:B``, a band of pulsation frequencies 0 < A < B (ValueError otherwise)."""
    parts = str(text).split(":")
    try:
        lo, hi = (float(x) for x in parts)
    except ValueError:
        raise ValueError(f"expects A:B with 0 < A < B, got {text!r}") from None
    if not 0 < lo < hi <= ranges.OMEGA_MAX:
        raise ValueError(f"expects A:B with 0 < A < B <= {ranges.OMEGA_MAX:g}, got {text!r}")
    return lo, hi


def _group(field: str) -> Callable[[str], float]:
    """``--beta``, ``--gamma``, ``--mu``: a finite number in the group's range."""
    return option_type(
        f"--{field}", lambda t: ranges.check_param(field, parse_float(t, f"--{field}"))
    )


def _v_list(text: str) -> ValueList:
    values = value_list(text, "--v")
    check_v(values.low)
    check_v(values.high)
    return values


def _fe_size(text: str) -> tuple[str, int]:
    """``(text, unknowns)`` of ``--fe Pk:n``, checked without building the mesh."""
    from fempipe.model.discretization import parse_fe_spec  # numpy: not for `fempipe --help`

    degree, n_el = parse_fe_spec(text)
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


def _spring(text: str) -> tuple[float, float]:
    """``KAPPA@XI_S`` of ``--spring``."""
    kappa_text, sep, xi_text = str(text).partition("@")
    if not sep:
        raise ValueError(f"expects KAPPA@XI_S, e.g. 50@0.5, got {text!r}")
    kappa, xi_s = parse_float(kappa_text, "--spring"), parse_float(xi_text, "--spring")
    if not 0.0 <= kappa <= SPRING_MAX:
        raise ValueError(f"stiffness kappa = {kappa:g} is outside 0 <= kappa <= {SPRING_MAX:g}")
    if not 0.0 < xi_s <= 1.0:
        raise ValueError(f"position xi_s = {xi_s:g} is outside 0 < xi_s <= 1")
    return (kappa, xi_s)


# argparse ``type=`` callables of the shared options.
workers_type = option_type("--workers", positive_int)
alpha_type = option_type("--alpha", lambda t: check_alpha(parse_alpha(t), t))
beta_type, gamma_type, mu_type = _group("beta"), _group("gamma"), _group("mu")
v_list_type = option_type("--v", _v_list)
U_list_type = option_type("--U", lambda text: value_list(text, "--U"))
fe_type = option_type("--fe", _fe_size)
modal_type = option_type("--modal", _modal_size)
spring_type = option_type("--spring", _spring)


def allow_large(args: argparse.Namespace) -> bool:
    """Whether ``--allow-large`` was given."""
    return bool(getattr(args, "allow_large", False))


def check_U(pipe: PipeSI, spec: ValueList) -> None:
    """CLIError unless every U of ``spec`` gives 0 <= v <= V_MAX for ``pipe``."""
    for U in (spec.low, spec.high):
        try:
            ranges.v_of_U(pipe, U)
        except ParamError as exc:
            raise CLIError("--U", str(exc)) from None


def parse_names(option: str, given: list[str] | None, known, what: str) -> list[str] | None:
    """The names of a repeatable, comma-separated ``option`` (None if not given), checked."""
    if not given:
        return None
    names = [n.strip() for item in given for n in item.split(",") if n.strip()]
    unknown = [n for n in names if n not in known]
    if unknown:
        raise CLIError(option, f"unknown {what} {unknown[0]!r}; known: {', '.join(known)}")
    return names


def parse_alpha_list(text: str, option: str, allow_large: bool = False) -> list[float]:
    """Inclinations ``0,pi/4,pi/2`` or ``start:stop:count`` in any ``--alpha`` spelling
    (``0deg:180deg:7``); CLIError naming ``option`` (also past :data:`MAX_VALUES`)."""
    try:
        split = _split_values(text, option, lambda s: check_alpha(parse_alpha(s), s))
        check_count(option, split[3], MAX_VALUES, allow_large, "values")
        return _expand(*split)
    except CLIError:
        raise
    except ValueError as exc:
        raise CLIError(option, str(exc).replace("--alpha ", f"{option} ")) from None

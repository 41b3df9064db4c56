"""The accepted input: defaults, ranges and the checks of one value (command line, cases files).

v <= 50 and gamma <= 2500 so that P3:16 resolves the clamp layer and the bending waves; mu <= 10
(overdamped from 0.57).  Why: docs/cli/options.md, "Accepted ranges".
"""

from __future__ import annotations

import math
import re

from fempipe.core.errors import ParamError
from fempipe.model.params import PAPER_CASE, Params, PipeSI

__all__ = [
    "ALPHA_MAX",
    "DEFAULT_BETA",
    "DEFAULT_G",
    "DEFAULT_GAMMA",
    "DEFAULT_MU",
    "GAMMA_MAX",
    "MU_MAX",
    "OMEGA_MAX",
    "V_MAX",
    "check_alpha",
    "check_param",
    "check_pipe",
    "check_pulsation",
    "check_v",
    "parse_alpha",
    "parse_float",
    "v_of_U",
]

#: Defaults of the dimensionless groups: the paper's case.
DEFAULT_BETA = PAPER_CASE["beta"]
DEFAULT_GAMMA = PAPER_CASE["gamma"]
DEFAULT_MU = PAPER_CASE["mu"]
DEFAULT_G = 9.81

V_MAX = 50.0
GAMMA_MAX = V_MAX**2
MU_MAX = 10.0
ALPHA_MAX = 2 * math.pi
#: The largest pulsation frequency searched (``--omega``, a cases file's omega_max), per unit tau.
OMEGA_MAX = 1e4

#: Why each range ends where it does (the end of the message of a value outside it).
WHY = {
    "v": "the default mesh P3:16 resolves bending waves of length 1/v down to v = 50",
    "gamma": "the default mesh P3:16 resolves the clamp layer 1/sqrt(gamma) down to gamma = 2500",
    "mu": "every mode is overdamped from mu = 0.57 on",
    "beta": "a mass ratio",
}
HIGH = {"v": V_MAX, "gamma": GAMMA_MAX, "mu": MU_MAX, "beta": 1.0}

_NUMBER = r"(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?"
_PI_RE = re.compile(rf"^([+-]?)\s*({_NUMBER})?\s*\*?\s*(?:pi|π)\s*(?:/\s*({_NUMBER}))?$")
_DEG_RE = re.compile(rf"^([+-]?\s*{_NUMBER})\s*(?:deg|degrees?|°)$")
_RAD_RE = re.compile(rf"^([+-]?\s*{_NUMBER})\s*(?:rad)?$")


def parse_alpha(text: str) -> float:
    """An inclination in radians from ``1.5708``, ``1.5708rad``, ``90deg``, ``-45°``, ``pi/2``,
    ``0.5pi``, ``3*pi/4``; ValueError naming ``--alpha`` and these forms otherwise."""
    s = str(text).strip().lower()
    value: float | None = None
    if m := _PI_RE.match(s):
        num = float(m.group(2)) if m.group(2) else 1.0
        den = float(m.group(3)) if m.group(3) else 1.0
        if den != 0.0:
            value = (-1.0 if m.group(1) == "-" else 1.0) * num * math.pi / den
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


def check_alpha(alpha: float, text: str, option: str = "--alpha") -> float:
    """``alpha`` if -2 pi <= alpha <= 2 pi, else ValueError quoting ``text``."""
    if abs(alpha) > ALPHA_MAX:
        raise ValueError(
            f"{option} {text!r} is outside -2pi <= alpha <= 2pi (alpha is an angle; "
            "take it modulo 2pi)"
        )
    return alpha


def parse_float(text: str, option: str) -> float:
    """A finite float, or ValueError naming ``option``."""
    try:
        value = float(str(text).strip())
    except ValueError:
        raise ValueError(f"{option} expects a number, got {text!r}") from None
    if not math.isfinite(value):
        raise ValueError(f"{option} must be finite, got {text!r}")
    return value


def check_param(field: str, x: float) -> float:
    """``x`` as the group ``field`` (beta, gamma, mu, v): Params' own check, then its range."""
    Params(**{field: x})  # ParamError naming the field
    if x > HIGH[field]:
        raise ParamError(
            field, f"{field} = {x:g} is outside 0 <= {field} <= {HIGH[field]:g} ({WHY[field]})"
        )
    return x


def check_v(x: float, option: str = "--v") -> float:
    """A flow velocity in [0, :data:`V_MAX`]; ValueError prefixed by ``option``."""
    try:
        return check_param("v", x)
    except ParamError as exc:
        raise ValueError(f"{option}: {exc}") from None


def check_pulsation(field: str, x: float) -> float:
    """``x`` as ``omega_min``, ``omega_max`` (0 < omega <= :data:`OMEGA_MAX`) or ``sigma_max``
    (0 < sigma <= 1: the pulsating flow v0 (1 + sigma sin(omega tau)) never reverses); else
    ParamError naming ``field``."""
    high = 1.0 if field == "sigma_max" else OMEGA_MAX
    if not 0.0 < x <= high:
        raise ParamError(field, f"{field} = {x:g} is outside 0 < {field} <= {high:g}")
    return x


def check_pipe(params: Params) -> Params:
    """``params`` of an SI pipe if its gamma and mu lie in their ranges, else ParamError."""
    for field, formula in (("gamma", "(m+M) g L^3/EI"), ("mu", "sqrt(EI/(m+M)) a/L^2")):
        x = getattr(params, field)
        if x > HIGH[field]:
            raise ParamError(
                field,
                f"the pipe has {field} = {formula} = {x:g}, outside 0 <= {field} <= "
                f"{HIGH[field]:g} ({WHY[field]})",
            )
    return params


def v_of_U(pipe: PipeSI, U: float) -> float:
    """The v of the flow ``U`` (m/s) if 0 <= v <= :data:`V_MAX` (ParamError on ``U`` otherwise)."""
    v = pipe.v_of_U(U)
    if v > V_MAX:
        raise ParamError(
            "U",
            f"U = {U:g} m/s is outside 0 <= U <= {pipe.U_of_v(V_MAX):.6g} m/s, the U of "
            f"v = {V_MAX:g} for this pipe ({WHY['v']})",
        )
    return v

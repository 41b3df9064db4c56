"""Physical parameters of the soft pipe conveying fluid.

:class:`Params` holds the dimensionless groups of Eq. (19) (``alpha``, ``beta``, ``gamma``,
``mu``, ``v``) and the variants'; :class:`PipeSI` a dimensional pipe, converted both ways.
Invalid values raise :class:`~fempipe.core.errors.ParamError` naming the ``field``.
Conventions: docs/theory/conventions.md; variants: docs/theory/variants.md.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, replace

from fempipe.core.errors import ParamError

__all__ = ["PAPER_CASE", "VARIANT_FIELDS", "Params", "PipeSI"]

#: The fields of :class:`Params` that pose the classical variants of the pipe
#: (end mass, external and hysteretic damping, intermediate springs); all zero
#: (or empty) is the paper's pipe.
VARIANT_FIELDS = ("end_mass", "external_damping", "hysteretic_damping", "springs")

#: The paper's reference case (Chen et al. 2020, Secs. 4-5): mass ratio,
#: gravity parameter and Kelvin--Voigt damping.  Stated here once; the
#: defaults of :class:`Params` and every "paper's case" elsewhere use it.
PAPER_CASE: dict[str, float] = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3}


def _check_finite(name: str, value: float) -> float:
    try:
        value = float(value)
    except (TypeError, ValueError, OverflowError):
        raise ParamError(name, f"{name} must be a real number, got {value!r}") from None
    if not math.isfinite(value):
        raise ParamError(name, f"{name} must be finite, got {value}")
    return value


@dataclass(frozen=True)
class Params:
    """Dimensionless parameters of the pipe and its variants, validated on construction.

    Parameters
    ----------
    alpha : float
        Inclination from the downward vertical, rad (0 hangs, pi stands).
    beta : float
        Mass ratio M/(m+M), in [0, 1].
    gamma : float
        Gravity parameter (m+M) g L^3 / EI >= 0.
    mu : float
        Kelvin--Voigt damping sqrt(EI/(m+M)) a / L^2 >= 0.
    v : float
        Flow velocity sqrt(M/EI) U L >= 0.
    end_mass : float
        Point mass at the free end, Gamma = M_e / ((m+M) L) >= 0 (no fluid in it).
    external_damping : float
        sigma = c L^2 / sqrt(EI (m+M)) >= 0 for a force -c r_dot per unit length.
    hysteretic_damping : float
        Loss factor mu_h >= 0, EI -> EI (1 + i mu_h sgn(omega)); linear stability only.
    springs : tuple of (kappa, xi_s)
        Isotropic springs tying xi_s in (0, 1] to its undeformed position, kappa = k L^3 / EI.
    """

    alpha: float = 0.0
    beta: float = PAPER_CASE["beta"]
    gamma: float = PAPER_CASE["gamma"]
    mu: float = PAPER_CASE["mu"]
    v: float = 0.0
    end_mass: float = 0.0
    external_damping: float = 0.0
    hysteretic_damping: float = 0.0
    springs: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        for name in ("alpha", "beta", "gamma", "mu", "v") + VARIANT_FIELDS[:3]:
            object.__setattr__(self, name, _check_finite(name, getattr(self, name)))
        for name in VARIANT_FIELDS[:3]:
            if getattr(self, name) < 0.0:
                raise ParamError(name, f"{name} must be >= 0, got {getattr(self, name)}")
        springs = []
        for item in self.springs:
            try:
                kappa, xi_s = item
            except (TypeError, ValueError):
                raise ParamError(
                    "springs", f"each spring is a pair (kappa, xi_s), got {item!r}"
                ) from None
            kappa = _check_finite("springs", kappa)
            xi_s = _check_finite("springs", xi_s)
            if kappa < 0.0:
                raise ParamError("springs", f"spring stiffness kappa must be >= 0, got {kappa}")
            if not 0.0 < xi_s <= 1.0:
                raise ParamError("springs", f"spring position xi_s must be in (0, 1], got {xi_s}")
            springs.append((kappa, xi_s))
        object.__setattr__(self, "springs", tuple(springs))
        if not 0.0 <= self.beta <= 1.0:
            raise ParamError("beta", f"beta must satisfy 0 <= beta <= 1, got {self.beta}")
        if self.gamma < 0.0:
            # Eq. (19): gamma = (m+M) g L^3/EI is a magnitude.  Gravity along
            # the pipe's axis is set by alpha: Eq. (20) is unchanged under
            # (alpha, gamma) -> (alpha + pi, -gamma).
            raise ParamError(
                "gamma",
                f"gamma must be >= 0, got {self.gamma}; a pipe standing up is alpha = pi "
                "with gamma > 0",
            )
        if self.mu < 0.0:
            raise ParamError("mu", f"mu must be >= 0, got {self.mu}")
        if self.v < 0.0:
            raise ParamError(
                "v", f"v must be >= 0 (the model assumes discharge at the free end), got {self.v}"
            )

    def with_flow(self, v: float) -> Params:
        """Return a copy with flow velocity ``v``."""
        return replace(self, v=v)

    def to_dict(self) -> dict:
        d = asdict(self)
        d["springs"] = [list(s) for s in self.springs]
        return d


@dataclass(frozen=True)
class PipeSI:
    """A dimensional pipe, in SI units.

    Parameters
    ----------
    L, EI : float
        Length (m) and bending stiffness (N m^2), > 0.
    m, M : float
        Pipe and fluid mass per unit length (kg/m), >= 0, m + M > 0.
    g : float
        Gravitational acceleration (m/s^2), >= 0.
    a : float
        Kelvin--Voigt retardation time (s), >= 0, Eq. (18).
    alpha : float
        Inclination from the downward vertical, rad.
    """

    L: float
    EI: float
    m: float
    M: float
    g: float = 9.81
    a: float = 0.0
    alpha: float = 0.0

    def __post_init__(self) -> None:
        for name in ("L", "EI", "m", "M", "g", "a", "alpha"):
            object.__setattr__(self, name, _check_finite(name, getattr(self, name)))
        if self.L <= 0:
            raise ParamError("L", f"L (length) must be > 0 m, got {self.L}")
        if self.EI <= 0:
            raise ParamError("EI", f"EI must be > 0 N m^2, got {self.EI}")
        if self.m < 0:
            raise ParamError("m", f"m (pipe mass per length) must be >= 0 kg/m, got {self.m}")
        if self.M < 0:
            raise ParamError("M", f"M (fluid mass per length) must be >= 0 kg/m, got {self.M}")
        if self.m + self.M <= 0:
            raise ParamError("m", "m + M must be > 0 kg/m")
        if self.g < 0:
            raise ParamError("g", f"g must be >= 0 m/s^2, got {self.g}")
        if self.a < 0:
            raise ParamError("a", f"a (Kelvin-Voigt coefficient) must be >= 0 s, got {self.a}")
        # The dimensionless groups of Eq. (19) must exist as floats: L^3 or
        # 1/EI can overflow for absurd input.
        for group, (value, field) in self._groups().items():
            if not math.isfinite(value):
                raise ParamError(
                    field,
                    f"{group} of Eq. (19) overflows for L = {self.L:g} m, EI = {self.EI:g} N m^2, "
                    f"m = {self.m:g} kg/m, M = {self.M:g} kg/m, g = {self.g:g} m/s^2, "
                    f"a = {self.a:g} s",
                )

    def _groups(self) -> dict[str, tuple[float, str]]:
        """beta, gamma, mu of Eq. (19), each with the field named if it overflows."""
        mt = self.m + self.M
        try:
            gamma = mt * self.g * self.L**3 / self.EI
        except OverflowError:  # L**3 of a float raises instead of giving inf
            gamma = math.inf
        try:
            mu = math.sqrt(self.EI / mt) * self.a / self.L**2
        except (OverflowError, ZeroDivisionError):  # L**2 overflows or underflows to 0
            mu = math.inf
        return {"beta": (self.M / mt, "M"), "gamma": (gamma, "EI"), "mu": (mu, "a")}

    @property
    def time_scale(self) -> float:
        """Seconds per unit of tau: L^2 sqrt((m+M)/EI)."""
        return self.L**2 * math.sqrt((self.m + self.M) / self.EI)

    @property
    def velocity_scale(self) -> float:
        """m/s per unit of v: sqrt(EI/M) / L (infinite if M = 0)."""
        if self.M == 0:
            return math.inf
        return math.sqrt(self.EI / self.M) / self.L

    def v_of_U(self, U: float) -> float:
        """Dimensionless flow velocity v = sqrt(M/EI) U L."""
        U = _check_finite("U", U)
        if U < 0:
            raise ParamError("U", f"U must be >= 0 m/s, got {U}")
        v = math.sqrt(self.M / self.EI) * U * self.L
        if not math.isfinite(v):
            raise ParamError("U", f"v = sqrt(M/EI) U L overflows for U = {U:g} m/s")
        return v

    def U_of_v(self, v: float) -> float:
        """Flow velocity in m/s for dimensionless ``v``."""
        return v * self.velocity_scale if v else 0.0

    def end_mass_ratio(self, M_e: float) -> float:
        """Gamma = M_e / ((m+M) L) of an end mass ``M_e`` in kg."""
        M_e = _check_finite("end_mass", M_e)
        if M_e < 0:
            raise ParamError("end_mass", f"the end mass must be >= 0 kg, got {M_e}")
        return M_e / ((self.m + self.M) * self.L)

    def params(self, U: float = 0.0) -> Params:
        """Dimensionless :class:`Params` at flow velocity ``U`` (m/s), Eq. (19)."""
        g = self._groups()
        return Params(
            alpha=self.alpha,
            beta=g["beta"][0],
            gamma=g["gamma"][0],
            mu=g["mu"][0],
            v=self.v_of_U(U),
        )

    def to_dict(self) -> dict[str, float]:
        return asdict(self)

"""The straight cantilevered pipe of the classical linear theory (fempipe.validation.classical)."""

from __future__ import annotations

import math
from dataclasses import dataclass


@dataclass(frozen=True)
class StraightPipe:
    """A straight cantilevered pipe: the parameters of the classical equation.

    Parameters
    ----------
    beta, gamma : float
        Mass ratio M/(m+M); gravity parameter (m+M) g L^3/EI >= 0.
    standing : bool
        False: hanging (alpha = 0); True: standing (alpha = pi, compressed).
    mu : float
        Kelvin-Voigt damping (Paidoussis' alpha).
    end_mass : float
        Gamma = M_e/((m+M) L).
    sigma : float
        External viscous damping c L^2/(EI (m+M))^(1/2) on the pipe (not the end mass).
    mu_h : float
        Hysteretic loss factor: EI -> EI (1 + i mu_h sgn(omega)).
    springs : tuple of (kappa, xi_s)
        Linear springs kappa = k L^3/EI at 0 < xi_s <= 1.
    """

    beta: float = 0.0
    gamma: float = 0.0
    standing: bool = False
    mu: float = 0.0
    end_mass: float = 0.0
    sigma: float = 0.0
    mu_h: float = 0.0
    springs: tuple[tuple[float, float], ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(
            self, "springs", tuple((float(k), float(x)) for k, x in self.springs if k != 0.0)
        )
        for k, x in self.springs:
            if not 0.0 < x <= 1.0 or k < 0.0:
                raise ValueError(f"a spring needs kappa >= 0 and 0 < xi_s <= 1, got {(k, x)}")
        if min(self.beta, self.gamma, self.mu, self.end_mass, self.sigma, self.mu_h) < 0.0:
            raise ValueError("beta, gamma, mu, end_mass, sigma and mu_h must be >= 0")

    @classmethod
    def from_params(cls, params) -> StraightPipe:
        """The straight pipe of a :class:`~fempipe.model.params.Params`; ValueError if inclined."""
        c = math.cos(params.alpha)
        if params.gamma != 0.0 and abs(abs(c) - 1.0) > 1e-14:
            raise ValueError(
                f"the classical theory needs a straight pipe: alpha = 0 or pi, or gamma = 0 "
                f"(got alpha = {params.alpha}, gamma = {params.gamma})"
            )
        return cls(
            beta=params.beta,
            gamma=params.gamma,
            standing=params.gamma != 0.0 and c < 0.0,
            mu=params.mu,
            end_mass=params.end_mass,
            sigma=params.external_damping,
            mu_h=params.hysteretic_damping,
            springs=tuple(params.springs),
        )

    @property
    def sign(self) -> float:
        """s_g: +1 hanging (tension), -1 standing (compression)."""
        return -1.0 if self.standing else 1.0

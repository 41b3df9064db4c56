"""The Hopf normal form at a flutter point: the result of the planar pipe's and the 3-D model's.

:func:`first_lyapunov_coefficient` applies :func:`~.lyapunov.lyapunov_coefficient` to Eq. (20)
in first-order form, with the transversality lambda'(v) along the static branch and the
predicted cycle amplitudes (docs/theory/stability.md, "Hopf criticality of the flutter events").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fempipe.core.parallel import single_blas
from fempipe.model.plane.operators import PipeModel

from .lyapunov import HopfCoefficient, lyapunov_coefficient
from .pipe import dense, pipe_derivatives, pipe_jacobian


@dataclass(frozen=True)
class HopfChecks3D:
    """Diagnostics of :func:`~fempipe.analyses.three_d.onset.hopf_normal_form_3d`.

    Attributes
    ----------
    v_out_of_plane : float or None
        v_cr of the linear out-of-plane model (the secant's start), if given.
    transversality_check : float
        Re lambda'(v) by a central difference of Re lambda on the branch.
    in_plane_fraction : float
        \\|q_theta\\| / \\|q_U\\|: 0 for the mirror-odd (out-of-plane) eigenvector.
    largest_real_eigenvalue, next_real_part : float
        The largest real eigenvalue (the gauge's); the largest Re lambda but the pair.
    """

    v_out_of_plane: float | None
    transversality_check: float
    in_plane_fraction: float
    largest_real_eigenvalue: float
    next_real_part: float
    secant_iterations: int = 0


@dataclass(frozen=True)
class HopfNormalForm:
    """The Hopf normal form at a flutter point (docs/theory/stability.md).

    Attributes
    ----------
    v, omega : float
        Flow velocity of the Hopf point and Im lambda there.
    l1, uncertainty : float
        First Lyapunov coefficient (q's positions of unit L2 norm) and its uncertainty.
    criticality : {'supercritical', 'subcritical', 'degenerate'}
    eigenvalue, eigenvalue_derivative : complex
        The critical eigenvalue (Re ~ 0) and lambda'(v) along the static branch.
    transversality, rho2_slope : float
        Re lambda'(v); rho^2 / (v - v_cr) = -Re(lambda') / (omega l1).
    side : {'above', 'below'} or None
        Side of v_cr where the cycles exist (None if degenerate or not transversal).
    amplitude_coefficients : dict
        c of ``(max - min)/2 ~ c sqrt(|v - v_cr|)``: ``theta_tip``, ``eta_tip`` (planar),
        ``Y_tip`` (3-D, where the cycles exist above v_cr).
    q_static, eigenvector : ndarray
        The equilibrium (planar q or 3-D U) and q (x - x0 ~ 2 rho Re(q e^{i omega tau})).
    section_gradient : ndarray
        Gradient of the Poincare section variable (eta_tip; 3-D: Y_tip).
    checks : HopfChecks3D or None
        The 3-D model's diagnostics.
    """

    v: float
    l1: float
    uncertainty: float
    criticality: str
    omega: float
    eigenvalue: complex
    eigenvalue_derivative: complex
    transversality: float
    rho2_slope: float
    side: str | None
    amplitude_coefficients: dict
    q_static: np.ndarray = field(repr=False)
    eigenvector: np.ndarray = field(repr=False)
    coefficient: HopfCoefficient = field(repr=False)
    section_gradient: np.ndarray = field(repr=False, default=None)
    checks: HopfChecks3D | None = None

    @classmethod
    def of(cls, hc, v, dlam, q_static, gradients, section, checks=None, sides=("above", "below")):
        """From the coefficient ``hc`` and lambda'(v) = ``dlam``; amplitude coefficients of
        ``gradients`` (name: d coordinate / dq) where the cycles exist on one of ``sides``."""
        slope, side = cycle_side(hc, dlam)
        g = gradients.items() if side in sides else ()
        coef = {k: amplitude_coefficient(x, hc.q, slope) for k, x in g}
        return cls(
            v=float(v),
            l1=hc.l1,
            uncertainty=hc.uncertainty,
            criticality=hc.criticality,
            omega=hc.omega,
            eigenvalue=hc.eigenvalue,
            eigenvalue_derivative=dlam,
            transversality=float(dlam.real),
            rho2_slope=float(slope),
            side=side,
            amplitude_coefficients=coef,
            q_static=q_static,
            eigenvector=hc.q,
            coefficient=hc,
            section_gradient=section,
            checks=checks,
        )

    def rho(self, v: float) -> float:
        """Predicted normal-form amplitude rho at v (nan on the side without cycles)."""
        r2 = self.rho2_slope * (v - self.v)
        return math.sqrt(r2) if r2 >= 0 else math.nan

    def initial_state(
        self, v: float, phase: float | None = None
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """(q, q', T) = q_static + 2 rho Re(q e^{i phase}), 2 pi / omega on the predicted cycle
        at v; the default phase puts the section variable at its static value and rising."""
        n = self.q_static.size
        if phase is None:
            # s - s0 ~ 2 rho Re(g e^{i phase}), g = ds . q: zero and rising where g e^{i phase} = -i |g|
            g = complex(self.section_gradient @ self.eigenvector[:n])
            phase = float(np.angle(-1j * np.conj(g))) if g != 0 else 0.0
        x = 2.0 * self.rho(v) * np.real(self.eigenvector * np.exp(1j * phase))
        return self.q_static + x[:n], x[n:], 2.0 * math.pi / self.omega

    def event_keys(self) -> dict:
        """The Hopf keys of a flutter event of ``fempipe critical --json`` (:data:`~.flutter.EVENT_KEYS`)."""
        a = self.amplitude_coefficients
        return {
            "first_lyapunov_coefficient": self.l1,
            "first_lyapunov_uncertainty": self.uncertainty,
            "criticality": self.criticality,
            "transversality": self.transversality,
            "cycle_side": self.side,
            "theta_tip_amplitude_coefficient": a.get("theta_tip"),
            "eta_tip_amplitude_coefficient": a.get("eta_tip"),
            "Y_tip_amplitude_coefficient": a.get("Y_tip"),
            "hopf_note": None,
        }

    def to_dict(self) -> dict:
        """Scalars for JSON: the planar event keys, or the 3-D onset's (with :attr:`checks`)."""
        c = self.checks
        if c is None:
            d = self.event_keys()
            del d["Y_tip_amplitude_coefficient"], d["hopf_note"]
            return d
        return {
            "v_cr": self.v,
            "v_cr_out_of_plane_model": c.v_out_of_plane,
            "first_lyapunov_coefficient": self.l1,
            "first_lyapunov_uncertainty": self.uncertainty,
            "criticality": self.criticality,
            "omega": self.omega,
            "transversality": self.transversality,
            "transversality_check": c.transversality_check,
            "rho2_slope": self.rho2_slope,
            "Y_tip_amplitude_coefficient": self.amplitude_coefficients.get("Y_tip", math.nan),
            "in_plane_fraction": c.in_plane_fraction,
            "largest_real_eigenvalue": c.largest_real_eigenvalue,
            "next_real_part": c.next_real_part,
            "ladder": [[float(h), float(x)] for h, x in self.coefficient.ladder],
        }


def cycle_side(hc: HopfCoefficient, dlam: complex) -> tuple[float, str | None]:
    """rho^2 / (v - v_cr) and the side of v_cr where the cycles exist (or None)."""
    slope = -dlam.real / (hc.omega * hc.l1) if hc.l1 != 0.0 else math.inf
    if hc.criticality == "degenerate" or dlam.real == 0.0 or not math.isfinite(slope):
        return slope, None
    return slope, "above" if slope > 0 else "below"


def amplitude_coefficient(gradient: np.ndarray, eigenvector: np.ndarray, slope: float) -> float:
    """c of ``(max - min)/2 ~ c sqrt(|v - v_cr|)`` of the coordinate of ``gradient``."""
    n = gradient.size
    return float(2.0 * abs(gradient @ eigenvector[:n]) * math.sqrt(abs(slope)))


@single_blas
def first_lyapunov_coefficient(
    model: PipeModel,
    q_static: np.ndarray,
    *,
    omega: float | None = None,
    step: float | None = None,
) -> HopfNormalForm:
    """The Hopf normal form of Eq. (20) at the static state q_static, v = model.params.v.

    Parameters
    ----------
    model : PipeModel
    q_static : ndarray, shape (n,)
        The static state (Eq. (31a)).
    omega : float, optional
        Frequency of the crossing pair; default the pair nearest the imaginary axis.
    step : float, optional
        A fixed difference step h > 0; default the ladder (docs/theory/stability.md, "Derivatives").

    Returns
    -------
    HopfNormalForm

    Raises
    ------
    ValueError
        With hysteretic damping, or without a complex pair.
    """
    if model.params.hysteretic_damping > 0.0:
        raise ValueError(
            "hysteretic_damping must be 0: hysteretic damping is a frequency-domain model "
            "with no equation of motion, hence no Hopf normal form"
        )
    n, disc = model.n, model.disc
    q0 = np.asarray(q_static, dtype=float)
    x0 = np.concatenate([q0, np.zeros(n)])
    G = np.zeros((2 * n, 2 * n))
    G[:n, :n] = dense(disc.gram)
    deriv = pipe_derivatives(model, x0)
    hc = lyapunov_coefficient(
        lambda x: pipe_jacobian(model, x), x0, omega=omega, norm=G, step=step, derivatives=deriv
    )
    q, p = hc.q, hc.p
    # lambda'(v) = p^H (dA/dv) q along the branch, tangent q_v = -R_q^{-1} R_v.
    v = model.params.v
    rv = model.static_parameter_derivative(q0, "v")
    # R_v = 0 (the straight pipe at alpha = 0, pi stays static at every v):
    # q_v = 0 without assembling and solving R_q.
    qv = -np.linalg.solve(dense(model.static_jacobian(q0)), rv) if rv.any() else np.zeros(n)
    xv = np.concatenate([qv, np.zeros(n)])
    hv = 1e-4 * max(1.0, abs(v))
    s = max(1.0, float(np.linalg.norm(xv)))  # a step of unit size in (x, v)
    dA = deriv(xv / s, hv, 1.0 / s)[0] * s
    dlam = complex(np.conj(p) @ (dA @ q))
    # d(theta_tip)/dq and d(eta_tip)/dq = int phi_j cos theta.
    grads = {
        "theta_tip": np.asarray(disc.tip, dtype=float),
        "eta_tip": np.asarray(disc.Phi.T @ (disc.quad.w * np.cos(disc.Phi @ q0))),
    }
    return HopfNormalForm.of(hc, v, dlam, q0, grads, grads["eta_tip"])

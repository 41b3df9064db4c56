"""The Hopf normal form of the pipe at a flutter point.

:func:`first_lyapunov_coefficient` applies the generic
:func:`~fempipe.analyses.stability.hopf.lyapunov.lyapunov_coefficient` to
Eq. (20) in first-order form, with the transversality lambda'(v) along the
static branch and the predicted cycle amplitudes (docs/theory/stability.md,
"Hopf criticality of the flutter events").
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from fempipe.core.parallel import single_blas
from fempipe.model.operators import PipeModel

from .lyapunov import HopfCoefficient, lyapunov_coefficient
from .pipe import dense, pipe_derivatives, pipe_jacobian


@dataclass(frozen=True)
class HopfNormalForm:
    """The Hopf normal form of the pipe at a flutter point (docs/theory/stability.md).

    Attributes
    ----------
    v : float
        Flow velocity of the Hopf point.
    l1 : float
        First Lyapunov coefficient, q_theta of unit L2 norm.
    uncertainty : float
        Numerical uncertainty of l1 (docs/theory/stability.md, "Derivatives").
    criticality : {'supercritical', 'subcritical', 'degenerate'}
    omega : float
        Im lambda at v.
    eigenvalue : complex
        The critical eigenvalue at v (Re ~ 0 to the event's accuracy).
    eigenvalue_derivative : complex
        lambda'(v) along the static branch.
    transversality : float
        Re lambda'(v).
    rho2_slope : float
        rho^2 / (v - v_cr) = -Re(lambda') / (omega l1): positive where the
        cycles exist above v_cr (docs/theory/stability.md, "Kuznetsov's formula").
    side : {'above', 'below'} or None
        Side of v_cr where the cycles exist (None if degenerate or not transversal).
    amplitude_coefficients : dict
        c of ``(max - min)/2 ~ c sqrt(|v - v_cr|)`` for theta_tip and eta_tip
        (``{}`` when ``side`` is None).
    q_static : ndarray, shape (n,)
        The equilibrium.
    eigenvector : ndarray of complex, shape (2n,)
        q of the normal form (x - x0 ~ 2 rho Re(q e^{i omega tau})).
    coefficient : HopfCoefficient
        The generic result (step diagnostics).
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
    eta_gradient: np.ndarray = field(repr=False, default=None)

    def rho(self, v: float) -> float:
        """Predicted normal-form amplitude rho at v (nan on the side without cycles)."""
        r2 = self.rho2_slope * (v - self.v)
        return math.sqrt(r2) if r2 >= 0 else math.nan

    def initial_state(
        self, v: float, phase: float | None = None
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """(q, q', T) on the predicted cycle at v: x0 + 2 rho Re(q e^{i phase}), T = 2 pi / omega.

        A starting guess for shooting (:func:`fempipe.analyses.limit_cycle.shoot`),
        also of unstable cycles a transient never reaches.  The default phase
        puts the state where eta_tip crosses its static value upwards, the
        Poincare section of :mod:`fempipe.analyses.limit_cycle` (at another phase the
        section could be nearly tangent to the orbit).
        """
        return predicted_cycle_state(
            self.q_static, self.eigenvector, self.eta_gradient, self.rho(v), self.omega, phase
        )

    def to_dict(self) -> dict:
        return {
            "first_lyapunov_coefficient": self.l1,
            "first_lyapunov_uncertainty": self.uncertainty,
            "criticality": self.criticality,
            "transversality": self.transversality,
            "cycle_side": self.side,
            "theta_tip_amplitude_coefficient": self.amplitude_coefficients.get("theta_tip"),
            "eta_tip_amplitude_coefficient": self.amplitude_coefficients.get("eta_tip"),
        }


def predicted_cycle_state(
    x_static: np.ndarray,
    eigenvector: np.ndarray,
    section_gradient: np.ndarray,
    rho: float,
    omega: float,
    phase: float | None = None,
) -> tuple[np.ndarray, np.ndarray, float]:
    """(q, q', T) = x_static + 2 rho Re(eigenvector e^{i phase}), 2 pi / omega: the normal
    form's cycle, a starting guess for shooting.

    ``eigenvector`` is the critical one of the first-order system (positions, then rates);
    the default phase puts the section variable (gradient ``section_gradient`` with
    respect to the positions) at its static value and rising.
    """
    n = x_static.size
    if phase is None:
        # s - s0 ~ 2 rho Re(g e^{i phase}), g = ds . q: zero and rising where g e^{i phase} = -i |g|
        g = complex(section_gradient @ eigenvector[:n])
        phase = float(np.angle(-1j * np.conj(g))) if g != 0 else 0.0
    x = 2.0 * rho * np.real(eigenvector * np.exp(1j * phase))
    return x_static + x[:n], x[n:], 2.0 * math.pi / omega


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
        With v at the Hopf point (a flutter event's v).
    q_static : ndarray, shape (n,)
        The static state there (Eq. (31a)).
    omega : float, optional
        Frequency of the crossing pair (the event's ``frequency``); default
        the pair nearest the imaginary axis.
    step : float, optional
        A fixed difference step h, > 0; default the ladder (docs/theory/stability.md, "Derivatives").

    Returns
    -------
    HopfNormalForm

    Raises
    ------
    ValueError
        With hysteretic damping (no equation of motion in time), or if the
        state has no complex pair.
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
    q, p, w = hc.q, hc.p, hc.omega
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
    crit = hc.criticality
    slope = -dlam.real / (w * hc.l1) if hc.l1 != 0.0 else math.inf
    side, coef = None, {}
    # d(theta_tip)/dq and d(eta_tip)/dq = int phi_j cos theta.
    grads = {
        "theta_tip": np.asarray(disc.tip, dtype=float),
        "eta_tip": np.asarray(disc.Phi.T @ (disc.quad.w * np.cos(disc.Phi @ q0))),
    }
    if crit != "degenerate" and dlam.real != 0.0 and math.isfinite(slope):
        side = "above" if slope > 0 else "below"
        r = math.sqrt(abs(slope))
        coef = {k: float(2.0 * abs(g @ q[:n]) * r) for k, g in grads.items()}
    return HopfNormalForm(
        v=float(v),
        l1=hc.l1,
        uncertainty=hc.uncertainty,
        criticality=crit,
        omega=w,
        eigenvalue=hc.eigenvalue,
        eigenvalue_derivative=dlam,
        transversality=float(dlam.real),
        rho2_slope=float(slope),
        side=side,
        amplitude_coefficients=coef,
        q_static=q0,
        eigenvector=q,
        coefficient=hc,
        eta_gradient=grads["eta_tip"],
    )

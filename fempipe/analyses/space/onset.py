"""The onset of the non-planar oscillation: the Hopf normal form of the 3-D model.

Where the linear out-of-plane analysis (:mod:`fempipe.model.out_of_plane`,
:func:`fempipe.analyses.stability.spatial_critical_velocity`) finds that a planar static state
loses stability out of its plane before it does in it (the horizontal pipe, alpha = pi/2), a
non-planar periodic orbit is born at that v_cr.  :func:`space_hopf_normal_form` computes its
Hopf normal form on the full 3-D model (:mod:`fempipe.model.space`) as the planar one does on
Eq. (20): the first-order system and its exact Jacobian (:func:`space_jacobian`), the planar
static state lifted exactly to 3-D at the v where the critical pair crosses the imaginary
axis (:func:`locate_hopf`), the first Lyapunov coefficient l1 of the generic
:func:`~fempipe.analyses.stability.hopf.lyapunov_coefficient`, the transversality, and the
amplitude of the tip's swing out of the plane, ``(max Y_tip - min Y_tip) / 2 ~ c
sqrt(v - v_cr)``.  The critical mode is odd under the mirror through the plane of the static
state, so Y_tip swings symmetrically; the gauge's real eigenvalues are never critical.

Derivation, symmetry and measurements: docs/theory/space.md, "The onset of the non-planar
oscillation"; checked against shot cycles by :mod:`fempipe.validation.space_onset`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace

import numpy as np
import scipy.linalg as sla

from fempipe.analyses.statics import solve_static
from fempipe.core.companion import first_order_matrix
from fempipe.core.parallel import single_blas
from fempipe.model.operators import PipeModel
from fempipe.model.out_of_plane import axisymmetric
from fempipe.model.space import SpaceModel, planar_state

from ..stability.hopf.flutter import EVENT_KEYS
from ..stability.hopf.lyapunov import HopfCoefficient, lyapunov_coefficient
from ..stability.hopf.normal_form import predicted_cycle_state
from ..stability.hopf.pipe import dense
from ..statics import solve_sagged

__all__ = [
    "SpaceHopfNormalForm",
    "critical_pair",
    "locate_hopf",
    "out_of_plane_event_keys",
    "space_hopf_normal_form",
    "space_jacobian",
]

#: |Re lambda| at which the secant of :func:`locate_hopf` stops (|lambda| ~ 14).
HOPF_TOL = 1e-12
#: The secant also stops when its step in v falls below this (relative): the accuracy to
#: which the stability events locate v (Brent, 1e-10).
HOPF_V_TOL = 1e-10


def space_jacobian(model: SpaceModel, x: np.ndarray) -> np.ndarray:
    """D_x F of the 3-D first-order system at x = (U, U'), shape (2 n, 2 n).

    ``[[0, I], [-M^{-1} R_U, -M^{-1} R_U']]`` with the exact Jacobians of
    :meth:`SpaceModel.jacobians` at the acceleration a(U, U') (off the
    equilibrium the derivative of M(U) a matters).
    """
    n = model.n
    U, Ud = x[:n], x[n:]
    M = model.mass_matrix(U)
    cf = sla.cho_factor(M)
    a = -sla.cho_solve(cf, model.residual(U, Ud, None))
    JU, JUd, _ = model.jacobians(U, Ud, a)
    return first_order_matrix(JU, JUd, M, factor="cholesky", mass_factor=cf)


def critical_pair(A: np.ndarray) -> complex:
    """The eigenvalue of A with Im > 0 nearest the imaginary axis (relative to its size).

    The gauge's eigenvalues are real (docs/theory/space.md) and never chosen.
    """
    lam = np.linalg.eigvals(A)
    upper = lam[lam.imag > 0]
    if upper.size == 0:
        raise ValueError("the Jacobian has no complex eigenvalue")
    return complex(upper[np.argmin(np.abs(upper.real) / np.abs(upper))])


def _static(planar: PipeModel, v: float, q0: np.ndarray) -> np.ndarray:
    return solve_static(planar.with_params(replace(planar.params, v=v)), q0, tol=1e-12).q


def _pair_at(space: SpaceModel, planar: PipeModel, v: float, q0: np.ndarray):
    q = _static(planar, v, q0)
    m = space.with_params(replace(space.params, v=v))
    x = np.concatenate([planar_state(q), np.zeros(space.n)])
    return critical_pair(space_jacobian(m, x)), q


def locate_hopf(
    planar: PipeModel, q_guess: np.ndarray, v_guess: float, *, dv: float = 1e-3
) -> tuple[float, np.ndarray, int]:
    """The v where the critical pair of the 3-D Jacobian at the planar static state crosses
    the imaginary axis: a secant on Re lambda(v) along the static branch.

    Parameters
    ----------
    planar : PipeModel
        The planar pipe (its static branch is the 3-D model's, planar reduction).
    q_guess : ndarray, shape (n,)
        A static state near the crossing (Newton's start).
    v_guess : float
        A velocity near the crossing (e.g. the out-of-plane model's v_cr).
    dv : float
        The secant's second point is v_guess + dv.

    Returns
    -------
    (v, q, iterations) with \\|Re lambda(v)\\| <= :data:`HOPF_TOL` |lambda|, or where the
    secant's step in v has fallen below :data:`HOPF_V_TOL` (on fine meshes the round-off of
    the dense eigenvalues, about 1e-8 in Re lambda on P3:16, is above HOPF_TOL |lambda|).
    """
    space = SpaceModel(planar.disc, planar.params)
    v0, v1 = float(v_guess), float(v_guess) + dv
    l0, q = _pair_at(space, planar, v0, q_guess)
    l1, q = _pair_at(space, planar, v1, q)
    for it in range(1, 40):
        if abs(l1.real) <= HOPF_TOL * abs(l1):
            return v1, q, it
        v2 = v1 - l1.real * (v1 - v0) / (l1.real - l0.real)
        if abs(v2 - v1) <= HOPF_V_TOL * max(1.0, abs(v1)):
            return v1, q, it
        v0, l0 = v1, l1
        v1 = v2
        l1, q = _pair_at(space, planar, v1, q)
    raise RuntimeError(f"the out-of-plane Hopf point was not located (Re lambda = {l1.real:.3e})")


@dataclass(frozen=True)
class SpaceHopfNormalForm:
    """The Hopf normal form of the 3-D model at the onset of the non-planar oscillation.

    Attributes
    ----------
    v : float
        v_cr where the critical pair of the 3-D Jacobian crosses the imaginary axis.
    v_out_of_plane : float or None
        v_cr of the linear out-of-plane model (the start of the secant), if given.
    l1 : float
        First Lyapunov coefficient, q_U of unit L2 norm over (theta, a, b).
    uncertainty : float
        Its numerical uncertainty (spread over the difference steps, :func:`lyapunov_coefficient`).
    criticality : {'supercritical', 'subcritical', 'degenerate'}
    omega : float
        Im lambda at v.
    eigenvalue : complex
        The critical eigenvalue at v (Re ~ 0).
    eigenvalue_derivative : complex
        lambda'(v) along the static branch.
    transversality : float
        Re lambda'(v).
    transversality_check : float
        Re lambda'(v) by the difference quotient of Re lambda at v +- 1e-4 on the branch
        (independent of the adjoint formula).
    rho2_slope : float
        rho^2 / (v - v_cr) = -Re(lambda') / (omega l1).
    amplitude_coefficient : float
        c of ``(max Y_tip - min Y_tip) / 2 ~ c sqrt(v - v_cr)`` (nan unless the cycles
        exist above v_cr and l1 is resolved).
    in_plane_fraction : float
        \\|q_theta\\| / \\|q_U\\|: 0 for the mirror-odd (out-of-plane) eigenvector.
    largest_real_eigenvalue : float
        The largest real eigenvalue of A at v (the gauge's relaxation, about -50: far from
        critical).
    next_real_part : float
        The largest Re lambda of A at v besides the critical pair (the spectral gap).
    secant_iterations : int
    U_static : ndarray, shape (n,)
        The planar static state at v, lifted to 3-D.
    eigenvector : ndarray of complex, shape (2 n,)
        q of the normal form (x - x0 ~ 2 rho Re(q e^{i omega tau})).
    y_gradient : ndarray, shape (n,)
        d Y_tip / dU at the static state.
    coefficient : HopfCoefficient
        The generic result (the ladder of steps).
    """

    v: float
    v_out_of_plane: float | None
    l1: float
    uncertainty: float
    criticality: str
    omega: float
    eigenvalue: complex
    eigenvalue_derivative: complex
    transversality: float
    transversality_check: float
    rho2_slope: float
    amplitude_coefficient: float
    in_plane_fraction: float
    largest_real_eigenvalue: float
    next_real_part: float
    secant_iterations: int = 0
    U_static: np.ndarray = field(repr=False, default=None)
    eigenvector: np.ndarray = field(repr=False, default=None)
    y_gradient: np.ndarray = field(repr=False, default=None)
    coefficient: HopfCoefficient = field(repr=False, default=None)

    def rho(self, v: float) -> float:
        """Predicted normal-form amplitude rho at v (nan on the side without cycles)."""
        r2 = self.rho2_slope * (v - self.v)
        return math.sqrt(r2) if r2 >= 0 else math.nan

    def amplitude(self, v: float) -> float:
        """Predicted (max Y_tip - min Y_tip) / 2 at v, to leading order."""
        return self.amplitude_coefficient * math.sqrt(max(v - self.v, 0.0))

    def initial_state(self, v: float) -> tuple[np.ndarray, np.ndarray, float]:
        """(U, U', T) on the predicted cycle at v: x0 + 2 rho Re(q e^{i phase}), T = 2 pi / omega.

        The phase puts Y_tip at zero and rising (the section eta_tip + Y_tip of
        :func:`fempipe.analyses.space.shooting.section_value` crosses its static value there
        to leading order, eta_tip being even under the mirror).
        """
        return predicted_cycle_state(
            self.U_static, self.eigenvector, self.y_gradient, self.rho(v), self.omega
        )

    def to_dict(self) -> dict:
        """Scalars for JSON."""
        return {
            "v_cr": self.v,
            "v_cr_out_of_plane_model": self.v_out_of_plane,
            "first_lyapunov_coefficient": self.l1,
            "first_lyapunov_uncertainty": self.uncertainty,
            "criticality": self.criticality,
            "omega": self.omega,
            "transversality": self.transversality,
            "transversality_check": self.transversality_check,
            "rho2_slope": self.rho2_slope,
            "Y_tip_amplitude_coefficient": self.amplitude_coefficient,
            "in_plane_fraction": self.in_plane_fraction,
            "largest_real_eigenvalue": self.largest_real_eigenvalue,
            "next_real_part": self.next_real_part,
            "ladder": [[float(h), float(x)] for h, x in self.coefficient.ladder],
        }


def _next_real_part(lam: np.ndarray, critical: complex) -> float:
    """max Re lambda over the eigenvalues but the critical pair (the two nearest it)."""
    d = np.minimum(np.abs(lam - critical), np.abs(lam - np.conj(critical)))
    rest = np.delete(lam, np.argsort(d)[:2])
    return float(rest.real.max()) if rest.size else math.nan


@single_blas
def space_hopf_normal_form(
    planar: PipeModel,
    q_guess: np.ndarray,
    v_guess: float,
    *,
    v_out_of_plane: float | None = None,
    step: float | None = None,
) -> SpaceHopfNormalForm:
    """The Hopf normal form of the 3-D model where the planar static state loses stability
    out of its plane (docs/theory/space.md, "The onset of the non-planar oscillation").

    Parameters
    ----------
    planar : PipeModel
        The planar pipe (its parameters but v; springs and hysteretic damping are refused by
        :class:`SpaceModel`).
    q_guess : ndarray, shape (n,)
        A planar static state near the Hopf point (Newton's start).
    v_guess : float
        A velocity near it, e.g. the out-of-plane model's v_cr.
    v_out_of_plane : float, optional
        The out-of-plane model's v_cr, kept for comparison (``v_out_of_plane``).
    step : float, optional
        A fixed difference step of :func:`lyapunov_coefficient`; default its ladder.

    Returns
    -------
    SpaceHopfNormalForm
    """
    v, q0, its = locate_hopf(planar, q_guess, v_guess)
    params = replace(planar.params, v=v)
    pm = planar.with_params(params)
    model = SpaceModel(planar.disc, params)
    n = model.n
    U0 = planar_state(q0)
    x0 = np.concatenate([U0, np.zeros(n)])
    gram = dense(planar.disc.gram)
    G = np.zeros((2 * n, 2 * n))
    G[:n, :n] = np.kron(np.eye(3), gram)
    jac = lambda x: space_jacobian(model, x)  # noqa: E731
    hc = lyapunov_coefficient(jac, x0, norm=G, step=step)
    A = jac(x0)
    lam_all = np.linalg.eigvals(A)
    real = lam_all[np.abs(lam_all.imag) <= 1e-9 * np.abs(lam_all)].real
    q, p, w = hc.q, hc.p, hc.omega
    # lambda'(v) = p^H (dA/dv) q along the branch, tangent q_v = -R_q^{-1} R_v.
    rv = pm.static_parameter_derivative(q0, "v")
    qv = -np.linalg.solve(dense(pm.static_jacobian(q0)), rv)
    xv = np.concatenate([planar_state(qv), np.zeros(n)])
    hv = 1e-4

    def jac_at(s: float) -> np.ndarray:
        m = model.with_params(replace(params, v=v + s))
        return space_jacobian(m, x0 + s * xv)

    dA = (jac_at(hv) - jac_at(-hv)) / (2.0 * hv)
    dlam = complex(np.conj(p) @ (dA @ q))
    # The same derivative from the eigenvalue itself on the re-solved branch.
    space = SpaceModel(planar.disc, params)
    lp = _pair_at(space, planar, v + hv, q0)[0]
    lm = _pair_at(space, planar, v - hv, q0)[0]
    check = (lp.real - lm.real) / (2.0 * hv)
    slope = -dlam.real / (w * hc.l1) if hc.l1 != 0.0 else math.inf
    gY = model.tip_position_gradient(U0)[2]
    c = math.nan
    if hc.criticality != "degenerate" and math.isfinite(slope) and slope > 0:
        c = float(2.0 * abs(gY @ q[:n]) * math.sqrt(slope))
    nt = planar.disc.n
    frac = float(np.linalg.norm(q[:nt]) / np.linalg.norm(q[:n]))
    return SpaceHopfNormalForm(
        v=float(v),
        v_out_of_plane=None if v_out_of_plane is None else float(v_out_of_plane),
        l1=hc.l1,
        uncertainty=hc.uncertainty,
        criticality=hc.criticality,
        omega=w,
        eigenvalue=hc.eigenvalue,
        eigenvalue_derivative=dlam,
        transversality=float(dlam.real),
        transversality_check=float(check),
        rho2_slope=float(slope),
        amplitude_coefficient=c,
        in_plane_fraction=frac,
        largest_real_eigenvalue=float(real.max()) if real.size else math.nan,
        next_real_part=_next_real_part(lam_all, hc.eigenvalue),
        secant_iterations=its,
        U_static=U0,
        eigenvector=q,
        y_gradient=gY,
        coefficient=hc,
    )


def out_of_plane_event_keys(planar: PipeModel, v: float) -> dict:
    """The Hopf keys of ``fempipe critical``'s flutter out of the plane at ``v`` on the primary
    (gravity-loaded) branch.

    The 3-D model's normal form there (:func:`space_hopf_normal_form` from the sagged static
    state at ``v``): the keys of :data:`fempipe.analyses.stability.hopf.EVENT_KEYS` with the
    tip's swing out of the plane ``Y_tip_amplitude_coefficient`` (the in-plane ``theta_tip`` and
    ``eta_tip`` ones null: they do not swing at first order) and ``hopf_note`` null.  Where
    there is no normal form (sin alpha = 0, where the pair is double; a failed computation) the
    keys are null and ``hopf_note`` says why.
    """

    def unavailable(reason: str) -> dict:
        return dict.fromkeys(EVENT_KEYS) | {"hopf_note": reason}

    if axisymmetric(planar.params):
        return unavailable(
            "sin(alpha) = 0: every plane is alike, the pair is double (an O(2) Hopf point: the "
            "in-plane normal form is the planar cycle's; the whirl is fempipe simulate --3d's)"
        )
    try:
        q = solve_sagged(planar.with_params(replace(planar.params, v=v))).q
        nf = space_hopf_normal_form(planar, q, v, v_out_of_plane=v)
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
        return unavailable(f"no 3-D normal form: {exc}")
    side = None
    if nf.criticality != "degenerate" and math.isfinite(nf.rho2_slope):
        side = "above" if nf.rho2_slope > 0 else "below"
    coefficient = nf.amplitude_coefficient if math.isfinite(nf.amplitude_coefficient) else None
    return unavailable("") | {
        "first_lyapunov_coefficient": nf.l1,
        "first_lyapunov_uncertainty": nf.uncertainty,
        "criticality": nf.criticality,
        "transversality": nf.transversality,
        "cycle_side": side,
        "Y_tip_amplitude_coefficient": coefficient,
        "hopf_note": None,
    }

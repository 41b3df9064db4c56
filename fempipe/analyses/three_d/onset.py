"""The onset of the non-planar oscillation: the Hopf normal form of the 3-D model.

Where a planar static state loses stability out of its plane first (alpha = pi/2), a
non-planar orbit is born; :func:`hopf_normal_form_3d` gives its normal form on the 3-D model
at the crossing (:func:`locate_hopf`), with ``(max Y_tip - min Y_tip) / 2 ~ c sqrt(v - v_cr)``.

Derivation: docs/theory/space.md, "The onset of the non-planar oscillation".
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import solve_static
from fempipe.core.parallel import single_blas
from fempipe.model.out_of_plane.model import axisymmetric
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.model import PipeModel3D, planar_state

from ..stability.hopf.flutter import EVENT_KEYS
from ..stability.hopf.lyapunov import lyapunov_coefficient
from ..stability.hopf.normal_form import HopfChecks3D, HopfNormalForm
from ..stability.hopf.pipe import dense, pipe_jacobian
from ..statics import solve_sagged

__all__ = [
    "critical_pair",
    "hopf_normal_form_3d",
    "locate_hopf",
    "out_of_plane_event_keys",
]

#: |Re lambda| at which the secant of :func:`locate_hopf` stops (|lambda| ~ 14).
HOPF_TOL = 1e-12
#: The secant also stops when its step in v falls below this (relative): the accuracy to
#: which the stability events locate v (Brent, 1e-10).
HOPF_V_TOL = 1e-10


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


def _pair_at(model: PipeModel3D, planar: PipeModel, v: float, q0: np.ndarray):
    q = _static(planar, v, q0)
    m = model.with_params(replace(model.params, v=v))
    x = np.concatenate([planar_state(q), np.zeros(model.n)])
    return critical_pair(pipe_jacobian(m, x)), q


def locate_hopf(
    planar: PipeModel, q_guess: np.ndarray, v_guess: float, *, dv: float = 1e-3
) -> tuple[float, np.ndarray, int]:
    """The v where the critical pair of the 3-D Jacobian at the planar static state crosses the
    imaginary axis: a secant on Re lambda(v) along the static branch.

    Parameters
    ----------
    planar : PipeModel
    q_guess, v_guess : ndarray, float
        A static state and velocity near the crossing (e.g. the out-of-plane v_cr).
    dv : float
        The secant's second point is v_guess + dv.

    Returns
    -------
    (v, q, iterations)
        With \\|Re lambda\\| <= :data:`HOPF_TOL` |lambda|, or the secant's step below
        :data:`HOPF_V_TOL` (the round-off of Re lambda on fine meshes).
    """
    model = PipeModel3D(planar.disc, planar.params)
    v0, v1 = float(v_guess), float(v_guess) + dv
    l0, q = _pair_at(model, planar, v0, q_guess)
    l1, q = _pair_at(model, planar, v1, q)
    for it in range(1, 40):
        if abs(l1.real) <= HOPF_TOL * abs(l1):
            return v1, q, it
        v2 = v1 - l1.real * (v1 - v0) / (l1.real - l0.real)
        if abs(v2 - v1) <= HOPF_V_TOL * max(1.0, abs(v1)):
            return v1, q, it
        v0, l0, v1 = v1, l1, v2
        l1, q = _pair_at(model, planar, v1, q)
    raise RuntimeError(f"the out-of-plane Hopf point was not located (Re lambda = {l1.real:.3e})")


def _next_real_part(lam: np.ndarray, critical: complex) -> float:
    """max Re lambda over the eigenvalues but the critical pair (the two nearest it)."""
    d = np.minimum(np.abs(lam - critical), np.abs(lam - np.conj(critical)))
    rest = np.delete(lam, np.argsort(d)[:2])
    return float(rest.real.max()) if rest.size else math.nan


@single_blas
def hopf_normal_form_3d(
    planar: PipeModel,
    q_guess: np.ndarray,
    v_guess: float,
    *,
    v_out_of_plane: float | None = None,
    step: float | None = None,
) -> HopfNormalForm:
    """The Hopf normal form of the 3-D model where the planar static state loses stability out of
    its plane (docs/theory/space.md, "The onset of the non-planar oscillation").

    Parameters
    ----------
    planar : PipeModel
    q_guess, v_guess : ndarray, float
        A planar static state and velocity near the Hopf point (e.g. the out-of-plane v_cr).
    v_out_of_plane : float, optional
        The out-of-plane v_cr, kept for comparison.
    step : float, optional
        A fixed difference step of :func:`lyapunov_coefficient`.

    Returns
    -------
    HopfNormalForm
        With ``amplitude_coefficients["Y_tip"]`` and :class:`HopfChecks3D`.
    """
    v, q0, its = locate_hopf(planar, q_guess, v_guess)
    params = replace(planar.params, v=v)
    pm = planar.with_params(params)
    model = PipeModel3D(planar.disc, params)
    n = model.n
    U0 = planar_state(q0)
    x0 = np.concatenate([U0, np.zeros(n)])
    G = np.zeros((2 * n, 2 * n))
    G[:n, :n] = np.kron(np.eye(3), dense(planar.disc.gram))
    jac = lambda x: pipe_jacobian(model, x)  # noqa: E731
    hc = lyapunov_coefficient(jac, x0, norm=G, step=step)
    A = jac(x0)
    lam_all = np.linalg.eigvals(A)
    real = lam_all[np.abs(lam_all.imag) <= 1e-9 * np.abs(lam_all)].real
    q, p = hc.q, hc.p
    # lambda'(v) = p^H (dA/dv) q along the branch, tangent q_v = -R_q^{-1} R_v.
    rv = pm.static_parameter_derivative(q0, "v")
    qv = -np.linalg.solve(dense(pm.static_jacobian(q0)), rv)
    xv = np.concatenate([planar_state(qv), np.zeros(n)])
    hv = 1e-4

    def jac_at(s: float) -> np.ndarray:
        m = model.with_params(replace(params, v=v + s))
        return pipe_jacobian(m, x0 + s * xv)

    dA = (jac_at(hv) - jac_at(-hv)) / (2.0 * hv)
    dlam = complex(np.conj(p) @ (dA @ q))
    # the same derivative from the eigenvalue itself on the re-solved branch
    lp, lm = (_pair_at(model, planar, v + s, q0)[0] for s in (hv, -hv))
    check = (lp.real - lm.real) / (2.0 * hv)
    gY, nt = model.tip_position_gradient(U0)[2], planar.disc.n
    checks = HopfChecks3D(
        v_out_of_plane=None if v_out_of_plane is None else float(v_out_of_plane),
        transversality_check=float(check),
        in_plane_fraction=float(np.linalg.norm(q[:nt]) / np.linalg.norm(q[:n])),
        largest_real_eigenvalue=float(real.max()) if real.size else math.nan,
        next_real_part=_next_real_part(lam_all, hc.eigenvalue),
        secant_iterations=its,
    )
    return HopfNormalForm.of(hc, v, dlam, U0, {"Y_tip": gY}, gY, checks, sides=("above",))


def out_of_plane_event_keys(planar: PipeModel, v: float) -> dict:
    """The Hopf keys (:data:`~fempipe.analyses.stability.hopf.EVENT_KEYS`) of the flutter out of
    the plane at ``v`` on the primary branch, from the 3-D normal form (``theta_tip``, ``eta_tip``
    null); where there is none (sin alpha = 0; a failure) null with ``hopf_note`` saying why.
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
        nf = hopf_normal_form_3d(planar, q, v, v_out_of_plane=v)
    except (RuntimeError, ValueError, np.linalg.LinAlgError) as exc:
        return unavailable(f"no 3-D normal form: {exc}")
    return nf.event_keys()

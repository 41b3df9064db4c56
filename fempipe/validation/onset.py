"""Critical flow velocities, computed independently of :mod:`fempipe.analyses.stability`.

v_cr is where the spectral abscissa of the linearized problem about the sagged static state
(Eqs. (31b)-(33), dense QZ) turns positive: bracketed on a grid in v, located by Brent's
method, each static state by Newton from the nearest known one.  The Fig. 5 and 6 cases
compare it with :func:`fempipe.analyses.stability.critical_velocity`; ``plane="out"``: the
motion out of the plane (:mod:`fempipe.model.out_of_plane.model`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import brentq

from fempipe.analyses.statics import NewtonError, solve_static
from fempipe.model.out_of_plane.model import OutOfPlaneOperators
from fempipe.model.params import PAPER_CASE, Params
from fempipe.model.plane.operators import PipeModel

from .static_shapes import static_shapes

__all__ = ["Onset", "critical_velocity", "spectrum"]


#: Newton iterations per static step of :class:`_Branch`: one step away Newton converges in
#: 3 to 5; beyond a fold it cannot, and failing fast keeps the fold's bisection cheap.
NEWTON_ITERATIONS = 12


class _Branch:
    """Static states on the sagged branch, by Newton from the nearest known state."""

    def __init__(self, disc, alpha: float, beta: float, gamma: float, mu: float, v0: float):

        self.disc = disc
        self.base = Params(alpha=alpha, beta=beta, gamma=gamma, mu=mu, v=v0)
        st = static_shapes(disc, alpha, gamma, [v0], beta=beta, mu=mu, n_points=3)
        self.known = {float(v0): st.q[0]}

    def model(self, v: float) -> PipeModel:
        return PipeModel(self.disc, self.base.with_flow(v))

    def state(self, v: float) -> np.ndarray:
        """Static state at v from the nearest known one (halving steps; NewtonError below 1e-7)."""
        u = min(self.known, key=lambda x: abs(x - v))
        q = self.known[u]
        h = v - u
        while u != v:
            target = v if abs(v - u) <= abs(h) else u + h
            try:
                q = solve_static(self.model(target), q0=q, max_iter=NEWTON_ITERATIONS).q
            except NewtonError:
                h *= 0.5
                if abs(h) < 1e-7:
                    raise
                continue
            u = target
            self.known[float(u)] = q
        return q


def spectrum(model: PipeModel, q_static: np.ndarray, plane: str = "in") -> np.ndarray:
    """Eigenvalues of the linearization in or out of the ``plane``, sorted by Re."""
    import scipy.linalg as sla

    if plane == "in":
        K, D, M = model.jacobians(q_static)
    else:
        mats = OutOfPlaneOperators(model).matrices(q_static)
        K, D, M = mats.K, mats.C, mats.M
    n = model.n
    # Generalised first-order form: no inverse of the (ill-conditioned) mass matrix.
    Z, eye = np.zeros((n, n)), np.eye(n)
    A = np.block([[Z, eye], [-K, -D]])
    B = np.block([[eye, Z], [Z, M]])
    lam = sla.eigvals(A, B)
    lam = lam[np.isfinite(lam)]
    return lam[np.argsort(-lam.real)]


@dataclass(frozen=True)
class Onset:
    """The first loss of stability: ``v_cr`` (NaN if none; 0 if unstable at rest), ``frequency``
    |Im lambda| (0: divergence), ``kind``, ``evaluations`` of the spectrum.
    """

    v_cr: float
    frequency: float
    kind: str
    evaluations: int


def critical_velocity(
    disc,
    alpha: float,
    beta: float = PAPER_CASE["beta"],
    gamma: float = PAPER_CASE["gamma"],
    mu: float = PAPER_CASE["mu"],
    v_max: float = 14.0,
    dv: float = 0.5,
    xtol: float = 1e-10,
    plane: str = "in",
) -> Onset:
    """v_cr of the sagged static branch by bracketing on 0, dv, ... v_max and Brent's method to
    ``xtol``; ``alpha``, ``beta``, ``gamma``, ``mu`` default to the paper's case.
    """
    br = _Branch(disc, alpha, beta, gamma, mu, 0.0)
    count = 0

    def growth(v: float) -> float:
        nonlocal count
        count += 1
        return float(spectrum(br.model(v), br.state(v), plane)[0].real)

    def onset(lo: float, hi: float) -> Onset:
        v_cr = brentq(growth, lo, hi, xtol=xtol, rtol=4 * np.finfo(float).eps)
        freq = abs(spectrum(br.model(v_cr), br.state(v_cr), plane)[0].imag)
        return Onset(float(v_cr), float(freq), "flutter" if freq > 1e-6 else "divergence", count)

    g_prev, v_prev = growth(0.0), 0.0
    if g_prev > 0:
        return Onset(0.0, float("nan"), "unstable at rest", count)
    v = dv
    while v <= v_max + 1e-12:
        try:
            g = growth(v)
        except NewtonError:
            # The sagged branch folds before v: locate the fold (last v with a state).
            lo, hi = v_prev, v
            while hi - lo > 1e-6:
                mid = 0.5 * (lo + hi)
                try:
                    if growth(mid) > 0:
                        hi = mid  # lost stability before the fold
                        break
                    lo = mid
                except NewtonError:
                    hi = mid
            else:
                return Onset(float(lo), 0.0, "fold", count)
            return onset(lo, hi)
        if g > 0:
            return onset(v_prev, v)
        v_prev = v
        v += dv
    return Onset(float("nan"), float("nan"), "stable", count)

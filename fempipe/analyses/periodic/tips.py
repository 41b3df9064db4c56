"""The tip's extrema over one period, from the integrator's collocation polynomials.

:func:`tip_extrema` samples the cubic collocation polynomial of every
Radau IIA step (:func:`_lagrange` on the nodes :data:`_NODES`) and refines
each extremum by a bounded scalar minimisation.
"""

from __future__ import annotations

import numpy as np

from fempipe.analyses.limit_cycle import TIP_KEYS, tip_coordinates
from fempipe.model.operators import PipeModel
from fempipe.solvers.radau import C as _RADAU_NODES

__all__ = ["tip_extrema"]

# Weights of the cubic through (0, q_old), (c_i, Q_i): the integrator's
# collocation polynomial, evaluated at s = (t - t_old) / h.
_NODES = np.r_[0.0, _RADAU_NODES]


def _lagrange(s: np.ndarray) -> np.ndarray:
    s = np.atleast_1d(s)[:, None]
    L = np.ones((s.shape[0], 4))
    for j in range(4):
        for m in range(4):
            if m != j:
                L[:, j] *= (s[:, 0] - _NODES[m]) / (_NODES[j] - _NODES[m])
    return L


def tip_extrema(model: PipeModel, record: list, per_step: int = 8) -> dict:
    """[min, max] of the tip coordinates over one period, from the collocation
    polynomials: sampled ``per_step`` times per step, each extremum refined by a
    bounded scalar minimisation on the polynomial of its step and the neighbours."""
    from scipy.optimize import minimize_scalar

    disc, alpha = model.disc, model.params.alpha
    s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
    L = _lagrange(s)  # (per_step, 4)
    nodes = np.stack([np.vstack([q_old[None, :], Q]) for _, _, q_old, Q in record])  # (m, 4, n)
    qs = np.einsum("sj,mjn->msn", L, nodes).reshape(-1, model.n)
    tips = tip_coordinates(disc, alpha, qs)
    ts = np.array([t0 + h * s for t0, h, _, _ in record]).ravel()
    t_end = record[-1][0] + record[-1][1]
    starts = np.array([r[0] for r in record])

    def state_at(t: float) -> np.ndarray:
        k = int(np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(record) - 1))
        t0, h, q_old, Q = record[k]
        w = _lagrange(np.array([(t - t0) / h]))[0]
        return w @ np.vstack([q_old[None, :], Q])

    out = {}
    for key in TIP_KEYS:
        y = np.asarray(tips[key])
        ext = []
        for sign in (1.0, -1.0):  # min, then max
            k = int(np.argmin(sign * y))
            a = ts[k - 1] if k > 0 else ts[k]
            b = ts[k + 1] if k + 1 < ts.size else t_end
            r = minimize_scalar(
                lambda t, key=key, sign=sign: sign * tip_coordinates(disc, alpha, state_at(t))[key],
                bounds=(a, b),
                method="bounded",
                options={"xatol": 1e-10 * max(1.0, t_end)},
            )
            ext.append(min(sign * y[k], float(r.fun)) * sign)
        out[key] = [float(min(ext)), float(max(ext))]
    return out

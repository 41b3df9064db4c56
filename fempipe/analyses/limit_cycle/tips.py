"""Tip coordinates on attractors, the Poincare section, and their extrema over a period.

:func:`tip_extrema` of an :class:`OrbitSamples` (:class:`QuinticOrbit`,
:class:`CollocationOrbit`, :class:`TipTrace`); :func:`section_value` is the shooting's
section variable (eta_tip; eta_tip + Y_tip in 3-D).
Accuracy: docs/theory/numerics.md, "Attractors and limit cycles".
"""

from __future__ import annotations

from typing import Literal, Protocol

import numpy as np

from fempipe.model.discretization import Discretization
from fempipe.model.kinematics import compute_tip
from fempipe.model.three_d.model import PipeModel3D
from fempipe.solvers.radau.collocation import product_weights

__all__ = [
    "TIP_KEYS",
    "TIP_KEYS_3D",
    "eta_tip",
    "eta_tip_gradient",
    "section_value",
    "section_gradient",
    "OrbitSamples",
    "QuinticOrbit",
    "CollocationOrbit",
    "TipTrace",
    "tip_extrema",
]

#: Tip coordinates recorded on attractors: eta(1) in the local frame, X_g(1) (along gravity)
#: and Z_g(1) (horizontal) in the global frame, Eq. (28).
TIP_KEYS = ("eta_tip", "X_tip", "Z_tip")
#: Those of the 3-D model, with Y_tip out of the plane of the static state.
TIP_KEYS_3D = (*TIP_KEYS, "Y_tip")


def _tips(model, q: np.ndarray) -> dict:
    """The tip coordinates of one state (n,) or many (m, n) of a planar or 3-D model."""
    if isinstance(model, PipeModel3D):
        return model.tip_coordinates(q)
    tip = compute_tip(model.disc, q, model.params.alpha)
    return {k: tip[k] for k in TIP_KEYS}


def eta_tip(disc: Discretization, q: np.ndarray) -> float:
    """eta_tip of a planar state (independent of alpha)."""
    return compute_tip(disc, q, 0.0)["eta_tip"]


def eta_tip_gradient(disc: Discretization, q: np.ndarray) -> np.ndarray:
    """d eta_tip / dq = \\int phi_j cos theta."""
    th = disc.Phi @ q
    return np.asarray(disc.Phi.T @ (disc.quad.w * np.cos(th)))


def section_value(model, q: np.ndarray) -> float:
    """The section variable: the tip's displacement along e_2 + e_3 (eta_tip + Y_tip).

    eta_tip in the plane; in 3-D it oscillates at the period of an out-of-plane swing, where
    eta_tip alone swings at twice that frequency (a figure eight) or not at all.
    """
    if isinstance(model, PipeModel3D):
        d = model.tip_coordinates(q)
        return d["eta_tip"] + d["Y_tip"]
    return eta_tip(model.disc, q)


def section_gradient(model, q: np.ndarray) -> np.ndarray:
    """d :func:`section_value` / dq, shape (n,)."""
    if isinstance(model, PipeModel3D):
        g = model.tip_position_gradient(q)
        return g[1] + g[2]
    return eta_tip_gradient(model.disc, q)


class OrbitSamples(Protocol):
    """What :func:`tip_extrema` needs of an orbit over one period."""

    #: End of the period (the start is the first step's).
    t_end: float

    def tip_samples(self, model, per_step: int) -> tuple[np.ndarray, dict]:
        """Times (m,) and tip coordinates (arrays (m,)) of ``per_step`` samples per step."""

    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        """q at tau = t, (n,) for a float, (m, n) for an array of times."""


def _step_times(
    starts: np.ndarray, lengths: np.ndarray, per_step: int, end: float | None = None
) -> np.ndarray:
    """``per_step`` equally spaced times per step from each step's start (then ``end``)."""
    s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
    ts = (np.asarray(starts)[:, None] + np.asarray(lengths)[:, None] * s[None, :]).ravel()
    return ts if end is None else np.append(ts, end)


#: Quintic Hermite basis on [0, 1] for (y0, h y0', h^2 y0'', y1, h y1', h^2 y1''):
#: coefficients of s^0..s^5, one row per datum.
_QUINTIC = np.array(
    [
        [1.0, 0.0, 0.0, -10.0, 15.0, -6.0],
        [0.0, 1.0, 0.0, -6.0, 8.0, -3.0],
        [0.0, 0.0, 0.5, -1.5, 1.5, -0.5],
        [0.0, 0.0, 0.0, 10.0, -15.0, 6.0],
        [0.0, 0.0, 0.0, -4.0, 7.0, -3.0],
        [0.0, 0.0, 0.0, 0.5, -1.0, 0.5],
    ]
)


class QuinticOrbit:
    """The quintic Hermite interpolant of q(t) through the times ``t`` and (q, q', q'') =
    (``q``, ``p``, ``a``) at the step ends, O(h^6) like them; samples include the last end."""

    def __init__(self, t, q, p, a) -> None:
        t, q, p, a = (np.asarray(x, dtype=float) for x in (t, q, p, a))
        keep = np.concatenate([np.diff(t) > 0, [True]])  # no zero-length steps
        t, q, p, a = t[keep], q[keep], p[keep], a[keep]
        h = np.diff(t)[:, None]
        self.t, self.h = t, h[:, 0]
        self.data = np.stack(
            [q[:-1], h * p[:-1], h**2 * a[:-1], q[1:], h * p[1:], h**2 * a[1:]], axis=1
        )  # (steps, 6, n)

    @property
    def t_end(self) -> float:
        return self.t[-1]

    def __call__(self, times: float | np.ndarray) -> np.ndarray:
        scalar = np.ndim(times) == 0
        times = np.atleast_1d(np.asarray(times, dtype=float))
        k = np.clip(np.searchsorted(self.t, times, side="right") - 1, 0, self.h.size - 1)
        s = (times - self.t[k]) / self.h[k]
        basis = np.vander(s, 6, increasing=True) @ _QUINTIC.T  # (m, 6)
        q = np.einsum("md,mdn->mn", basis, self.data[k])
        return q[0] if scalar else q

    def tip_samples(self, model, per_step: int) -> tuple[np.ndarray, dict]:
        ts = _step_times(self.t[:-1], self.h, per_step, end=self.t[-1])
        return ts, _tips(model, self(ts))


class CollocationOrbit:
    """The collocation polynomials of the steps of one period from ``record``, ``(t_old, h,
    q_old, Q)`` per step (``Radau.last``); samples without the last end."""

    def __init__(self, record: list) -> None:
        self.record = record
        self.starts = np.array([r[0] for r in record])
        self.t_end = record[-1][0] + record[-1][1]

    def __call__(self, t: float | np.ndarray) -> np.ndarray:
        if np.ndim(t) > 0:
            return np.array([self._at(x) for x in np.asarray(t)])
        return self._at(t)

    def _at(self, t: float) -> np.ndarray:
        record = self.record
        k = int(np.clip(np.searchsorted(self.starts, t, side="right") - 1, 0, len(record) - 1))
        t0, h, q_old, Q = record[k]
        w = product_weights(np.array([(t - t0) / h]))[0]
        return w @ np.vstack([q_old[None, :], Q])

    def tip_samples(self, model, per_step: int) -> tuple[np.ndarray, dict]:
        s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
        L = product_weights(s)  # (per_step, 4)
        nodes = np.stack([np.vstack([q_old[None, :], Q]) for _, _, q_old, Q in self.record])
        qs = np.einsum("sj,mjn->msn", L, nodes).reshape(-1, nodes.shape[-1])
        h = np.array([r[1] for r in self.record])
        return _step_times(self.starts, h, per_step), _tips(model, qs)


class TipTrace:
    """Tip coordinates recorded on every step of an integration of a planar ``model``:
    ``per_step`` samples on each step's collocation polynomial (the last at its end).  It
    cannot be evaluated between its samples: :func:`tip_extrema` needs ``fine = 0``."""

    def __init__(self, model, per_step: int = 4) -> None:
        self.model, self.per_step = model, int(per_step)
        self.steps: list[tuple[np.ndarray, dict]] = []

    def record(self, stepper) -> None:
        """Append the samples of the stepper's last step."""
        t_old, t = stepper.t_old, stepper.t
        ts = np.linspace(t_old, t, self.per_step + 1)[1:]
        qs = np.array([stepper.dense(s)[0] for s in ts[:-1]] + [stepper.q])
        self.steps.append((ts, _tips(self.model, qs)))

    def __len__(self) -> int:
        return len(self.steps)

    def __getitem__(self, steps: slice) -> TipTrace:
        """The trace of a range of steps."""
        out = TipTrace(self.model, self.per_step)
        out.steps = self.steps[steps]
        return out

    @property
    def t_end(self) -> float:
        return self.steps[-1][0][-1]

    def times(self) -> np.ndarray:
        return np.concatenate([s[0] for s in self.steps])

    def values(self, key: str) -> np.ndarray:
        """The samples of one tip coordinate."""
        return np.concatenate([s[1][key] for s in self.steps])

    def tip_samples(self, model, per_step: int) -> tuple[np.ndarray, dict]:
        if per_step != self.per_step or model.params.alpha != self.model.params.alpha:
            raise ValueError(
                f"the trace was recorded with per_step = {self.per_step}, alpha = "
                f"{self.model.params.alpha:g}, not {per_step}, {model.params.alpha:g}"
            )
        return self.times(), {k: self.values(k) for k in self.steps[0][1]}

    def __call__(self, t):
        raise TypeError("a TipTrace has no values between its samples: use fine = 0")


def _vertex(t: np.ndarray, y: np.ndarray, k: int) -> float:
    """The extreme value of the parabola through the samples k - 1, k, k + 1, or y[k]."""
    if 0 < k < y.size - 1 and t[k + 1] > t[k] > t[k - 1]:
        y0, y1, y2 = y[k - 1], y[k], y[k + 1]
        h0, h1 = t[k] - t[k - 1], t[k + 1] - t[k]
        # Divided differences: where two steps of different lengths meet, the samples of a
        # trace are unequally spaced.
        d0, d1 = (y1 - y0) / h0, (y2 - y1) / h1
        curvature = (d1 - d0) / (h0 + h1)
        if curvature != 0:
            slope = (d0 * h1 + d1 * h0) / (h0 + h1)  # p'(t[k])
            return float(y1 - slope * slope / (4 * curvature))
    return float(y[k])


def tip_extrema(
    model,
    orbit: OrbitSamples,
    *,
    per_step: int = 8,
    refine: Literal["parabola", "bounded"] = "parabola",
    fine: int = 32,
    uniform: bool = False,
) -> dict[str, list[float]]:
    """[min, max] of the tip coordinates over one period: each extremum of ``per_step`` samples per
    step refined between its neighbouring samples.

    Parameters
    ----------
    model : PipeModel or PipeModel3D
    orbit : OrbitSamples
    per_step : int
    refine, fine : {'parabola', 'bounded'}, int
        The vertex of the parabola through the extreme sample and its neighbours (after ``fine``
        new samples between them), or ``minimize_scalar`` on the interpolant (xatol 1e-10).
    uniform : bool
        With ``fine = 0``: the parabola through samples taken as equally spaced.

    Returns
    -------
    dict
        ``{key: [min, max]}`` for :data:`TIP_KEYS` (:data:`TIP_KEYS_3D` in 3-D).
    """
    if refine not in ("parabola", "bounded"):
        raise ValueError(f"refine must be 'parabola' or 'bounded', got {refine!r}")
    if int(fine) < 0:
        raise ValueError(f"fine must be >= 0, got {fine}")
    ts, tips = orbit.tip_samples(model, per_step)
    if uniform:
        if fine != 0 or refine != "parabola":
            raise ValueError("uniform needs refine='parabola' and fine = 0")
        ts = np.arange(ts.size, dtype=float)
    extremum = _bounded if refine == "bounded" else _parabola
    out = {}
    for key in tips:
        y = np.asarray(tips[key])
        lo, hi = (extremum(model, orbit, key, ts, y, sign, int(fine)) for sign in (1.0, -1.0))
        if refine == "bounded":
            out[key] = [float(min(lo, hi)), float(max(lo, hi))]
        else:
            out[key] = [min(lo, float(y.min())), max(hi, float(y.max()))]
    return out


def _bracket(orbit: OrbitSamples, ts: np.ndarray, k: int) -> tuple[float, float]:
    """The times of the samples beside sample k (the end of the period after the last)."""
    a = ts[k - 1] if k > 0 else ts[k]
    b = ts[k + 1] if k + 1 < ts.size else orbit.t_end
    return a, b


def _parabola(model, orbit, key, ts, y, sign, fine) -> float:
    """The minimum (sign 1) or maximum (sign -1): parabola through the extreme sample."""
    pick = np.argmin if sign > 0 else np.argmax
    k = int(pick(y))
    if fine > 0:
        a, b = _bracket(orbit, ts, k)
        ts = np.linspace(a, b, fine + 1)
        y = _tips(model, orbit(ts))[key]
        k = int(pick(y))
    v = _vertex(ts, y, k)
    return min(v, float(y.min())) if sign > 0 else max(v, float(y.max()))


def _bounded(model, orbit, key, ts, y, sign, fine) -> float:
    """The minimum (sign 1) or maximum (sign -1): bounded minimization on the interpolant."""
    from scipy.optimize import minimize_scalar  # not at import: keeps it off simulate's start

    k = int(np.argmin(sign * y))
    a, b = _bracket(orbit, ts, k)
    r = minimize_scalar(
        lambda t: sign * _tips(model, orbit(t))[key],
        bounds=(a, b),
        method="bounded",
        options={"xatol": 1e-10 * max(1.0, orbit.t_end)},
    )
    return min(sign * y[k], float(r.fun)) * sign

"""The tip extrema of an orbit (fempipe.analyses.limit_cycle.tips) against an analytic orbit.

The orbit q(t) is a sum of harmonics with random shapes, so q, q' and q'' are known exactly
at every time, and the extrema of its tip coordinates over a period are found without the
routine under test: dense sampling of the exact orbit, then scipy's bounded minimization on
it.  Each representation of an orbit (the quintic Hermite interpolant through the step ends,
the collocation cubics of the steps, the trace of samples) must find them to its order in the
step length: observed orders from two step lengths against the theory.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.optimize import minimize_scalar

from fempipe import FiniteElement, Params, PipeModel
from fempipe.analyses.limit_cycle.tips import (
    TIP_KEYS,
    CollocationOrbit,
    QuinticOrbit,
    TipTrace,
    tip_extrema,
)
from fempipe.model.kinematics import compute_tip
from fempipe.solvers.radau import C as RADAU_NODES
from fempipe.solvers.radau import Radau, StepRecord

DISC = FiniteElement(4, 3)
OMEGA = 2 * math.pi / 0.8  # period 0.8, a cycle's scale
PERIOD = 2 * math.pi / OMEGA
_SHAPES = np.random.default_rng(33).standard_normal((4, DISC.n)) * np.array(
    [[0.2], [0.5], [0.4], [0.15]]
)


def _model(alpha: float) -> PipeModel:
    return PipeModel(DISC, Params(alpha=alpha))


def _tips(q, alpha: float) -> dict:
    """The tip coordinates :data:`TIP_KEYS` of states q."""
    tip = compute_tip(DISC, q, alpha)
    return {k: tip[k] for k in TIP_KEYS}


def exact(t, derivative: int = 0) -> np.ndarray:
    """q(t) (shape (m, n) for an array t) or its first or second derivative."""
    t = np.atleast_1d(np.asarray(t, dtype=float))[:, None]
    a, b, c, d = _SHAPES
    w = OMEGA
    if derivative == 0:
        return a + b * np.cos(w * t) + c * np.sin(w * t) + d * np.cos(2 * w * t + 0.3)
    if derivative == 1:
        return w * (-b * np.sin(w * t) + c * np.cos(w * t) - 2 * d * np.sin(2 * w * t + 0.3))
    return -(w**2) * (b * np.cos(w * t) + c * np.sin(w * t) + 4 * d * np.cos(2 * w * t + 0.3))


def reference_extrema(alpha: float) -> dict:
    """[min, max] of each tip coordinate of the exact orbit over one period."""
    ts = np.linspace(0.0, PERIOD, 20001)
    tips = _tips(exact(ts), alpha)
    out = {}
    for key in TIP_KEYS:
        ext = []
        for sign in (1.0, -1.0):
            k = int(np.argmin(sign * tips[key]))
            r = minimize_scalar(
                lambda t, key=key, sign=sign: sign * _tips(exact(t), alpha)[key][0],
                bounds=(ts[k] - 2 * (ts[1] - ts[0]), ts[k] + 2 * (ts[1] - ts[0])),
                method="bounded",
                options={"xatol": 1e-13},
            )
            ext.append(sign * min(sign * tips[key][k], r.fun))
        out[key] = [min(ext), max(ext)]
    return out


def step_ends(m: int, jitter: float = 0.3) -> np.ndarray:
    """m steps over one period, of unequal lengths (within a factor (1 +- jitter))."""
    h = 1.0 + jitter * np.sin(np.arange(m) * 2.1)
    return np.r_[0.0, np.cumsum(h) / h.sum() * PERIOD]


def quintic(m: int) -> QuinticOrbit:
    t = step_ends(m)
    return QuinticOrbit(t, exact(t), exact(t, 1), exact(t, 2))


def collocation(m: int) -> CollocationOrbit:
    t = step_ends(m)
    record = [
        (float(t0), float(t1 - t0), exact(t0)[0], exact(t0 + RADAU_NODES * (t1 - t0)))
        for t0, t1 in zip(t[:-1], t[1:], strict=True)
    ]
    return CollocationOrbit(record)


def trace(m: int, alpha: float, per_step: int = 4) -> TipTrace:
    """A trace recorded from a stepper whose dense output is the exact orbit."""
    out = TipTrace(_model(alpha), per_step=per_step)
    t = step_ends(m)
    for t0, t1 in zip(t[:-1], t[1:], strict=True):
        out.record(SimpleNamespace(t_old=t0, t=t1, q=exact(t1)[0], dense=lambda s: (exact(s)[0],)))
    return out


def _errors(found: dict, ref: dict) -> np.ndarray:
    return np.array([abs(f - r) for k in TIP_KEYS for f, r in zip(found[k], ref[k], strict=True)])


ALPHAS = [0.0, math.pi / 3]


def _sup_error(orbit, alpha: float) -> float:
    """The largest error of the interpolant's tip coordinates over the period (dense grid)."""
    ts = np.linspace(0.0, PERIOD, 4001)[:-1]
    mine = _tips(orbit(ts), alpha)
    theirs = _tips(exact(ts), alpha)
    return max(np.abs(mine[k] - theirs[k]).max() for k in TIP_KEYS)


@pytest.mark.parametrize("alpha", ALPHAS)
@pytest.mark.parametrize(
    ("build", "kwargs", "least_order"),
    [
        (quintic, {}, 5.0),  # quintic Hermite interpolant: h^6
        (quintic, {"refine": "bounded"}, 5.0),
        (collocation, {"refine": "bounded"}, 3.4),  # the collocation cubic: h^4
        (collocation, {}, 3.4),
    ],
)
def test_extrema_of_an_interpolated_orbit(alpha, build, kwargs, least_order):
    """An extremum of an interpolant is off by at most the interpolant's largest error
    (|max f - max g| <= sup |f - g|; the refinement adds no error of its own), and that
    falls at the interpolant's order: mean observed order from 12 to 96 steps."""
    ref = reference_extrema(alpha)
    orbit = build(24)
    error = _errors(tip_extrema(_model(alpha), orbit, **kwargs), ref).max()
    assert error <= _sup_error(orbit, alpha) + 1e-12
    e = [_errors(tip_extrema(_model(alpha), build(m), **kwargs), ref).max() for m in (12, 96)]
    assert math.log2(e[0] / e[1]) / 3 >= least_order, e


@pytest.mark.parametrize("alpha", ALPHAS)
def test_extrema_of_a_trace(alpha):
    """A trace cannot be evaluated between its samples: the parabola through the extreme
    sample and its neighbours (unequally spaced where steps of two lengths meet) is off by
    O(h^3); mean observed order from 12 to 96 steps."""
    ref = reference_extrema(alpha)
    e = [
        _errors(tip_extrema(_model(alpha), trace(m, alpha), per_step=4, fine=0), ref).max()
        for m in (12, 96)
    ]
    assert math.log2(e[0] / e[1]) / 3 >= 2.5, e
    part = trace(24, alpha)[3:]  # a range of steps is a trace of its own
    found = tip_extrema(_model(alpha), part, per_step=4, fine=0)
    for k in TIP_KEYS:
        assert found[k][0] <= part.values(k).min() and found[k][1] >= part.values(k).max()


def test_a_trace_of_a_parabola_gives_its_vertex():
    """Samples of a parabola, spaced like a trace whose steps change length at the extreme
    sample: the refined extremum is the vertex, to round-off."""
    from fempipe.analyses.limit_cycle.tips import _vertex

    t = np.array([0.0, 0.1, 0.2, 0.3, 0.36, 0.42, 0.48])
    for k in (3, 4):
        y = 2.0 - 3.0 * (t - t[k] - 0.013) ** 2
        assert _vertex(t, y, k) == pytest.approx(2.0, abs=1e-14)
        assert _vertex(t, -y, k) == pytest.approx(-2.0, abs=1e-14)


def test_arguments_are_checked():
    orbit, alpha = quintic(12), 0.0
    with pytest.raises(ValueError, match="refine"):
        tip_extrema(_model(alpha), orbit, refine="golden")
    with pytest.raises(ValueError, match="fine"):
        tip_extrema(_model(alpha), orbit, fine=-1)
    samples = trace(12, alpha)
    with pytest.raises(ValueError, match="per_step"):
        tip_extrema(_model(alpha), samples, per_step=8, fine=0)
    with pytest.raises(TypeError):  # a trace cannot be evaluated between its samples
        tip_extrema(_model(alpha), samples, per_step=4)


def test_collocation_orbit_is_the_integrator_s_cubic():
    """Inside a step the collocation orbit is the integrator's dense output (to round-off)."""
    from fempipe.model.dynamics_problem import PipeDynamics

    model = PipeModel(DISC, Params(alpha=0.3))
    orbit = collocation(12)
    t_old, h, q_old, Q = orbit.record[5]
    st = Radau(PipeDynamics(model), q_old, np.zeros(model.n), 0.0)
    st.last = StepRecord(t_old, h, q_old, np.zeros(model.n), Q, np.zeros_like(Q), None)
    for s in (0.1, 0.5, 0.9):
        np.testing.assert_allclose(orbit(t_old + s * h), st.dense(t_old + s * h)[0], atol=1e-14)
    times = np.array([t_old + 0.5 * h, t_old + 1.5 * h])
    np.testing.assert_array_equal(orbit(times), [orbit(x) for x in times])

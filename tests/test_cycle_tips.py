"""The one tip-extrema routine (fempipe.analyses.limit_cycle.tips.tip_extrema) against
the three computations it replaces, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from fempipe import FiniteElement, Params, PipeModel
from fempipe.analyses.limit_cycle import find_attractor
from fempipe.analyses.limit_cycle.tips import (
    TIP_KEYS,
    CollocationOrbit,
    QuinticOrbit,
    TipTrace,
    tip_coordinates,
    tip_extrema,
)
from fempipe.solvers.radau import Radau, StepRecord

DISC = FiniteElement(4, 3)


# -- the computations as they were before the routine (reference copies) --
def _refined_range(t, y):
    out = []
    for k in (int(np.argmin(y)), int(np.argmax(y))):
        if 0 < k < y.size - 1 and t[k + 1] > t[k] > t[k - 1]:
            y0, y1, y2 = y[k - 1], y[k], y[k + 1]
            den = y0 - 2 * y1 + y2
            if den != 0:
                s = 0.5 * (y0 - y2) / den
                out.append(float(y1 - 0.25 * (y0 - y2) * s))
                continue
        out.append(float(y[k]))
    return [min(out[0], float(y.min())), max(out[1], float(y.max()))]


def _cycle_tip_ranges(disc, alpha, t, q, p, a, per_step=8, fine=32):
    orbit = QuinticOrbit(t, q, p, a)
    s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
    ts = np.append((orbit.t[:-1, None] + orbit.h[:, None] * s[None, :]).ravel(), orbit.t[-1])
    coarse = tip_coordinates(disc, orbit(ts), alpha)
    out = {}
    for key in TIP_KEYS:
        y = coarse[key]
        rng = []
        for k, sign in ((int(np.argmin(y)), 1.0), (int(np.argmax(y)), -1.0)):
            lo, hi = ts[max(k - 1, 0)], ts[min(k + 1, ts.size - 1)]
            tf = np.linspace(lo, hi, fine + 1)
            r = _refined_range(tf, tip_coordinates(disc, orbit(tf), alpha)[key])
            rng.append(r[0] if sign > 0 else r[1])
        out[key] = [min(rng[0], float(y.min())), max(rng[1], float(y.max()))]
    return out


def _one_period(model, q0, p0, T):
    """Step ends (t, q, q', q''), the collocation record and a 4-per-step trace of one period."""
    st = Radau(model, q0, p0, 0.0, rtol=1e-5)
    ends = [(0.0, q0.copy(), p0.copy(), st.qddot.copy())]
    record, trace = [], TipTrace(model.disc, model.params.alpha, per_step=4)
    for t, q, p in st.steps(T):
        ends.append((t, q, p, st.qddot.copy()))
        t_old, h, q_old, _p_old, Q, _P, _acc = st.last
        record.append((t_old, h, q_old, Q))
        trace.record(st)
    return ends, record, trace


@pytest.fixture(scope="module")
def cycles():
    out = []
    for alpha, v in ((0.0, 10.0), (math.pi / 4, 8.0)):
        m = PipeModel(DISC, Params(alpha=alpha, v=v))
        c = find_attractor(m).cycle
        out.append((m, _one_period(m, c.q0, c.qdot0, c.period)))
    return out


def _same(a: dict, b: dict) -> None:
    assert list(a) == list(b) == list(TIP_KEYS)
    for k in TIP_KEYS:
        assert [float(x).hex() for x in a[k]] == [float(x).hex() for x in b[k]], k


def test_quintic_parabola_is_the_shooting_s(cycles):
    for m, (ends, _record, _trace) in cycles:
        args = zip(*ends, strict=True)
        old = _cycle_tip_ranges(m.disc, m.params.alpha, *args)
        new = tip_extrema(m.disc, QuinticOrbit(*zip(*ends, strict=True)), m.params.alpha)
        _same(new, old)


def test_trace_parabola_is_the_transient_s(cycles):
    for m, (_ends, _record, trace) in cycles:
        old = {k: _refined_range(trace.times(), trace.values(k)) for k in TIP_KEYS}
        _same(tip_extrema(m.disc, trace, m.params.alpha, per_step=4, fine=0), old)
        _same(
            tip_extrema(m.disc, trace[3:], m.params.alpha, per_step=4, fine=0),
            {k: _refined_range(trace[3:].times(), trace[3:].values(k)) for k in TIP_KEYS},
        )
    with pytest.raises(ValueError, match="per_step"):
        tip_extrema(m.disc, trace, m.params.alpha, per_step=8, fine=0)
    with pytest.raises(TypeError):
        tip_extrema(m.disc, trace, m.params.alpha, per_step=4)


def _collocation_tip_extrema(model, record, per_step=8):
    """The tip extrema of the cycle branches as periodic computed them before it called
    tip_extrema (a copy: the bit-for-bit reference of the bounded refinement)."""
    from scipy.optimize import minimize_scalar

    from fempipe.solvers.radau import C

    nodes_s = np.r_[0.0, C]

    def lagrange(s):
        s = np.atleast_1d(s)[:, None]
        L = np.ones((s.shape[0], 4))
        for j in range(4):
            for m in range(4):
                if m != j:
                    L[:, j] *= (s[:, 0] - nodes_s[m]) / (nodes_s[j] - nodes_s[m])
        return L

    disc, alpha = model.disc, model.params.alpha
    s = np.linspace(0.0, 1.0, per_step + 1)[:-1]
    nodes = np.stack([np.vstack([q_old[None, :], Q]) for _, _, q_old, Q in record])
    qs = np.einsum("sj,mjn->msn", lagrange(s), nodes).reshape(-1, model.n)
    tips = tip_coordinates(disc, qs, alpha)
    ts = np.array([t0 + h * s for t0, h, _, _ in record]).ravel()
    t_end = record[-1][0] + record[-1][1]
    starts = np.array([r[0] for r in record])

    def state_at(t):
        k = int(np.clip(np.searchsorted(starts, t, side="right") - 1, 0, len(record) - 1))
        t0, h, q_old, Q = record[k]
        return lagrange(np.array([(t - t0) / h]))[0] @ np.vstack([q_old[None, :], Q])

    out = {}
    for key in TIP_KEYS:
        y = np.asarray(tips[key])
        ext = []
        for sign in (1.0, -1.0):
            k = int(np.argmin(sign * y))
            a = ts[k - 1] if k > 0 else ts[k]
            b = ts[k + 1] if k + 1 < ts.size else t_end
            r = minimize_scalar(
                lambda t, key=key, sign=sign: sign * tip_coordinates(disc, state_at(t), alpha)[key],
                bounds=(a, b),
                method="bounded",
                options={"xatol": 1e-10 * max(1.0, t_end)},
            )
            ext.append(min(sign * y[k], float(r.fun)) * sign)
        out[key] = [float(min(ext)), float(max(ext))]
    return out


def _periodic_tip_extrema():
    """The tip extrema periodic computed before it called tip_extrema (a copy)."""
    return _collocation_tip_extrema


@pytest.mark.parametrize("per_step", [8, 5])
def test_collocation_bounded_is_periodic_s(cycles, per_step):
    """On the same steps, the routine gives periodic's extrema bit for bit: on one
    period of two cycles and on random polynomials of random steps."""
    periodic_tip_extrema = _periodic_tip_extrema()
    if periodic_tip_extrema is not _collocation_tip_extrema:  # the copy is periodic's
        m, (_ends, record, _trace) = cycles[0]
        _same(
            _collocation_tip_extrema(m, record, per_step),
            periodic_tip_extrema(m, record, per_step=per_step),
        )
    for m, (_ends, record, _trace) in cycles:
        new = tip_extrema(
            m.disc, CollocationOrbit(record), m.params.alpha, per_step=per_step, refine="bounded"
        )
        _same(new, periodic_tip_extrema(m, record, per_step=per_step))
    rng = np.random.default_rng(per_step)
    for alpha in (0.0, 0.7, math.pi):
        m = PipeModel(DISC, Params(alpha=alpha))
        h = rng.uniform(0.01, 0.1, 12)
        t0 = np.r_[0.0, np.cumsum(h)[:-1]] + 0.3
        record = [
            (
                float(a),
                float(b),
                rng.standard_normal(m.n) * 0.3,
                rng.standard_normal((3, m.n)) * 0.3,
            )
            for a, b in zip(t0, h, strict=True)
        ]
        new = tip_extrema(
            m.disc, CollocationOrbit(record), alpha, per_step=per_step, refine="bounded"
        )
        _same(new, periodic_tip_extrema(m, record, per_step=per_step))


def test_collocation_orbit_is_the_integrator_s_cubic(cycles):
    """Inside a step the collocation orbit is the integrator's dense output (to round-off)."""
    m, (_ends, record, _trace) = cycles[0]
    orbit = CollocationOrbit(record)
    t_old, h, q_old, Q = record[5]
    st = Radau(m, q_old, np.zeros(m.n), 0.0)
    st.last = StepRecord(t_old, h, q_old, np.zeros(m.n), Q, np.zeros_like(Q), None)
    for s in (0.1, 0.5, 0.9):
        np.testing.assert_allclose(orbit(t_old + s * h), st.dense(t_old + s * h)[0], atol=1e-14)
    times = np.array([t_old + 0.5 * h, t_old + 1.5 * h])
    np.testing.assert_array_equal(orbit(times), [orbit(x) for x in times])


def test_refine_is_checked(cycles):
    m, (ends, _record, _trace) = cycles[0]
    orbit = QuinticOrbit(*zip(*ends, strict=True))
    with pytest.raises(ValueError, match="refine"):
        tip_extrema(m.disc, orbit, 0.0, refine="golden")
    with pytest.raises(ValueError, match="fine"):
        tip_extrema(m.disc, orbit, 0.0, fine=-1)
    # The bounded refinement on the quintic and the parabola agree closely.
    a = tip_extrema(m.disc, orbit, 0.0)
    b = tip_extrema(m.disc, orbit, 0.0, refine="bounded")
    for k in TIP_KEYS:
        np.testing.assert_allclose(a[k], b[k], atol=1e-9)

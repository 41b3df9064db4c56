"""The nonlinear motion of the pipe in three dimensions and its attractor (:func:`simulate_3d`).

The 3-D model is integrated from the perturbed planar static state until the attractor is
recognized on the Poincare section eta_tip + Y_tip: equilibrium, periodic (planar or
nonplanar), whirl, quasi-periodic (two incommensurate spectral peaks) or non-periodic.

Classification and measurements: docs/theory/space.md.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from fempipe.analyses.three_d.whirl import fit_l2, tip_turn
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D, planar_state

from ...solvers.radau import Radau
from ..dynamics import make_initial_state
from ..limit_cycle import TIP_KEYS_3D, LimitCycle, ShootingError, section_value, shoot
from ..statics import solve_static

__all__ = [
    "Motion3D",
    "out_of_plane_perturbation",
    "simulate_3d",
    "tip_frequencies",
    "two_frequencies",
]


@dataclass(frozen=True)
class Motion3D:
    """The attractor of a 3-D motion and the trajectory that reached it.

    Attributes
    ----------
    kind, motion : str
        equilibrium, periodic, whirl, quasi-periodic or non-periodic; planar or nonplanar.
    whirl_rate : float or None
        Angular velocity of a whirl, right-handed about e_1, rad per tau.
    tip : dict
        ``[min, max]`` of :data:`~fempipe.analyses.limit_cycle.TIP_KEYS_3D` on the attractor.
    planarity : float
        Smaller over larger principal extent of the tip's horizontal path (axisymmetric pipe),
        or out-of-plane over in-plane extent.
    frequencies : tuple of float or None
        Without recurrence: the two incommensurate frequencies (cycles per tau), or the strongest.
    t, U, Udot : ndarray
        The trajectory at every accepted step.
    """

    kind: str
    motion: str
    period: float | None
    period_n: int | None
    whirl_rate: float | None
    tip: dict
    planarity: float
    frequencies: tuple[float, ...] | None = None
    cycle: LimitCycle | None = field(default=None, repr=False)
    t: np.ndarray = field(default=None, repr=False)
    U: np.ndarray = field(default=None, repr=False)
    Udot: np.ndarray = field(default=None, repr=False)
    steps: int = 0
    rejected_steps: int = 0
    t_end: float = 0.0
    cpu_time: float = 0.0

    def to_dict(self) -> dict:
        mu = None if self.cycle is None else self.cycle.floquet_multipliers[:6]
        return {
            "attractor": self.kind,
            "floquet_multipliers": None
            if mu is None
            else [[float(z.real), float(z.imag)] for z in mu],
            "stable": None if self.cycle is None else self.cycle.stable,
            "motion": self.motion,
            "period": self.period,
            "period_n": self.period_n,
            "whirl_rate": self.whirl_rate,
            "tip": self.tip,
            "planarity": self.planarity,
            "frequencies": None if self.frequencies is None else list(self.frequencies),
            "steps": self.steps,
            "rejected_steps": self.rejected_steps,
            "t_end": self.t_end,
            "cpu_time": self.cpu_time,
        }


def out_of_plane_perturbation(
    model: PipeModel3D, q_static: np.ndarray, mode: int, amplitude: float
):
    """(a, b) of an out-of-plane rotation psi = amplitude sin((2 mode - 1) pi xi / 2) about the
    planar state q_static: a = psi sin(theta/2) / 2, b = -psi cos(theta/2) / 2 (first order,
    gauge g = 0), fitted in L2 at the quadrature points."""
    Phi = model.disc.Phi
    theta = (Phi.toarray() if hasattr(Phi, "toarray") else np.asarray(Phi)) @ q_static
    psi = amplitude * np.sin((2 * mode - 1) * math.pi * model.disc.quad.x / 2)
    return tuple(fit_l2(model, s * psi * f(theta / 2)) for s, f in ((0.5, np.sin), (-0.5, np.cos)))


def _locate(model, stepper, t0, t1, g0, g1, level):
    """The section crossing in [t0, t1] on the step's dense output (secant, 30 iterations)."""
    a, b, fa, fb = t0, t1, g0 - level, g1 - level
    for _ in range(30):
        t = b - fb * (b - a) / (fb - fa) if fb != fa else 0.5 * (a + b)
        t = min(max(t, a), b)
        q, p = stepper.dense(t)
        ft = section_value(model, q) - level
        if abs(ft) < 1e-13 or abs(b - a) < 1e-14:
            return t, q, p
        if (ft > 0) == (fb > 0):
            b, fb = t, ft
        else:
            a, fa = t, ft
    return t, q, p


def _planarity(model: PipeModel3D, U: np.ndarray, axisymmetric: bool) -> float:
    d = model.tip_coordinates(np.atleast_2d(U))
    tips = np.column_stack([d["eta_tip"], d["Y_tip"]])
    centred = tips - tips.mean(axis=0)
    if axisymmetric:
        sv = np.linalg.svd(centred, compute_uv=False)
        return float(sv[1] / sv[0]) if sv[0] > 0 else 0.0
    extent = np.ptp(tips, axis=0)
    return float(extent[1] / extent[0]) if extent[0] > 0 else (0.0 if extent[1] == 0 else math.inf)


def simulate_3d(
    model: PipeModel,
    *,
    mode: int = 1,
    amplitude: float = 0.01,
    out_of_plane_amplitude: float = 0.01,
    t_max: float = 300.0,
    rtol: float = 1e-6,
    recurrence_tol: float = 1e-5,
    start_tol: float = 1e-3,
    shoot_rtol: float = 1e-7,
    use_shooting: bool = True,
    min_swing: float = 1e-2,
    planar_tol: float = 1e-3,
    n_max: int = 8,
    callback: Callable[[float], None] | None = None,
    initial: tuple[np.ndarray, np.ndarray] | None = None,
) -> Motion3D:
    """Integrate the 3-D model from the perturbed static state and classify its attractor.

    Parameters
    ----------
    model : PipeModel
        The planar model; the motion starts from its static state.
    mode, amplitude, out_of_plane_amplitude : int, float, float
        The sine mode and its in-plane and out-of-plane (psi) amplitudes, rad.
    recurrence_tol, start_tol : float
        Returns that agree to this (RMS): periodic without shooting; shot from the last.
    shoot_rtol, use_shooting, min_swing : float, bool, float
        Shoot only when the section variable swings by more than ``min_swing``.
    planar_tol : float
        :attr:`Motion3D.planarity` below this: a planar motion.
    callback : callable, optional
        Called with tau after every step.
    initial : (U0, Ud0), optional
        A 3-D state to start from instead.
    """
    start = time.process_time()
    space = PipeModel3D(model.disc, model.params)
    q_s = solve_static(model).q
    if initial is not None:
        U0, Ud0 = (np.array(x, dtype=float) for x in initial)
    else:
        U0, Ud0 = _perturbed_static_state(
            model, space, q_s, mode, amplitude, out_of_plane_amplitude
        )
    level = section_value(space, planar_state(q_s))
    stepper = Radau(PipeDynamics3D(space), U0, Ud0, rtol=rtol)
    samples = [(stepper.t, stepper.q.copy(), stepper.qdot.copy())]
    watch = _Returns(
        space,
        level,
        section_value(space, stepper.q),
        scale=max(1.0, float(np.sqrt(np.mean(U0**2)))),
        shoot=use_shooting,
        shoot_rtol=shoot_rtol,
        min_swing=min_swing,
        start_tol=start_tol,
        recurrence_tol=recurrence_tol,
        n_max=n_max,
    )
    kind, period, period_n, cycle = "non-periodic", None, None, None
    for t, q, p in stepper.steps(t_max):
        samples.append((t, q, p))
        if callback is not None:
            callback(t)
        found = watch.step(stepper, samples[-2][0], t, q)
        if found is not None:
            kind, period_n, period, cycle = found
            break
        if _settled(t, p, watch.sections, watch.swings, watch.scale):
            kind = "equilibrium"
            break
    t, U, P = (np.array(x) for x in zip(*samples, strict=True))
    kind, motion, planarity, whirl_rate, tip, frequencies = _classify(
        space, kind, period, cycle, t, U, planar_tol
    )
    return Motion3D(
        kind=kind,
        motion=motion,
        period=period,
        period_n=period_n,
        whirl_rate=whirl_rate,
        tip=tip,
        planarity=planarity,
        frequencies=frequencies,
        cycle=cycle,
        t=t,
        U=U,
        Udot=P,
        steps=stepper.stats.steps + (cycle.total_steps if cycle is not None else 0),
        rejected_steps=stepper.stats.rejected_steps
        + (cycle.rejected_steps if cycle is not None else 0),
        t_end=float(t[-1]),
        cpu_time=time.process_time() - start,
    )


class _Returns:
    """The upward returns to the section; :meth:`step` gives (kind, period_n, period, cycle)."""

    def __init__(
        self,
        space,
        level,
        g0,
        *,
        scale,
        shoot,
        shoot_rtol,
        min_swing,
        start_tol,
        recurrence_tol,
        n_max,
    ) -> None:
        self.space, self.level, self.g_old, self.scale = space, level, g0, scale
        self.shoot, self.shoot_rtol, self.min_swing = shoot, shoot_rtol, min_swing
        self.start_tol, self.recurrence_tol, self.n_max = start_tol, recurrence_tol, n_max
        self.sections: list[tuple[float, np.ndarray, np.ndarray]] = []
        self.swings: list[float] = []
        self.swing = [math.inf, -math.inf]  # the section variable's range since the last return
        self.attempts = 0

    def step(self, stepper, t_old: float, t: float, q: np.ndarray):
        g = section_value(self.space, q)
        g_old, self.g_old = self.g_old, g
        self.swing = [min(self.swing[0], g), max(self.swing[1], g)]
        if not g_old < self.level <= g:
            return None
        self.sections.append(_locate(self.space, stepper, t_old, t, g_old, g, self.level))
        self.swings.append(self.swing[1] - self.swing[0])
        self.swing = [g, g]
        shot = self._shoot()
        if shot is not None:
            return shot
        found = _recurrence(self.sections, self.n_max, self.recurrence_tol, self.scale)
        # A decaying oscillation's returns agree too once it is small: periodic only
        # when the swing has stopped shrinking.
        sw = self.swings
        if found is not None and len(sw) > 2 and abs(sw[-1] - sw[-2]) <= STEADY_SWING * sw[-1]:
            return "periodic", found[0], found[1], None
        return None

    def _shoot(self):
        """Shoot the orbit from the last return if the returns almost repeat."""
        # Shoot only an oscillation of some size that has stopped growing (near the
        # static state the returns of a slowly growing oscillation agree too, and
        # Newton then finds the equilibrium), at most three times.
        swings = self.swings
        big = (
            len(swings) > 2
            and swings[-1] > self.min_swing
            and abs(swings[-1] - swings[-2]) < 1e-2 * swings[-1]
        )
        if not (self.shoot and self.attempts < 3 and big):
            return None
        # a non-planar oscillation crosses the section twice a period (eta_tip
        # swings at twice the frequency of Y_tip): look for period-n returns
        first = _recurrence(self.sections, self.n_max, self.start_tol, self.scale)
        if first is None:
            return None
        self.attempts += 1
        _t, q_k, p_k = self.sections[-1]
        try:
            problem = PipeDynamics3D(self.space)
            cycle = shoot(problem, q_k, p_k, first[1], level=self.level, rtol=self.shoot_rtol)
        except ShootingError:
            return None
        if not cycle.stable:
            return None  # an orbit the motion is only passing: integrate on
        return "periodic", first[0], cycle.period, cycle


def _perturbed_static_state(model, space, q_s, mode, amplitude, out_of_plane_amplitude):
    """(U0, Ud0): the static state perturbed in the plane (as the planar ``simulate``) and
    out of it (:func:`out_of_plane_perturbation`)."""
    q0, p0 = make_initial_state(model, mode, amplitude, q_static=q_s)
    a0, b0 = out_of_plane_perturbation(space, q_s, mode, out_of_plane_amplitude)
    U0, Ud0 = planar_state(q0), planar_state(p0)
    nt = model.disc.n
    U0[nt : 2 * nt], U0[2 * nt :] = a0, b0
    return U0, Ud0


def _classify(space, kind, period, cycle, t, U, planar_tol):
    """(kind, motion, planarity, whirl_rate, tip, frequencies) of a finished run."""
    window = t >= (t[-1] - period if period else 0.9 * t[-1])
    wU, wt = U[window], t[window]
    if cycle is not None:  # the attractor's own orbit
        wU, wt = cycle.orbit_q, cycle.orbit_t
    axisymmetric = abs(math.sin(space.params.alpha)) < 1e-12
    planarity = _planarity(space, wU, axisymmetric) if kind != "equilibrium" else 0.0
    motion = "planar" if planarity < planar_tol else "nonplanar"
    whirl_rate = None
    if kind == "periodic" and motion == "nonplanar" and axisymmetric:
        whirl_rate = _whirl_rate(space, wU, wt, period)
        if whirl_rate is not None:
            kind = "whirl"
    if cycle is not None:
        tip = cycle.tip
    else:
        d = space.tip_coordinates(np.atleast_2d(wU))
        tip = {k: [float(d[k].min()), float(d[k].max())] for k in TIP_KEYS_3D}
    frequencies = None
    if kind == "non-periodic":
        half = t >= 0.5 * t[-1]
        d = space.tip_coordinates(U[half])
        pair = two_frequencies(t[half], [d["eta_tip"], d["Y_tip"]])
        if pair is not None and len(pair) == 2:
            kind = "quasi-periodic"
        frequencies = pair
    return kind, motion, planarity, whirl_rate, tip, frequencies


#: An equilibrium: the section not crossed for this long (tau) and the rates below
#: :data:`REST_RATE` (RMS of U_dot).
REST_TIME = 10.0
REST_RATE = 1e-8
#: A swing of the section variable below this (times the state's scale) between returns:
#: an oscillation that has died out.
REST_SWING = 1e-9
#: Successive swings of a periodic motion agree to this (relative); those of an
#: oscillation decaying at the rate of the least damped mode do not (a factor e^(Re lambda T)
#: a return).
STEADY_SWING = 1e-3


def _settled(t: float, p: np.ndarray, sections: list, swings: list, scale: float) -> bool:
    """At rest: slow, and no return for :data:`REST_TIME` or a swing below :data:`REST_SWING`."""
    if float(np.sqrt(np.mean(np.square(p)))) >= REST_RATE:
        return False
    last = sections[-1][0] if sections else 0.0
    return t - last > REST_TIME or bool(swings and swings[-1] < REST_SWING * scale)


def _recurrence(sections, n_max: int, tol: float, scale: float):
    """(n, period) when the last section state agrees with the one n returns before."""
    if len(sections) < 3:
        return None
    t_last, q_last, p_last = sections[-1]
    for n in range(1, min(n_max, len(sections) - 2) + 1):
        t_prev, q_prev, p_prev = sections[-1 - n]
        T = t_last - t_prev
        dq = np.sqrt(np.mean((q_last - q_prev) ** 2))
        dp = np.sqrt(np.mean((p_last - p_prev) ** 2)) * T / (2 * math.pi)
        if max(dq, dp) < tol * scale:
            return n, T
    return None


def _whirl_rate(model: PipeModel3D, U: np.ndarray, t: np.ndarray, period: float) -> float | None:
    """The tip's angular velocity about the vertical if it turns at a constant distance, else None."""
    radius, angle = tip_turn(model.tip_coordinates(np.atleast_2d(U)))
    if radius.min() < 0.95 * radius.max():
        return None
    turn = angle[-1] - angle[0]
    if abs(abs(turn) - 2 * math.pi) > 0.2:
        return None
    return float(turn / (t[-1] - t[0]))


def tip_frequencies(t: np.ndarray, signals: list, n_peaks: int = 6) -> list[tuple[float, float]]:
    """``(frequency, amplitude)`` of the strongest peaks of the summed power spectrum of
    ``signals`` (cycles per tau; relative amplitude): resampled, Hann-windowed, each peak
    refined by the parabola through the log power of its three bins.
    """
    t = np.asarray(t, dtype=float)
    m = max(256, t.size)
    tu = np.linspace(t[0], t[-1], m)
    dt = tu[1] - tu[0]
    win = np.hanning(m)
    power = 0.0
    for y in signals:
        yu = np.interp(tu, t, np.asarray(y, dtype=float))
        power = power + np.abs(np.fft.rfft((yu - yu.mean()) * win)) ** 2
    power = np.asarray(power)
    f = np.fft.rfftfreq(m, dt)
    inner = np.arange(2, power.size - 1)
    peaks = inner[(power[inner] > power[inner - 1]) & (power[inner] >= power[inner + 1])]
    peaks = peaks[np.argsort(-power[peaks])][:n_peaks]
    out = []
    top = power[peaks[0]] if peaks.size else 1.0
    for k in peaks:
        a, b, c = np.log(power[k - 1 : k + 2] + 1e-300)
        den = a - 2 * b + c
        shift = 0.5 * (a - c) / den if den != 0 else 0.0
        out.append((float(f[k] + shift * (f[1] - f[0])), float(np.sqrt(power[k] / top))))
    return out


def two_frequencies(
    t: np.ndarray, signals: list, floor: float = 0.05, q_max: int = 8, min_cycles: float = 20.0
):
    """``(f1, f2)`` if the spectrum (:func:`tip_frequencies`) has a second peak above
    ``floor`` of the strongest f1 whose ratio to f1 is no p/q with q <= ``q_max`` (to twice
    the frequency resolution), both with ``min_cycles`` cycles in the record; else ``(f1,)``,
    or None without a peak."""
    peaks = tip_frequencies(t, signals)
    if not peaks:
        return None
    f1 = peaks[0][0]
    res = 2.0 / (t[-1] - t[0]) / f1
    for f, amp in peaks[1:]:
        if amp < floor or f <= 0 or min(f, f1) * (t[-1] - t[0]) < min_cycles:
            continue
        r = f / f1
        near = min(abs(r - round(r * q) / q) for q in range(1, q_max + 1))
        if near > res:
            return (f1, f)
    return (f1,)

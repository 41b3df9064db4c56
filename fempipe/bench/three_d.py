"""Benchmarks of the 3-D model's limit cycles against the planar ones (``OPENBLAS_NUM_THREADS=1``).

``space_cycle`` (alpha = pi/2, v = 10) and ``space_nonplanar_cycle`` (v = 6):
docs/cli/commands.md, "fempipe bench".
"""

from __future__ import annotations

import math
import statistics
import time
from dataclasses import replace

import numpy as np

from fempipe.analyses.limit_cycle import find_attractor, shoot
from fempipe.analyses.three_d.floquet import compute_out_of_plane_floquet
from fempipe.bench.harness import best_time, register
from fempipe.model.discretization import DEFAULT_FE, FiniteElement, discretization_from_name
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D, planar_state
from fempipe.solvers.radau import Radau
from fempipe.validation.space_runs import planar_model, space_cycles


def _cpu(fn, repeats: int):
    """Median CPU seconds of ``repeats`` calls and the last result."""
    return best_time(fn, repeats, time.process_time, statistics.median)


@register("space_cycle")
def bench_space_cycle(quick: bool = False) -> dict:
    """CPU-s of a 3-D limit cycle against the planar one (module docstring)."""
    disc = FiniteElement(4, 3) if quick else discretization_from_name(DEFAULT_FE)
    repeats = 1 if quick else 3
    params = Params(alpha=math.pi / 2, v=10.0)
    planar = PipeModel(disc, params)
    space = PipeModel3D(disc, params)
    guess = find_attractor(planar).cycle
    t_planar, cycle = _cpu(
        lambda: shoot(PipeDynamics(planar), guess.q0, guess.qdot0, guess.period), repeats
    )
    U0, Ud0 = planar_state(guess.q0), planar_state(guess.qdot0)
    t_space, cycle3 = _cpu(lambda: shoot(PipeDynamics3D(space), U0, Ud0, guess.period), repeats)
    t_oop, oop = _cpu(lambda: compute_out_of_plane_floquet(planar, cycle), repeats)
    t_oop3, oop3 = _cpu(lambda: compute_out_of_plane_floquet(planar, cycle, method="3d"), repeats)
    U, Ud = planar_state(cycle.q0), planar_state(cycle.qdot0)
    Udd = space.acceleration(U, Ud)
    stages = (np.tile(U, (3, 1)), np.tile(Ud, (3, 1)), np.tile(Udd, (3, 1)))
    n_jac = 3 if quick else 20
    t_jac, _ = _cpu(lambda: [space.jacobians(*stages) for _ in range(n_jac)], 1)
    mu3 = np.abs(cycle3.floquet_multipliers)
    t_pp, steps_p = _cpu(
        lambda: _period(PipeDynamics(planar), cycle.q0, cycle.qdot0, cycle.period), repeats
    )
    t_ps, steps_s = _cpu(
        lambda: _period(PipeDynamics3D(space), U, planar_state(cycle.qdot0), cycle.period), repeats
    )
    shares = _period_shares(disc, params, U, planar_state(cycle.qdot0), cycle.period)
    return {
        "discretization": disc.name,
        "alpha": params.alpha,
        "v": params.v,
        "planar_cpu_s": t_planar,
        "planar_iterations": cycle.iterations,
        "planar_steps_total": cycle.total_steps,
        "space_cpu_s": t_space,
        "space_iterations": cycle3.iterations,
        "space_steps_total": cycle3.total_steps,
        "ratio_space_over_planar": t_space / t_planar if t_planar > 0 else math.nan,
        "period_planar": cycle.period,
        "period_space": cycle3.period,
        "max_nontrivial_planar": cycle.max_nontrivial_multiplier,
        "largest_space_multipliers": [float(x) for x in mu3[:4]],
        "stable_planar": cycle.stable,
        "stable_space": cycle3.stable,
        "out_of_plane_floquet_cpu_s": t_oop,
        "max_nontrivial_out_of_plane": oop.max_nontrivial,
        "out_of_plane_floquet_3d_cpu_s": t_oop3,
        "max_nontrivial_out_of_plane_3d": oop3.max_nontrivial,
        "jacobians_3_stages_ms": 1e3 * t_jac / n_jac,
        "planar_period_cpu_s": t_pp,
        "planar_period_steps": steps_p,
        "space_period_cpu_s": t_ps,
        "space_period_steps": steps_s,
        "ratio_per_period": t_ps / t_pp if t_pp > 0 else math.nan,
        **shares,
        "ratio_per_period_without_weak_form": (
            (
                shares["space_period_instrumented_cpu_s"]
                - shares["space_period_jacobians_cpu_s"]
                - shares["space_period_residuals_cpu_s"]
            )
            / t_pp
            if t_pp > 0
            else math.nan
        ),
    }


def _period_shares(disc, params, U, Ud, period: float) -> dict:
    """One 3-D period with the monodromy on a model that accounts its weak form's CPU."""

    class Accounted(PipeModel3D):
        jacobians_cpu = residuals_cpu = 0.0

        def jacobians(self, *args, **kwargs):
            t0 = time.process_time()
            out = super().jacobians(*args, **kwargs)
            Accounted.jacobians_cpu += time.process_time() - t0
            return out

        def residual(self, *args, **kwargs):
            t0 = time.process_time()
            out = super().residual(*args, **kwargs)
            Accounted.residuals_cpu += time.process_time() - t0
            return out

    t0 = time.process_time()
    _period(PipeDynamics3D(Accounted(disc, params)), U, Ud, period)
    return {
        "space_period_instrumented_cpu_s": time.process_time() - t0,
        "space_period_jacobians_cpu_s": Accounted.jacobians_cpu,
        "space_period_residuals_cpu_s": Accounted.residuals_cpu,
    }


def _period(problem, q0, qdot0, period: float, rtol: float = 1e-7) -> int:
    """One period with the monodromy (the shooting's integration, no Newton step); its steps."""
    stepper = Radau(problem, q0, qdot0, rtol=rtol, sensitivity=True)
    for _ in stepper.steps(period):
        pass
    return stepper.stats.steps


@register("space_nonplanar_cycle")
def bench_space_nonplanar_cycle(quick: bool = False) -> dict:
    """CPU-s of a non-planar 3-D limit cycle (module docstring)."""
    elements = 4 if quick else discretization_from_name(DEFAULT_FE).n_elements
    alpha, v = math.pi / 2, 6.0
    found = space_cycles(sorted({4, elements}), alpha, v)[elements]
    pm = planar_model(elements, alpha)
    space = PipeModel3D(pm.disc, replace(pm.params, v=v))
    repeats = 1 if quick else 2
    t_shoot, cycle = _cpu(
        lambda: shoot(PipeDynamics3D(space), found.q0, found.qdot0, found.period), repeats
    )
    t_period, steps = _cpu(
        lambda: _period(PipeDynamics3D(space), found.q0, found.qdot0, found.period), repeats
    )
    return {
        "discretization": pm.disc.name,
        "alpha": alpha,
        "v": v,
        "period": cycle.period,
        "Y_tip": cycle.tip["Y_tip"],
        "stable": cycle.stable,
        "shoot_cpu_s": t_shoot,
        "shoot_iterations": cycle.iterations,
        "shoot_steps_total": cycle.total_steps,
        "period_cpu_s": t_period,
        "period_steps": steps,
        "ms_per_step_with_monodromy": 1e3 * t_period / steps,
    }

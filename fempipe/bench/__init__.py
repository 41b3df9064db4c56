"""Performance benchmarks (timings, never unit tests).

A benchmark is a function ``fn(quick: bool = False) -> dict`` registered
under a name in :data:`BENCHMARKS`; ``fempipe bench`` runs them all or
``--only NAME``.  To add one from another module::

    from fempipe.bench import register

    @register("my_solver")
    def bench_my_solver(quick: bool = False) -> dict:
        ...
        return {"seconds": t, ...}

and list that module in :data:`BENCHMARK_MODULES` so the CLI imports it.
A result dict may carry a ``"table"`` (list of flat dicts), which the CLI
prints as a table; everything else is printed as ``key: value``.

The static benchmarks:

``static_path``
    A 61-point path in v = 0..10 at the default discretisation, the paper's
    case (:data:`fempipe.model.params.PAPER_CASE`) at alpha = pi/2 and the
    Texier--Dorbolo pipe (the paper's Section 3.1, Fig. 2(b)) at alpha = pi/2, through
    :func:`fempipe.analyses.statics.solve_path` (what ``fempipe static`` does) and,
    for comparison, the pseudo-arclength :func:`fempipe.analyses.statics.continuation`
    from v = 0 to 10.
``static_scaling``
    The same 61-point path (paper's case) on P3 meshes of 8, 16, ..., 256
    elements: wall time per point and the exponent p of time ~ n_elements^p,
    fitted over the whole range and over the finest three meshes.
"""

from __future__ import annotations

import importlib
import logging
import math
import os
import platform
import time
from collections.abc import Callable

import numpy as np

from fempipe.model.params import PAPER_CASE

__all__ = [
    "BENCHMARKS",
    "BENCHMARK_MODULES",
    "available",
    "child_cpu_seconds",
    "register",
    "run",
]

log = logging.getLogger(__name__)

#: name -> benchmark function ``fn(quick=False) -> dict``.
BENCHMARKS: dict[str, Callable[..., dict]] = {}

#: Modules imported by :func:`available` so that their ``@register`` runs.
BENCHMARK_MODULES: tuple[str, ...] = (
    "fempipe.bench",
    "fempipe.bench.dynamics",
    "fempipe.bench.stability",
    "fempipe.bench.bifurcation",
    "fempipe.bench.hopf",
)

#: The paper's reference case (:data:`fempipe.model.params.PAPER_CASE`) at alpha = pi/2.
PAPER = {"alpha": math.pi / 2, **PAPER_CASE}
#: Texier & Dorbolo's pipe (paper Section 3.1, Fig. 2b): SI values.
TEXIER_DORBOLO = {"L": 0.094, "EI": 1.8e-5, "m": 0.0159, "M": 0.0058, "g": 9.8}


def register(name: str) -> Callable[[Callable[..., dict]], Callable[..., dict]]:
    """Decorator: register ``fn(quick=False) -> dict`` as benchmark ``name``."""

    def deco(fn: Callable[..., dict]) -> Callable[..., dict]:
        if name in BENCHMARKS and BENCHMARKS[name] is not fn:
            raise ValueError(f"benchmark {name!r} is already registered")
        BENCHMARKS[name] = fn
        return fn

    return deco


def available() -> dict[str, Callable[..., dict]]:
    """All registered benchmarks, after importing :data:`BENCHMARK_MODULES`."""
    for mod in BENCHMARK_MODULES:
        importlib.import_module(mod)
    return dict(BENCHMARKS)


def environment() -> dict:
    """Where the numbers were measured."""
    import scipy

    return {
        "python": platform.python_version(),
        "numpy": np.__version__,
        "scipy": scipy.__version__,
        "machine": platform.machine(),
        "cpu_count": os.cpu_count(),
    }


def run(
    names: list[str] | None = None,
    quick: bool = False,
    callback: Callable[[str, dict], None] | None = None,
) -> dict:
    """Run benchmarks by name (all if None).

    Parameters
    ----------
    names : list of str, optional
    quick : bool
        Smaller problems and one repetition (a smoke run, not a measurement).
    callback : callable, optional
        Called as ``callback(name, result)`` after each benchmark.

    Returns
    -------
    dict
        ``{"environment": ..., "quick": quick, "benchmarks": {name: result}}``.

    Raises
    ------
    ValueError
        For an unknown name (naming the known ones).
    """
    table = available()
    names = list(table) if not names else list(names)
    unknown = [n for n in names if n not in table]
    if unknown:
        raise ValueError(f"unknown benchmark {unknown[0]!r}; known: {', '.join(sorted(table))}")
    out = {"environment": environment(), "quick": quick, "benchmarks": {}}
    for name in names:
        log.info("benchmark %s", name)
        res = table[name](quick=quick)
        out["benchmarks"][name] = res
        if callback:
            callback(name, res)
    return out


# ---------------------------------------------------------------------------
# Static benchmarks
# ---------------------------------------------------------------------------


def _best_time(fn: Callable[[], object], repeats: int) -> tuple[float, object]:
    """Minimum wall time of ``repeats`` calls (the least disturbed run) and the last result."""
    best, result = math.inf, None
    for _ in range(repeats):
        t0 = time.perf_counter()
        result = fn()
        best = min(best, time.perf_counter() - t0)
    return best, result


def _fit_exponent(n: np.ndarray, t: np.ndarray) -> float:
    """Least-squares slope of log t against log n."""
    return float(np.polyfit(np.log(n), np.log(t), 1)[0])


def _path_case(name: str, params, disc, values: list[float], repeats: int) -> dict:
    from fempipe.analyses.statics import continuation, solve_path
    from fempipe.model.kinematics import tip_values
    from fempipe.model.operators import PipeModel

    model = PipeModel(disc, params)
    t_path, sols = _best_time(lambda: solve_path(model, values), repeats)
    t_arc, branch = _best_time(lambda: continuation(model, "v", stop=values[-1]), repeats)
    last = sols[-1]
    tip = tip_values(disc, last.q, params.alpha)
    tip_arc = tip_values(disc, branch.points[-1].q, params.alpha)
    return {
        "case": name,
        "discretization": disc.name,
        "n_dofs": disc.n,
        "n_points": len(values),
        "v_max": values[-1],
        "seconds": t_path,
        "ms_per_point": 1e3 * t_path / len(values),
        "newton_iterations_total": int(sum(s.iterations for s in sols)),
        "theta_tip_at_v_max": tip["theta_tip"],
        "X_tip_at_v_max": tip["X_tip"],
        "arclength_seconds": t_arc,
        "arclength_steps": branch.steps,
        "arclength_rejected_steps": branch.rejected_steps,
        # Both routes must land on the same state: a cheap consistency check.
        "arclength_theta_tip_diff": abs(tip_arc["theta_tip"] - tip["theta_tip"]),
    }


@register("static_path")
def bench_static_path(quick: bool = False) -> dict:
    """61-point path in v = 0..10 at the default discretisation, two cases."""
    from fempipe.model.discretization import DEFAULT_FE, parse_discretization
    from fempipe.model.params import Params, PipeSI

    n_points = 11 if quick else 61
    repeats = 1 if quick else 3
    values = list(np.linspace(0.0, 10.0, n_points))
    disc = parse_discretization(DEFAULT_FE)
    td = PipeSI(alpha=math.pi / 2, **TEXIER_DORBOLO).params(0.0)
    rows = [
        _path_case("paper alpha=pi/2", Params(**PAPER), disc, values, repeats),
        _path_case("Texier-Dorbolo alpha=pi/2", td, disc, values, repeats),
    ]
    return {"repeats": repeats, "table": rows}


@register("static_scaling")
def bench_static_scaling(quick: bool = False) -> dict:
    """Cost of the 61-point path as the P3 mesh doubles from 8 to 256 elements."""
    from fempipe.analyses.statics import solve_path
    from fempipe.model.discretization import FiniteElement
    from fempipe.model.operators import PipeModel
    from fempipe.model.params import Params

    n_points = 11 if quick else 61
    repeats = 1 if quick else 3
    meshes = [8, 16, 32] if quick else [8, 16, 32, 64, 128, 256]
    values = list(np.linspace(0.0, 10.0, n_points))
    params = Params(**PAPER)
    rows = []
    for n_el in meshes:
        disc = FiniteElement(n_el, 3)
        model = PipeModel(disc, params)
        t, sols = _best_time(lambda model=model: solve_path(model, values), repeats)
        rows.append(
            {
                "n_elements": n_el,
                "n_dofs": disc.n,
                "seconds": t,
                "ms_per_point": 1e3 * t / n_points,
                "newton_iterations_total": int(sum(s.iterations for s in sols)),
                "us_per_newton_iteration": 1e6 * t / sum(s.iterations for s in sols),
            }
        )
    n = np.array([r["n_elements"] for r in rows], dtype=float)
    tt = np.array([r["seconds"] for r in rows])
    return {
        "element": "P3",
        "n_points": n_points,
        "repeats": repeats,
        "exponent_all": _fit_exponent(n, tt),
        "exponent_finest_3": _fit_exponent(n[-3:], tt[-3:]),
        "table": rows,
    }


# ---------------------------------------------------------------------------
# Stability benchmarks
# ---------------------------------------------------------------------------


@register("stability_vcr")
def bench_stability_vcr(quick: bool = False) -> dict:
    """v_cr at alpha = pi/2 (paper's case) on the default discretisation, events to 1e-10 in v.

    Target: under 3 s.  Accuracy: the relative difference to P3:32 (target 1e-6).
    """
    from fempipe.analyses.stability import critical_velocity, resolution
    from fempipe.model.discretization import DEFAULT_FE, FiniteElement, parse_discretization
    from fempipe.model.operators import PipeModel
    from fempipe.model.params import Params

    disc = parse_discretization(DEFAULT_FE)
    resolution(disc)  # canonical modes, cached per discretisation
    model = PipeModel(disc, Params(**PAPER))
    t, res = _best_time(lambda: critical_velocity(model, 10.0), 1 if quick else 3)
    out = {
        "discretization": disc.name,
        "alpha": PAPER["alpha"],
        "v_cr": res.v_cr,
        "type": res.critical.type,
        "mode": res.critical.mode,
        "frequency": res.critical.frequency,
        "n_spectra": res.n_spectra,
        "seconds": t,
        "target_seconds": 3.0,
    }
    if not quick:
        fine = critical_velocity(PipeModel(FiniteElement(32, 3), Params(**PAPER)), 10.0)
        out["v_cr_P3_32"] = fine.v_cr
        out["rel_diff_vs_P3_32"] = abs(res.v_cr / fine.v_cr - 1.0)
    return out


@register("critical_3d")
def bench_critical_3d(quick: bool = False) -> dict:
    """The analysis of ``fempipe critical`` in three dimensions against the planar one.

    At alpha = pi/4, pi/2, 3pi/4 and pi (paper's case, default discretisation,
    v in [0, 10], branches followed) the planar analysis
    (:func:`~fempipe.analyses.stability.stability_analysis`, the command before the
    out-of-plane analysis existed, and ``--planar``) and the analysis of
    both planes (:func:`~fempipe.analyses.stability.spatial_stability_analysis`) are
    timed in turn, in CPU seconds of this process (one BLAS thread), each the
    minimum of its repeats.  Target: the ratio of the sums at most 1.5.
    """
    from fempipe.analyses.stability import (
        resolution,
        spatial_stability_analysis,
        stability_analysis,
    )
    from fempipe.model.discretization import DEFAULT_FE, parse_discretization
    from fempipe.model.operators import PipeModel
    from fempipe.model.params import Params

    disc = parse_discretization(DEFAULT_FE)
    resolution(disc)
    repeats = 1 if quick else 3
    cases = []
    for alpha in (math.pi / 4, math.pi / 2, 3 * math.pi / 4, math.pi):
        model = PipeModel(disc, Params(**{**PAPER, "alpha": alpha}))
        t_in, t_3d, res3 = math.inf, math.inf, None
        for _ in range(repeats):
            t0 = time.process_time()
            planar = stability_analysis(model, 10.0)
            t_in = min(t_in, time.process_time() - t0)
            t0 = time.process_time()
            res3 = spatial_stability_analysis(model, 10.0)
            t_3d = min(t_3d, time.process_time() - t0)
        cases.append(
            {
                "alpha": alpha,
                "v_cr_planar": planar.v_cr,
                "v_cr_in_plane": res3.in_plane.v_cr,
                "v_cr_out_of_plane": res3.out_of_plane.v_cr,
                "first_plane": None if res3.critical is None else res3.critical.plane,
                "cpu_planar": t_in,
                "cpu_3d": t_3d,
                "ratio": t_3d / t_in,
            }
        )
    total_in = sum(c["cpu_planar"] for c in cases)
    total_3d = sum(c["cpu_3d"] for c in cases)
    return {
        "discretization": disc.name,
        "cases": cases,
        "cpu_planar": total_in,
        "cpu_3d": total_3d,
        "ratio": total_3d / total_in,
        "target_ratio": 1.5,
    }


@register("stability_curve")
def bench_stability_curve(quick: bool = False) -> dict:
    """v_cr(alpha) at 37 inclinations 0..pi (Fig. 6) on 2 processes; target under 60 s."""
    from fempipe.analyses.stability import stability_map
    from fempipe.model.discretization import DEFAULT_FE, parse_discretization

    n_alpha = 5 if quick else 37
    alphas = np.linspace(0.0, math.pi, n_alpha)
    disc = parse_discretization(DEFAULT_FE)
    t0 = time.perf_counter()
    smap = stability_map(
        disc, alphas, [(PAPER["beta"], PAPER["gamma"])], mu=PAPER["mu"], v_max=10.0, workers=2
    )
    t = time.perf_counter() - t0
    rows = smap.rows()
    return {
        "n_alpha": n_alpha,
        "workers": 2,
        "seconds": t,
        "target_seconds": 60.0,
        "failed_points": sum(1 for r in rows if r["error"]),
        "table": [{k: r[k] for k in ("alpha", "v_cr", "type", "mode", "v_flutter")} for r in rows],
    }


@register("convergence_vcr")
def bench_convergence_vcr(quick: bool = False) -> dict:
    """The v_cr convergence study of ``fempipe convergence`` at the paper's case, alpha = pi/2.

    ``fempipe convergence --quantity v_cr_in_plane --alpha pi/2 --v 0,10 --fe
    P1,P2,P3 --modal 2:32 --basis sine,beam`` (quick: 2:8 elements, 2:8
    modes): the paper's planar v_cr, as before ``--quantity v_cr`` became the
    first loss in three dimensions (out of the plane at this alpha), in
    this process: CPU seconds of the whole study and of each family, and the
    observed orders (theory 2, 4, 6 in dofs for P1, P2, P3; 3 for the sine
    modes, 4 for the beam modes).
    """
    from dataclasses import replace

    from fempipe.model.params import Params
    from fempipe.studies.convergence import Family, Quantity, doubling, run_study

    elements = doubling(2, 8 if quick else 64)
    modes = doubling(2, 8 if quick else 32)
    families = [Family("fe", tuple(elements), degree=k) for k in (1, 2, 3)] + [
        Family("modal", tuple(modes), basis=b) for b in ("sine", "beam")
    ]
    q = Quantity("v_cr_in_plane", replace(Params(**PAPER), v=0.0), v_max=10.0)
    t0 = time.process_time()
    study = run_study(q, families)
    cpu = time.process_time() - t0
    return {
        "v_cr_reference": float(study.reference.value),
        "reference_error_estimate": study.reference.error_estimate,
        "cpu_seconds": cpu,
        "table": [
            {
                "family": s.family,
                "n": f"{int(s.n[0])}..{int(s.n[-1])}",
                "cpu_seconds": round(s.cpu_time, 2),
                "observed_order": round(s.observed_order, 3),
                "expected_order": s.expected_order,
                "finest_error": float(s.errors[-1]),
            }
            for s in study.series
        ],
    }


# ---------------------------------------------------------------------------
# Start-up benchmark
# ---------------------------------------------------------------------------

#: CPU seconds (user + sys) allowed for ``import fempipe`` and the start of the
#: ``fempipe`` command (``--help``, and the imports before a computation).
STARTUP_TARGET = 0.4

#: (label, argument list after the interpreter, whether the target applies):
#: numpy and scipy.linalg are the floors (what a computation pays anyway).
_STARTUP_COMMANDS: tuple[tuple[str, list[str], bool], ...] = (
    ("import numpy", ["-c", "import numpy"], False),
    ("import scipy.linalg", ["-c", "import scipy.linalg"], False),
    ("import fempipe", ["-c", "import fempipe"], True),
    ("fempipe --help", ["-m", "fempipe", "--help"], True),
    ("fempipe critical --help", ["-m", "fempipe", "critical", "--help"], True),
)


_BYTECODE_CACHE: str | None = None


def child_cpu_seconds(argv: list[str], env: dict | None = None) -> tuple[float, str]:
    """User + system CPU seconds and stdout of one fresh ``python ARGV`` (``sys.executable``).

    ``env`` changes the child's environment: ``{name: value}``, a value of
    None removes the variable.

    The CPU time is the change of ``getrusage(RUSAGE_CHILDREN)`` over the run.
    All children of a benchmark run share one bytecode cache
    (``PYTHONPYCACHEPREFIX``, a temporary directory removed at exit): an installed
    package loads its modules from compiled bytecode, and with
    PYTHONDONTWRITEBYTECODE set (as some harnesses do) fempipe's modules would
    otherwise be compiled from source at every start while numpy's and scipy's
    load their installed .pyc files.  The first run of a command fills the cache;
    benchmarks make one untimed run first.

    Raises
    ------
    RuntimeError
        If the process fails, with the end of its stderr.
    """
    import atexit
    import resource
    import shutil
    import subprocess
    import sys
    import tempfile

    global _BYTECODE_CACHE
    if _BYTECODE_CACHE is None:
        _BYTECODE_CACHE = tempfile.mkdtemp(prefix="fempipe-bench-pycache-")
        atexit.register(shutil.rmtree, _BYTECODE_CACHE, True)
    child_env = dict(os.environ)
    child_env.pop("PYTHONDONTWRITEBYTECODE", None)
    child_env["PYTHONPYCACHEPREFIX"] = _BYTECODE_CACHE
    for name, value in (env or {}).items():
        if value is None:
            child_env.pop(name, None)
        else:
            child_env[name] = value
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    res = subprocess.run([sys.executable, *argv], capture_output=True, text=True, env=child_env)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if res.returncode != 0:
        raise RuntimeError(f"python {' '.join(argv)} failed: {res.stderr.strip()[-500:]}")
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return cpu, res.stdout


@register("startup")
def bench_startup(quick: bool = False) -> dict:
    """CPU seconds of ``import fempipe`` and ``fempipe --help`` in a fresh python; target 0.4.

    Each command runs as a new ``python`` process (``sys.executable``); its
    user + system CPU time is the change of ``getrusage(RUSAGE_CHILDREN)``,
    median of 5 runs (quick: 1).  ``import numpy`` and ``import scipy.linalg``
    are the floors for comparison: the package loads scipy and scikit-fem
    only when a computation needs them.
    """
    runs = 1 if quick else 5
    rows = []
    for label, argv, targeted in _STARTUP_COMMANDS:
        child_cpu_seconds(argv)  # fills the bytecode cache
        times = [child_cpu_seconds(argv)[0] for _ in range(runs)]
        median = float(np.median(times))
        row = {"command": label, "cpu_seconds": round(median, 3), "min": round(min(times), 3)}
        if targeted:
            row["target_seconds"] = STARTUP_TARGET
            row["meets_target"] = median < STARTUP_TARGET
        rows.append(row)
    return {"runs": runs, "target_seconds": STARTUP_TARGET, "table": rows}

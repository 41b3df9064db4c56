"""Start-up cost: what ``import fempipe`` and the ``fempipe`` command load before computing.

Not timings (those are the ``startup`` benchmark, ``fempipe bench --only
startup``): each check runs a fresh interpreter and looks at ``sys.modules``.
scipy, scikit-fem and numpy cost 0.2-0.5 CPU-s to import; the plotting and
I/O libraries more.  They must be imported inside the functions that use
them (or by the lazy names of ``fempipe/__init__.py``), not at module level
of anything the start-up path reaches.
"""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

import fempipe
from fempipe.cli import SUBCOMMANDS

#: Loaded only where a computation, a plot or a file format needs them.
HEAVY = ("scipy", "skfem", "matplotlib", "meshio", "tqdm", "dask")


def _fresh(code: str) -> dict:
    """Run ``code`` in a new interpreter; it prints one JSON object as its last line."""
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


_LOADED = (
    "def loaded(names):\n"
    "    return sorted(n for n in names if n in sys.modules)\n"
    "def quiet(argv):\n"
    "    import contextlib, io\n"
    "    from fempipe.cli import main\n"
    "    with contextlib.redirect_stdout(io.StringIO()), "
    "contextlib.redirect_stderr(io.StringIO()):\n"
    "        return main(argv)\n"
)


def test_import_and_top_level_help_load_no_numpy_scipy_or_plotting():
    """``import fempipe`` and ``fempipe --help`` need none of the heavy libraries."""
    code = (
        "import json, sys\n" + _LOADED + f"heavy = {('numpy', *HEAVY)!r}\n"
        "import fempipe\n"
        "after_import = loaded(heavy)\n"
        "code = quiet(['--help'])\n"
        "print(json.dumps({'import': after_import, 'help': loaded(heavy), 'code': code}))\n"
    )
    got = _fresh(code)
    assert got == {"import": [], "help": [], "code": 0}


def test_subcommand_help_loads_no_scipy_or_plotting():
    """``fempipe COMMAND --help`` for every command: numpy at most, no solver libraries."""
    code = (
        "import json, sys\n" + _LOADED + f"heavy = {HEAVY!r}\n"
        f"out = {{name: [quiet([name, '--help']), loaded(heavy)]"
        f" for name in {list(SUBCOMMANDS)!r}}}\n"
        "print(json.dumps(out))\n"
    )
    got = _fresh(code)
    assert got == {name: [0, []] for name in SUBCOMMANDS}


def test_a_command_imports_only_its_own_subcommand_module():
    code = (
        "import json, sys\n" + _LOADED + "quiet(['critical', '--help'])\n"
        f"print(json.dumps(loaded({[m for m, _ in SUBCOMMANDS.values()]!r})))\n"
    )
    assert _fresh(code) == ["fempipe.cli.critical"]


def test_critical_and_simulate_do_not_import_scipy_optimize():
    """``scipy.optimize`` (with scipy.spatial, special, fft) is a third of their start-up.

    Brent's method (:mod:`fempipe.core.rootfinding`) and the eigenvalue matching
    (:mod:`fempipe.core.matching`) stand in for its two functions they use.
    """
    code = (
        "import json, sys\n" + _LOADED + "codes = [\n"
        "    quiet(['critical', '--alpha', '0', '--fe', 'P2:4', '--v', '0,8']),\n"
        "    quiet(['simulate', '--alpha', '0', '--v', '8', '--fe', 'P2:4', '--json']),\n"
        "]\n"
        "print(json.dumps([codes, loaded(['scipy.linalg', 'scipy.optimize', "
        "'scipy.spatial', 'scipy.integrate'])]))\n"
    )
    assert _fresh(code) == [[0, 0], ["scipy.linalg"]]


# The public names of the package, as the eager ``__init__`` imported them.
from fempipe.analyses.bifurcation import (  # noqa: E402
    compute_bifurcation_diagram,
)
from fempipe.analyses.dynamics import (  # noqa: E402
    IntegrationError,
    PulsatingFlow,
    Trajectory,
    make_initial_state,
    simulate,
    simulate_steps,
)
from fempipe.analyses.limit_cycle import (  # noqa: E402
    Attractor,
    LimitCycle,
    ShootingError,
    find_attractor,
    shoot,
)
from fempipe.analyses.parametric import compute_parametric_chart  # noqa: E402
from fempipe.analyses.periodic import (  # noqa: E402
    CycleBranch,
    CycleDiagram,
    compute_cycle_diagram,
    continue_cycles,
    find_hopf_points,
)
from fempipe.analyses.stability import (  # noqa: E402
    StabilityInPlanes,
    StabilityResult,
    analyse_stability,
    compute_spectrum,
    find_critical_velocity,
    map_stability,
    trace_root_locus,
)
from fempipe.analyses.stability.hopf import HopfNormalForm  # noqa: E402
from fempipe.analyses.statics import (  # noqa: E402
    Branch,
    NewtonError,
    StaticSolution,
    continue_static,
    solve_path,
    solve_sagged,
    solve_static,
    switch_branch,
)
from fempipe.analyses.three_d import (  # noqa: E402
    Motion3D,
    Whirl,
    classify_3d,
    compute_out_of_plane_floquet,
    find_whirl,
    hopf_normal_form_3d,
    simulate_3d,
)
from fempipe.analyses.three_d.diagram import compute_diagram_3d  # noqa: E402
from fempipe.core.errors import (  # noqa: E402
    ParamError,
    SolverError,
)
from fempipe.model.discretization import (  # noqa: E402
    FiniteElement,
    Modal,
    parse_discretization,
)
from fempipe.model.kinematics import (  # noqa: E402
    compute_shape,
    compute_tip,
)
from fempipe.model.out_of_plane.model import (  # noqa: E402
    OutOfPlaneModel,
    build_out_of_plane_model,
)
from fempipe.model.out_of_plane.motion import (  # noqa: E402
    OutOfPlaneMotion,
)
from fempipe.model.params import (  # noqa: E402
    Params,
    PipeSI,
)
from fempipe.model.plane.operators import (  # noqa: E402
    PipeModel,
)
from fempipe.model.three_d.model import PipeModel3D  # noqa: E402
from fempipe.studies.compare import (  # noqa: E402
    Comparison,
    compare_values,
)
from fempipe.studies.convergence import (  # noqa: E402
    ConvergenceStudy,
    Quantity,
    estimate_order,
    extrapolate_richardson,
    run_study,
)
from fempipe.studies.error_estimate import (  # noqa: E402
    ErrorEstimate,
)
from fempipe.studies.estimates import estimate_errors  # noqa: E402

PUBLIC = {
    "Params": Params,
    "PipeSI": PipeSI,
    "FiniteElement": FiniteElement,
    "Modal": Modal,
    "parse_discretization": parse_discretization,
    "PipeModel": PipeModel,
    "OutOfPlaneModel": OutOfPlaneModel,
    "build_out_of_plane_model": build_out_of_plane_model,
    "OutOfPlaneMotion": OutOfPlaneMotion,
    "compute_shape": compute_shape,
    "compute_tip": compute_tip,
    "ParamError": ParamError,
    "SolverError": SolverError,
    "solve_static": solve_static,
    "StaticSolution": StaticSolution,
    "NewtonError": NewtonError,
    "solve_sagged": solve_sagged,
    "solve_path": solve_path,
    "continue_static": continue_static,
    "switch_branch": switch_branch,
    "Branch": Branch,
    "compute_spectrum": compute_spectrum,
    "trace_root_locus": trace_root_locus,
    "analyse_stability": analyse_stability,
    "find_critical_velocity": find_critical_velocity,
    "StabilityResult": StabilityResult,
    "map_stability": map_stability,
    "StabilityInPlanes": StabilityInPlanes,
    "simulate": simulate,
    "simulate_steps": simulate_steps,
    "make_initial_state": make_initial_state,
    "Trajectory": Trajectory,
    "PulsatingFlow": PulsatingFlow,
    "IntegrationError": IntegrationError,
    "shoot": shoot,
    "find_attractor": find_attractor,
    "LimitCycle": LimitCycle,
    "Attractor": Attractor,
    "ShootingError": ShootingError,
    "find_hopf_points": find_hopf_points,
    "continue_cycles": continue_cycles,
    "CycleBranch": CycleBranch,
    "compute_cycle_diagram": compute_cycle_diagram,
    "CycleDiagram": CycleDiagram,
    "compute_bifurcation_diagram": compute_bifurcation_diagram,
    "compute_parametric_chart": compute_parametric_chart,
    "PipeModel3D": PipeModel3D,
    "simulate_3d": simulate_3d,
    "Motion3D": Motion3D,
    "compute_out_of_plane_floquet": compute_out_of_plane_floquet,
    "classify_3d": classify_3d,
    "compute_diagram_3d": compute_diagram_3d,
    "hopf_normal_form_3d": hopf_normal_form_3d,
    "HopfNormalForm": HopfNormalForm,
    "find_whirl": find_whirl,
    "Whirl": Whirl,
    "run_study": run_study,
    "ConvergenceStudy": ConvergenceStudy,
    "Quantity": Quantity,
    "estimate_order": estimate_order,
    "extrapolate_richardson": extrapolate_richardson,
    "compare_values": compare_values,
    "Comparison": Comparison,
    "ErrorEstimate": ErrorEstimate,
    "estimate_errors": estimate_errors,
}


@pytest.mark.parametrize("name", sorted(PUBLIC))
def test_public_names_are_the_defining_modules_objects(name):
    assert getattr(fempipe, name) is PUBLIC[name]


def test_all_and_dir_list_the_public_names():
    assert sorted(fempipe.__all__) == sorted(PUBLIC)
    assert set(fempipe.__all__) <= set(dir(fempipe))
    namespace: dict = {}
    exec("from fempipe import *", namespace)
    assert {k: v for k, v in namespace.items() if k != "__builtins__"} == PUBLIC


def test_an_unknown_name_is_an_attribute_error():
    assert not hasattr(fempipe, "no_such_name")
    with pytest.raises(AttributeError, match="no_such_name"):
        fempipe.no_such_name  # noqa: B018


def test_the_continuation_function_has_no_module_of_its_name():
    """``fempipe.continue_static`` is the function of :mod:`fempipe.analyses.statics`; the
    engine lives in :mod:`fempipe.solvers.continuation`, so no submodule of the
    package is named like a public function (and none can shadow it)."""
    import importlib.util

    code = (
        "import json, importlib.util\n"
        "import fempipe.solvers.continuation\n"
        "import fempipe\n"
        "from fempipe import continue_static\n"
        "from fempipe.analyses.statics import continue_static as fn\n"
        "print(json.dumps([continue_static is fn, fempipe.continue_static is fn,"
        " importlib.util.find_spec('fempipe.continue_static') is None]))\n"
    )
    assert _fresh(code) == [True, True, True]
    names = set(fempipe.__all__)
    clashes = [
        m.name for m in __import__("pkgutil").iter_modules(fempipe.__path__) if m.name in names
    ]
    assert clashes == []
    assert importlib.util.find_spec("fempipe.analyses.statics") is not None


def test_startup_benchmark_runs_every_command_once_when_quick():
    """A smoke run of ``fempipe bench --only startup --quick`` (the numbers are not checked)."""
    from fempipe.bench import available

    res = available()["startup"](quick=True)
    assert res["runs"] == 1
    rows = {r["command"]: r for r in res["table"]}
    assert list(rows) == [
        "import numpy",
        "import scipy.linalg",
        "import fempipe",
        "fempipe --help",
        "fempipe critical --help",
    ]
    assert all(r["cpu_seconds"] > 0 for r in rows.values())
    assert [c for c, r in rows.items() if "target_seconds" in r] == list(rows)[2:]


_BLAS_PROBE = (
    "import json, os, sys\n"
    "from fempipe.cli import BLAS_THREAD_VARIABLES, main\n"
    "import contextlib, io\n"
    "with contextlib.redirect_stdout(io.StringIO()):\n"
    "    main(['critical', '--help'])\n"
    "import numpy, scipy.linalg\n"
    "from threadpoolctl import threadpool_info\n"
    "threads = sorted({i['num_threads'] for i in threadpool_info() if i['user_api'] == 'blas'})\n"
    "env = {k: os.environ.get(k) for k in BLAS_THREAD_VARIABLES}\n"
    "print(json.dumps({'threads': threads, 'env': env}))\n"
)


def _blas_probe(env_changes: dict) -> dict:
    import os

    env = {k: v for k, v in os.environ.items() if not k.endswith("_NUM_THREADS")}
    env.update(env_changes)
    res = subprocess.run(
        [sys.executable, "-c", _BLAS_PROBE], capture_output=True, text=True, env=env
    )
    assert res.returncode == 0, res.stderr
    return json.loads(res.stdout.strip().splitlines()[-1])


def test_command_line_starts_blas_with_one_thread_unless_the_user_set_it():
    """``fempipe COMMAND`` sets the BLAS thread variables the user left unset to 1 before
    numpy loads (no thread pools to start); a value the user set is kept."""
    got = _blas_probe({})
    assert got["threads"] == [1]
    assert got["env"] == {
        "OPENBLAS_NUM_THREADS": "1",
        "MKL_NUM_THREADS": "1",
        "BLIS_NUM_THREADS": "1",
    }
    mine = _blas_probe({"OPENBLAS_NUM_THREADS": "2"})
    assert mine["threads"] == [2]
    assert mine["env"]["OPENBLAS_NUM_THREADS"] == "2"
    assert mine["env"]["MKL_NUM_THREADS"] == "1"


def test_main_in_a_session_with_numpy_leaves_the_environment_alone(monkeypatch):
    """Called from Python after numpy is loaded, ``main`` changes no variable: they would
    not act on this process, and a session's environment is the user's."""
    import os

    import numpy  # noqa: F401

    from fempipe.core import parallel

    for name in parallel.BLAS_THREAD_VARIABLES:
        monkeypatch.delenv(name, raising=False)
    assert parallel.one_blas_thread() == ()
    assert all(name not in os.environ for name in parallel.BLAS_THREAD_VARIABLES)

"""The command line refuses bad or absurd input before computing, and fails loudly.

Everything runs in-process through ``fempipe.cli.main(argv)``.  Where a test
must show that nothing was computed, the solver entry point is replaced by a
function that fails the test if called.
"""

from __future__ import annotations

import math
import os
import signal
import subprocess
import sys

import pytest

from fempipe.cli import build_parser, main
from fempipe.cli.common import setup_from_args
from fempipe.cli.parsing import MAX_DOFS, MAX_VALUES
from fempipe.io.ranges import GAMMA_MAX, MU_MAX, V_MAX

TD_ARGS = ["--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058", "--g", "9.8"]


def run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def assert_refused(code, out, err, option, *words):
    """Exit 2, nothing on stdout, one line on stderr naming the option (and ``words``)."""
    assert code == 2, err
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("fempipe ") and ": error: " in lines[0]
    assert option in lines[0]
    for w in words:
        assert w in lines[0], lines[0]
    assert "Traceback" not in err


class ComputeStartedError(Exception):
    """Raised by a stand-in solver: the command started computing."""


@pytest.fixture
def no_compute(monkeypatch):
    """Every solver entry point the subcommands call fails the test if reached."""
    import fempipe.analyses.bifurcation
    import fempipe.analyses.limit_cycle
    import fempipe.analyses.stability
    import fempipe.analyses.statics

    def computed(*args, **kwargs):
        raise ComputeStartedError

    for module, name in (
        (fempipe.analyses.statics, "solve_path"),
        (fempipe.analyses.statics, "solve_static"),
        (fempipe.analyses.stability, "trace_root_locus"),
        (fempipe.analyses.stability, "analyse_stability"),
        (fempipe.analyses.stability, "map_stability"),
        (fempipe.analyses.limit_cycle, "find_attractor"),
        (fempipe.analyses.bifurcation, "compute_bifurcation_diagram"),
    ):
        monkeypatch.setattr(module, name, computed)


# ------------------------------------------------------------ negative gravity --
@pytest.mark.parametrize("alpha", [[], ["--alpha", "pi/2"]])
def test_negative_gamma_says_a_standing_pipe_is_alpha_pi(alpha, capsys, no_compute):
    code, out, err = run(["static", *alpha, "--gamma", "-10"], capsys)
    assert_refused(code, out, err, "--gamma", "alpha = pi", "gamma > 0")


# ---------------------------------------------------------- absurd magnitudes --
@pytest.mark.parametrize(
    "argv, option, allowed",
    [
        (["static", "--alpha", "pi/2", "--v", "1e160"], "--v", f"0 <= v <= {V_MAX:g}"),
        (["static", "--alpha", "pi/2", "--v", "1e100"], "--v", f"0 <= v <= {V_MAX:g}"),
        (["static", "--v", "0:1e100:3"], "--v", f"0 <= v <= {V_MAX:g}"),
        (["spectrum", "--v", "1e300"], "--v", f"0 <= v <= {V_MAX:g}"),
        (["critical", "--v", "0,1e300"], "--v", f"0 <= v <= {V_MAX:g}"),
        (["simulate", "--v", "1e300"], "--v", f"0 <= v <= {V_MAX:g}"),
        (["static", *TD_ARGS, "--U", "1e300"], "--U", "0 <= U <= "),
        (["static", *TD_ARGS, "--U", "0,40"], "--U", "0 <= U <= "),
        (["static", "--gamma", "1e5"], "--gamma", f"0 <= gamma <= {GAMMA_MAX:g}"),
        (["static", "--mu", "1e300"], "--mu", f"0 <= mu <= {MU_MAX:g}"),
        (["spectrum", "--mu", "1e300"], "--mu", f"0 <= mu <= {MU_MAX:g}"),
        (["static", "--alpha", "1e300"], "--alpha", "2pi"),
        (["static", "--length", "1e200", *TD_ARGS[2:], "--U", "0"], "--EI", "overflows"),
        (["static", "--length", "10", *TD_ARGS[2:], "--U", "0"], "--length", "gamma <= "),
        (["static", *TD_ARGS, "--a", "1e3", "--U", "0"], "--a", f"0 <= mu <= {MU_MAX:g}"),
        (["static", "--continuation", "gamma", "--values", "0:1e9:3"], "--values", "gamma <= "),
        (["stability-map", "--gammas", "10,1e9"], "--gammas", "gamma <= "),
    ],
)
def test_absurd_magnitudes_are_refused_naming_option_and_range(
    argv, option, allowed, tmp_path, capsys, no_compute
):
    out_dir = tmp_path / "out"
    code, out, err = run([*argv, "--out", str(out_dir)], capsys)
    assert_refused(code, out, err, option, allowed)
    assert not out_dir.exists()


def test_the_ends_of_the_ranges_are_accepted():
    """v = V_MAX, gamma = GAMMA_MAX and mu = MU_MAX themselves are inside."""
    args = build_parser().parse_args(
        ["static", "--v", f"0,{V_MAX!r}", "--gamma", repr(GAMMA_MAX), "--mu", repr(MU_MAX)]
    )
    setup = setup_from_args(args)
    assert setup.v == [0.0, V_MAX]
    assert (setup.params.gamma, setup.params.mu) == (GAMMA_MAX, MU_MAX)


def test_the_U_limit_is_the_U_of_the_largest_v(capsys, no_compute):
    """For an SI pipe --U is bounded by the U of v = V_MAX, v = sqrt(M/EI) U L (Eq. (19))."""
    U_max = V_MAX / (math.sqrt(0.0058 / 1.8e-5) * 0.094)
    args = build_parser().parse_args(["static", *TD_ARGS, "--U", f"0,{U_max * (1 - 1e-12)!r}"])
    assert setup_from_args(args).v[-1] == pytest.approx(V_MAX, rel=1e-11)
    code, out, err = run(["static", *TD_ARGS, "--U", f"0,{U_max * (1 + 1e-9)!r}"], capsys)
    assert_refused(code, out, err, "--U", f"{U_max:.6g} m/s")


# ----------------------------------------------------------------- large work --
@pytest.mark.parametrize(
    "argv, option",
    [
        (["static", "--v", f"0:1:{MAX_VALUES + 1}"], "--v"),
        (["static", *TD_ARGS, "--U", f"0:1:{MAX_VALUES + 1}"], "--U"),
        (["static", "--fe", "P3:1000", "--v", "0,1", "--alpha", "pi/2"], "--fe"),
        (["static", "--modal", str(MAX_DOFS + 1), "--v", "0"], "--modal"),
        (["static", "--continuation", "alpha", "--values", "0:pi:5000"], "--values"),
        (["static", "--continuation", "gamma", "--values", "0:10:5000"], "--values"),
        (["spectrum", "--v", f"0:1:{MAX_VALUES + 1}"], "--v"),
        (["spectrum", "--fe", f"P10:{MAX_DOFS // 10 + 1}"], "--fe"),
        (["critical", "--fe", "P2:1000"], "--fe"),
        (["stability-map", "--alphas", "0:pi:2000"], "--alphas"),
        (["stability-map", "--alphas", "0:pi:101", "--betas", "0:1:10"], "--alphas"),
        (["simulate", "--t-max", "1e9"], "--t-max"),
        (["bifurcation", "--v", "5:12:600"], "--v"),
        (["bifurcation", "--t-max", "1e9"], "--t-max"),
    ],
)
def test_large_work_needs_allow_large(argv, option, capsys, no_compute):
    code, out, err = run(argv, capsys)
    assert_refused(code, out, err, option, "--allow-large")


def test_a_hundred_million_points_are_refused_at_once(capsys, no_compute):
    """The count is checked before the list is built (1e8 floats would be gigabytes)."""
    import time

    start = time.perf_counter()
    code, out, err = run(["static", "--v", "0:1:100000000"], capsys)
    assert_refused(code, out, err, "--v", "100000000", "--allow-large")
    assert time.perf_counter() - start < 5.0


@pytest.mark.parametrize(
    "argv",
    [
        ["static", "--fe", "P3:400", "--v", "0"],
        ["static", "--v", f"0:1:{MAX_VALUES + 1}"],
        ["simulate", "--modal", "2", "--t-max", "2e4"],
    ],
)
def test_allow_large_lets_the_work_start(argv, capsys, no_compute):
    with pytest.raises(ComputeStartedError):
        main([*argv, "--allow-large"])


# ---------------------------------------------------------------- structure --
def test_stability_map_refuses_alpha(capsys, no_compute):
    """Its inclinations come from --alphas; a --alpha would be silently ignored."""
    code, out, err = run(["stability-map", "--alpha", "pi/2", "--modal", "2"], capsys)
    assert_refused(code, out, err, "--alpha", "--alphas")


def test_a_subcommand_that_fails_to_import_fails_loudly(monkeypatch):
    import fempipe.cli as cli

    monkeypatch.setitem(cli.SUBCOMMANDS, "broken", ("fempipe.cli.no_such_module", "broken"))
    with pytest.raises(ModuleNotFoundError, match="no_such_module"):
        cli.build_parser()


def test_every_solver_failure_exits_1_with_one_line(monkeypatch, capsys):
    """A SolverError of any solver is caught once, in main."""
    import fempipe.analyses.limit_cycle
    from fempipe.core.errors import SolverError

    def fail(*args, **kwargs):
        raise SolverError("shooting did not converge\n  at v = 9")

    monkeypatch.setattr(fempipe.analyses.limit_cycle, "find_attractor", fail)
    code, out, err = run(["simulate", "--modal", "2", "--v", "9"], capsys)
    assert code == 1 and out == ""
    assert err.strip().splitlines() == [
        "fempipe simulate: error: shooting did not converge at v = 9"
    ]


@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_sigterm_and_sigint_end_the_command_with_one_line(signum, code, monkeypatch, capsys):
    import fempipe.analyses.statics

    def interrupted(*args, **kwargs):
        os.kill(os.getpid(), signum)
        raise AssertionError("the signal did not interrupt")  # pragma: no cover

    monkeypatch.setattr(fempipe.analyses.statics, "solve_path", interrupted)
    # as from a terminal: Ctrl-C not ignored (a job started with & in a script inherits SIG_IGN)
    previous = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        got, out, err = run(["static", "--v", "0,1"], capsys)
    finally:
        signal.signal(signal.SIGINT, previous)
    assert got == code and out == ""
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err
    assert signal.Signals(signum).name in err
    # The handlers are restored: SIGTERM is back to its default.
    assert signal.getsignal(signal.SIGTERM) == signal.SIG_DFL


def test_wrote_lines_are_exactly_the_files_written(tmp_path, capsys):
    out_dir = tmp_path / "out"
    code, out, err = run(
        ["static", "--alpha", "pi/2", "--v", "0,1", "--fe", "P2:4", "--out", str(out_dir)], capsys
    )
    assert code == 0, err
    wrote = {line.removeprefix("wrote ") for line in err.splitlines() if line.startswith("wrote ")}
    assert wrote == {str(p) for p in out_dir.iterdir()}
    assert len(wrote) == 4


def test_cli_startup_does_not_import_plotting_or_io_libraries():
    """``fempipe --help`` stays fast: matplotlib, meshio, tqdm are imported where used."""
    code = (
        "import sys; from fempipe.cli import build_parser; build_parser(); "
        "print(sorted(m for m in ('matplotlib', 'meshio', 'tqdm') if m in sys.modules))"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert res.stdout.strip() == "[]"


# ---------------------------------------------------------------- variants --
@pytest.mark.parametrize(
    "command, argv, option, words",
    [
        ("static", ["--end-mass", "-0.1"], "--end-mass", ("0 <= --end-mass",)),
        ("critical", ["--end-mass", "1e3"], "--end-mass", ("<= 100",)),
        ("critical", ["--external-damping", "-1"], "--external-damping", ()),
        ("spectrum", ["--hysteretic-damping", "-0.01"], "--hysteretic-damping", ()),
        ("critical", ["--hysteretic-damping", "2"], "--hysteretic-damping", ("<= 1",)),
        ("static", ["--spring=-5@0.5"], "--spring", ("kappa",)),
        ("static", ["--spring", "5@0"], "--spring", ("0 < xi_s <= 1",)),
        ("static", ["--spring", "5@1.2"], "--spring", ("0 < xi_s <= 1",)),
        ("static", ["--spring", "5"], "--spring", ("KAPPA@XI_S",)),
        ("static", ["--spring", "five@0.5"], "--spring", ()),
        ("simulate", ["--hysteretic-damping", "0.01"], "--hysteretic-damping", ("time-domain",)),
        ("bifurcation", ["--hysteretic-damping", "0.01"], "--hysteretic-damping", ("time-domain",)),
        ("static", ["--end-mass-kg", "0.01"], "--end-mass-kg", ("SI pipe",)),
        (
            "static",
            [*TD_ARGS, "--end-mass-kg", "0.01", "--end-mass", "0.1"],
            "--end-mass-kg",
            ("not both",),
        ),
        ("static", [*TD_ARGS, "--end-mass-kg", "-1"], "--end-mass-kg", ()),
    ],
)
def test_bad_variant_values_are_refused(command, argv, option, words, capsys, no_compute):
    code, out, err = run([command, *argv], capsys)
    assert_refused(code, out, err, option, *words)

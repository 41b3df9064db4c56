"""The command line at its edges: output paths, partial writes, cut ranges, signals, silence.

In-process through ``fempipe.cli.main(argv)`` where possible; the signal
test runs the command in a subprocess and interrupts it for real.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from fempipe.cli import main

CHEAP = ["static", "--v", "0,1", "--modal", "2"]


def run(argv, capsys):
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    return lines[0]


class ComputeStartedError(Exception):
    """Raised by a stand-in solver: the command started computing."""


@pytest.fixture
def no_compute(monkeypatch):
    import fempipe.analyses.statics

    def computed(*args, **kwargs):
        raise ComputeStartedError

    monkeypatch.setattr(fempipe.analyses.statics, "solve_path", computed)


# ---------------------------------------------------------------- --out --
@pytest.mark.parametrize("kind", ["file", "under_file", "empty", "proc"])
def test_unusable_out_is_refused_before_any_work(kind, tmp_path, monkeypatch, capsys, no_compute):
    monkeypatch.chdir(tmp_path)
    Path("f").write_text("x")
    out = {"file": "f", "under_file": "f/sub", "empty": "", "proc": "/proc/fempipe-x/y"}[kind]
    code, stdout, err = run([*CHEAP, "--out", out], capsys)
    assert code == 2 and stdout == ""
    line = one_line(err)
    assert line.startswith("fempipe static: error: --out: ")
    # Nothing was written into the current directory.
    assert sorted(os.listdir()) == ["f"]


def test_an_unwritable_out_is_found_before_computing(tmp_path, capsys, no_compute):
    if os.geteuid() == 0:
        pytest.skip("root may write into a read-only directory")
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o500)
    code, _, err = run([*CHEAP, "--out", str(ro / "x")], capsys)
    assert code == 2 and "--out" in one_line(err)


def test_a_clash_in_out_writes_no_file_of_the_run(tmp_path, capsys):
    """A directory where a result file goes: exit 2, one line, and no other file appears."""
    out = tmp_path / "o"
    (out / "shapes.png").mkdir(parents=True)
    code, _, err = run([*CHEAP, "--out", str(out)], capsys)
    assert code == 2
    assert "--out" in one_line(err) and "shapes.png" in err
    assert sorted(p.name for p in out.iterdir()) == ["shapes.png"]


def test_a_write_that_fails_part_way_leaves_the_directory_as_it_was(tmp_path, monkeypatch, capsys):
    import fempipe.io

    out = tmp_path / "o"
    out.mkdir()
    (out / "static.json").write_text("old")
    real = fempipe.io.write_figure

    def disk_full(path, fig, **kw):
        real(path, fig, **kw)
        raise OSError(28, "No space left on device", str(path))

    monkeypatch.setattr(fempipe.io, "write_figure", disk_full)
    code, _, err = run([*CHEAP, "--out", str(out)], capsys)
    assert code == 1
    assert "No space left on device" in one_line(err)
    # The old file is untouched, no new file and no staging directory is left.
    assert [p.name for p in out.iterdir()] == ["static.json"]
    assert (out / "static.json").read_text() == "old"


# ------------------------------------------------------------- critical --
def _short_budget(monkeypatch, seen: dict, cap: int | None):
    import fempipe.analyses.stability

    real = fempipe.analyses.stability.analyse_stability  # --planar and both planes

    def analysis(model, **kw):
        seen.update(kw)
        if cap is not None:
            kw["max_steps"] = cap
        return real(model, **kw)

    monkeypatch.setattr(fempipe.analyses.stability, "analyse_stability", analysis)


def test_critical_step_budget_follows_the_range(monkeypatch, capsys):
    seen: dict = {}
    _short_budget(monkeypatch, seen, cap=40)
    argv = ["critical", "--modal", "2", "--v", "0,2", "--ds-max", "0.0005", "--no-branches"]
    code, out, err = run([*argv, "--json"], capsys)
    # The budget given to the library covers the range at --ds-max ...
    assert seen["max_steps"] * seen["ds_max"] >= 2.0
    # ... and a range that was not covered (here: budget cut to 40 steps) is
    # a warning and exit 1, not a silent exit 0.
    assert code == 1
    line = one_line(err)
    assert "warning" in line and "--allow-partial" in line
    assert '"end_reason": "max_steps"' in out


def test_critical_allow_partial_accepts_a_cut_range(monkeypatch, capsys):
    _short_budget(monkeypatch, {}, cap=40)
    argv = ["critical", "--modal", "2", "--v", "0,2", "--ds-max", "0.0005", "--no-branches"]
    code, _, err = run([*argv, "--allow-partial", "--quiet"], capsys)
    assert code == 0
    assert "ran out of continuation steps" in one_line(err)


# -------------------------------------------------------------- signals --
@pytest.mark.parametrize("signum, code", [(signal.SIGINT, 130), (signal.SIGTERM, 143)])
def test_a_real_signal_ends_a_running_command_with_one_line(signum, code, tmp_path):
    """A real SIGINT/SIGTERM during a two-worker map: one line, 130/143, --out untouched."""
    out = tmp_path / "o"
    cmd = [
        sys.executable,
        "-m",
        "fempipe",
        "stability-map",
        "--alphas",
        "0:pi:400",  # ~20 s on 2 cores (40 took < 6 s): still running at the signal
        "--workers",
        "2",
        "--out",
        str(out),
        "--quiet",
    ]
    # as from a terminal: Ctrl-C not ignored (a job started with & in a script inherits SIG_IGN)
    proc = subprocess.Popen(
        cmd,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )
    time.sleep(6.0)
    assert proc.poll() is None, proc.communicate()
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == code, err
    line = one_line(err)
    assert line.startswith("fempipe stability-map: interrupted by ")
    assert not out.exists() or list(out.iterdir()) == []


# ------------------------------------------------------------- progress --
def test_progress_lines_outside_a_terminal(monkeypatch, capsys):
    """stderr is not a terminal under pytest: plain progress lines, not silence."""
    import importlib

    try:  # a line at every update (the interval is 20 s)
        reporting = importlib.import_module("fempipe.cli.reporting")
        monkeypatch.setattr(reporting, "LOG_INTERVAL", 0.0)
    except ModuleNotFoundError:  # the layout before progress lines existed
        pass
    code, _, err = run(["static", "--v", "0:1:3", "--modal", "2"], capsys)
    assert code == 0
    lines = [s for s in err.splitlines() if s.startswith("fempipe: static (v): ")]
    assert [s.split(": ")[2].split()[0] for s in lines] == ["1/3", "2/3", "3/3"]
    # --quiet silences them.
    code, _, err = run(["static", "--v", "0:1:3", "--modal", "2", "--quiet"], capsys)
    assert code == 0 and err == ""


# ------------------------------------------------------------- messages --
@pytest.mark.parametrize(
    "argv, start",
    [
        (["static", "--bogus"], "fempipe static: error: --bogus: "),
        (["critical", "--v", "0,1", "--frobnicate", "3"], "fempipe critical: error: --frobnicate"),
        (["static", "--g", "9.8", "--v", "0,1"], "fempipe static: error: --g: "),
        (["static", "--fe", "P3:4", "--modal", "3"], "fempipe static: error: --modal: "),
    ],
)
def test_every_error_has_the_one_form(argv, start, capsys, no_compute):
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    assert one_line(err).startswith(start), err


# ------------------------------------------------------ documented facts --
def test_validate_does_not_write_into_the_committed_report_by_default():
    from fempipe.cli import build_parser
    from fempipe.cli.validate import DEFAULT_OUT

    args = build_parser().parse_args(["validate"])
    assert args.out is None
    assert Path(DEFAULT_OUT).parts[:2] != ("validation", "report")
    # ... and the default folder is ignored by git.
    assert _ignored(Path(DEFAULT_OUT) / "REPORT.md")


def test_readme_example_output_folders_are_ignored_by_git():
    """... in the README and the docs pages, whose examples a user runs in the tree."""
    import re

    root = Path(__file__).resolve().parents[1]
    pages = [root / "README.md", *sorted((root / "docs").rglob("*.md"))]
    text = "\n".join(p.read_text(encoding="utf-8") for p in pages)
    found = re.findall(r"--out ([a-z][\w.-]*(?:/[\w.-]+)*)/?(?=[\s`]|$)", text)
    folders = set(found) - {"validation/report"}
    assert folders
    for folder in sorted(folders):
        assert _ignored(Path(folder) / "x.json"), folder


def _ignored(path: Path) -> bool:
    """Whether a top-level pattern of the repository's .gitignore ignores ``path``.

    Read from the file itself (CI tests a copy of the tree without .git): the
    patterns for output folders are anchored directories, ``/name/`` or
    ``/glob-*/``, which ignore everything below a matching first component.
    """
    import fnmatch

    root = Path(__file__).resolve().parents[1]
    patterns = [
        line.strip()
        for line in (root / ".gitignore").read_text(encoding="utf-8").splitlines()
        if line.strip() and not line.startswith("#")
    ]
    first = path.parts[0]
    return any(
        p.startswith("/") and p.endswith("/") and fnmatch.fnmatchcase(first, p.strip("/"))
        for p in patterns
    )


def test_the_gitignore_reader_can_say_no():
    assert not _ignored(Path("fempipe") / "cli" / "x.json")
    assert not _ignored(Path("validation") / "report" / "REPORT.md")


def test_bench_prints_nested_results_as_lines_not_a_python_dict(capsys):
    from fempipe.cli.bench import print_results

    print_results(
        {
            "environment": {"python": "3"},
            "quick": True,
            "benchmarks": {"fig07": {"wall_time": 1.5, "v_cr": {"P3:8": 1.25, "modal:4": 1.5}}},
        }
    )
    out = capsys.readouterr().out
    assert "{" not in out and "}" not in out
    assert "P3:8: 1.25" in out


def test_static_json_says_which_point_includes_the_gravity_loading(capsys):
    import json

    code, out, _ = run([*CHEAP, "--json"], capsys)
    assert code == 0
    points = json.loads(out)["points"]
    assert [p["includes_gravity_loading"] for p in points] == [True, False]
    assert all("newton_iterations" in p for p in points)


# ------------------------------------------------------------- simulate --
def test_simulate_refuses_a_run_projected_to_take_too_long(monkeypatch, capsys):
    """v = 20: the projection from the first seconds refuses the run with its reason."""
    import fempipe.cli.simulate as sim

    monkeypatch.setattr(sim, "PROJECT_AFTER", 0.2, raising=False)
    monkeypatch.setattr(sim, "CPU_LIMIT", 1.0, raising=False)
    argv = ["simulate", "--v", "20", "--modal", "3", "--t-max", "300", "--no-shooting"]
    code, out, err = run(argv, capsys)
    assert code == 2 and out == ""
    line = one_line(err)
    assert "--t-max" in line and "min" in line and "--allow-large" in line


def test_simulate_writes_the_tip_time_series(tmp_path, capsys):
    """tip.csv: tau, theta(1), eta(1), X_g(1), Z_g(1) and rates; --output-dt a uniform grid.

    The rates are checked against finite differences of the positions on the
    uniform grid (independent of the analytic tip velocity).
    """
    import numpy as np

    from fempipe.io import read_csv

    argv = ["simulate", "--v", "3", "--alpha", "pi/2", "--modal", "3", "--t-max", "4"]
    assert main([*argv, "--no-shooting", "--out", str(tmp_path), "--output-dt", "0.002"]) == 0
    capsys.readouterr()
    cols = read_csv(tmp_path / "tip.csv")
    assert list(cols)[:5] == ["tau", "theta_tip", "eta_tip", "X_tip", "Z_tip"]
    tau = cols["tau"]
    np.testing.assert_allclose(np.diff(tau), 0.002, rtol=0, atol=1e-12)
    assert tau[0] == 0.0 and tau.size > 40
    for name in ("theta_tip", "eta_tip", "X_tip", "Z_tip"):
        fd = np.gradient(cols[name], tau)[2:-2]
        rate = cols[f"{name}_rate"][2:-2]
        scale = np.abs(rate).max()
        assert scale > 0
        assert np.abs(fd - rate).max() < 1e-2 * scale, name
    # The horizontal pipe: X_g along gravity, the tip below the clamp.
    assert np.all(cols["X_tip"] > 0)


# ------------------------------------------------------------ CSV files --
def test_events_csv_is_sorted_by_v(tmp_path, capsys):
    """alpha = pi: the primary branch's events and the folds of its child branches, interleaved."""
    from fempipe.io import read_csv

    argv = ["critical", "--alpha", "pi", "--v", "0,6", "--modal", "3", "--out", str(tmp_path)]
    assert main([*argv, "--quiet"]) == 0
    capsys.readouterr()
    cols = read_csv(tmp_path / "events.csv")
    v = cols["v"].tolist()
    assert len(set(cols["branch"])) > 1  # events of more than one branch
    assert v == sorted(v)


def test_spectrum_csv_names_the_pair_member_and_the_system_stability(tmp_path, capsys):
    from collections import Counter

    from fempipe.io import read_csv

    argv = ["spectrum", "--alpha", "pi", "--v", "0:6:4", "--modal", "3", "--out", str(tmp_path)]
    assert main([*argv, "--quiet"]) == 0
    capsys.readouterr()
    cols = read_csv(tmp_path / "spectrum.csv")
    rows = [dict(zip(cols, values, strict=True)) for values in zip(*cols.values(), strict=True)]
    # The old columns are kept, the new ones added.
    assert {"v", "mode", "lambda_re", "lambda_im", "stable"} <= set(rows[0])
    assert all(r["system_stable"] == r["stable"] for r in rows)
    # Each mode is a pair of eigenvalues at each v: members 1 and 2, and an
    # index that numbers the eigenvalues at each v from 0.
    members = Counter((r["v"], r["mode"]) for r in rows)
    assert set(members.values()) == {2}
    for (v, mode), _ in members.items():
        got = sorted(r["pair_member"] for r in rows if (r["v"], r["mode"]) == (v, mode))
        assert got == [1, 2]
    for v in {r["v"] for r in rows}:
        idx = [int(r["eigenvalue_index"]) for r in rows if r["v"] == v]
        assert idx == list(range(len(idx)))
    # system_stable is the whole system's: False as soon as any eigenvalue has Re > 0.
    for v in {r["v"] for r in rows}:
        at_v = [r for r in rows if r["v"] == v]
        unstable = any(float(r["lambda_re"]) > 0 for r in at_v)
        assert all(r["system_stable"] == (not unstable) for r in at_v)

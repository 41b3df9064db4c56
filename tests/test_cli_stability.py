"""``fempipe spectrum``, ``fempipe critical``, ``fempipe stability-map``: in-process CLI tests."""

import json
import math

import numpy as np
import pytest
from clirun import run_json

from fempipe import FiniteElement, Params, PipeModel
from fempipe.analyses.stability import find_critical_velocity
from fempipe.analyses.stability.hopf import EVENT_KEYS as HOPF_KEYS
from fempipe.cli import main

EVENT_KEYS = {
    "v",
    "type",
    "branch",
    "frequency",
    "mode",
    "stable_before",
    "stable_after",
    "plane",
}
EVENT_TYPES = {"flutter", "divergence", "restabilization", "mode_restabilization", "fold"}


def test_critical_json_contract(capsys):
    """The --json contract of the docs, and v_cr equal to the library's."""
    d = run_json(capsys, ["critical", "--alpha", "pi/2", "--v", "0,8", "--json", "--quiet"])
    assert isinstance(d["v_cr"], float)
    # Flutter events also carry the Hopf keys (fempipe.analyses.stability.hopf.EVENT_KEYS).
    hopf = set(HOPF_KEYS)
    assert d["events"] and all(
        set(e) == EVENT_KEYS | (hopf if e["type"] == "flutter" else set()) for e in d["events"]
    )
    assert all(e["type"] in EVENT_TYPES for e in d["events"])
    first = d["events"][0]
    assert first["type"] == "flutter" and first["mode"] == 2 and first["branch"] == "primary"
    assert first["stable_before"] is True and first["stable_after"] is False
    assert first["frequency"] > 0
    # v_cr is the first loss of stability in 3-D: out of the plane at alpha = pi/2
    # (docs, "Out of the plane"); the in-plane one is the planar library's.
    model = PipeModel(FiniteElement(16, 3), Params(alpha=math.pi / 2))
    lib = find_critical_velocity(model, 8.0)
    out = find_critical_velocity(model, 8.0, planes=("out",))
    assert first["plane"] == "out" and d["first_instability"]["plane"] == "out"
    assert d["v_cr_in_plane"] == pytest.approx(lib.v_cr, abs=1e-12)
    assert d["v_cr"] == d["v_cr_out_of_plane"] == pytest.approx(out.v_cr, abs=1e-9)
    assert d["discretization"]["n_elements"] == 16 and d["params"]["gamma"] == 18.9


def test_critical_alpha_pi_lists_start_events_and_branches(capsys, tmp_path):
    """alpha = pi: the divergence present at v = 0 is listed at v = 0; the buckled
    branches and their folds are reported; files are written."""
    d = run_json(
        capsys,
        ["critical", "--alpha", "pi", "--v", "0,6", "--json", "--quiet", "--out", str(tmp_path)],
    )
    assert d["v_cr"] == 0.0
    prim = [e for e in d["events"] if e["branch"] == "primary" and e["plane"] == "in"]
    assert [e["type"] for e in prim] == ["divergence", "restabilization", "flutter"]
    assert prim[0]["v"] == 0.0
    # The straight column: out of the plane the same events (every plane alike).
    out = [e for e in d["events"] if e["branch"] == "primary" and e["plane"] == "out"]
    assert [e["type"] for e in out] == [e["type"] for e in prim]
    assert max(abs(a["v"] - b["v"]) for a, b in zip(out, prim, strict=True)) < 1e-9
    # The buckled branches are stable out of their plane (the neutral rotation aside).
    assert not [e for e in d["events"] if e["branch"] != "primary" and e["plane"] == "out"]
    folds = [e for e in d["events"] if e["type"] == "fold"]
    assert {e["branch"] for e in folds} == {"B1+", "B1-"}
    assert {b["name"] for b in d["branches"]} == {"primary", "B1+", "B1-"}
    for name in ("critical.json", "events.csv", "branches.png"):
        assert (tmp_path / name).stat().st_size > 0
    assert json.loads((tmp_path / "critical.json").read_text())["v_cr"] == 0.0


def test_critical_si_pipe_reports_U_cr(capsys):
    """Texier-Dorbolo's pipe (the paper's Sec. 3.1) in SI units: U_cr = v_cr / 1.6874 m/s."""
    argv = ["critical", "--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058"]
    argv += ["--alpha", "90deg", "--U", "0,6", "--no-branches", "--json", "--quiet"]
    d = run_json(capsys, argv)
    assert d["U_cr"] == pytest.approx(d["v_cr"] / (math.sqrt(0.0058 / 1.8e-5) * 0.094), rel=1e-12)


def test_spectrum_json_and_files(capsys, tmp_path):
    argv = ["spectrum", "--alpha", "0", "--v", "0:8:9", "--modal", "4", "--json", "--quiet"]
    d = run_json(capsys, argv + ["--out", str(tmp_path)])
    assert [p["v"] for p in d["points"]] == pytest.approx(np.linspace(0, 8, 9))
    assert d["points"][0]["stable"] and not d["points"][-1]["stable"]
    e = d["points"][0]["eigenvalues"][0]
    # The paper's convention: Omega = -i lambda.
    assert e["Omega_re"] == e["im"] and e["Omega_im"] == -e["re"]
    for name in ("spectrum.json", "spectrum.csv", "argand.png"):
        assert (tmp_path / name).stat().st_size > 0
    rows = (tmp_path / "spectrum.csv").read_text().splitlines()
    assert rows[0].startswith("v [1],mode [-],lambda_re [1/T]")


def test_spectrum_table(capsys):
    assert main(["spectrum", "--v", "0,1", "--modes", "2", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert "mode 2" in out and "mode 3" not in out


def test_stability_map_parallel(capsys, tmp_path):
    argv = ["stability-map", "--alphas", "0,pi/2", "--betas", "0.142,0.3", "--modal", "4"]
    argv += ["--workers", "2", "--json", "--quiet", "--out", str(tmp_path)]
    d = run_json(capsys, argv)
    assert len(d["points"]) == 4 and len(d["curves"]) == 2
    assert all(p["type"] == "flutter" and p["mode"] == 2 for p in d["points"])
    for name in ("stability_map.json", "stability_map.csv", "stability_map.png"):
        assert (tmp_path / name).stat().st_size > 0


@pytest.mark.parametrize(
    ("argv", "option"),
    [
        (["spectrum", "--modes", "0"], "--modes"),
        (["spectrum", "--fe", "P1:1"], "--fe"),
        (["critical", "--v", "3"], "--v"),
        (["critical", "--ds-max", "-1"], "--ds-max"),
        (["stability-map", "--alphas", "north"], "--alphas"),
        (["stability-map", "--betas", "2"], "--betas"),
        (["stability-map", "--workers", "0"], "--workers"),
        (["stability-map", "--v", "1,5"], "--v"),
    ],
)
def test_bad_input_one_line_exit_2(capsys, argv, option):
    assert main(argv + ["--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1
    assert err[0].startswith(f"fempipe {argv[0]}: error: {option}")


def test_critical_refuses_a_range_that_runs_downwards(capsys):
    """``--v 5:3:4`` was swapped silently: now exit 2, naming the option and the order."""
    assert main(["critical", "--alpha", "0", "--v", "5:3:4", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert "--v" in err and "downwards" in err and "give 3 first" in err


def test_critical_without_events_says_so(capsys):
    """No event over the range: a sentence with the range, not an empty table header."""
    assert main(["critical", "--alpha", "0", "--v", "0:3:2", "--quiet", "--fe", "P3:4"]) == 0
    out = capsys.readouterr().out
    assert "events: none (no eigenvalue crosses Re lambda = 0 for 0 <= v <= 3)" in out
    assert "system below -> above" not in out


def test_critical_defines_its_mode_numbers(capsys):
    assert main(["critical", "--alpha", "pi/2", "--v", "0,8", "--quiet", "--fe", "P3:4"]) == 0
    out = capsys.readouterr().out
    assert "flutter in mode 2" in out
    assert "mode k: the eigenvalue that is the k-th natural mode of the pipe without flow" in out

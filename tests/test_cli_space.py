"""``fempipe simulate --3d`` and the planar simulate's 3-D verdict, in-process."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from fempipe.cli import main
from fempipe.io import read_csv


def test_simulate_3d_writes_its_files(tmp_path, capsys):
    out = tmp_path / "run"
    args = ["simulate", "--3d", "--alpha", "1.2", "--v", "3", "--fe", "P2:2", "--t-max", "0.5"]
    assert main(args + ["--json", "--out", str(out)]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["model"] == "3d"
    assert r["motion"] in ("planar", "nonplanar")
    assert set(r["tip"]) == {"eta_tip", "X_tip", "Z_tip", "Y_tip"}
    assert max(map(abs, r["tip"]["Y_tip"])) > 1e-4  # the perturbation left the plane
    tip = read_csv(out / "tip.csv")
    assert tip["tau"][-1] == pytest.approx(0.5)
    assert np.abs(tip["Y_tip"]).max() > 0
    frames = sorted((out / "trajectory").glob("*.vtu"))
    mesh = meshio.read(frames[-1])
    # the frame of every file: gravity -y, the static plane x-y, out of plane +z
    assert np.allclose(mesh.point_data["Y_g"], mesh.points[:, 2])
    assert np.allclose(mesh.points[:, 1], -mesh.point_data["X_g"])
    assert mesh.points[-1, 2] == pytest.approx(tip["Y_tip"][-1], abs=1e-12)
    for name in ("simulate.json", "tip_orbit.png", "snapshots_3d.png", "trajectory.pvd"):
        assert (out / name).stat().st_size > 0


def test_simulate_3d_text_names_the_cycle_multipliers_and_frequencies(capsys):
    from fempipe.cli.simulate import _summary_3d

    r = {
        "params": {"alpha": 1.57, "beta": 0.142, "gamma": 18.9, "mu": 0.005, "v": 6.5},
        "attractor": "periodic",
        "motion": "nonplanar",
        "period": 0.42,
        "tip": {"Y_tip": [-0.4, 0.4]},
        "floquet_multipliers": [[1.0, 0.0], [0.0, 0.7554], [0.2, 0.0]],
        "stable": True,
        "planarity": 14.3,
        "steps": 10,
        "rejected_steps": 0,
        "t_end": 3.9,
        "cpu_time": 1.0,
    }
    _summary_3d(r)
    assert "|Floquet multipliers| 1, 0.7554, 0.2 (stable)" in capsys.readouterr().out
    _summary_3d(r | {"stable": False, "attractor": "quasi-periodic", "frequencies": [1.5, 2.25]})
    text = capsys.readouterr().out
    assert "(unstable)" in text and "frequencies 1.5, 2.25" in text


def test_simulate_3d_refuses_a_pulsating_flow(capsys):
    code = main(["simulate", "--3d", "--sigma", "0.1", "--omega", "3", "--fe", "P2:2"])
    assert code != 0
    assert "--sigma" in capsys.readouterr().err


def test_planar_simulate_says_whether_its_cycle_survives_in_3d(capsys):
    args = ["simulate", "--alpha", "0", "--v", "10", "--fe", "P3:4", "--json"]
    assert main(args) == 0
    r = json.loads(capsys.readouterr().out)
    mus = [complex(a, b) for a, b in r["out_of_plane_floquet_multipliers"]]
    # alpha = 0: the cycle turned about the vertical is a cycle, a multiplier 1 (to the
    # discretization error of P3:4, 2e-3)
    assert min(abs(m - 1) for m in mus) < 5e-3
    # that multiplier is reported on its own, with its distance from 1 (no warning: FE keep
    # the symmetry to better than 1e-2)
    neutral = complex(*r["neutral_out_of_plane_multiplier"])
    assert neutral == min(mus, key=lambda m: abs(m - 1))
    assert r["out_of_plane_symmetry_defect"] == pytest.approx(abs(neutral - 1), rel=1e-12)
    assert "stable_3d_note" not in r
    in_plane = r["max_nontrivial_multiplier"] < 1
    assert r["stable_3d"] == (r["max_nontrivial_out_of_plane_multiplier"] < 1 and in_plane)
    assert main(args + ["--planar"]) == 0
    assert "stable_3d" not in json.loads(capsys.readouterr().out)


def test_planar_simulate_warns_that_few_sine_modes_give_rough_3d_verdicts(capsys):
    """Three sine modes break the rotation symmetry of the hanging pipe: the neutral
    multiplier (exactly 1 in the continuum, 1 - 2e-3 on P3:4 above) is more than 1e-2 from
    1, and the JSON and the text say that the verdict is rough."""
    from fempipe.cli.simulate import _print_summary

    assert main(["simulate", "--alpha", "0", "--v", "10", "--modal", "3", "--json"]) == 0
    r = json.loads(capsys.readouterr().out)
    assert r["out_of_plane_symmetry_defect"] > 1e-2
    assert "modal:3" in r["stable_3d_note"]
    _print_summary(r)  # the text output of the same run
    assert "note: the neutral multiplier" in capsys.readouterr().out


def test_rough_verdict_note_names_the_discretization_and_the_defect():
    from fempipe.analyses.three_d.verdict import ROUGH_DEFECT, rough_verdict_note

    assert rough_verdict_note("P3:8", 1.5e-5) is None
    assert rough_verdict_note("P3:8", None) is None
    assert "P2:2" in rough_verdict_note("P2:2", 2 * ROUGH_DEFECT)
    # a few modes are rough even where no symmetry measures it (alpha not 0 or pi)
    assert "modal:4" in rough_verdict_note("modal:4", None)


# --- bifurcation: which planar states survive in 3-D, and the 3-D sweep -------------

PLANAR_CHEAP = ["--fe", "P2:2", "--quiet", "--json"]


@pytest.fixture
def fake_floquet(monkeypatch):
    """The out-of-plane monodromy replaced by a stand-in (its multiplier v - 5.6, so that
    it crosses 1 at v = 6.6), counting its calls: the plumbing without the ~2 s per orbit."""
    import fempipe.analyses.periodic.out_of_plane as oop
    from fempipe.analyses.three_d import OutOfPlaneFloquet

    calls = []

    def fake(model, cycle, rtol=1e-7):
        calls.append(model.params.v)
        rho = model.params.v - 5.6
        mu = np.array([rho, 0.1], dtype=complex)
        return OutOfPlaneFloquet(
            multipliers=mu,
            planar_multipliers=np.asarray(cycle.floquet_multipliers),
            axisymmetric=False,
            trivial=None,
            max_nontrivial=abs(rho),
            stable=abs(rho) < 1,
            gauge_largest=0.0,
            steps=0,
            cpu_time=0.0,
        )

    monkeypatch.setattr(oop, "compute_out_of_plane_floquet", fake)
    return calls


def test_bifurcation_keeps_the_3d_verdicts_with_its_points(tmp_path, capsys, fake_floquet):
    """Continuation: every orbit gains its out-of-plane multipliers and stable_3d (stable
    in the plane and out of it), every equilibrium its out-of-plane verdict; they are
    kept in the point store (a rerun computes none) and --planar leaves them out."""
    out = tmp_path / "bif"
    argv = ["bifurcation", "--alpha", "0", "--v", "6,7", *PLANAR_CHEAP, "--out", str(out)]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    cycles = [p for p in d["points"] if p["attractor"] == "periodic"]
    static = [p for p in d["points"] if p["attractor"] == "equilibrium"]
    assert cycles and static
    assert len(fake_floquet) == len(cycles)  # every orbit, stable or not
    for p in cycles:
        mu = p["max_nontrivial_out_of_plane_multiplier"]
        assert mu == pytest.approx(abs(p["v"] - 5.6))
        assert p["out_of_plane_floquet_multipliers"][0] == [pytest.approx(p["v"] - 5.6), 0.0]
        assert p["stable_out_of_plane"] == (mu < 1)
        assert p["stable_3d"] == (p["stable"] and mu < 1)
    assert {p["stable_3d"] for p in cycles} == {True, False}
    for p in static:
        # alpha = 0: the pipe hangs straight, and a straight pipe has the same spectrum in
        # every plane through its axis (symmetry): the out-of-plane verdict is the planar one.
        assert p["stable_out_of_plane"] == p["stable"]
        assert p["stable_3d"] == p["stable"]
    stored = sorted((out / "points").glob("*-3d.json"))
    assert len(stored) == 2  # the static branch's and the orbits'
    mtimes = [f.stat().st_mtime_ns for f in stored]
    assert main(argv) == 0  # resumes: every verdict from the store
    again = json.loads(capsys.readouterr().out)
    assert len(fake_floquet) == len(cycles)
    assert [f.stat().st_mtime_ns for f in stored] == mtimes
    assert [p["stable_3d"] for p in again["points"]] == [p["stable_3d"] for p in d["points"]]
    assert main(["bifurcation", "--alpha", "0", "--v", "6,7", *PLANAR_CHEAP, "--planar"]) == 0
    planar = json.loads(capsys.readouterr().out)
    assert not any("stable_3d" in p for p in planar["points"])
    from fempipe.cli.bifurcation import _print_table

    _print_table(d)  # the plain table gains the column
    lines = capsys.readouterr().out.splitlines()
    assert lines[0].split()[-1] == "3d"
    row = {True: "yes", False: "no"}
    assert [ln.split()[-1] for ln in lines[1 : 1 + len(d["points"])]] == [
        row[p["stable_3d"]] for p in d["points"]
    ]


def test_bifurcation_sweep_reports_stable_3d_of_its_attractors(tmp_path, capsys, fake_floquet):
    """Sweep: the periodic attractor's verdict from its out-of-plane multipliers, the
    equilibrium's from the out-of-plane spectrum; a planar run's store gains them on
    a rerun without --planar."""
    out = tmp_path / "sw"
    argv = ["bifurcation", "--method", "sweep", "--alpha", "0", "--v", "5,7", "--directions"]
    argv += ["up", *PLANAR_CHEAP, "--out", str(out)]
    assert main([*argv, "--planar"]) == 0
    assert "stable_3d" not in json.loads(capsys.readouterr().out)["points"][1]
    assert main(argv) == 0
    eq, cyc = json.loads(capsys.readouterr().out)["points"]
    assert eq["attractor"] == "equilibrium" and cyc["attractor"] == "periodic"
    assert eq["stable_3d"] is True  # the straight hanging pipe below flutter, in any plane
    assert cyc["max_nontrivial_out_of_plane_multiplier"] == pytest.approx(7 - 5.6)
    assert cyc["stable_3d"] is False
    assert fake_floquet == [7.0]


@pytest.mark.slow
def test_bifurcation_3d_verdicts_agree_with_the_planar_monodromy(capsys):
    """The real out-of-plane monodromy: its planar block is the planar orbit's monodromy
    (the same equations integrated on the 3-D model), so the largest non-trivial
    multipliers agree.  (The neutral multiplier of the rotation about the vertical is
    not resolved on P2:2, 0.98 + 0.01i; the validation case fig07 checks it on P3:8.)"""
    argv = ["bifurcation", "--alpha", "0", "--v", "6,7", *PLANAR_CHEAP]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    cycles = [p for p in d["points"] if p["attractor"] == "periodic"]
    for p in cycles:
        assert p["planar_block_max_multiplier"] == pytest.approx(p["max_multiplier"], abs=1e-3)
        assert p["stable_3d"] == (p["stable"] and p["max_nontrivial_out_of_plane_multiplier"] < 1)


def test_bifurcation_3d_writes_points_diagrams_and_resumes(tmp_path, capsys):
    out = tmp_path / "b3"
    argv = ["bifurcation", "--3d", "--method", "sweep", "--alpha", "1.2", "--v", "3,4"]
    argv += ["--fe", "P3:3", "--t-max", "0.3", "--quiet", "--json", "--out", str(out)]
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert d["model"] == "3d" and len(d["points"]) == 4  # up and down
    for p in d["points"]:
        assert p["direction"] in ("up", "down")
        assert p["motion"] in ("planar", "nonplanar")
        assert p["attractor"] in (
            "equilibrium",
            "periodic",
            "whirl",
            "quasi-periodic",
            "non-periodic",
        )
        for k in ("eta_tip", "X_tip", "Z_tip", "Y_tip"):
            assert len(p[k]) == 2 and p[k][0] <= p[k][1]
        assert {"period", "whirl_rate", "started"} <= set(p)
    assert [p["v"] for p in d["points"]] == [3.0, 4.0, 4.0, 3.0]
    # each sweep's second point goes on from the first one's state unless it came to rest
    for first, second in (d["points"][:2], d["points"][2:]):
        expect = "static state" if first["attractor"] == "equilibrium" else "previous attractor"
        assert (first["started"], second["started"]) == ("static state", expect)
    for name in ("Y_tip.png", "eta_tip.png", "X_tip.png", "Z_tip.png", "bifurcation.json"):
        assert (out / name).stat().st_size > 0
    stored = sorted((out / "points").glob("space-*.json"))
    assert len(stored) == 4
    mtimes = [f.stat().st_mtime_ns for f in stored]
    assert main(argv) == 0  # resumes: nothing recomputed, the same points
    again = json.loads(capsys.readouterr().out)
    assert [f.stat().st_mtime_ns for f in stored] == mtimes
    assert again["points"] == d["points"]


@pytest.mark.parametrize(
    "extra, option",
    [
        (["--method", "continuation"], "--method"),
        (["--planar"], "--planar"),
        (["--alphas", "0,1"], "--alphas"),
        (["--workers", "2"], "--workers"),
    ],
)
def test_bifurcation_3d_refuses_options_without_meaning_in_3d(capsys, extra, option):
    code = main(["bifurcation", "--3d", "--fe", "P3:3", "--v", "3,4", *extra])
    err = capsys.readouterr().err
    assert code != 0 and option in err

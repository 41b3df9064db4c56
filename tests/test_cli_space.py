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
    in_plane = r["max_nontrivial_multiplier"] < 1
    assert r["stable_3d"] == (r["max_nontrivial_out_of_plane_multiplier"] < 1 and in_plane)
    assert main(args + ["--planar"]) == 0
    assert "stable_3d" not in json.loads(capsys.readouterr().out)

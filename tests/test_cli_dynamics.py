"""``fempipe simulate`` and ``fempipe bifurcation`` in-process (main(argv))."""

from __future__ import annotations

import json

import numpy as np
import pytest
from clirun import run_json

from fempipe.cli import main

# The cheapest flutter model (two sine modes) keeps these tests to seconds.
CHEAP = ["--modal", "2"]


def test_simulate_json_contract(capsys):
    d = run_json(capsys, ["simulate", *CHEAP, "--v", "9", "--json", "--quiet"])
    for key in (
        "attractor",
        "period",
        "tip",
        "floquet_multipliers",
        "steps",
        "rejected_steps",
        "wall_time",
    ):
        assert key in d
    assert d["attractor"] == "periodic"
    assert set(d["tip"]) == {"eta_tip", "X_tip", "Z_tip"}
    assert all(len(v) == 2 and v[0] <= v[1] for v in d["tip"].values())
    # the library gives the same cycle
    from fempipe import Modal, Params, PipeModel
    from fempipe.analyses.limit_cycle import find_attractor

    att = find_attractor(PipeModel(Modal(2), Params(v=9.0)))
    assert d["period"] == pytest.approx(att.period, rel=1e-6)


def test_simulate_equilibrium_below_flutter(capsys):
    d = run_json(capsys, ["simulate", *CHEAP, "--v", "3", "--json", "--quiet"])
    assert d["attractor"] == "equilibrium" and d["period"] is None


def test_simulate_pulsating_flow(capsys):
    d = run_json(
        capsys,
        [
            "simulate",
            *CHEAP,
            "--v",
            "3",
            "--sigma",
            "0.5",
            "--omega",
            "10",
            "--t-max",
            "2",
            "--json",
            "--quiet",
        ],
    )
    assert d["attractor"] == "forced" and d["flow"]["sigma"] == 0.5


def test_simulate_out_files(tmp_path, capsys):
    out = tmp_path / "run"
    d = run_json(capsys, ["simulate", *CHEAP, "--v", "9", "--json", "--quiet", "--out", str(out)])
    for name in (
        "simulate.json",
        "time_traces.png",
        "phase_portrait.png",
        "oscillating_shapes.png",
        "pipe.gif",
        "trajectory.pvd",
    ):
        assert (out / name).stat().st_size > 0, name
    assert json.loads((out / "simulate.json").read_text())["period"] == d["period"]
    # The trajectory reads back with meshio: line cells, theta and velocity per point.
    from fempipe.io.trajectory import read_trajectory

    times, meshes = read_trajectory(out / "trajectory.pvd")
    assert len(meshes) == times.size > 10 and np.all(np.diff(times) > 0)
    mesh = meshes[-1]
    assert mesh.cells[0].type == "line"
    assert {"theta", "theta_dot", "velocity"} <= set(mesh.point_data)
    # The clamp is at the origin and the centerline has unit length.
    pts = mesh.points
    assert np.allclose(pts[0], 0.0)
    assert np.sum(np.linalg.norm(np.diff(pts, axis=0), axis=1)) == pytest.approx(1.0, abs=1e-3)
    from PIL import Image

    with Image.open(out / "pipe.gif") as im:
        assert im.format == "GIF" and im.n_frames > 10


@pytest.mark.parametrize(
    "argv, option",
    [
        (["--rtol", "0"], "--rtol"),
        (["--mode", "0"], "--mode"),
        (["--sigma", "2"], "--sigma"),
        (["--t-max", "-1"], "--t-max"),
        (["--v", "1,2"], "--v"),
        (["--fe", "Q3"], "--fe"),
    ],
)
def test_simulate_bad_input(capsys, argv, option):
    code = main(["simulate", *argv])
    err = capsys.readouterr().err
    assert code == 2
    assert err.startswith("fempipe simulate: error:") and option in err
    assert err.count("\n") == 1


def test_bifurcation_json_contract_and_resume(tmp_path, capsys):
    out = tmp_path / "bif"
    argv = [
        "bifurcation",
        "--method",
        "sweep",
        *CHEAP,
        "--planar",
        "--v",
        "5,9",
        "--json",
        "--quiet",
        "--out",
        str(out),
        "--workers",
        "2",
    ]
    d = run_json(capsys, argv)
    assert len(d["points"]) == 4
    for p in d["points"]:
        assert {"v", "direction", "attractor", "eta_tip", "X_tip", "Z_tip", "period"} <= set(p)
        assert p["direction"] in ("up", "down")
    for name in ("eta_tip.png", "X_tip.png", "Z_tip.png", "bifurcation.json"):
        assert (out / name).stat().st_size > 0
    stored = sorted((out / "points").glob("a00-*.json"))
    assert len(stored) == 4
    mtimes = [p.stat().st_mtime_ns for p in stored]
    again = run_json(capsys, argv)  # resumes: nothing recomputed, same answer
    assert [p.stat().st_mtime_ns for p in stored] == mtimes
    assert [p["eta_tip"] for p in again["points"]] == [p["eta_tip"] for p in d["points"]]


def test_bifurcation_on_a_dask_cluster(capsys):
    """``--dask ADDRESS``: the two sweeps (up, down) run as two tasks on the cluster
    (here an in-process local cluster with one worker thread, on loopback) and
    give the points of the serial run."""
    from dask import distributed

    argv = [
        "bifurcation",
        "--method",
        "sweep",
        *CHEAP,
        "--v",
        "5,9",
        "--json",
        "--quiet",
        "--planar",
    ]
    with (
        distributed.LocalCluster(
            n_workers=1,
            threads_per_worker=1,
            processes=False,
            protocol="tcp://",
            host="127.0.0.1",
            dashboard_address=None,
        ) as cluster,
        distributed.Client(cluster) as observer,
        distributed.get_task_stream(client=observer) as tasks,
    ):
        d = run_json(capsys, [*argv, "--dask", cluster.scheduler_address])
    assert len(tasks.data) == 2  # one task per sweep, run by the cluster's worker
    serial = run_json(capsys, argv)

    def strip(points):  # timings differ from run to run
        return [
            {k: v for k, v in p.items() if k != "wall_time" and not k.endswith("cpu_time")}
            for p in points
        ]

    assert len(d["points"]) == 4
    assert strip(d["points"]) == strip(serial["points"])


@pytest.mark.parametrize(
    "argv, option",
    [
        (["--directions", "sideways"], "--directions"),
        (["--workers", "0"], "--workers"),
        (["--alphas", "north"], "--alphas"),
        (["--shoot-rtol", "0"], "--shoot-rtol"),
    ],
)
def test_bifurcation_bad_input(capsys, argv, option):
    code = main(["bifurcation", *argv])
    err = capsys.readouterr().err
    assert code == 2 and option in err and err.count("\n") == 1


def test_bifurcation_table_names_stability_and_the_continuations_own_points(capsys):
    """The plain table: whole words for the attractor, a ``stable`` column and a
    ``point`` column telling the requested v from the continuation's own steps,
    each row agreeing with the JSON of the same run."""
    argv = ["bifurcation", *CHEAP, "--alphas", "0", "--v", "5,6,8", "--quiet", "--planar"]
    assert main(argv) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    d = run_json(capsys, [*argv, "--json"])
    header, rows = lines[0].split(), [ln.split() for ln in lines[1:]]
    assert header[:6] == ["alpha", "branch", "v", "attractor", "stable", "point"]
    rows = [r for r in rows if r[0] != "special"]
    assert len(rows) == len(d["points"])
    for r, p in zip(rows, d["points"], strict=True):
        assert r[3] == p["attractor"]
        assert r[4] == {True: "yes", False: "no"}[p["stable"]]
        assert r[5] == ("requested" if p["requested"] else "step")
        assert float(r[2]) == pytest.approx(p["v"], rel=1e-3)
    assert {r[5] for r in rows} == {"requested", "step"}
    assert {r[4] for r in rows} == {"yes", "no"}  # the straight pipe loses stability


def test_bifurcation_panels_name_the_papers_panel_only_for_the_papers_case():
    """Fig. 7 is alpha = 0 with (a) eta, (b) X_g, (c) Z_g; Figs. 8-10 are eta, X_g,
    Z_g with (a)-(d) alpha = pi/4 ... pi; another case or inclination gets no 'cf.'."""
    import math

    from fempipe.model.params import PAPER_CASE
    from fempipe.plotting.dynamics import paper_panel

    p = dict(PAPER_CASE, end_mass=0.0, springs=[])
    keys = ("eta_tip", "X_tip", "Z_tip")
    assert [paper_panel(k, 0.0, p) for k in keys] == [
        " (cf. Fig. 7(a))",
        " (cf. Fig. 7(b))",
        " (cf. Fig. 7(c))",
    ]
    assert [paper_panel(k, math.pi / 2, p) for k in keys] == [
        " (cf. Fig. 8(b))",
        " (cf. Fig. 9(b))",
        " (cf. Fig. 10(b))",
    ]
    assert paper_panel("Z_tip", math.pi, p) == " (cf. Fig. 10(d))"
    assert paper_panel("eta_tip", 0.3, p) == ""
    assert paper_panel("eta_tip", 0.0, dict(p, gamma=10.0)) == ""
    assert paper_panel("eta_tip", 0.0, dict(p, end_mass=0.2)) == ""


def test_bifurcation_solver_failure_says_the_points_are_kept(tmp_path, monkeypatch, capsys):
    """A failed sweep ends with exit 1 and one line; with --out it says a rerun resumes."""
    import fempipe.analyses.bifurcation
    from fempipe.core.errors import SolverError

    def fail(*args, **kwargs):
        raise SolverError("integration failed at v = 9")

    monkeypatch.setattr(fempipe.analyses.bifurcation, "compute_bifurcation_diagram", fail)
    out = tmp_path / "run"
    code = main(
        [
            "bifurcation",
            "--method",
            "sweep",
            *CHEAP,
            "--v",
            "8,9",
            "--out",
            str(out),
            "--quiet",
            "--planar",
        ]
    )
    lines = capsys.readouterr().err.strip().splitlines()
    assert code == 1 and len(lines) == 1
    assert lines[0].startswith("fempipe bifurcation: error: integration failed at v = 9; ")
    assert lines[0].endswith(f"kept in {out}/points; rerun the command to resume")


def test_simulate_shoot_rtol_default_is_tighter_with_error_estimate():
    """--shoot-rtol defaults to 1e-5, and to 1e-7 with --error-estimate (the
    shooting tolerance is the estimates' floor, which 1e-5 would put above
    the discretization error of a P3:16 cycle); a given value is kept."""
    import argparse

    from fempipe.cli import simulate as sim

    parser = argparse.ArgumentParser()
    sim.add_arguments(parser)
    base = ["--modal", "2", "--v", "9"]
    assert sim.shoot_rtol_of(parser.parse_args(base)) == 1e-5
    assert sim.shoot_rtol_of(parser.parse_args([*base, "--error-estimate"])) == 1e-7
    given = parser.parse_args([*base, "--error-estimate", "--shoot-rtol", "3e-6"])
    assert sim.shoot_rtol_of(given) == 3e-6


def test_simulate_figures_continue_the_transient_without_a_jump(monkeypatch, tmp_path):
    """time_traces.png and trajectory.pvd: where the transient ends, the displayed
    cycle goes on from the orbit's nearest point, so the join moves the state by
    no more than a display step does (the orbit's own first sample lies up to
    0.16 rad away at alpha = pi/2, v = 10, a jump in the traces)."""
    import fempipe.cli.simulate as sim

    seen = {}
    display = sim._display_states

    def spy(att, traj, n_periods=3):
        t, q, p = display(att, traj, n_periods)
        seen.update(n=traj.t.size, t=t, q=q, start=att.cycle.orbit_q[0], end=traj.q[-1])
        return t, q, p

    monkeypatch.setattr(sim, "_display_states", spy)
    # --planar: the out-of-plane Floquet multipliers play no part in the figures
    argv = ["simulate", "--alpha", "pi/2", "--v", "10", "--planar", "--quiet"]
    argv += ["--out", str(tmp_path)]
    assert main(argv) == 0
    n, t, q = seen["n"], seen["t"], seen["q"]
    assert np.all(np.diff(t) > 0)
    steps = np.max(np.abs(np.diff(q[n:], axis=0)), axis=1)
    join = np.max(np.abs(q[n] - q[n - 1]))
    assert join < 2.0 * np.median(steps), (join, np.median(steps))
    # The case (default P3:16) is one where the orbit's first sample is far from
    # the transient's end.
    assert np.max(np.abs(seen["start"] - seen["end"])) > 3.0 * join

"""``fempipe static`` (and the shared option parser, and ``fempipe bench``) run in-process."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fempipe.cli import main
from fempipe.cli.parsing import parse_values
from fempipe.io import read_csv
from fempipe.io.ranges import parse_alpha
from fempipe.model.discretization import DEFAULT_FE

TD_ARGS = ["--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058", "--g", "9.8"]
L_TD = 0.094
POINT_KEYS = {
    "v",
    "theta_tip",
    "eta_tip",
    "X_tip",
    "Z_tip",
    "varsigma_tip",
    "tip_drop",
    "newton_iterations",
    "residual_norm",
}
SI_KEYS = {"U", "X_tip_m", "Z_tip_m", "eta_tip_m", "varsigma_tip_m", "tip_drop_mm"}


def run(argv, capsys):
    """main(argv) -> (exit code, stdout, stderr); argparse's errors too return 2."""
    code = main(argv)
    out = capsys.readouterr()
    return code, out.out, out.err


def run_json(argv, capsys):
    code, out, err = run([*argv, "--json", "--quiet"], capsys)
    assert code == 0, err
    return json.loads(out)  # the whole of stdout is one JSON document


# --------------------------------------------------------------------- parsing --
@pytest.mark.parametrize(
    "text, expected",
    [
        ("1.5708", 1.5708),
        ("1.5708rad", 1.5708),
        ("0", 0.0),
        ("90deg", math.pi / 2),
        ("-45deg", -math.pi / 4),
        ("180°", math.pi),
        ("pi", math.pi),
        ("pi/2", math.pi / 2),
        ("0.5pi", math.pi / 2),
        ("-pi/4", -math.pi / 4),
        ("3pi/4", 3 * math.pi / 4),
        ("3*pi/4", 3 * math.pi / 4),
        ("2pi/3", 2 * math.pi / 3),
        (" PI/2 ", math.pi / 2),
    ],
)
def test_parse_alpha_forms(text, expected):
    assert parse_alpha(text) == pytest.approx(expected, rel=1e-15, abs=1e-15)


@pytest.mark.parametrize("text", ["abc", "", "pi/0", "90degg", "1..2", "pipi", "nan", "inf"])
def test_parse_alpha_rejects_garbage_naming_the_option(text):
    with pytest.raises(ValueError, match="^--alpha"):
        parse_alpha(text)


@pytest.mark.parametrize(
    "text, expected",
    [
        ("0,2,4", [0.0, 2.0, 4.0]),
        ("3", [3.0]),
        ("0:6:13", list(np.linspace(0, 6, 13))),
        ("1:1:1", [1.0]),
        ("5:0:3", [5.0, 2.5, 0.0]),
    ],
)
def test_parse_values(text, expected):
    got = parse_values(text, "--v")
    assert got == pytest.approx(expected, abs=1e-15)
    assert got[-1] == expected[-1]  # a range ends exactly on stop


@pytest.mark.parametrize("text", ["1,,2", "", "a", "0:1", "0:1:0", "0:1:x", "0:1:2:3", "1,nan"])
def test_parse_values_rejects_bad_text_naming_the_option(text):
    with pytest.raises(ValueError, match="^--v "):
        parse_values(text, "--v")


# ------------------------------------------------------------------------ JSON --
def test_json_has_the_contract_keys(capsys):
    d = run_json(["static", "--alpha", "pi/2", "--v", "0,2,4"], capsys)
    assert set(d) == {"points", "params", "discretization"}
    assert [p["v"] for p in d["points"]] == [0.0, 2.0, 4.0]
    for p in d["points"]:
        assert POINT_KEYS <= set(p)
        assert not SI_KEYS & set(p)
        assert p["residual_norm"] < 1e-9 and p["newton_iterations"] >= 1
        # Inextensible pipe: the tip stays on the unit circle around the clamp.
        assert math.hypot(p["X_tip"], p["Z_tip"]) <= 1.0
    variants = {"end_mass": 0.0, "external_damping": 0.0, "hysteretic_damping": 0.0}
    assert d["params"].pop("springs") == []
    assert d["params"] == pytest.approx(
        {"alpha": math.pi / 2, "beta": 0.142, "gamma": 18.9, "mu": 5e-3, **variants}, rel=1e-15
    )
    assert f"P{d['discretization']['degree']}:{d['discretization']['n_elements']}" == DEFAULT_FE
    # The flow straightens the sagging pipe (Fig. 2): the tip rises as v grows.
    drops = [p["tip_drop"] for p in d["points"]]
    assert drops[0] > drops[1] > drops[2] > 0


def test_json_si_input_reports_si_values(capsys):
    d = run_json(["static", *TD_ARGS, "--alpha", "90deg", "--U", "0,1", "--fe", "P2:8"], capsys)
    assert d["params"]["pipe_SI"]["L"] == L_TD
    p0, p1 = d["points"]
    assert SI_KEYS <= set(p1)
    assert (p0["U"], p1["U"]) == (0.0, 1.0)
    assert abs(p1["v"] - 1.6874) <= 0.5e-4  # the paper, Sec. 3.1: v = 1.6874 U
    for p in (p0, p1):
        assert p["X_tip_m"] == pytest.approx(p["X_tip"] * L_TD, rel=1e-15)
        assert p["eta_tip_m"] == pytest.approx(p["eta_tip"] * L_TD, rel=1e-15)
        # alpha = pi/2: the undeformed tip is at X_g = 0, so the drop is X_tip.
        assert p["tip_drop_mm"] == pytest.approx(p["X_tip"] * L_TD * 1e3, rel=1e-12)
    assert p1["tip_drop_mm"] < p0["tip_drop_mm"]


def test_modal_discretization_and_mirror_symmetry(capsys):
    """Eq. (20) is odd under (theta, alpha) -> (-theta, -alpha): a negative --alpha gives the
    mirror image, to round-off (tolerance 1e-12: Newton converges to ~1e-14)."""
    a = run_json(["static", "--alpha", "pi/4", "--v", "0,3", "--modal", "6"], capsys)
    b = run_json(["static", "--alpha=-pi/4", "--v", "0,3", "--modal", "6"], capsys)
    assert a["discretization"]["kind"] == "modal" and a["discretization"]["n_modes"] == 6
    for pa, pb in zip(a["points"], b["points"], strict=True):
        assert pb["theta_tip"] == pytest.approx(-pa["theta_tip"], abs=1e-12)
        assert pb["Z_tip"] == pytest.approx(-pa["Z_tip"], abs=1e-12)
        assert pb["X_tip"] == pytest.approx(pa["X_tip"], abs=1e-12)
        assert abs(pa["theta_tip"]) > 0.1  # not the trivial state


def test_continuation_in_gamma(capsys):
    d = run_json(
        ["static", "--alpha", "pi/4", "--continuation", "gamma", "--values", "0:60:4", "--v", "2"],
        capsys,
    )
    assert [p["gamma"] for p in d["points"]] == [0.0, 20.0, 40.0, 60.0]
    assert all(p["v"] == 2.0 for p in d["points"])
    assert "gamma" not in d["params"] and d["params"]["v"] == 2.0
    # Without gravity the straight pipe is an equilibrium of Eq. (31a) for any v.
    assert d["points"][0]["theta_tip"] == 0.0
    assert d["points"][0]["X_tip"] == pytest.approx(math.cos(math.pi / 4), abs=1e-14)
    # Growing gravity turns the pipe towards the plumb line theta = -alpha.
    th = [p["theta_tip"] for p in d["points"]]
    assert all(-math.pi / 4 < t1 < t0 for t0, t1 in zip(th[:-1], th[1:], strict=True))


def test_continuation_in_alpha(capsys):
    d = run_json(
        ["static", "--continuation", "alpha", "--values", "0deg:90deg:3", "--fe", "P2:8"], capsys
    )
    assert [p["alpha"] for p in d["points"]] == pytest.approx([0, math.pi / 4, math.pi / 2])
    assert d["points"][0]["theta_tip"] == 0.0  # hanging down: straight


# ------------------------------------------------------------------- the table --
def test_human_table(capsys):
    code, out, err = run(["static", "--v", "0:2:3", "--alpha", "pi/2", "--quiet"], capsys)
    assert code == 0, err
    lines = out.strip().splitlines()
    assert lines[0].startswith("static deformation, alpha = 1.5708")
    assert "theta_tip" in lines[1]
    assert len(lines) == 2 + 3


# ------------------------------------------------------------------ --out files --
@pytest.fixture(scope="module")
def td_out(tmp_path_factory):
    out = tmp_path_factory.mktemp("static") / "out"
    argv = ["static", *TD_ARGS, "--alpha", "90deg", "--U", "0:3:4", "--out", str(out), "--quiet"]
    assert main(argv) == 0
    return out


def test_out_writes_the_four_files(td_out):
    assert sorted(p.name for p in td_out.iterdir()) == [
        "shapes.png",
        "shapes.vtu",
        "static.csv",
        "static.json",
    ]
    assert td_out.joinpath("shapes.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    d = json.loads(td_out.joinpath("static.json").read_text())
    cols = read_csv(td_out / "static.csv")
    assert POINT_KEYS | SI_KEYS <= set(cols)
    assert len(cols["theta_tip"]) == len(d["points"]) == 4
    for i, p in enumerate(d["points"]):
        assert cols["theta_tip"][i] == p["theta_tip"]  # full precision in the CSV


def test_out_shapes_read_back_with_meshio(td_out):
    """The VTU shapes agree with the JSON tip values, which come from a different code
    path (Gauss sums in compute_tip vs sampled shapes): tip theta to 1e-12 (both exact for
    the FE interpolant), tip position to 1e-12 (same quadrature rule, different sums)."""
    import meshio

    mesh = meshio.read(td_out / "shapes.vtu")
    assert [c.type for c in mesh.cells] == ["line"]
    assert {"theta", "xi", "eta", "X_g", "Z_g", "v", "shape_index"} <= set(mesh.point_data)
    d = json.loads(td_out.joinpath("static.json").read_text())
    idx = mesh.point_data["shape_index"].astype(int)
    assert sorted(set(idx)) == [0, 1, 2, 3]
    for i, p in enumerate(d["points"]):
        sel = idx == i
        xi = mesh.point_data["xi"][sel]
        tip = np.argmax(xi)
        assert xi[tip] == 1.0 and xi.min() == 0.0
        assert mesh.point_data["theta"][sel][tip] == pytest.approx(p["theta_tip"], abs=1e-12)
        assert mesh.point_data["v"][sel][0] == p["v"]
        pts = mesh.points[sel]
        # Points: the centerline in metres, gravity along -y: (Z_g L, -X_g L, 0).
        assert pts[tip, 0] == pytest.approx(p["Z_tip_m"], abs=1e-12)
        assert pts[tip, 1] == pytest.approx(-p["X_tip_m"], abs=1e-12)
        assert np.all(pts[:, 2] == 0.0)
        # Inextensibility: the polyline is as long as the pipe, to the sampling's chord error.
        length = np.sum(np.linalg.norm(np.diff(pts[np.argsort(xi)], axis=0), axis=1))
        assert length == pytest.approx(L_TD, rel=1e-3)


# ------------------------------------------------------------------- bad input --
@pytest.mark.parametrize(
    "argv, option",
    [
        (["--gamma", "-1"], "--gamma"),
        (["--beta", "1.5"], "--beta"),
        (["--mu", "nan"], "--mu"),
        (["--fe", "P9x"], "--fe"),
        (["--fe", "P2:0"], "--fe"),
        (["--fe", "P11:4"], "--fe"),
        (["--modal", "0"], "--modal"),
        (["--alpha", "abc"], "--alpha"),
        (["--v", "1,,2"], "--v"),
        (["--v", "-1"], "--v"),
        (["--v", "0:1:0"], "--v"),
        (["--U", "1"], "--U"),
        (["--length", "0.1"], "--EI"),
        ([*TD_ARGS, "--gamma", "3"], "--gamma"),
        ([*TD_ARGS, "--U", "0,-1"], "--U"),
        (["--continuation", "gamma"], "--values"),
        (["--continuation", "alpha", "--values", "0,x"], "--values"),
        (["--fe", "P2:4", "--modal", "3"], "--modal"),  # argparse's own error
        (["--continuation", "beta"], "--continuation"),  # argparse's own error
    ],
)
def test_bad_input_exit_2_with_one_line_naming_the_option(argv, option, tmp_path, capsys):
    out_dir = tmp_path / "out"
    code, out, err = run(["static", *argv, "--out", str(out_dir)], capsys)
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("fempipe")
    assert ": error: " in lines[0]
    assert option in lines[0]
    assert not out_dir.exists()


def test_newton_failure_exit_1_names_where_and_writes_nothing(monkeypatch, tmp_path, capsys):
    """A genuine NewtonError (Newton limited to one iteration at v = 4) after one finished
    point: one line naming v, the iterations and the residual; exit 1; no files."""
    import fempipe.analyses.statics as static
    from fempipe.analyses.statics import solve_static

    def failing_path(model, values, parameter="v", callback=None, **kw):
        first = solve_static(model)
        callback(0, first)
        solve_static(model.with_params(model.params.with_flow(values[1])), max_iter=1)
        raise AssertionError("unreachable: max_iter=1 cannot converge from the straight state")

    monkeypatch.setattr(static, "solve_path", failing_path)
    out_dir = tmp_path / "out"
    argv = ["static", "--alpha", "pi/2", "--v", "0,4,8", "--out", str(out_dir), "--json"]
    code, out, err = run(argv, capsys)
    assert code == 1
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    msg = lines[0]
    assert msg.startswith("fempipe static: error: ")
    assert "v=4" in msg and "1 iterations" in msg and "residual" in msg
    assert "1 of 3 points solved" in msg
    assert not out_dir.exists() or not any(out_dir.iterdir())


# ------------------------------------------------------------------------ bench --
def test_bench_quick_runs_and_both_static_routes_agree(capsys):
    d = run_json(["bench", "--quick", "--only", "static_path"], capsys)
    assert set(d) == {"environment", "quick", "benchmarks"} and d["quick"] is True
    rows = d["benchmarks"]["static_path"]["table"]
    assert len(rows) == 2
    for row in rows:
        assert row["seconds"] > 0 and row["n_points"] == 11
        # solve_path (Newton + extrapolation) and pseudo-arclength continuation reach
        # the same state at v = 10 (both converged to ||R|| ~ 1e-10 relative).
        assert row["arclength_theta_tip_diff"] < 1e-8


def test_bench_unknown_name_is_bad_input(capsys):
    code, out, err = run(["bench", "--only", "nope"], capsys)
    assert code == 2 and out == ""
    assert len(err.strip().splitlines()) == 1
    assert err.startswith("fempipe bench: error: --only: unknown benchmark 'nope'; known: ")


def test_points_report_linear_stability(capsys):
    """The straight standing column (alpha = pi) beyond Greenhill's gamma = 7.837 is
    an unstable equilibrium at v = 0; below it, and the sagged horizontal pipe at
    v = 0, are stable (no flow: a conservative system at an energy minimum)."""
    d = run_json(["static", "--alpha", "pi", "--v", "0", "--gamma", "18.9"], capsys)
    assert d["points"][0]["stable"] is False
    d = run_json(["static", "--alpha", "pi", "--v", "0", "--gamma", "7.0"], capsys)
    assert d["points"][0]["stable"] is True
    d = run_json(["static", "--alpha", "pi/2", "--v", "0"], capsys)
    assert d["points"][0]["stable"] is True


def test_si_run_without_a_says_its_damping_differs(capsys):
    """The SI pipe's Kelvin-Voigt damping is zero unless --a is given, the dimensionless
    runs' is the paper's 0.005: every SI run that takes the other default says so."""
    from fempipe.cli import main

    si = ["static", "--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058"]
    si += ["--U", "1", "--fe", "P3:2"]
    assert main(si) == 0
    assert "no Kelvin-Voigt damping unless --a is given" in capsys.readouterr().err
    for argv in (si + ["--a", "0.001"], si + ["--quiet"], ["static", "--v", "1", "--fe", "P3:2"]):
        assert main(argv) == 0
        assert "notice" not in capsys.readouterr().err, argv

"""The commands in three dimensions: spectrum, static, stability-map, convergence, compare.

The pipe is round: beside the motion in the plane of its static state (the
paper's Eq. (32)) each command analyses the motion out of it
(:mod:`fempipe.model.out_of_plane.model`), and its verdicts and critical velocities are
those of three dimensions; ``--planar`` gives the paper's planar output as
before.  Small discretizations (four sine modes, P3:8) keep each run to
seconds.  The paper's case at alpha = pi/2 loses stability out of the plane
first (Modal(4): flutter at 5.853 out of the plane, 6.241 in it); at
alpha = 0 the two planes are the same problem.
"""

from __future__ import annotations

import json
import math

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import pytest  # noqa: E402
from clirun import run_json  # noqa: E402

from fempipe.cli import main  # noqa: E402
from fempipe.io import read_csv  # noqa: E402

#: The keys of ``fempipe spectrum --json`` before the out-of-plane analysis (and with --planar).
SPECTRUM_KEYS = {"points", "modes", "params", "discretization", "n_spectra"}
SPECTRUM_POINT_KEYS = {"v", "stable", "max_real", "theta_tip", "eigenvalues"}
EIGENVALUE_KEYS = {"mode", "re", "im", "Omega_re", "Omega_im"}


# ---------------------------------------------------------------------------
# spectrum


def test_spectrum_lists_both_planes_and_decides_in_three_dimensions(capsys, tmp_path):
    """alpha = pi/2, Modal(4): at v = 6 the pipe is stable in its plane and flutters out of it."""
    argv = ["spectrum", "--alpha", "pi/2", "--v", "0,3,6,6.5", "--modal", "4", "--json"]
    d = run_json(capsys, [*argv, "--quiet", "--out", str(tmp_path)])
    assert set(d) == SPECTRUM_KEYS | {
        "modes_out_of_plane",
        "n_spectra_in_plane",
        "n_spectra_out_of_plane",
    }
    assert d["n_spectra"] == d["n_spectra_in_plane"] + d["n_spectra_out_of_plane"]
    for pt in d["points"]:
        assert pt["eigenvalues"] and pt["eigenvalues_out_of_plane"]
        assert all(e["plane"] == "in" for e in pt["eigenvalues"])
        assert all(e["plane"] == "out" for e in pt["eigenvalues_out_of_plane"])
        assert all(set(e) == EIGENVALUE_KEYS | {"plane"} for e in pt["eigenvalues_out_of_plane"])
        assert pt["stable"] == (pt["stable_in_plane"] and pt["stable_out_of_plane"])
        assert pt["max_real"] == max(pt["max_real_in_plane"], pt["max_real_out_of_plane"])
        # Each plane's verdict is its eigenvalues' (Re lambda > 0 unstable).
        assert pt["stable_out_of_plane"] == all(
            e["re"] <= 1e-8 * max(1.0, math.hypot(e["re"], e["im"]))
            for e in pt["eigenvalues_out_of_plane"]
        )
    at = {pt["v"]: pt for pt in d["points"]}
    assert at[3.0]["stable"] is True
    assert at[6.0]["stable_in_plane"] is True and at[6.0]["stable_out_of_plane"] is False
    assert at[6.0]["stable"] is False
    assert at[6.5]["stable_in_plane"] is False
    # The CSV files: spectrum.csv the in-plane rows with the 3-D verdict, the
    # out-of-plane rows in their own file with the same columns and plane.
    rows = read_csv(tmp_path / "spectrum.csv")
    out = read_csv(tmp_path / "spectrum_out_of_plane.csv")
    assert set(out) == set(rows) | {"plane"}
    assert set(out["plane"]) == {"out"}
    n_out = sum(len(pt["eigenvalues_out_of_plane"]) for pt in d["points"])
    assert len(out["v"]) == n_out
    assert list(out["stable"][out["v"] == 6.0]) == [False] * int((out["v"] == 6.0).sum())


def test_spectrum_planes_coincide_on_the_hanging_pipe(capsys):
    """alpha = 0: the straight pipe; every plane through its axis is alike."""
    argv = ["spectrum", "--alpha", "0", "--v", "0:8:5", "--modal", "4", "--json", "--quiet"]
    d = run_json(capsys, argv)
    assert d["modes"] == d["modes_out_of_plane"]
    for pt in d["points"]:
        assert pt["stable_in_plane"] == pt["stable_out_of_plane"] == pt["stable"]
        ins = sorted((e["mode"], e["im"], e["re"]) for e in pt["eigenvalues"])
        outs = sorted((e["mode"], e["im"], e["re"]) for e in pt["eigenvalues_out_of_plane"])
        assert [m for m, _, _ in ins] == [m for m, _, _ in outs]
        for (_, a_im, a_re), (_, b_im, b_re) in zip(ins, outs, strict=True):
            assert abs(a_im - b_im) + abs(a_re - b_re) <= 1e-8 * max(1.0, abs(a_im))


def test_spectrum_planar_is_the_paper_output(capsys):
    """--planar: the keys of the planar command, the in-plane values of the 3-D run."""
    argv = ["spectrum", "--alpha", "pi/2", "--v", "0,6", "--modal", "4", "--json", "--quiet"]
    planar = run_json(capsys, [*argv, "--planar"])
    assert set(planar) == SPECTRUM_KEYS
    for pt in planar["points"]:
        assert set(pt) == SPECTRUM_POINT_KEYS
        assert all(set(e) == EIGENVALUE_KEYS for e in pt["eigenvalues"])
    spatial = run_json(capsys, argv)
    assert planar["modes"] == spatial["modes"]
    for p, s in zip(planar["points"], spatial["points"], strict=True):
        assert p["stable"] == s["stable_in_plane"]
        assert p["max_real"] == s["max_real_in_plane"]
        assert p["eigenvalues"] == [
            {k: x for k, x in e.items() if k != "plane"} for e in s["eigenvalues"]
        ]
    assert planar["points"][1]["stable"] is True  # in the plane, v = 6 is below v_cr


def _legend_texts(ax) -> list[str]:
    return [t.get_text() for t in ax.get_legend().get_texts()]


def test_argand_marks_the_out_of_plane_loci():
    """argand.png: the out-of-plane loci dashed with open triangles, named in the legend;
    not drawn again where they are the in-plane loci (alpha = 0), which the title says."""
    from test_figures import text_faults

    from fempipe.analyses.stability import trace_root_locus
    from fempipe.model.discretization import Modal
    from fempipe.model.params import Params
    from fempipe.model.plane.operators import PipeModel
    from fempipe.plotting.stability import plot_argand

    values = [0.0, 2.0, 4.0, 6.0]
    model = PipeModel(Modal(4), Params(alpha=math.pi / 2))
    loci = trace_root_locus(model, values, n_modes=3, planes=("in", "out"))
    ax = plot_argand(loci[0], out_of_plane=loci[1])
    try:
        legend = _legend_texts(ax)
        assert {"in the plane", "out of the plane"} <= set(legend)
        assert {"mode 1", "mode 2", "mode 3"} <= set(legend)
        dashed = [ln for ln in ax.get_lines() if ln.get_linestyle() == "--"]
        triangles = [ln for ln in ax.get_lines() if ln.get_marker() == "^"]
        assert len(dashed) >= 3 and len(triangles) >= 3
        assert all(ln.get_markerfacecolor() == "none" for ln in triangles)
        assert not text_faults(ax.figure)
    finally:
        plt.close(ax.figure)
    model = PipeModel(Modal(4), Params(alpha=0.0))
    loci = trace_root_locus(model, values, n_modes=3, planes=("in", "out"))
    ax = plot_argand(loci[0], out_of_plane=loci[1])
    try:
        assert "out of the plane the same loci" in ax.get_title()
        assert not any(ln.get_marker() == "^" for ln in ax.get_lines())
        assert "out of the plane" not in _legend_texts(ax)
    finally:
        plt.close(ax.figure)


@pytest.mark.parametrize("argv", [["--planar"], []])
def test_spectrum_table(capsys, argv):
    from fempipe.cli import main

    assert main(["spectrum", "--alpha", "pi/2", "--v", "0,6", "--modal", "4", *argv]) == 0
    out = capsys.readouterr().out
    assert ("out of the plane" in out) == (not argv)


# ---------------------------------------------------------------------------
# static

STATIC_STABILITY = ("stable", "stable_in_plane", "stable_out_of_plane")


def test_static_stable_in_three_dimensions(capsys, tmp_path):
    """alpha = pi/2, Modal(4): v = 6 is stable in the plane, unstable out of it, so not
    stable; the CSV has the three columns; --planar keeps the planar verdict alone."""
    argv = ["static", "--alpha", "pi/2", "--v", "0,6,7", "--modal", "4", "--json", "--quiet"]
    d = run_json(capsys, [*argv, "--out", str(tmp_path)])
    flags = [tuple(pt[k] for k in STATIC_STABILITY) for pt in d["points"]]
    assert flags == [(True, True, True), (False, True, False), (False, False, False)]
    cols = read_csv(tmp_path / "static.csv")
    for k in STATIC_STABILITY:
        assert [bool(x) for x in cols[k]] == [pt[k] for pt in d["points"]]
    planar = run_json(capsys, [*argv, "--planar"])
    for p, s in zip(planar["points"], d["points"], strict=True):
        assert set(s) - set(p) == {"stable_in_plane", "stable_out_of_plane"}
        assert p["stable"] == s["stable_in_plane"]
        assert {k: x for k, x in s.items() if k not in STATIC_STABILITY[1:]} == dict(
            p, stable=s["stable"]
        )
    # The hanging pipe: both planes alike.
    d = run_json(capsys, ["static", "--alpha", "0", "--v", "6,7", "--modal", "4", "--json"])
    for pt in d["points"]:
        assert pt["stable"] == pt["stable_in_plane"] == pt["stable_out_of_plane"]


def test_shapes_tell_the_out_of_plane_instability():
    """shapes.png: solid stable, grey dashed unstable in the plane, grey dash-dot unstable
    out of the plane only, each kind named in the legend."""
    from test_figures import text_faults

    from fempipe.plotting.static import OUT_OF_PLANE_STYLE, UNSTABLE_COLOR, plot_shapes

    shapes = _shapes([0.0, 6.0, 7.0])
    ax = plot_shapes(
        shapes,
        ["v = 0", "v = 6", "v = 7"],
        alpha=math.pi / 2,
        stable=[True, False, False],
        stable_in_plane=[True, True, False],
    )
    try:
        lines = {ln.get_label(): ln for ln in ax.get_lines() if ln.get_label().startswith("v = ")}
        assert lines["v = 0"].get_linestyle() == "-"
        assert lines["v = 6 (unstable out of the plane)"].get_linestyle() == OUT_OF_PLANE_STYLE
        assert lines["v = 7 (unstable in the plane)"].get_linestyle() == "--"
        for k in ("v = 6 (unstable out of the plane)", "v = 7 (unstable in the plane)"):
            assert matplotlib.colors.same_color(lines[k].get_color(), UNSTABLE_COLOR)
        legend = _legend_texts(ax)
        assert "grey dashed: unstable in the plane" in legend
        assert "grey dash-dot: unstable out of the plane only" in legend
        assert not text_faults(ax.figure)
    finally:
        plt.close(ax.figure)


def _shapes(values):
    from fempipe.analyses.statics import solve_path
    from fempipe.model.discretization import Modal
    from fempipe.model.kinematics import compute_shape
    from fempipe.model.params import Params
    from fempipe.model.plane.operators import PipeModel

    model = PipeModel(Modal(4), Params(alpha=math.pi / 2))
    return [compute_shape(model.disc, s.q, math.pi / 2) for s in solve_path(model, values)]


# ---------------------------------------------------------------------------
# stability-map

MAP_POINT_KEYS = {"alpha", "beta", "gamma", "v_cr", "type", "frequency", "mode", "v_flutter"}
MAP_POINT_KEYS |= {"error"}


def test_stability_map_in_three_dimensions(capsys, tmp_path):
    """Both planes' v_cr per alpha, v_cr the first of the two: the same at alpha = 0, out of
    the plane first at pi/2 (the library's find_critical_velocity); --planar as before."""
    from fempipe.analyses.stability import find_critical_velocity
    from fempipe.model.discretization import Modal
    from fempipe.model.params import Params
    from fempipe.model.plane.operators import PipeModel

    argv = ["stability-map", "--alphas", "0,pi/2", "--modal", "4", "--json", "--quiet"]
    d = run_json(capsys, [*argv, "--out", str(tmp_path)])
    a0, a90 = d["points"]
    for pt in d["points"]:
        assert pt["v_cr"] == min(pt["v_cr_in_plane"], pt["v_cr_out_of_plane"])
        assert pt["v_flutter"] == min(pt["v_flutter_in_plane"], pt["v_flutter_out_of_plane"])
        plane = "in_plane" if pt["first_plane"] == "in" else "out_of_plane"
        for k in ("v_cr", "frequency", "type", "mode"):
            assert pt[k] == pt[f"{k}_{plane}"]
    assert a0["first_plane"] == "in"
    assert a0["v_cr_in_plane"] == pytest.approx(a0["v_cr_out_of_plane"], abs=1e-9)
    assert a0["frequency_in_plane"] == pytest.approx(a0["frequency_out_of_plane"], abs=1e-9)
    assert a90["first_plane"] == "out" and a90["type"] == "flutter"
    assert a90["v_cr_out_of_plane"] < a90["v_cr_in_plane"] - 0.3
    lib = find_critical_velocity(
        PipeModel(Modal(4), Params(alpha=math.pi / 2)), 10.0, ds_max=0.2, planes=("in", "out")
    )
    assert a90["v_cr_in_plane"] == pytest.approx(lib.in_plane.v_cr, abs=1e-12)
    assert a90["v_cr_out_of_plane"] == pytest.approx(lib.out_of_plane.v_cr, abs=1e-12)
    cols = read_csv(tmp_path / "stability_map.csv")
    assert list(cols["first_plane"]) == ["in", "out"]
    assert list(cols["v_cr_out_of_plane"]) == [pt["v_cr_out_of_plane"] for pt in d["points"]]
    planar = run_json(capsys, [*argv, "--planar"])
    for p, s in zip(planar["points"], d["points"], strict=True):
        assert set(p) == MAP_POINT_KEYS
        assert p["v_cr"] == s["v_cr_in_plane"] and p["frequency"] == s["frequency_in_plane"]
    assert set(planar) == set(d)


def test_stability_map_figure_shows_both_planes_and_the_first():
    """stability_map.png in 3-D: per curve the in-plane line (○), the out-of-plane one
    (dashed, △) and the band along v_cr in 3-D; the key in a legend below the axes."""
    from test_figures import text_faults

    from fempipe.analyses.stability import map_stability
    from fempipe.model.discretization import Modal
    from fempipe.plotting.stability import plot_stability_map

    smap = map_stability(Modal(4), [0.0, math.pi / 2, math.pi], [(0.142, 18.9)], workers=1)
    ax = plot_stability_map(smap)
    try:
        (legend,) = ax.figure.legends
        texts = [t.get_text() for t in legend.get_texts()]
        assert "in the plane" in texts and "out of the plane" in texts
        assert any("3-D" in t for t in texts)
        lines = ax.get_lines()
        assert any(ln.get_marker() == "^" and ln.get_linestyle() == "--" for ln in lines)
        assert any(ln.get_marker() == "o" and ln.get_linestyle() == "-" for ln in lines)
        # The band follows v_cr in 3-D: the out-of-plane flutter at pi/2.
        (band,) = [ln for ln in lines if ln.get_linewidth() > 5]
        assert band.get_ydata()[1] == smap.points[0][1]["v_cr_out_of_plane"]
        assert "○" in ax.get_title() and "△" in ax.get_title()
        assert not text_faults(ax.figure)
    finally:
        plt.close(ax.figure)


# ---------------------------------------------------------------------------
# convergence


def test_convergence_of_each_plane_and_of_three_dimensions(capsys, tmp_path):
    """alpha = pi/2, P3 on 2, 4, 8 elements: v_cr (3-D) is v_cr_out_of_plane member by
    member, below v_cr_in_plane; each converges at P3's order."""
    argv = ["convergence", "--alpha", "pi/2", "--v", "0,10", "--fe", "P3", "--elements", "2:8"]
    runs = {}
    for q in ("v_cr", "v_cr_in_plane", "v_cr_out_of_plane"):
        out = tmp_path / q
        runs[q] = d = run_json(
            capsys, [*argv, "--quantity", q, "--json", "--quiet", "--out", str(out)]
        )
        assert d["quantity"] == q
        cols = read_csv(out / "convergence.csv")
        assert list(cols[q]) == d["series"][0]["values"]
        assert f"{q}_error" in cols
    vals = {q: d["series"][0]["values"] for q, d in runs.items()}
    for v3, vi, vo in zip(
        vals["v_cr"], vals["v_cr_in_plane"], vals["v_cr_out_of_plane"], strict=True
    ):
        assert v3 == pytest.approx(min(vi, vo), abs=1e-9)
        assert vo < vi - 0.3
    assert "three dimensions" in runs["v_cr"]["quantity_details"]["description"]
    assert "out of the plane" in runs["v_cr_out_of_plane"]["quantity_details"]["description"]
    ref = {q: d["reference"]["value"] for q, d in runs.items()}
    assert ref["v_cr"] == pytest.approx(5.8208946, abs=2e-6)  # the P3:16 value of the docs
    assert ref["v_cr_in_plane"] == pytest.approx(6.2100953, abs=2e-6)


def test_critical_quantities_coincide_on_the_hanging_pipe():
    """alpha = 0: both planes the same problem; planar=True is the in-plane value."""
    from fempipe.model.discretization import Modal
    from fempipe.model.params import Params
    from fempipe.studies.convergence import Quantity

    disc = Modal(4)
    p = Params(alpha=0.0, v=0.0)
    v = {
        n: Quantity(n, p, v_max=10.0)(disc) for n in ("v_cr", "v_cr_in_plane", "v_cr_out_of_plane")
    }
    assert v["v_cr_in_plane"] == pytest.approx(v["v_cr_out_of_plane"], abs=1e-9)
    assert v["v_cr"] == pytest.approx(v["v_cr_in_plane"], abs=1e-9)
    f = [Quantity(n, p, v_max=10.0)(disc) for n in ("frequency_in_plane", "frequency_out_of_plane")]
    assert f[0] == pytest.approx(f[1], abs=1e-8)
    p = Params(alpha=math.pi / 2, v=0.0)
    planar = Quantity("v_cr", p, v_max=10.0, planar=True)
    assert planar(disc) == Quantity("v_cr_in_plane", p, v_max=10.0)(disc)
    assert planar.to_dict()["planar"] is True
    assert "planar" not in Quantity("v_cr", p, v_max=10.0).to_dict()


# ---------------------------------------------------------------------------
# compare


def test_compare_accepts_each_plane(capsys, tmp_path):
    """v_cr_in_plane, v_cr_out_of_plane, frequency_out_of_plane as columns; a user's v_cr is
    the first loss of stability in either plane, as critical's (here out of the plane), or with
    --planar the planar model's (the same number as v_cr_in_plane)."""
    from fempipe.model.discretization import Modal
    from fempipe.model.params import Params
    from fempipe.studies.convergence import Quantity

    path = tmp_path / "user.csv"
    path.write_text(
        "alpha_deg,v_cr,v_cr_in_plane,v_cr_out_of_plane [1],frequency_out_of_plane [1/T]\n"
        "90,6.24,6.24,5.85,14.4\n"
    )
    assert main(["compare", str(path), "--modal", "4", "--json", "--quiet"]) == 1
    d = json.loads(capsys.readouterr().out)
    rows = {r["quantity"]: r for r in d["rows"]}
    # the two analyses locate one crossing, each to Brent's 1e-10
    assert rows["v_cr"]["fempipe"] == pytest.approx(rows["v_cr_out_of_plane"]["fempipe"], abs=1e-9)
    code = main(["compare", str(path), "--modal", "4", "--json", "--quiet", "--planar"])
    d = json.loads(capsys.readouterr().out)
    assert code == (0 if all(r["verdict"] == "agrees" for r in d["rows"]) else 1)
    rows = {r["quantity"]: r for r in d["rows"]}
    assert list(rows) == ["v_cr", "v_cr_in_plane", "v_cr_out_of_plane", "frequency_out_of_plane"]
    assert rows["v_cr"]["fempipe"] == rows["v_cr_in_plane"]["fempipe"]
    assert rows["v_cr_out_of_plane"]["fempipe"] < rows["v_cr_in_plane"]["fempipe"] - 0.3
    assert rows["frequency_out_of_plane"]["unit"] == "1/T"
    p = Params(alpha=math.pi / 2, v=0.0)
    lib = Quantity("v_cr_out_of_plane", p, v_max=15.0)(Modal(4))
    assert rows["v_cr_out_of_plane"]["fempipe"] == pytest.approx(lib, abs=1e-12)
    assert all(r["error_estimate"] is not None for r in d["rows"])
    assert {"v_cr_in_plane", "v_cr_out_of_plane"} <= set(d["error_estimate"]["floors"])


@pytest.mark.parametrize("name", ["v_cr", "v_cr_in_plane", "frequency_out_of_plane"])
def test_convergence_figure_title_fits(name):
    """convergence.png: the longer descriptions of the 3-D quantities wrap inside the canvas."""
    import numpy as np
    from test_figures import text_faults

    from fempipe.model.params import Params
    from fempipe.plotting.convergence import plot_convergence
    from fempipe.studies.convergence import ConvergenceStudy, Quantity, Reference, Series

    dofs = np.array([6, 12, 24])
    errors = 1e-2 * (dofs / 6.0) ** -6.0
    series = Series("fe-P3", np.array([2, 4, 8]), dofs, 5.8 + errors, errors, 6.0, (0, 1), 6.0)
    study = ConvergenceStudy(
        Quantity(name, Params(alpha=math.pi / 2, v=0.0), v_max=10.0),
        Reference(5.8, 1e-8, "synthetic", "fe-P3"),
        (series,),
        1e-7,
        0.0,
    )
    ax = plot_convergence(study)
    try:
        assert not text_faults(ax.figure)
    finally:
        plt.close(ax.figure)

"""``fempipe.studies.error_estimate`` and ``--error-estimate`` of static, critical and simulate.

The estimates are checked against the true error, measured on an
independent fine discretization computed here with the library (P3:64 for
static states, P3:16 for v_cr, P3:4 for a limit cycle: each at least 100x
more accurate than the coarse case it judges): the estimate must bound it and
be at most 100x larger.  Without the option the output must be exactly what
it was (the key sets of the existing contract).
"""

from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import clirun
import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.stability.hopf import EVENT_KEYS as HOPF_KEYS
from fempipe.analyses.statics import solve_path
from fempipe.cli import main
from fempipe.io import read_csv
from fempipe.model.kinematics import compute_tip
from fempipe.model.projection import project
from fempipe.studies.error_estimate import (
    SAFETY_FACTOR,
    describe,
    estimate,
    expected_order,
    match_events,
    refine,
    refinement_ratio,
)

TIP = ("theta_tip", "eta_tip", "X_tip", "Z_tip", "varsigma_tip")
#: The keys of a static point, of critical and of simulate before --error-estimate existed.
STATIC_POINT_KEYS = {
    "v",
    *TIP,
    "tip_drop",
    "newton_iterations",
    "gravity_loading_iterations",
    "residual_norm",
    "includes_gravity_loading",
    "stable",
}
CRITICAL_KEYS = {
    "v_cr",
    "events",
    "critical",
    "v_flutter",
    "v_range",
    "params",
    "discretization",
    "branches",
    "n_spectra",
}
#: What critical adds in three dimensions (docs, "Out of the plane").
SPATIAL_KEYS = {
    "first_instability",
    "v_cr_in_plane",
    "frequency_in_plane",
    "v_cr_out_of_plane",
    "frequency_out_of_plane",
    "v_flutter_in_plane",
    "v_flutter_out_of_plane",
    "critical_in_plane",
    "critical_out_of_plane",
    "branches_out_of_plane",
}
SPATIAL_ERROR_KEYS = {
    "v_cr_in_plane_error",
    "v_cr_in_plane_refined",
    "v_cr_out_of_plane_error",
    "v_cr_out_of_plane_refined",
}
EVENT_KEYS = {"v", "type", "branch", "frequency", "mode", "stable_before", "stable_after", "plane"}
SIMULATE_KEYS = {
    "params",
    "discretization",
    "attractor",
    "period",
    "period_n",
    "tip",
    "floquet_multipliers",
    "max_nontrivial_multiplier",
    "t_transient",
    "message",
    # the planar equilibrium's verdict out of the plane (fempipe.analyses.three_d)
    "stable_out_of_plane",
    "stable_3d",
    "steps",
    "rejected_steps",
    "n_residual",
    "n_jacobian",
    "wall_time",
}


def run_json(capsys, argv) -> dict:
    return clirun.run_json(capsys, [*argv, "--json", "--quiet"])


def assert_bounds(err, coarse, reference, what=""):
    """The estimate bounds |coarse - reference| and is at most 100x larger."""
    true = abs(coarse - reference)
    assert err >= true, f"{what}: estimate {err:.3g} below the true error {true:.3g}"
    assert err <= 100 * true, f"{what}: estimate {err:.3g} > 100 x true error {true:.3g}"


# ------------------------------------------------------------- the module --
@pytest.mark.parametrize("degree", [1, 2, 3, 5])
def test_expected_order_fe_is_2k(degree):
    assert expected_order(FiniteElement(4, degree)) == 2 * degree


def test_expected_order_modal():
    assert expected_order(Modal(3)) == 3.0

    class Unstated(Modal):  # a basis whose class states no order
        expected_order = None

    other = Unstated(3)
    other.basis = "beam"
    assert expected_order(other) is None

    class Stated(Modal):
        expected_order = 4.0

    assert expected_order(Stated(3)) == 4.0


def test_refine_halves_elements_and_doubles_even_modes_odd_to_odd():
    fe = FiniteElement(4, 2, n_gauss=5)
    fine = refine(fe)
    assert (fine.degree, fine.n_elements, fine.n_gauss) == (2, 8, 5)
    np.testing.assert_allclose(fine.nodes[::2], fe.nodes, rtol=0, atol=1e-15)
    m = refine(Modal(3))
    # Odd N -> 2N + 1: the sine modes' error alternates with the parity of N.
    assert type(m) is Modal and m.n_modes == 7 and m.name == "modal:7"
    np.testing.assert_allclose(m.k[:3], Modal(3).k)
    assert refinement_ratio(Modal(3)) == pytest.approx(7 / 3)
    assert refine(Modal(4)).n_modes == 8 and refinement_ratio(Modal(4)) == 2.0


def test_refine_keeps_a_modal_basis():
    beam = Modal(3, basis="beam")
    fine = refine(beam)
    assert fine.n_modes == 7 and fine.basis == "beam"
    assert expected_order(beam) == beam.expected_order


def test_estimate_is_the_grid_convergence_index():
    # Fs |c - f| r^p / (r^p - 1) = 3 * 0.5 * 4 / 3 with p = 2, r = 2.
    assert SAFETY_FACTOR == 3.0
    assert estimate(1.0, 1.5, 2.0) == pytest.approx(2.0, rel=1e-15)
    assert estimate(1.0, 1.5, 1.0, ratio=3.0) == pytest.approx(3 * 0.5 * 3 / 2, rel=1e-15)
    # Order unknown: the bracket is dropped.
    assert estimate(1.0, 1.5, None) == pytest.approx(1.5, rel=1e-15)
    # Vectorized, with a floor (scalar or per element) and NaN passed through.
    e = estimate(np.array([1.0, 2.0, np.nan]), np.array([1.0 + 1e-3, 2.0, 0.0]), 6.0, floor=1e-10)
    np.testing.assert_allclose(e[:2], [3e-3 * 64 / 63, 1e-10], rtol=1e-12)
    assert np.isnan(e[2])
    assert estimate(1.0, 1.0 + 1e-14, 6.0, floor=1e-10) == 1e-10
    assert estimate([0.0, 0.0], [0.0, 0.0], 3.0, floor=[1e-9, 1e-8]).tolist() == [1e-9, 1e-8]
    with pytest.raises(ValueError, match="ratio"):
        estimate(1.0, 2.0, 2.0, ratio=1.0)
    with pytest.raises(ValueError, match="order"):
        estimate(1.0, 2.0, 0.0)


def test_estimate_bounds_a_model_sequence():
    """For Q_h = Q + C h^p (+ a smaller term) the estimate is about Fs times the true error."""
    p, Q = 4.0, 1.0
    for h in (0.5, 0.25, 0.1):
        coarse = Q + 0.3 * h**p + 0.05 * h ** (p + 1)
        fine = Q + 0.3 * (h / 2) ** p + 0.05 * (h / 2) ** (p + 1)
        ratio = estimate(coarse, fine, p) / abs(coarse - Q)
        assert 2.5 < ratio < 3.5


def test_describe_to_dict():
    d = describe(FiniteElement(16, 3), floor="Newton").to_dict()
    assert d["method"] == "h-refinement" and d["refined"] == "P3:32"
    assert d["discretization"] == "P3:16" and d["safety_factor"] == 3.0
    assert d["order"] == 6 and isinstance(d["order"], int) and d["ratio"] == 2.0
    assert "2^6 / (2^6 - 1)" in d["formula"] and d["floor"] == "Newton"
    m = describe(Modal(4)).to_dict()
    assert m["method"] == "N-doubling" and m["refined"] == "modal:8" and m["order"] == 3


@pytest.mark.parametrize("coarse", [FiniteElement(4, 2), FiniteElement(3, 3), Modal(3)])
def test_projection_is_exact_between_nested_spaces(coarse):
    rng = np.random.default_rng(1)
    fine = refine(coarse)
    q = rng.standard_normal((coarse.n, 2))
    x = rng.uniform(0, 1, 17)
    qf = project(coarse, q, fine)
    assert qf.shape == (fine.n, 2)
    np.testing.assert_allclose(fine.evaluate(qf, x), coarse.evaluate(q, x), atol=1e-12)
    np.testing.assert_allclose(project(coarse, q[:, 0], fine), qf[:, 0], atol=1e-14)


def test_match_events_by_branch_type_and_mode_not_position():
    def ev(branch, type_, mode, v):
        return {"branch": branch, "type": type_, "mode": mode, "v": v}

    coarse = [
        ev("primary", "flutter", 2, 6.0),
        ev("primary", "flutter", 3, 9.0),
        ev("B1+", "fold", 1, 3.1),
        ev("B1-", "fold", 1, 3.1),
        ev("primary", "flutter", 2, 9.5),
    ]
    fine = [
        ev("B1-", "fold", 1, 3.11),
        ev("primary", "divergence", 1, 0.0),
        ev("primary", "flutter", 2, 6.1),
        ev("B1+", "fold", 1, 3.11),
    ]
    pairs, unmatched = match_events(coarse, fine)
    assert pairs == [2, None, 3, 0, None]
    assert unmatched == [1]


# ---------------------------------------------------------------- static --
def _static_reference(alpha, vs):
    disc = FiniteElement(64, 3)
    sols = solve_path(PipeModel(disc, Params(alpha=alpha)), vs)
    return [compute_tip(disc, s.q, alpha) for s in sols]


@pytest.mark.parametrize(
    "disc, refined, order",
    [
        (["--fe", "P2:4"], "P2:8", 4),
        (["--modal", "3"], "modal:7", 3),
        (["--modal", "3", "--basis", "beam"], "modal-beam:7", 4),
    ],
)
def test_static_estimates_bound_the_true_error(capsys, disc, refined, order):
    argv = ["static", *disc, "--alpha", "pi/2", "--v", "0,5"]
    d = run_json(capsys, [*argv, "--error-estimate"])
    ref = _static_reference(math.pi / 2, [0.0, 5.0])
    for pt, r in zip(d["points"], ref, strict=True):
        for k in TIP:
            assert {k + "_error", k + "_refined"} <= set(pt)
            assert_bounds(pt[k + "_error"], pt[k], r[k], f"{k} at v = {pt['v']}")
        assert pt["tip_drop_error"] == pytest.approx(pt["X_tip_error"], rel=1e-9)
    est = d["error_estimate"]
    assert est["refined"] == refined and est["order"] == order and est["notes"] == []
    # The reported numbers are those of the run without the option.
    plain = run_json(capsys, argv)
    for a, b in zip(plain["points"], d["points"], strict=True):
        assert all(a[k] == b[k] for k in a)


def test_static_without_the_option_is_unchanged(capsys, tmp_path):
    d = run_json(capsys, ["static", "--fe", "P2:4", "--v", "0,1", "--out", str(tmp_path)])
    assert set(d) == {"points", "params", "discretization"}
    # stable is the 3-D verdict, with each plane's beside it (docs, "Out of the plane")
    keys = STATIC_POINT_KEYS | {"stable_in_plane", "stable_out_of_plane"}
    assert all(set(p) == keys for p in d["points"])
    planar = run_json(capsys, ["static", "--fe", "P2:4", "--v", "0,1", "--planar"])
    assert all(set(p) == STATIC_POINT_KEYS for p in planar["points"])
    header = (tmp_path / "static.csv").read_text().splitlines()[0]
    assert "_error" not in header and "_refined" not in header


def test_static_csv_and_si_values(capsys, tmp_path):
    si = ["--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058", "--g", "9.8"]
    argv = ["static", "--modal", "3", *si, "--alpha", "90deg", "--U", "0,1"]
    plain = tmp_path / "plain"
    run_json(capsys, [*argv, "--out", str(plain)])
    d = run_json(capsys, [*argv, "--error-estimate", "--out", str(tmp_path / "est")])
    old = (plain / "static.csv").read_text().splitlines()[0].split(",")
    new = (tmp_path / "est" / "static.csv").read_text().splitlines()[0].split(",")
    # The existing columns first, unchanged; then the errors, with their column's unit.
    assert new[: len(old)] == old
    assert "X_tip_error [L]" in new and "theta_tip_error [rad]" in new
    assert "tip_drop_mm_error [mm]" in new and not any("_refined" in c for c in new)
    cols = read_csv(tmp_path / "est" / "static.csv")
    for i, pt in enumerate(d["points"]):
        assert pt["X_tip_m_error"] == pytest.approx(0.094 * pt["X_tip_error"], rel=1e-12)
        assert pt["tip_drop_mm_error"] == pytest.approx(94 * pt["tip_drop_error"], rel=1e-12)
        for k in ("X_tip_error", "theta_tip_error", "X_tip_m_error"):
            assert cols[k][i] == pt[k]


def test_static_table_shows_plus_minus(capsys):
    assert main(["static", "--modal", "3", "--v", "1", "--error-estimate", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert out.count(" ± ") >= 4 and "N-doubling to modal:7" in out


# -------------------------------------------------------------- critical --
@pytest.mark.parametrize("disc", [["--fe", "P2:4"], ["--modal", "3"]])
def test_critical_v_cr_estimate_bounds_the_true_error(capsys, disc):
    from fempipe.analyses.stability import find_critical_velocity

    argv = ["critical", *disc, "--alpha", "pi/2", "--v", "0,8", "--no-branches"]
    d = run_json(capsys, [*argv, "--error-estimate"])
    model = PipeModel(FiniteElement(16, 3), Params(alpha=math.pi / 2))
    ref = find_critical_velocity(model, 8.0, planes=("in", "out"))
    assert_bounds(d["v_cr_error"], d["v_cr"], ref.v_cr, "v_cr")
    for plane in ("in_plane", "out_of_plane"):
        key = "v_cr_" + plane
        assert_bounds(d[key + "_error"], d[key], getattr(ref, plane).v_cr, key)
    c = d["critical"]
    assert_bounds(c["frequency_error"], c["frequency"], ref.critical.frequency, "frequency")
    assert c["v_error"] == d["v_cr_error"] == d["v_flutter_error"]
    assert d["v_cr_refined"] == c["v_refined"]
    ev = d["events"][0]
    assert ev["v_error"] == d["v_cr_error"] and ev["error_note"] is None
    assert d["error_estimate"]["method"] in ("h-refinement", "N-doubling")


def test_critical_events_matched_by_kind_and_mode(capsys, tmp_path):
    """alpha = pi: the start divergence, the restabilization, the flutter and the folds
    of both buckled branches all find their partner in the refined run."""
    d = run_json(
        capsys,
        ["critical", "--fe", "P2:4", "--alpha", "pi", "--v", "0,6", "--error-estimate"]
        + ["--out", str(tmp_path)],
    )
    assert set(d) == CRITICAL_KEYS | SPATIAL_KEYS | SPATIAL_ERROR_KEYS | {
        "v_cr_error",
        "v_cr_refined",
        "v_flutter_error",
        "v_flutter_refined",
        "error_estimate",
    }
    kinds = {(e["branch"], e["type"]) for e in d["events"]}
    assert {("B1+", "fold"), ("B1-", "fold"), ("primary", "restabilization")} <= kinds
    for e in d["events"]:
        assert e["error_note"] is None and e["v_error"] > 0
        # Each event's refined partner is of its own kind, close by.
        assert abs(e["v_refined"] - e["v"]) < 0.05
    start = d["events"][0]
    assert start["v"] == start["v_refined"] == 0.0 and start["v_error"] == 1e-10
    cols = read_csv(tmp_path / "events.csv")
    assert {"v_error", "frequency_error"} <= set(cols) and "v_refined" not in cols
    rows = sorted(d["events"], key=lambda e: e["v"])
    np.testing.assert_array_equal(cols["v_error"], [e["v_error"] for e in rows])


def test_critical_unmatched_event_gets_null_and_a_note(capsys, monkeypatch):
    """An event missing in the refined run: null error, a note; no v_cr estimate."""
    import dataclasses

    import fempipe.analyses.stability as stability

    real = stability.analyse_stability
    calls = []

    def fake(model, **kw):
        res = real(model, **kw)
        calls.append(model.disc.name)
        if len(calls) == 2:  # the refined run: its flutter renamed to another mode
            events = tuple(dataclasses.replace(e, mode=7) for e in res.events)
            res = dataclasses.replace(res, events=events, critical=events[0])
        return res

    monkeypatch.setattr(stability, "analyse_stability", fake)
    # The planar analysis (the pairing of events is the same code in 3-D, by plane too).
    argv = ["critical", "--planar", "--modal", "3", "--alpha", "pi/2", "--v", "0,8"]
    argv += ["--no-branches"]
    d = run_json(capsys, [*argv, "--error-estimate"])
    assert calls == ["modal:3", "modal:7"]
    ev = d["events"][0]
    assert ev["v_error"] is None and ev["v_refined"] is None
    assert "no flutter of mode 2" in ev["error_note"]
    assert d["v_cr_error"] is None and d["v_cr_refined"] is not None
    notes = " ".join(d["error_estimate"]["notes"])
    assert "flutter of mode 7" in notes and "v_cr" in notes


def test_critical_without_the_option_is_unchanged(capsys):
    d = run_json(capsys, ["critical", "--modal", "3", "--alpha", "pi/2", "--v", "0,8"])
    assert set(d) == CRITICAL_KEYS | SPATIAL_KEYS
    planar = run_json(
        capsys, ["critical", "--modal", "3", "--alpha", "pi/2", "--v", "0,8"] + ["--planar"]
    )
    assert set(planar) == CRITICAL_KEYS
    # Flutter events also carry the Hopf keys (fempipe.analyses.stability.hopf.EVENT_KEYS).
    hopf = set(HOPF_KEYS)
    assert all(
        set(e) == EVENT_KEYS | (hopf if e["type"] == "flutter" else set()) for e in d["events"]
    )
    assert "v_error" not in d["critical"]


def test_critical_text_shows_plus_minus(capsys):
    argv = ["critical", "--modal", "3", "--alpha", "pi/2", "--v", "0,8", "--no-branches"]
    assert main([*argv, "--error-estimate", "--quiet"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("stability")
    m = re.search(r"v_cr = (\d+\.\d{10}) ± (\d\.\de[-+]\d+)", out)
    assert m, out
    # The JSON's v_cr and error: events are located to 1e-10 max(1, |v|) (not to the
    # printed last digit), the error shown with two digits.
    d = run_json(capsys, [*argv, "--error-estimate", "--json", "--quiet"])
    assert float(m[1]) == pytest.approx(d["v_cr"], abs=1e-10 * d["v_cr"] + 5e-11)
    assert float(m[2]) == pytest.approx(d["v_cr_error"], rel=0.05)


# -------------------------------------------------------------- simulate --
def test_simulate_cycle_estimates_bound_the_true_error(capsys):
    from fempipe.analyses.limit_cycle import find_attractor

    d = run_json(capsys, ["simulate", "--modal", "3", "--v", "9", "--error-estimate"])
    assert d["attractor"] == d["attractor_refined"] == "periodic"
    ref = find_attractor(PipeModel(FiniteElement(4, 3), Params(v=9.0)))
    assert_bounds(d["period_error"], d["period"], ref.period, "period")
    assert set(d["tip_error"]) == set(d["tip"]) == set(d["tip_refined"])
    for k, (lo, hi) in d["tip"].items():
        e_lo, e_hi = d["tip_error"][k]
        assert_bounds(e_lo, lo, ref.tip[k][0], f"{k} min")
        assert_bounds(e_hi, hi, ref.tip[k][1], f"{k} max")
    assert d["error_estimate"]["refined"] == "modal:7" and d["error_estimate"]["notes"] == []


def test_simulate_equilibrium_and_without_the_option(capsys):
    argv = ["simulate", "--modal", "3", "--v", "3"]
    plain = run_json(capsys, argv)
    assert set(plain) == SIMULATE_KEYS
    d = run_json(capsys, [*argv, "--error-estimate"])
    assert d["attractor"] == d["attractor_refined"] == "equilibrium"
    assert d["period"] is None and d["period_error"] is None
    # The straight hanging pipe is exact on both: the error is the floor, Newton's
    # 1e-10 max(1, |X_tip|), with X_tip = 1 to round-off (1 + 2e-16 on some kernels).
    assert d["tip"]["X_tip"] == pytest.approx([1.0, 1.0], abs=1e-14)
    assert d["tip_error"]["X_tip"] == [1e-10 * max(1.0, abs(x)) for x in d["tip"]["X_tip"]]
    assert set(d) - set(plain) == {
        "attractor_refined",
        "period_error",
        "period_refined",
        "tip_error",
        "tip_refined",
        "error_estimate",
    }


def test_simulate_attractors_of_different_kinds_give_no_number(capsys, monkeypatch):
    import fempipe.studies.estimates.attractor as attractor_estimates

    def fake(model, att, fine_model, **kwargs):
        return attractor_estimates.AttractorSummary.of("equilibrium", tip=att.tip), []

    monkeypatch.setattr(attractor_estimates, "refine_cycle", fake)
    d = run_json(capsys, ["simulate", "--modal", "2", "--v", "9", "--error-estimate"])
    assert d["attractor"] == "periodic" and d["attractor_refined"] == "equilibrium"
    assert d["period_error"] is None and d["tip_error"] is None
    assert "the attractors differ" in " ".join(d["error_estimate"]["notes"])


# -------------------------------------------------------------- progress --
def _progress_counts(monkeypatch, capsys, argv):
    import fempipe.cli.reporting as reporting

    monkeypatch.setattr(reporting, "LOG_INTERVAL", 0.0)
    assert main(argv) == 0
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("fempipe: ")]
    return [line.split(": ")[2].split(",")[0] for line in lines]


def test_progress_counts_the_refined_work(monkeypatch, capsys):
    static = ["static", "--modal", "2", "--v", "0,1,2"]
    assert _progress_counts(monkeypatch, capsys, static)[-1].startswith("3/3")
    assert _progress_counts(monkeypatch, capsys, [*static, "--error-estimate"])[-1].startswith(
        "6/6"
    )
    crit = ["critical", "--modal", "3", "--alpha", "pi/2", "--v", "0,8", "--no-branches"]
    plain = int(_progress_counts(monkeypatch, capsys, crit)[-1])
    both = int(_progress_counts(monkeypatch, capsys, [*crit, "--error-estimate"])[-1])
    assert both > plain + 10
    sim = ["simulate", "--modal", "3", "--v", "3", "--error-estimate"]
    assert _progress_counts(monkeypatch, capsys, sim)[-1].startswith("200/200")


# ---------------------------------------------------------- measurement --
def test_bound_measurement_on_a_small_subset():
    """validation/error_estimate_bounds.py, the docs' measurement, on four cases."""
    sys.path.insert(0, str(Path(__file__).parents[1] / "validation"))
    from error_estimate_bounds import measure

    config = {
        "static_alphas": (math.pi / 2,),
        "static_vs": (2.0,),
        "critical_alphas": (math.pi / 2,),
        "discretizations": ("P2:4", "modal:3"),
        "static_reference": 32,
        "critical_reference": 16,
    }
    res = measure(config)
    s = res["summary"]["all"]
    assert s["cases"] == 2 * 4 + 2 * 2 and s["no_estimate"] == 0
    assert s["resolvable"] == s["cases"] and s["bounded"] == s["cases"]
    assert 1.0 <= s["min_ratio"] <= s["max_pessimism"] <= 100.0


def test_expected_order_with_the_variants_of_the_pipe():
    """Variants that break the solution's smoothness lower the order the estimate assumes."""
    fe = FiniteElement(4, 3)
    assert expected_order(fe, Params(springs=((50.0, 0.5),))) == 6.0  # a node of P3:4
    assert expected_order(fe, Params(springs=((50.0, 0.3),))) == 3.0  # inside an element
    assert expected_order(FiniteElement(4, 1), Params(springs=((50.0, 0.3),))) == 2.0
    assert expected_order(fe, Params(end_mass=0.5, external_damping=1.0)) == 6.0
    beam = Modal(4, basis="beam")
    assert expected_order(beam, Params(end_mass=0.2)) == 2.0
    assert expected_order(beam, Params(springs=((50.0, 1.0),))) == 2.0
    assert expected_order(beam, Params(springs=((50.0, 0.5),))) == 3.0
    assert expected_order(Modal(4), Params(end_mass=0.2)) == 3.0


def test_static_estimate_bounds_the_error_with_a_spring_inside_an_element(capsys):
    """The estimate states order 3 (theta'' jumps inside an element) and bounds the error."""
    argv = ["static", "--fe", "P3:4", "--alpha", "pi/2", "--spring", "30@0.3", "--v", "2"]
    d = run_json(capsys, [*argv, "--error-estimate"])
    assert d["error_estimate"]["order"] == 3
    p = Params(alpha=math.pi / 2, springs=((30.0, 0.3),))
    # P3 on 70 elements has a node at 0.3: the reference converges as h^6.
    ref_disc = FiniteElement(70, 3)
    (sol,) = solve_path(PipeModel(ref_disc, p), [0.0, 2.0])[-1:]
    ref = compute_tip(ref_disc, sol.q, p.alpha)
    (pt,) = d["points"]
    for k in TIP:
        assert_bounds(pt[k + "_error"], pt[k], ref[k], k)


# -------------------------------------------------------------- library --
def test_library_attaches_the_static_estimates_of_the_cli(capsys):
    """fempipe.studies.estimates gives a library user the numbers of --error-estimate."""
    from fempipe.studies.error_estimate import ERROR, REFINED, STATIC_TIP_KEYS
    from fempipe.studies.estimates import estimate_errors

    argv = ["static", "--modal", "3", "--alpha", "pi/2", "--v", "0,2", "--error-estimate"]
    d = run_json(capsys, argv)
    model = PipeModel(Modal(3), Params(alpha=math.pi / 2))
    sols = solve_path(model, [0.0, 2.0])
    seen = []
    points = []
    for sol in sols:
        tip = compute_tip(model.disc, sol.q, math.pi / 2)
        row = {k: tip[k] for k in STATIC_TIP_KEYS}
        row["tip_drop"] = tip["X_tip"] - math.cos(math.pi / 2)
        points.append(row)
    result = estimate_errors({"points": points}, model, sols, callback=lambda i, s: seen.append(i))
    assert seen == [0, 1]
    assert (
        result["error_estimate"]["refined"] == "modal:7" and result["error_estimate"]["notes"] == []
    )
    assert result["error_estimate"] == d["error_estimate"]
    for mine, cli in zip(result["points"], d["points"], strict=True):
        for k in (*STATIC_TIP_KEYS, "tip_drop"):
            assert mine[k + ERROR] == cli[k + ERROR] and mine[k + REFINED] == cli[k + REFINED]

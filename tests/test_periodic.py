"""Pseudo-arclength continuation of periodic orbits (fempipe.analyses.periodic, bifurcation --method
continuation).

The reference for the orbits is the independent attractor finder of the sweep
(:func:`fempipe.analyses.limit_cycle.find_attractor`: a transient integration from the
perturbed equilibrium, then shooting from the recurrent section point), which
shares only the integrator with the continuation; the Hopf point and the
equilibria's stability come from the linear stability analysis, checked here
against the orbits' own limits (the period tends to 2 pi / omega, the swing to 0).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from clirun import run_json

from fempipe.analyses.limit_cycle import find_attractor
from fempipe.analyses.periodic import (
    CycleContinuationError,
    CyclePoint,
    compute_cycle_diagram,
    continue_cycles,
    find_hopf_points,
    special_points,
)
from fempipe.analyses.stability import linearly_stable
from fempipe.analyses.statics import solve_static
from fempipe.cli import main
from fempipe.model.discretization import parse_discretization
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

# P2:4 flutters at v_H = 6.3398 (alpha = 0); the requested values straddle it, and
# 6.345 lies between v_H and the first orbit of the continuation (a step passes it).
VALUES = "6.0,6.345,6.65,6.95"
ARGV = ["bifurcation", "--fe", "P2:4", "--v", VALUES, "--json", "--quiet", "--planar"]


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """One continuation run through the CLI, with its store."""
    from contextlib import redirect_stdout
    from io import StringIO

    out = tmp_path_factory.mktemp("cycles") / "run"
    buf = StringIO()  # capsys is function-scoped: capture by hand
    with redirect_stdout(buf):
        code = main([*ARGV, "--out", str(out)])
    assert code == 0
    return json.loads(buf.getvalue()), out


def _cycles(d, requested=True):
    return [
        p
        for p in d["points"]
        if p["direction"] == "continuation" and (p["requested"] or not requested)
    ]


def test_json_contract(run):
    d, out = run
    assert d["method"] == "continuation"
    keys = {"v", "direction", "index", "alpha", "attractor", "eta_tip", "X_tip", "Z_tip",
            "period", "period_n", "max_multiplier", "steps", "rejected_steps", "wall_time",
            "stable", "branch", "requested", "source", "floquet_multipliers"}  # fmt: skip
    for p in d["points"]:
        assert keys <= set(p)
    eq = [p for p in d["points"] if p["direction"] == "static"]
    assert [p["v"] for p in eq] == [6.0, 6.345, 6.65, 6.95]
    # Every requested v above the Hopf point is landed on exactly, once.
    assert sorted(p["v"] for p in _cycles(d)) == [6.345, 6.65, 6.95]
    assert any(not p["requested"] for p in _cycles(d, requested=False))
    assert [b["name"] for b in d["branches"]] == ["H1"] and d["errors"] == []
    for name in ("eta_tip.png", "X_tip.png", "Z_tip.png", "bifurcation.json"):
        assert (out / name).stat().st_size > 0


def test_stable_cycles_agree_with_the_sweep(run):
    """Period and tip extrema of the continued orbits = those of the attractor finder."""
    d, _ = run
    disc = parse_discretization("P2:4")
    for p in _cycles(d):
        assert p["stable"] and p["max_multiplier"] < 1
        if p["v"] < 6.6:  # the attractor finder's transient is too slow this near v_H
            continue
        m = PipeModel(disc, Params(alpha=0.0, v=p["v"]))
        att = find_attractor(m, shoot_rtol=1e-6)
        assert att.kind == "periodic"
        assert abs(att.period - p["period"]) < 1e-6
        for k in ("eta_tip", "X_tip", "Z_tip"):
            assert np.max(np.abs(np.subtract(att.tip[k], p[k]))) < 1e-6, k


def test_multipliers_at_the_requested_v_are_those_of_the_orbit(run):
    """The Floquet multipliers reported at a requested v are those of the converged orbit
    (the monodromy of a shot at rtol 1e-10 from it): the trivial one at 1, the others
    to 1e-6, not those of an earlier chord iterate (1e-3 off, see MONODROMY_NEAR)."""
    from fempipe.analyses.limit_cycle import shoot

    d, _ = run
    disc = parse_discretization("P2:4")
    for p in _cycles(d):
        if p["v"] < 6.6:  # the attractor finder's transient is too slow this near v_H
            continue
        m = PipeModel(disc, Params(alpha=0.0, v=p["v"]))
        att = find_attractor(m, shoot_rtol=1e-6)
        c = shoot(PipeDynamics(m), att.cycle.q0, att.cycle.qdot0, att.cycle.period, rtol=1e-10)
        ref = np.sort(np.abs(c.floquet_multipliers))[::-1][: len(p["floquet_multipliers"])]
        got = np.sort(np.abs([complex(*z) for z in p["floquet_multipliers"]]))[::-1]
        assert np.max(np.abs(got - ref)) < 1e-6, (p["v"], got[:3], ref[:3])


def test_corrector_takes_the_monodromy_at_the_orbit_when_asked():
    """From a predictor 1e-4 off the orbit the chord iteration keeps the monodromy of
    its first iterate: 1e-3 of the amplitude away is near enough on the continuation's
    own steps (MONODROMY_NEAR), not at a requested v (MONODROMY_AT_ORBIT), where one
    more flow gives the multipliers of the converged orbit (shot at rtol 1e-10)."""
    from fempipe.analyses.limit_cycle import shoot
    from fempipe.analyses.periodic import (
        MONODROMY_AT_ORBIT,
        MONODROMY_NEAR,
        CycleCorrector,
        HopfPoint,
    )

    m = PipeModel(parse_discretization("P2:4"), Params(alpha=0.0, v=6.95))
    c = shoot(*_orbit_guess(m), rtol=1e-10)
    ref = np.sort(np.abs(c.floquet_multipliers))[::-1]
    n = m.n
    hopf = HopfPoint(6.34, 2 * math.pi / c.period, "flutter", np.zeros(n), np.zeros(2 * n))
    u = np.r_[c.q0, c.qdot0, c.period, m.params.v]
    off = u * (1.0 + 1e-4 * np.cos(np.arange(u.size)))
    off[-1] = u[-1]
    errors = {}
    for near in (MONODROMY_NEAR, MONODROMY_AT_ORBIT):
        cont = CycleCorrector(m, hopf, 1e-7, 1e-8, 1e-7, 12)
        _, _, mono, _, _ = cont.correct(off, None, u, 1e-7, near)
        got = np.sort(np.abs(np.linalg.eigvals(mono)))[::-1]
        errors[near] = float(np.max(np.abs(got - ref)))
    assert errors[MONODROMY_AT_ORBIT] < 1e-6
    assert errors[MONODROMY_NEAR] > 10 * errors[MONODROMY_AT_ORBIT]


def _orbit_guess(m):
    att = find_attractor(m, shoot_rtol=1e-6)
    return PipeDynamics(m), att.cycle.q0, att.cycle.qdot0, att.cycle.period


def test_branch_starts_at_the_hopf_point(run):
    """The first orbits extrapolate to the Hopf point of the linear analysis: near it
    v - v_H and T - 2 pi / omega grow like the squared amplitude (Kuznetsov, Sec. 3.5)."""
    d, _ = run
    hopf = d["hopf_points"][0]
    a, b = [p for p in _cycles(d, requested=False) if not p["requested"]][:2]
    assert hopf["v"] < a["v"] < b["v"]  # supercritical: the orbits lie on the unstable side
    sa, sb = ((p["eta_tip"][1] - p["eta_tip"][0]) ** 2 for p in (a, b))

    def at_zero(key):
        return a[key] - sa * (b[key] - a[key]) / (sb - sa)

    T_H = 2 * math.pi / hopf["omega"]
    assert abs(at_zero("v") - hopf["v"]) < 2e-3
    assert abs(at_zero("period") - T_H) < 1e-3 * T_H


def test_hopf_points_carry_the_equilibrium_where_the_branch_starts(run, capsys):
    """Each Hopf point of the JSON carries the tip of its equilibrium ([y, y], as
    the diagram's points): the straight pipe at alpha = 0, and at alpha = pi/2
    the static solution at v_H solved on its own (the figures mark the Hopf
    point there, also when v_H lies outside the requested v)."""
    from fempipe.model.kinematics import compute_tip

    d, _ = run
    (h,) = d["hopf_points"]
    assert (h["eta_tip"], h["X_tip"], h["Z_tip"]) == ([0.0, 0.0], [1.0, 1.0], [0.0, 0.0])
    argv = [
        "bifurcation",
        "--modal",
        "2",
        "--alphas",
        "pi/2",
        "--v",
        "6,7",
        "--json",
        "--quiet",
        "--planar",
    ]
    (h,) = run_json(capsys, argv)["hopf_points"]
    assert 6.0 < h["v"] < 7.0
    disc = parse_discretization(modal=2)
    m = PipeModel(disc, Params(alpha=math.pi / 2, v=h["v"]))
    tip = compute_tip(disc, solve_static(m).q, math.pi / 2)
    for k in ("eta_tip", "X_tip", "Z_tip"):
        assert h[k][0] == h[k][1]
        assert abs(h[k][0] - tip[k]) < 1e-8, k


def test_equilibria_stability_is_the_linear_criterion(run):
    d, _ = run
    disc = parse_discretization("P2:4")
    for p in (p for p in d["points"] if p["direction"] == "static"):
        m = PipeModel(disc, Params(alpha=0.0, v=p["v"]))
        assert p["stable"] == linearly_stable(m, solve_static(m).q)


def test_rerun_resumes_without_recomputing(run, capsys):
    d, out = run
    stored = sorted((out / "points").glob("*.json"))
    mtimes = [f.stat().st_mtime_ns for f in stored]
    again = run_json(capsys, [*ARGV, "--out", str(out)])
    assert [f.stat().st_mtime_ns for f in stored] == mtimes
    assert again["points"] == d["points"]
    # A changed argument is refused, not mixed with the stored points.
    code = main([*ARGV[:-2], "--orbit-rtol", "1e-6", "--json", "--quiet", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "--out" in err and "different run" in err


def test_interrupted_branch_resumes_to_the_same_points(run, tmp_path):
    """Stop after a few points; the rerun continues from the stored state and
    ends on the same orbits as the uninterrupted run."""
    d, _ = run
    model = PipeModel(parse_discretization("P2:4"), Params(alpha=0.0, v=6.0))
    calls = []

    class StopError(Exception):
        pass

    def stop_after_three(_done, _total):
        calls.append(1)
        if len(calls) == 4:  # the static part, then three orbits
            raise StopError

    values = [float(v) for v in VALUES.split(",")]
    with pytest.raises(StopError):
        compute_cycle_diagram(
            model, values, store_dir=tmp_path, progress=stop_after_three, rtol=1e-5
        )
    branch = json.loads((tmp_path / "a00-H1.json").read_text())
    assert 3 <= len(branch["points"]) < 8 and branch["end_reason"] is None
    diag = compute_cycle_diagram(model, values, store_dir=tmp_path, rtol=1e-5)
    got = [(p["v"], p["period"], p["eta_tip"]) for p in _cycles(diag.to_dict(), False)]
    want = [(p["v"], p["period"], p["eta_tip"]) for p in _cycles(d, False)]
    assert got == want


def test_failure_names_v_and_step_and_keeps_the_points(monkeypatch):
    import fempipe.analyses.periodic.problem as per
    from fempipe.solvers.radau import IntegrationError

    model = PipeModel(parse_discretization("P2:4"), Params(alpha=0.0, v=6.0))
    (hopf,), _ = find_hopf_points(model, 6.0, 7.0)
    real = per.period_flow

    def failing(m, x, T, rtol, sensitivity):
        if m.params.v > hopf.v + 0.05:
            raise IntegrationError("diverging", 0.0, 1e-9)
        return real(m, x, T, rtol, sensitivity)

    monkeypatch.setattr(per, "period_flow", failing)
    states = []
    with pytest.raises(CycleContinuationError) as exc:
        continue_cycles(model, hopf, (6.0, 7.0), [6.65], on_point=states.append)
    msg = str(exc.value)
    assert "cannot be continued beyond v = " in msg and "(step " in msg
    kept = exc.value.branch.points
    assert kept and all(p.v <= hopf.v + 0.05 for p in kept)
    # Resumed from its last state, the failed branch fails again with its points (no work).
    with pytest.raises(CycleContinuationError) as again:
        continue_cycles(model, hopf, (6.0, 7.0), [6.65], resume=states[-1])
    assert str(again.value) == msg
    assert [p.v for p in again.value.branch.points] == [p.v for p in kept]


def _pt(v, T, mu):
    return CyclePoint(
        v=v,
        period=T,
        q0=np.zeros(1),
        qdot0=np.zeros(1),
        tip={"eta_tip": [-v, v]},
        multipliers=np.array([1.0, *mu], dtype=complex),
    )


def test_special_points_are_detected_and_located():
    """A branch turning back in v (fold at the vertex of v(s)), a real multiplier
    through -1 and a complex pair through the unit circle, each linear in v."""
    # v rises, then falls: a fold between, at the vertex of the parabola (above 0.75).
    sp = special_points([_pt(0.0, 1.0, [0.5]), _pt(0.75, 1.0, [0.5]), _pt(0.74, 1.0, [0.5])])
    assert [s.type for s in sp] == ["fold"] and sp[0].v > 0.75
    # mu = -0.8 - 0.4 (v - 1): -1 at v = 1.5
    pd = [_pt(1.0, 1.0, [-0.8]), _pt(2.0, 1.2, [-1.2])]
    (s,) = special_points(pd)
    assert s.type == "period_doubling" and s.v == pytest.approx(1.5)
    assert s.period == pytest.approx(1.1)
    # |mu| = 0.9 + 0.2 (v - 1): 1 at v = 1.5
    r0, r1 = 0.9, 1.1
    ns = [_pt(1.0, 1.0, [r0 * 1j, -r0 * 1j]), _pt(2.0, 1.0, [r1 * 1j, -r1 * 1j])]
    (s,) = special_points(ns)
    assert s.type == "neimark_sacker" and s.v == pytest.approx(1.5)
    assert special_points([pd[0], _pt(2.0, 1.0, [-0.9])]) == []


@pytest.mark.slow
def test_fig07_default_discretization_agrees_with_the_sweep(capsys):
    """P3:16, alpha = 0, v = 5:12:36: every stable orbit of the continuation
    agrees with the sweep up to 1e-6 in the period and the tip extrema."""
    argv = ["bifurcation", "--v", "5:12:36", "--json", "--quiet", "--planar"]
    cont = run_json(capsys, argv)
    sweep = run_json(capsys, [*argv, "--method", "sweep", "--directions", "up"])
    cyc = {round(p["v"], 9): p for p in _cycles(cont) if p["stable"]}
    n = 0
    for p in sweep["points"]:
        if p["attractor"] != "periodic":
            continue
        q = cyc[round(p["v"], 9)]
        n += 1
        assert abs(p["period"] - q["period"]) < 1e-6
        for k in ("eta_tip", "X_tip", "Z_tip"):
            assert np.max(np.abs(np.subtract(p[k], q[k]))) < 1e-6
    assert n >= 25
    # Equilibria: stable below v_cr, unstable above, as the sweep finds them.
    for p in sweep["points"]:
        if p["attractor"] == "equilibrium":
            eq = next(e for e in cont["points"] if e["direction"] == "static" and e["v"] == p["v"])
            assert eq["stable"]


@pytest.mark.slow
def test_subcritical_branch_folds_where_the_attractor_finder_loses_the_cycle():
    """A pipe with an end mass (beta = 0.15, Gamma = 0.5) flutters subcritically:
    unstable orbits leave the Hopf point towards lower v and turn, stable, at a
    cyclic fold.  Independently, the attractor finder started far from the
    equilibrium finds a periodic attractor just above the fold and the
    equilibrium just below it."""
    model = PipeModel(
        parse_discretization("P2:4"), Params(alpha=0.0, beta=0.15, end_mass=0.5, v=1.0)
    )
    (hopf,), _ = find_hopf_points(model, 1.0, 8.0)
    br = continue_cycles(model, hopf, (hopf.v - 1.0, hopf.v + 0.5), [], ds_max=0.3)
    assert not br.points[0].stable and br.points[0].v < hopf.v
    assert br.points[-1].stable and br.points[-1].v > hopf.v
    folds = [s for s in br.special_points if s.type == "fold"]
    assert len(folds) == 1 and [s.type for s in br.special_points] == ["fold"]
    v_fold = folds[0].v
    big = br.points[-1]
    for dv, kind in ((+0.004, "periodic"), (-0.01, "equilibrium")):
        m = model.with_params(model.params.with_flow(v_fold + dv))
        att = find_attractor(m, big.q0, big.qdot0, t_max=600.0)
        assert att.kind == kind, (dv, att.kind)

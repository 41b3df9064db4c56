"""Stability in three dimensions: the out-of-plane operators and the analysis of both planes."""

from __future__ import annotations

import json
import math
from dataclasses import replace

import numpy as np
import pytest

import fempipe.analyses.stability.analysis as analysis
from fempipe.analyses.stability import PLANES as BOTH
from fempipe.analyses.stability import analyse_stability, find_critical_velocity
from fempipe.analyses.statics import solve_sagged, solve_static
from fempipe.cli import main
from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.out_of_plane.model import (
    OutOfPlaneOperators,
    build_in_plane_model,
    build_out_of_plane_model,
)
from fempipe.model.params import Params
from fempipe.model.plane.operators import PipeModel

PAPER = {"beta": 0.142, "gamma": 18.9, "mu": 0.005}


def _energy_3d(model: PipeModel, q: np.ndarray, psi: np.ndarray) -> float:
    """Bending, gravity (pipe and end mass) and spring energy of the 3-D pipe whose tangent is
    t = cos(psi) (cos theta, sin theta, 0) + sin(psi) e_3, psi = Phi psi_coef (pipe frame).

    Written from the 3-D kinematics alone: |t'|^2, the weight's potential -gamma \\int g . r,
    the springs' (kappa/2) |r(xi_s) - xi_s e_1|^2; it shares no formula with the operators.
    """
    disc, p = model.disc, model.params
    quad = disc.quad
    Phi = disc.Phi.toarray() if disc.sparse else disc.Phi
    dPhi = disc.dPhi.toarray() if disc.sparse else disc.dPhi
    th, dth = Phi @ q, dPhi @ q
    ps, dps = Phi @ psi, dPhi @ psi
    bend = 0.5 * quad.w @ (dps**2 + dth**2 * np.cos(ps) ** 2)
    # gravity along (cos alpha, -sin alpha, 0) in the pipe's frame: g . t
    gt = np.cos(ps) * (np.cos(p.alpha) * np.cos(th) - np.sin(p.alpha) * np.sin(th))
    grav = -p.gamma * quad.w @ ((1.0 - quad.x + p.end_mass) * gt)
    springs = 0.0
    for kappa, xi_s in p.springs:
        rule = model.part_rule(xi_s)
        P = rule.Phi.toarray() if disc.sparse else np.asarray(rule.Phi)
        t_s, p_s = P @ q, P @ psi
        t3 = np.stack([np.cos(p_s) * np.cos(t_s), np.cos(p_s) * np.sin(t_s), np.sin(p_s)], axis=1)
        d = rule.w @ t3 - np.array([xi_s, 0.0, 0.0])
        springs += 0.5 * kappa * d @ d
    return float(bend + grav + springs)


@pytest.mark.parametrize(
    "disc", [FiniteElement(8, 3), Modal(6), Modal(6, basis="beam")], ids=lambda d: d.name
)
def test_stiffness_is_the_second_variation_of_the_3d_energy(disc):
    """At v = 0 the out-of-plane K is the Hessian in psi of the 3-D potential energy.

    Central differences of the energy of the kinematics alone (step 1e-3:
    truncation error ~1e-7 relative, round-off ~1e-10) against x^T K x for two
    random directions and their cross term.  Gravity, an end mass and two
    springs load the curved static state (alpha = 2), so every stiffness
    term (curvature, axial force of the weight, end mass and springs) is
    checked.
    """
    p = Params(alpha=2.0, v=0.0, end_mass=0.3, springs=((15.0, 0.45), (5.0, 1.0)), **PAPER)
    model = PipeModel(disc, p)
    q = solve_sagged(model).q
    K = OutOfPlaneOperators(model).matrices(q).K
    rng = np.random.default_rng(3)
    x, y = rng.standard_normal(disc.n), rng.standard_normal(disc.n)
    h = 1e-3

    def hess(a, b):
        e = lambda s, t: _energy_3d(model, q, s * a + t * b)  # noqa: E731
        return (e(h, h) - e(h, -h) - e(-h, h) + e(-h, -h)) / (4 * h * h)

    for a, b in ((x, x), (y, y), (x, y)):
        assert hess(a, b) == pytest.approx(a @ (0.5 * (K + K.T)) @ b, rel=1e-5)
    # without flow K is symmetric (a potential); the follower force is not
    assert np.abs(K - K.T).max() <= 1e-12 * np.abs(K).max()


@pytest.mark.parametrize(
    "disc", [FiniteElement(8, 3), Modal(5), Modal(5, basis="beam")], ids=lambda d: d.name
)
def test_straight_pipe_out_of_plane_equals_in_plane(disc):
    """theta^s = 0: every out-of-plane term is the planar one (all variants switched on)."""
    p = Params(
        alpha=0.0, v=3.5, end_mass=0.2, external_damping=0.3, springs=((8.0, 0.55),), **PAPER
    )
    model = PipeModel(disc, p)
    q = np.zeros(disc.n)
    out = build_out_of_plane_model(model)
    for a, b in zip(model.linearization(q), out.linearization(q), strict=True):
        assert np.abs(a - b).max() <= 1e-13 * max(1.0, np.abs(a).max())


def test_mirror_symmetry_of_the_out_of_plane_critical_velocity():
    """(theta, alpha) -> (-theta, -alpha) maps the static states and their out-of-plane
    problem onto each other: the same v_cr, to the 1e-10 of the events."""
    disc = FiniteElement(8, 3)
    r = [
        find_critical_velocity(PipeModel(disc, Params(alpha=a, **PAPER)), v_max=10, planes=BOTH)
        for a in (1.1, -1.1)
    ]
    assert r[0].out_of_plane.v_cr == pytest.approx(r[1].out_of_plane.v_cr, abs=1e-9)
    assert r[0].out_of_plane.critical.frequency == pytest.approx(
        r[1].out_of_plane.critical.frequency, abs=1e-8
    )


def test_neutral_rotation_mode_of_the_buckled_standing_pipe():
    """alpha = pi, buckled: lambda = 0 with the rotated static shape, the rest stable, and the
    uncorrected K x shrinking under refinement (the continuum's exact null vector)."""
    from fempipe.analyses.stability import compute_spectrum

    resid = []
    for n_el in (4, 8, 16):
        disc = FiniteElement(n_el, 3)
        model = PipeModel(disc, Params(alpha=math.pi, v=1.0, **PAPER))
        G = disc.gram.toarray()
        q = solve_static(model, q0=np.linalg.solve(G, disc.Phi.T @ (disc.quad.w * 2 * disc.quad.x)))
        assert abs(disc.tip @ q.q) > 1.0  # buckled
        ops = OutOfPlaneOperators(model)
        mats = ops.matrices(q.q)
        resid.append(mats.neutral_residual)
        assert np.linalg.norm(mats.K @ mats.neutral) <= 1e-12 * np.linalg.norm(mats.K)
        spec = compute_spectrum(build_out_of_plane_model(model), q.q)
        k = int(np.argmin(np.abs(spec.lam)))
        assert abs(spec.lam[k]) <= 1e-9
        x = np.real(spec.vectors[:, k] / spec.vectors[np.argmax(np.abs(mats.neutral)), k])
        x *= mats.neutral[np.argmax(np.abs(mats.neutral))]
        assert np.allclose(x, mats.neutral, atol=1e-8 * np.abs(mats.neutral).max())
        others = np.delete(spec.lam, k)
        assert np.all(others.real < 0.0)
    orders = np.log2(np.array(resid[:-1]) / np.array(resid[1:]))
    assert np.all(orders > 3.0)  # measured 3.7, 4.0


@pytest.mark.parametrize(
    "params",
    [
        {"alpha": 2.4},
        {"alpha": math.pi / 2, "end_mass": 0.2},
        {"alpha": 2.9, "gamma": 30.0},
    ],
)
def test_sparser_out_of_plane_samples_give_the_same_events(params, monkeypatch):
    """The out-of-plane analysis beside the in-plane one samples every third point: its
    events are those of every point to 1e-10 (located by Brent's method either way)."""
    model = PipeModel(FiniteElement(8, 3), Params(**{**PAPER, **params}))
    runs = {}
    for stride in (1, analysis.OUT_OF_PLANE_STRIDE):
        monkeypatch.setattr(analysis, "OUT_OF_PLANE_STRIDE", stride)
        runs[stride] = analyse_stability(model, v_max=12, planes=BOTH).out_of_plane.events
    a, b = runs.values()
    assert [(e.branch, e.type, e.mode) for e in a] == [(e.branch, e.type, e.mode) for e in b]
    assert max(abs(x.v - y.v) for x, y in zip(a, b, strict=True)) <= 1e-9


def test_inclined_pipe_flutters_out_of_the_plane_first():
    """Paper's case at alpha = pi/2: the first loss of stability is out of the plane; the FE
    value agrees with the beam modes (error ~N^-4) and with P3 on twice the elements."""
    p = Params(alpha=math.pi / 2, **PAPER)
    r8 = find_critical_velocity(PipeModel(FiniteElement(8, 3), p), v_max=10, planes=BOTH)
    r16 = find_critical_velocity(PipeModel(FiniteElement(16, 3), p), v_max=10, planes=BOTH)
    beam = find_critical_velocity(PipeModel(Modal(12, basis="beam"), p), v_max=10, planes=BOTH)
    assert r16.critical.plane == "out" and r16.critical.type == "flutter"
    assert r16.out_of_plane.v_cr < 0.95 * r16.in_plane.v_cr
    assert r8.out_of_plane.v_cr == pytest.approx(r16.out_of_plane.v_cr, abs=1e-5)
    assert beam.out_of_plane.v_cr == pytest.approx(r16.out_of_plane.v_cr, rel=1e-4)
    first = r16.first_instability()
    assert first["plane"] == "out" and first["v"] == r16.v_cr


def test_hanging_pipe_loses_stability_in_every_plane_at_once():
    r = find_critical_velocity(
        PipeModel(FiniteElement(8, 3), Params(alpha=0.0, **PAPER)), 10, planes=BOTH
    )
    assert r.out_of_plane.v_cr == r.in_plane.v_cr
    assert r.critical.plane == "in"


def test_critical_command_json_and_planar(capsys):
    args = ["critical", "--alpha", "90deg", "--v", "0,8", "--fe", "P3:6", "--no-branches"]
    assert main(args + ["--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in (
        "v_cr_in_plane",
        "frequency_in_plane",
        "v_cr_out_of_plane",
        "frequency_out_of_plane",
        "first_instability",
    ):
        assert key in d
    assert d["v_cr"] == min(d["v_cr_in_plane"], d["v_cr_out_of_plane"])
    assert d["first_instability"]["plane"] == "out"
    assert d["first_instability"]["v"] == d["v_cr"]
    assert all(e["plane"] in ("in", "out") for e in d["events"])
    out = [e for e in d["events"] if e["plane"] == "out" and e["type"] == "flutter"]
    assert out[0]["hopf_note"] is None and out[0]["Y_tip_amplitude_coefficient"] > 0
    assert main(args + ["--json", "--planar"]) == 0
    planar = json.loads(capsys.readouterr().out)
    assert "v_cr_out_of_plane" not in planar
    assert planar["v_cr"] == pytest.approx(d["v_cr_in_plane"], abs=1e-12)
    assert main(args) == 0
    text = capsys.readouterr().out
    assert "first loses stability out of the plane" in text


def test_critical_error_estimate_keys(capsys):
    args = ["critical", "--alpha", "120deg", "--v", "0,8", "--fe", "P3:4", "--no-branches"]
    assert main(args + ["--json", "--error-estimate"]) == 0
    d = json.loads(capsys.readouterr().out)
    for key in ("v_cr_error", "v_cr_in_plane_error", "v_cr_out_of_plane_error"):
        assert d[key] is not None and d[key] > 0
    assert d["v_cr_out_of_plane_refined"] == pytest.approx(d["v_cr_out_of_plane"], abs=1e-3)


def test_with_params_keeps_the_plane():
    planar = PipeModel(FiniteElement(4, 2), Params(alpha=1.0))
    model = build_out_of_plane_model(planar)
    assert model.plane == "out" and build_out_of_plane_model(model) is model
    assert model.with_params(replace(model.params, v=2.0)).plane == "out"
    back = build_in_plane_model(model)
    assert type(back) is PipeModel and back.plane == "in" and build_in_plane_model(planar) is planar
    assert back.disc is planar.disc and back.params == planar.params


def test_readme_example_of_the_3d_stability_runs(capsys):
    """The docs' Python example of the 3-D stability (docs/api/usage.md) runs and prints
    what it says."""
    from pathlib import Path

    page = Path(__file__).resolve().parents[1] / "docs" / "api" / "usage.md"
    block = page.read_text(encoding="utf-8").split("Stability in three dimensions (", 1)[1]
    code = block.split("```python\n", 1)[1].split("```", 1)[0]
    exec(compile(code, str(page), "exec"), {})
    lines = capsys.readouterr().out.splitlines()
    assert "'plane': 'out'" in lines[0] and "5.82089" in lines[0]
    assert lines[1].startswith("6.21009") and "5.82089" in lines[1]


def test_planes_is_validated_and_chooses_the_result():
    """``planes`` names the linear problems: a bad value is a ParamError naming it; an
    out-of-plane model needs "out"; one plane gives a StabilityResult of that plane."""
    from fempipe.analyses.stability import StabilityResult, trace_root_locus
    from fempipe.core.errors import ParamError

    model = PipeModel(Modal(2), Params(alpha=1.0, **PAPER))
    for planes in (("up",), (), ("in", "in"), "sideways"):
        with pytest.raises(ParamError, match="planes") as err:
            find_critical_velocity(model, 2.0, planes=planes)
        assert err.value.field == "planes"
    with pytest.raises(ParamError, match="planes"):
        trace_root_locus(build_out_of_plane_model(model), [0.0, 1.0])
    with pytest.raises(ParamError, match="'in', 'out'"):
        analyse_stability(model, 2.0, planes=("in", "z"))
    out = find_critical_velocity(build_out_of_plane_model(model), 10.0, planes=("out",))
    same = find_critical_velocity(model, 10.0, planes=("out",))
    assert isinstance(out, StabilityResult) and out.plane == "out"
    assert out.v_cr == same.v_cr
    assert find_critical_velocity(model, 10.0).plane == "in"

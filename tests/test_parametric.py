"""Parametric resonance under a pulsating flow (fempipe.analyses.parametric), checked against
computations that share none of its code: the spectrum of the mean flow (no pulsation), the
package's Radau integration of Eq. (20) itself with the pulsating flow (its variational
equation along the straight state, and a small motion), and a Ritz basis of every mode."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from fempipe import FiniteElement, Params, PipeModel, PulsatingFlow, compute_spectrum
from fempipe.analyses.parametric import PulsationPencil, ReducedPulsation, floquet_multipliers
from fempipe.analyses.parametric.regions import Candidate, candidates, locate_region
from fempipe.model.dynamics_problem import PipeDynamics
from fempipe.solvers.radau import Radau

HANGING = Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.005)  # Paidoussis & Issid's pipe
DISC = FiniteElement(6, 3)


def _model(v0: float) -> PipeModel:
    return PipeModel(DISC, Params(**{**HANGING.__dict__, "v": v0}))


@pytest.fixture(scope="module")
def reduced6():
    return ReducedPulsation(PulsationPencil.of(_model(6.0)), 6.0, 3)


def _largest(rho: np.ndarray, k: int = 4) -> np.ndarray:
    return rho[np.argsort(-np.abs(rho))][:k]


def test_without_pulsation_the_multipliers_are_exp_lambda_t(reduced6):
    """sigma = 0: the multipliers are exp(lambda T) of the mean flow's spectrum (Eq. (32),
    computed by the stability analysis's own eigensolver)."""
    omega = 20.0
    lam = np.asarray(compute_spectrum(_model(6.0), np.zeros(DISC.n)).lam)
    lam = lam[lam.imag >= 0]
    lam = lam[np.argsort(-lam.real)][:2]
    expected = np.exp(lam * 2 * math.pi / omega)
    rho = _largest(floquet_multipliers(reduced6, 0.0, omega))
    for e in expected:
        assert np.abs(rho - e).min() < 1e-9 * max(1.0, abs(e))


@pytest.mark.parametrize(("sigma", "omega"), [(0.2, 29.5), (0.3, 21.0)])
def test_monodromy_is_that_of_the_integrated_equation_of_motion(reduced6, sigma, omega):
    """The monodromy of Eq. (20) linearized about the straight state, as the package's Radau
    integrator propagates it (its sensitivity along q = 0, the residual's own Jacobians
    with the pulsating flow): the same largest multipliers, inside a region (|rho| > 1) and
    outside it."""
    model = _model(6.0)
    T = 2 * math.pi / omega
    stepper = Radau(
        PipeDynamics(model, PulsatingFlow(6.0, sigma, omega)),
        np.zeros(model.n),
        np.zeros(model.n),
        0.0,
        h_fixed=T / 400,
        sensitivity=True,
    )
    for _ in stepper.steps(T):
        pass
    theirs = _largest(np.linalg.eigvals(stepper.sensitivity_matrix), 3)
    ours = _largest(floquet_multipliers(reduced6, sigma, omega), 3)
    np.testing.assert_allclose(ours, theirs, atol=1e-7)
    assert (abs(ours[0]) > 1.0) == (sigma == 0.2)


def test_the_ritz_basis_converges_to_the_full_problem():
    """Three modes with their static corrections against a basis of every mode (the full
    discretized problem written in another basis)."""
    disc = FiniteElement(16, 3)
    pencil = PulsationPencil.of(PipeModel(disc, Params(**{**HANGING.__dict__, "v": 6.0})))
    few = ReducedPulsation(pencil, 6.0, 3)
    every = ReducedPulsation(pencil, 6.0, disc.n)
    assert every.size == 2 * disc.n and few.size < every.size
    for sigma, omega in ((0.2, 29.5), (0.4, 12.0)):
        np.testing.assert_allclose(
            _largest(floquet_multipliers(few, sigma, omega)),
            _largest(floquet_multipliers(every, sigma, omega)),
            atol=1e-9,
        )


def test_a_small_motion_grows_like_the_largest_multiplier(reduced6):
    """Eq. (20) integrated with the pulsating flow from a small perturbation: inside the
    region the state grows, over the last of 12 periods by |rho_max|; outside it decays."""
    model = _model(6.0)
    q0 = 1e-7 * np.random.default_rng(4).standard_normal(model.n)
    for sigma, omega in ((0.2, 29.5), (0.2, 24.0)):
        T = 2 * math.pi / omega
        stepper = Radau(
            PipeDynamics(model, PulsatingFlow(6.0, sigma, omega)),
            q0,
            np.zeros(model.n),
            0.0,
            h_fixed=T / 200,
        )
        norms = []
        for k in range(1, 13):
            for _ in stepper.steps(k * T):
                pass
            norms.append(np.linalg.norm(np.r_[stepper.q, stepper.qdot / omega]))
        rho = abs(floquet_multipliers(reduced6, sigma, omega)[0])
        if rho > 1:
            assert norms[-1] / norms[-2] == pytest.approx(rho, rel=1e-3)
        else:  # the next multipliers are not far below: no clean ratio, only the decay
            assert norms[-1] < 0.25 * norms[0] and rho < 0.9


def test_a_region_is_located_where_a_multiplier_reaches_modulus_one(reduced6):
    """The principal region of the second mode: at its threshold the critical multiplier is
    -1 (period doubling); just below it no frequency of the window is unstable; at each
    boundary frequency the largest modulus is 1, and larger between them."""
    w2 = reduced6.eigenvalues.imag[1]
    cand = Candidate("principal", 1, (2,), 2 * w2)
    window = (0.8 * cand.omega, 1.2 * cand.omega)
    region, count = locate_region(reduced6, cand, window, [0.1, 0.15])
    assert region is not None and count == region.evaluations > 10
    assert abs(region.multiplier + 1) < 1e-6
    assert 0 < region.sigma_threshold < 0.1
    assert abs(region.omega_threshold / cand.omega - 1) < 0.02

    def largest(s, w):
        return abs(floquet_multipliers(reduced6, s, w)[0])

    below = region.sigma_threshold * (1 - 1e-3)
    assert max(largest(below, w) for w in np.linspace(*window, 61)) < 1
    for s, lo, hi in region.boundary:
        assert lo < region.omega_threshold < hi
        assert largest(s, lo) == pytest.approx(1, abs=1e-6)
        assert largest(s, hi) == pytest.approx(1, abs=1e-6)
        assert largest(s, 0.5 * (lo + hi)) > 1
    assert [row[0] for row in region.boundary] == [0.1, 0.15]
    # the same search on any callable (sigma, omega) -> multipliers
    again, _ = locate_region(lambda s, w: floquet_multipliers(reduced6, s, w), cand, window, [0.1])
    assert again.sigma_threshold == pytest.approx(region.sigma_threshold, abs=1e-8)


def test_candidates_name_the_resonances():
    got = candidates([2.0, 5.0], (1.0, 11.0), max_order=2)
    names = [(c.kind, c.order, c.mode, c.omega) for c in got]
    assert ("principal", 1, (1,), 4.0) in names and ("principal", 1, (2,), 10.0) in names
    assert ("sum", 1, (1, 2), 7.0) in names and ("difference", 1, (1, 2), 3.0) in names
    assert ("principal", 2, (1,), 2.0) in names and ("sum", 2, (1, 2), 3.5) in names
    assert [c.omega for c in got] == sorted(c.omega for c in got)


def test_a_pipe_without_flow_acceleration_terms():
    """beta = 0: no Coriolis force and no flow acceleration (their matrices vanish); the
    reduced problem still is the full one, and at sigma = 0 its multipliers are exp(lambda T)."""
    model = PipeModel(DISC, Params(alpha=0.0, beta=0.0, gamma=10.0, mu=0.005, v=3.0))
    pencil = PulsationPencil.of(model)
    assert np.abs(pencil.C1).max() == 0 and np.abs(pencil.K3).max() == 0
    reduced = ReducedPulsation(pencil, 3.0, 3)
    lam = reduced.eigenvalues
    # 512 steps: the time discretization's error (1e-8 at the default 128) falls to 1e-11;
    # the eigenvalues' round-off moves with the BLAS kernel (2e-10 on Prescott), hence 1e-9,
    # the bound of the sigma = 0 test with flow
    rho = floquet_multipliers(reduced, 0.0, 10.0, steps=512)
    for e in np.exp(lam * 2 * math.pi / 10.0):
        assert np.abs(rho - e).min() < 1e-9


def test_bad_input_is_refused():
    with pytest.raises(ValueError, match="alpha"):
        PulsationPencil.of(PipeModel(DISC, Params(alpha=1.0)))
    pencil = PulsationPencil.of(_model(6.0))
    with pytest.raises(ValueError, match="pairs"):
        ReducedPulsation(pencil, 6.0, 0)
    red = ReducedPulsation(pencil, 6.0, 2)
    with pytest.raises(ValueError, match="omega"):
        red.monodromy(0.1, 0.0)
    with pytest.raises(ValueError, match="steps"):
        red.monodromy(0.1, 1.0, steps=0)


def test_the_chart_of_the_hanging_pipe():
    """v0 = 6, omega in 20..36: the principal region of mode 2 (the flutter mode, the least
    damped) and nothing else opens for sigma <= 0.2; mode 1, damped above the ratio
    1/sqrt(2) by the flow at this v0, is not a resonator; both planes carry the region."""
    from fempipe.analyses.parametric import compute_parametric_chart

    chart = compute_parametric_chart(_model(6.0), 6.0, (20.0, 36.0), [0.1, 0.2])
    lam = dict(zip(chart.modes, chart.eigenvalues, strict=True))
    assert 1 not in lam and lam[2].imag > -lam[2].real
    (region,) = chart.regions
    c = region.candidate
    assert (c.kind, c.order, c.mode) == ("principal", 1, (2,))
    assert c.omega == pytest.approx(2 * lam[2].imag, rel=1e-12)
    assert abs(region.multiplier + 1) < 1e-6 and 0 < region.sigma_threshold < 0.1
    assert [row[0] for row in region.boundary] == [0.1, 0.2]
    d = chart.to_dict()
    assert [r["plane"] for r in d["regions"]] == ["in", "out"]
    assert d["regions"][0]["sigma_threshold"] == region.sigma_threshold
    assert d["regions"][0]["mode"] == [2] and d["regions"][0]["kind"] == "principal"
    assert len(d["closed"]) == len(chart.closed) >= 1
    assert chart.evaluations > 0


def test_the_chart_refuses_what_it_cannot_chart():
    from fempipe.analyses.parametric import compute_parametric_chart

    with pytest.raises(ValueError, match="omega"):
        compute_parametric_chart(_model(6.0), 6.0, (30.0, 20.0), [0.1])
    with pytest.raises(ValueError, match="sigma"):
        compute_parametric_chart(_model(6.0), 6.0, (20.0, 30.0), [1.5])
    with pytest.raises(ValueError, match="unstable"):
        compute_parametric_chart(_model(6.0), 7.5, (20.0, 30.0), [0.1])
    with pytest.raises(ValueError, match="planes"):
        compute_parametric_chart(_model(6.0), 6.0, (20.0, 30.0), [0.1], planes=("up",))


def test_the_bent_pipe_tends_to_the_straight_one():
    """As alpha -> 0 the forced orbit's multipliers, in the plane and out of it (the planar
    motion and its out-of-plane variation, flow acceleration included), tend to the straight
    pipe's (the Ritz-reduced monodromy, another computation) like alpha^2."""
    from fempipe.analyses.parametric.forced import solve_forced_response

    disc = FiniteElement(2, 4)
    straight = ReducedPulsation(PulsationPencil.of(PipeModel(disc, _model(6.0).params)), 6.0, 3)
    ref = _largest(floquet_multipliers(straight, 0.2, 29.5, 256), 2)
    gaps = []
    for alpha in (1e-2, 1e-3):
        bent = PipeModel(disc, replace(_model(6.0).params, alpha=alpha))
        r = solve_forced_response(bent, 0.2, 29.5, out_of_plane=True, rtol=1e-9, steps=64)
        assert abs(ref[0]) > 1.3  # inside the principal region of mode 2: a real test
        gaps.append(
            [
                abs(_largest(rho, 2) - ref).max()
                for rho in (r.multipliers, r.out_of_plane_multipliers)
            ]
        )
    (in1, out1), (in2, out2) = gaps
    assert in2 < 1e-6 and out2 < 1e-6
    assert 30 < in1 / in2 and 30 < out1 / out2  # alpha^2: 100 for alpha / 10


def test_the_command(tmp_path, capsys):
    """``fempipe parametric`` in-process: its JSON contract, its files, its errors (exit 2)."""
    import json

    from fempipe.cli import main

    argv = ["parametric", "--v", "6", "--beta", "0.2", "--gamma", "10", "--modal", "4",
            "--omega", "24:36", "--sigma", "0.1,0.2", "--compare-modal", "3", "--quiet"]  # fmt: skip
    assert main([*argv, "--json"]) == 0
    d = json.loads(capsys.readouterr().out)
    (inp, out) = d["regions"]
    assert (inp["plane"], out["plane"]) == ("in", "out") and inp["kind"] == "principal"
    assert set(inp) >= {"mode", "kind", "plane", "sigma_threshold", "omega_threshold", "boundary"}
    assert [row[0] for row in inp["boundary"]] == [0.1, 0.2]
    assert list(d["compare"]) == ["modal:3"] and d["compare"]["modal:3"]["regions"]
    assert d["discretization"]["name"] == "modal:4" and d["cpu_seconds"] > 0
    assert main([*argv, "--out", str(tmp_path / "out")]) == 0
    text = capsys.readouterr().out
    assert "opens at sigma" in text and "modal:3" in text
    for name in ("parametric.json", "parametric.csv", "chart.png"):
        assert (tmp_path / "out" / name).stat().st_size > 200
    header = (tmp_path / "out" / "parametric.csv").read_text().splitlines()[0]
    assert header.startswith("discretization") and "sigma_threshold [1]" in header
    for bad, option in (
        (["--v", "5,6"], "--v"),
        (["--v", "5", "--omega", "30:20"], "--omega"),
        (["--v", "5", "--sigma", "0,0.2"], "--sigma"),
        (["--v", "9"], "--v"),
    ):
        try:
            code = main(["parametric", *bad, "--modal", "3", "--compare-modal", "none", "--quiet"])
        except SystemExit as exc:  # argparse's own errors
            code = exc.code
        assert code == 2, bad
        assert option in capsys.readouterr().err


def test_the_thresholds_are_quantities_of_a_convergence_study():
    """``fempipe convergence --quantity sigma_threshold``: the threshold of the first region to
    open in the band, the same as the chart's; refused without a band."""
    from fempipe.studies.convergence import Quantity

    q = Quantity("sigma_threshold", _model(6.0).params, omega_band=(24.0, 36.0), sigma_max=0.2)
    w = Quantity("omega_threshold", _model(6.0).params, omega_band=(24.0, 36.0), sigma_max=0.2)
    disc = FiniteElement(3, 3)
    from fempipe.analyses.parametric import compute_parametric_chart

    (region,) = compute_parametric_chart(
        PipeModel(disc, _model(6.0).params), 6.0, (24.0, 36.0), [0.2]
    ).regions
    assert q(disc) == pytest.approx(region.sigma_threshold, abs=2e-8)  # the chart: 1e-8
    assert w(disc) == pytest.approx(region.omega_threshold, rel=1e-4)
    assert "24 <= omega <= 36" in q.describe()
    with pytest.raises(ValueError, match="band"):
        Quantity("sigma_threshold", _model(6.0).params)


def test_the_forced_response_of_a_bent_pipe():
    """The periodic response to the pulsation, by Newton on the period map: on the straight
    pipe (alpha = 0) it is the straight state, with the reduced problem's multipliers; on the
    horizontal pipe (alpha = pi/2) it tends to the static state as sigma -> 0, with the
    multipliers exp(lambda T) of the static state's spectrum (Eq. (32)); at sigma = 0.3 it
    converges, moves the pipe, and its multipliers do not depend on the steps (rtol 1e-8 against 1e-10 and twice the steps)."""
    from fempipe.analyses.parametric.forced import solve_forced_response
    from fempipe.analyses.statics import solve_sagged

    straight = solve_forced_response(_model(6.0), 0.2, 29.5)
    assert straight.iterations == 0 and straight.amplitude == 0.0
    np.testing.assert_allclose(
        _largest(straight.multipliers, 3),
        _largest(
            floquet_multipliers(
                ReducedPulsation(PulsationPencil.of(_model(6.0)), 6.0, 3), 0.2, 29.5
            ),
            3,
        ),
        atol=1e-7,
    )
    bent = PipeModel(
        FiniteElement(4, 3), Params(alpha=math.pi / 2, beta=0.142, gamma=18.9, mu=0.005, v=4.0)
    )
    omega = 20.0
    small = solve_forced_response(bent, 1e-7, omega)
    assert np.linalg.norm(small.q0 - solve_sagged(bent).q) < 1e-5
    lam = compute_spectrum(bent, solve_sagged(bent).q).lam
    for e in np.exp(lam * 2 * math.pi / omega)[:4]:
        assert np.abs(small.multipliers - e).min() < 1e-7
    moved = solve_forced_response(bent, 0.3, omega)
    assert moved.residual <= 1e-9 and 1 <= moved.iterations <= 6 and moved.amplitude > 0.05
    finer = solve_forced_response(
        bent, 0.3, omega, guess=(moved.q0, moved.qdot0), steps=256, rtol=1e-10
    )
    np.testing.assert_allclose(_largest(finer.multipliers), _largest(moved.multipliers), atol=1e-7)
    with pytest.raises(ValueError, match="omega"):
        solve_forced_response(bent, 0.3, 0.0)


@pytest.mark.slow
def test_the_chart_of_a_slightly_bent_pipe():
    """A bent pipe's chart (forced orbits, both planes) tends to the straight pipe's region
    (the Ritz-reduced Floquet problem) as alpha -> 0: its threshold in and out of the plane
    within O(alpha^2) of it; and the 3-D model's out-of-plane multipliers about a forced
    orbit of the horizontal pipe agree with the linear out-of-plane equation's."""
    from fempipe.analyses.dynamics import PulsatingFlow
    from fempipe.analyses.parametric import compute_parametric_chart, solve_forced_response
    from fempipe.analyses.three_d.floquet import compute_out_of_plane_floquet

    disc = FiniteElement(2, 4)
    kw = {"sigma_tol": 1e-7, "omega_tol": 1e-7}
    flat = compute_parametric_chart(PipeModel(disc, HANGING), 6.0, (26.0, 33.0), [0.2], **kw)
    bent = compute_parametric_chart(
        PipeModel(disc, replace(HANGING, alpha=0.02)), 6.0, (26.0, 33.0), [0.2], **kw
    )
    (ref,) = flat.regions
    assert (
        not bent.straight
        and [r.candidate.plane for r in bent.regions] == ["in", "out"]
        or [r.candidate.plane for r in bent.regions] == ["out", "in"]
    )
    for r in bent.regions:
        assert abs(r.sigma_threshold - ref.sigma_threshold) < 4e-4 * ref.sigma_threshold
        assert r.candidate.mode == ref.candidate.mode and abs(r.multiplier + 1) < 1e-4
    d = bent.to_dict()
    assert {r["plane"] for r in d["regions"]} == {"in", "out"} and d["frequencies_out_of_plane"]
    # two discretizations of one continuum: 3e-5 apart on P2:4, 7e-11 on P2:8, 1e-12 on P3:8
    model = PipeModel(
        FiniteElement(2, 8), Params(alpha=math.pi / 2, beta=0.142, gamma=18.9, mu=0.005, v=4.0)
    )
    orbit = solve_forced_response(model, 0.4, 12.0, out_of_plane=True)
    flow = PulsatingFlow(4.0, 0.4, 12.0)
    linear = compute_out_of_plane_floquet(model, orbit, rtol=1e-10, flow=flow)
    three_d = compute_out_of_plane_floquet(model, orbit, rtol=1e-10, flow=flow, method="3d")
    np.testing.assert_allclose(
        _largest(orbit.out_of_plane_multipliers, 2), _largest(linear.multipliers, 2), atol=1e-8
    )
    np.testing.assert_allclose(
        _largest(linear.multipliers, 2), _largest(three_d.multipliers, 2), atol=1e-8
    )


def test_an_edge_beyond_a_stable_gap_is_found():
    """The lower edge of the hanging pipe's region at v0 = 6, sigma = 0.5 lies at 12.74, with
    the pipe stable down to 7.92 and unstable again below (quasi-static: the flow exceeds v_cr
    for part of each period): the outward walk must not step over that gap."""
    from fempipe.analyses.parametric.regions import _edge

    def margin(w: float) -> float:
        return (w - 12.7399) * (w - 7.9244)  # < 0 in the gap only

    assert _edge(margin, 29.47, 2.0, 1e-10) == pytest.approx(12.7399, abs=1e-8)
    assert math.isnan(_edge(lambda w: 1.0, 29.47, 2.0, 1e-10))


@pytest.mark.slow
def test_the_command_on_a_bent_pipe(capsys):
    """``fempipe parametric`` on a slightly bent pipe: forced orbits, the region in the plane
    alone with --planar, the out-of-plane keys without it."""
    import json

    from fempipe.cli import main

    argv = ["parametric", "--v", "6", "--alpha", "0.02", "--beta", "0.2", "--gamma", "10",
            "--fe", "P2:3", "--omega", "27:32", "--sigma", "0.2", "--max-order", "1",
            "--compare-modal", "none", "--quiet", "--json"]  # fmt: skip
    assert main([*argv, "--planar"]) == 0
    d = json.loads(capsys.readouterr().out)
    assert [r["plane"] for r in d["regions"]] == ["in"] and "planes_note" not in d
    assert d["regions"][0]["mode"] == [2] and 0.05 < d["regions"][0]["sigma_threshold"] < 0.2
    assert main(argv) == 0
    d = json.loads(capsys.readouterr().out)
    assert sorted(r["plane"] for r in d["regions"]) == ["in", "out"]
    assert len(d["frequencies_out_of_plane"]) == len(d["modes_out_of_plane"]) >= 2


def test_a_tip_near_the_band_end_is_found():
    """A region open widest at the band's lower end at the largest sigma, closed at half of
    it, with its tip inside the band: a model margin log|rho| = sigma (1 - 0.02 d^2) - 0.2 -
    max(sigma - 0.2, 0) d (d = omega - 27.1) has the tip (0.2, 27.1) exactly."""

    def source(s: float, w: float) -> np.ndarray:
        d = w - 27.1
        return np.array([-math.exp(s * (1 - 0.02 * d * d) - 0.2 - max(s - 0.2, 0.0) * d)])

    cand = Candidate("principal", 1, (2,), 27.5)
    region, _ = locate_region(source, cand, (27.0, 32.0), [0.3], sigma_tol=1e-10)
    assert region is not None
    assert region.sigma_threshold == pytest.approx(0.2, abs=1e-9)
    assert region.omega_threshold == pytest.approx(27.1, abs=1e-3)
    assert math.isnan(region.boundary[0][1]) and 27.1 < region.boundary[0][2] < 32.0

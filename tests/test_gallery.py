"""The examples gallery: every ``examples/plot_*.py`` runs and one number of each is right.

Each script sets a module-level ``RESULT``; the test runs the script as sphinx-gallery does
(a fresh ``__main__`` without ``__file__``, the Agg backend, an empty temporary working
directory that must stay empty) and checks ``RESULT`` against a value computed here by other means: a closed
form, an independent solver of :mod:`fempipe.validation` (scipy's ``solve_bvp`` on the
strong form of Eq. (31a); Paidoussis' straight-pipe theory on Legendre spectral elements),
a symmetry, or the theoretical order of a convergence study.  The tolerances say which
discretization error they allow for.  The scripts take about 19 CPU-s together (in the default test run)."""

from __future__ import annotations

import functools
import math
import os
from pathlib import Path

import numpy as np
import pytest
from gallery_exec import run_like_sphinx_gallery
from scipy.optimize import brentq
from scipy.special import jv

ROOT = Path(__file__).resolve().parents[1]
EXAMPLES = sorted((ROOT / "examples").glob("plot_*.py"))


def run_example(name: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    """Run ``examples/<name>.py`` as sphinx-gallery does (no ``__file__``: its final
    ``show_or_save()`` leaves the figures to the gallery) in an empty cwd; its globals (the
    cwd must stay empty)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.chdir(tmp_path)
    plt.close("all")
    try:
        g = run_like_sphinx_gallery(ROOT / "examples" / f"{name}.py")
        n_figures = len(plt.get_fignums())
    finally:
        plt.close("all")
    assert os.listdir(tmp_path) == [], "an example wrote into the working directory"
    assert 1 <= n_figures <= 2
    return g


@functools.cache
def classical_v_cr() -> float:
    """v_cr of the paper's hanging pipe (beta 0.142, gamma 18.9, mu 5e-3) by the classical
    linear theory of the straight pipe (Paidoussis' equation for the lateral displacement on
    Legendre spectral elements, p = 24, converged to about 1e-9): an implementation that
    shares no code with fempipe's solvers."""
    from fempipe.validation.classical import StraightPipe, critical_velocity

    return critical_velocity(
        StraightPipe(beta=0.142, gamma=18.9, mu=5e-3), v_max=10.0, method="legendre"
    ).v_cr


def bvp_x_tip(alpha: float, gamma: float, v: float) -> float:
    """X_g(1) from scipy's solve_bvp on the strong form of Eq. (31a)."""
    from fempipe.validation.bvp import solve_static_bvp

    return solve_static_bvp(alpha, gamma, v, tol=1e-11).X_tip


def test_there_are_enough_examples():
    assert len(EXAMPLES) >= 12
    for path in EXAMPLES:
        head = path.read_text().split('"""')[1].strip().splitlines()
        # sphinx-gallery's title block: a title underlined by '=' of at least its length
        assert set(head[1]) == {"="} and len(head[1]) >= len(head[0]), path.name
        assert "RESULT =" in path.read_text(), path.name


def test_si_pipe_static(tmp_path, monkeypatch):
    g = run_example("plot_si_pipe_static", tmp_path, monkeypatch)
    p = g["pipe"].params(U=2.0)
    # P3:8: tip error O(h^6), about 1e-8
    assert g["RESULT"] == pytest.approx(bvp_x_tip(p.alpha, p.gamma, p.v), abs=1e-6)


def test_convergence_study(tmp_path, monkeypatch):
    g = run_example("plot_convergence_study", tmp_path, monkeypatch)
    assert g["RESULT"] == pytest.approx(4.0, abs=0.3)  # P2 tip values: 2k = 4
    # and the study's reference is the true X_tip (its correction estimate was 1.6e-7)
    bvp = bvp_x_tip(np.pi / 3, 18.9, 4.0)
    assert g["study"].reference.value == pytest.approx(bvp, abs=1e-6)


def test_fe_vs_paper_n3(tmp_path, monkeypatch):
    g = run_example("plot_fe_vs_paper_n3", tmp_path, monkeypatch)
    # P3:8 to 1e-6 (its error is about 1e-8); the N = 3 error there is 2.6e-3
    assert g["RESULT"] == pytest.approx(bvp_x_tip(np.pi / 3, 18.9, 4.0), abs=1e-6)


def test_sine_vs_beam_modes(tmp_path, monkeypatch):
    g = run_example("plot_sine_vs_beam_modes", tmp_path, monkeypatch)
    assert g["RESULT"] == pytest.approx(3.0, abs=0.25)  # sine modes: N^-3 (README)
    assert g["orders"]["beam"] > g["RESULT"] + 0.7  # beam modes: one order more


def test_spectrum_argand(tmp_path, monkeypatch):
    g = run_example("plot_spectrum_argand", tmp_path, monkeypatch)
    # Euler-Bernoulli cantilever: 1 + cos(x) cosh(x) = 0, x = beta_1 L = 1.8751...
    x = brentq(lambda x: 1.0 + math.cos(x) * math.cosh(x), 1.0, 3.0, xtol=1e-15)
    assert g["RESULT"] == pytest.approx(x**2, rel=1e-7)  # P3:8: error O(h^6)
    # beta = 0.2, gamma = 0, mu = 1e-3: the classical straight pipe's flutter
    from fempipe.validation.classical import StraightPipe, critical_velocity

    ref = critical_velocity(
        StraightPipe(beta=0.2, gamma=0.0, mu=1e-3), v_max=8.0, method="legendre"
    ).v_cr
    assert g["crit"].v_cr == pytest.approx(ref, abs=1e-4)


def test_vcr_vs_alpha(tmp_path, monkeypatch):
    g = run_example("plot_vcr_vs_alpha", tmp_path, monkeypatch)
    # P2:6 against the converged classical value: a discretization error of about 1e-3
    assert g["RESULT"] == pytest.approx(classical_v_cr(), abs=5e-3)


def test_standing_pitchfork(tmp_path, monkeypatch):
    g = run_example("plot_standing_pitchfork", tmp_path, monkeypatch)
    # Greenhill's heavy column: J_{-1/3}((2/3) sqrt(gamma)) = 0, gamma = 7.8373...
    greenhill = brentq(lambda s: jv(-1.0 / 3.0, 2.0 / 3.0 * math.sqrt(s)), 5.0, 10.0, xtol=1e-14)
    assert g["RESULT"] == pytest.approx(greenhill, abs=1e-3)  # P2:6
    # the mirror symmetry alpha -> 2 pi - alpha, theta -> -theta maps one fold onto the other
    folds = sorted(set(np.round(g["folds"], 9)))
    assert len(folds) == 2
    assert folds[0] + folds[1] == pytest.approx(2 * np.pi, abs=1e-6)


def test_limit_cycle_floquet(tmp_path, monkeypatch):
    g = run_example("plot_limit_cycle_floquet", tmp_path, monkeypatch)
    # an autonomous system's periodic orbit has the multiplier 1; shooting tolerance 1e-5
    assert g["RESULT"] == pytest.approx(1.0, abs=1e-4)
    others = sorted(abs(g["mult"]))[:-1]
    assert max(others) < 1.0  # and the cycle above a supercritical Hopf point is stable


def test_bifurcation_continuation(tmp_path, monkeypatch):
    g = run_example("plot_bifurcation_continuation", tmp_path, monkeypatch)
    # P2:4 against the converged classical v_cr: a discretization error of about 6e-3
    assert g["RESULT"] == pytest.approx(classical_v_cr(), abs=1.5e-2)


def test_compare_csv(tmp_path, monkeypatch):
    g = run_example("plot_compare_csv", tmp_path, monkeypatch)
    # P2:8 against the converged classical v_cr; fempipe's own estimate covers the difference
    row = next(r for r in g["result"]["rows"] if r["quantity"] == "v_cr")
    assert abs(g["RESULT"] - classical_v_cr()) < min(2e-3, row["error_estimate"])


def test_variants(tmp_path, monkeypatch):
    g = run_example("plot_variants", tmp_path, monkeypatch)

    # Blevins: 1 + cos l cosh l + Gamma l (cos l sinh l - sin l cosh l) = 0, omega = l^2
    def f(x, G=0.5):
        return (
            1
            + math.cos(x) * math.cosh(x)
            + G * x * (math.cos(x) * math.sinh(x) - math.sin(x) * math.cosh(x))
        )

    x = brentq(f, 0.5, 2.5, xtol=1e-15)
    assert g["RESULT"] == pytest.approx(x**2, rel=1e-7)


def test_error_estimates(tmp_path, monkeypatch):
    g = run_example("plot_error_estimates", tmp_path, monkeypatch)
    true = abs(g["points"][2]["X_tip"] - bvp_x_tip(np.pi / 2, 10.0, 2.0))
    # the estimate bounds the true error, and not by orders of magnitude (safety factor 3)
    assert true <= g["RESULT"] <= 10 * true


def test_dask_sweep(tmp_path, monkeypatch):
    pytest.importorskip("dask.distributed")
    g = run_example("plot_dask_sweep", tmp_path, monkeypatch)
    # the onset is the first swept v above the classical v_cr (N = 3 is off by 0.04 only)
    assert g["RESULT"] == min(v for v in g["flows"] if v > classical_v_cr())
    assert all(p["attractor"] == "equilibrium" for p in g["diagram"].points if p["v"] < g["RESULT"])


def test_3d_which_cycles_survive(tmp_path, monkeypatch):
    g = run_example("plot_3d_which_cycles_survive", tmp_path, monkeypatch)
    # the hanging pipe is axisymmetric: the rotated cycle is a cycle, its multiplier exactly 1
    # in the continuum; P3:6 leaves a discretization error of about 8e-6 in the 3-D model,
    # 1.5e-4 in the linear psi equation (measured; 4.2e-5 on P3:8: it converges)
    linear, full = g["RESULT"]
    assert full == pytest.approx(1.0, abs=1e-4)
    assert linear == pytest.approx(1.0, abs=1e-3)
    hanging, standing = (oop for _cycle, oop, _oop3 in g["results"].values())
    for _cycle, oop, oop3 in g["results"].values():
        # two discretizations of the same multipliers: one verdict, close values
        assert oop.stable == oop3.stable
        assert abs(oop.max_nontrivial - oop3.max_nontrivial) < 1e-3
    # every other out-of-plane multiplier of a stable cycle's neighbourhood lies inside the circle
    assert hanging.stable and abs(hanging.trivial.imag) < 1e-12
    # the standing pipe's planar cycle has one out-of-plane multiplier outside it
    assert not standing.stable


def test_parametric_resonance(tmp_path, monkeypatch):
    """The small motion integrated by Eq. (20) with the pulsating flow (Radau, fixed steps)
    grows per period by the largest Floquet multiplier of the reduced monodromy."""
    from fempipe.analyses.parametric import PulsationPencil, ReducedPulsation, floquet_multipliers

    g = run_example("plot_parametric_resonance", tmp_path, monkeypatch)
    model = g["model"]
    reduced = ReducedPulsation(PulsationPencil.of(model), 6.0, 3)
    rho = floquet_multipliers(reduced, 0.2, g["region"].omega_threshold)[0]
    assert rho.real < -1 and abs(rho.imag) < 1e-9
    assert g["RESULT"] == pytest.approx(abs(rho), rel=2e-3)

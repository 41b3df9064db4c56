"""The course "FEM for slender structures, on this pipe": every lesson runs and shows what it says.

Each ``docs/course/lesson_*.py`` is run as sphinx-gallery runs it (``runpy``, ``__main__``,
Agg backend, an empty temporary working directory that must stay empty); its key numbers,
read from the lesson's globals, are checked against values from elsewhere: closed forms
(an exact solution, Greenhill's and the Euler-Bernoulli cantilever's characteristic
equations, exact integrals of polynomials), the theoretical orders (k + 1, 2k, 5, N^-3),
and independent solvers (scipy's ``solve_bvp``, the classical straight-pipe theory).  The
lessons take about 10 CPU-s together (in the default test run).
"""

from __future__ import annotations

import math
import os
import runpy
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq
from scipy.special import jv

ROOT = Path(__file__).resolve().parents[1]
LESSONS = sorted((ROOT / "docs" / "course").glob("lesson_*.py"))


def run_lesson(stem: str, tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> dict:
    """Run ``docs/course/<stem>*.py`` in an empty cwd; its globals."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (path,) = [p for p in LESSONS if p.name.startswith(stem)]
    monkeypatch.setenv("MPLBACKEND", "Agg")
    monkeypatch.chdir(tmp_path)
    try:
        g = runpy.run_path(str(path), run_name="__main__")
    finally:
        plt.close("all")
    assert os.listdir(tmp_path) == [], "a lesson wrote into the working directory"
    return g


def test_the_lessons_are_lessons():
    """5 to 8 lessons, each a sphinx-gallery script that says what to see and ends with
    exercises, and each readable as a percent-format notebook."""
    assert 5 <= len(LESSONS) <= 8
    header = (ROOT / "docs" / "course" / "GALLERY_HEADER.rst").read_text()
    assert header.splitlines()[1].startswith("====")
    for path in LESSONS:
        text = path.read_text()
        assert "What you should see" in text, path.name
        assert "# Exercises" in text.split("# %%")[-1], path.name
    jupytext = pytest.importorskip("jupytext")
    for path in LESSONS:
        nb = jupytext.read(path, fmt="py:percent")
        assert sum(c.cell_type == "code" for c in nb.cells) >= 3, path.name


def test_lesson_01_weak_form(tmp_path, monkeypatch):
    g = run_lesson("lesson_01", tmp_path, monkeypatch)
    # Eq. (19) by hand for the SI pipe
    m, M, L, EI, grav = 0.0159, 0.0058, 0.094, 1.8e-5, 9.8
    assert g["params"].beta == pytest.approx(M / (m + M), rel=1e-12)
    assert g["params"].gamma == pytest.approx((m + M) * grav * L**3 / EI, rel=1e-12)
    # the sine-mode Galerkin tip against the closed form -gamma/6, and its order N^-3
    assert g["tip_errors"][-1] < 1e-6
    assert g["galerkin_order"] == pytest.approx(3.0, abs=0.15)
    # fempipe P2:16 against solve_bvp: the P2 discretization error, 3.6e-7
    assert abs(g["X_fe"] - g["X_bvp"]) < 1e-6


def test_lesson_02_lagrange_elements(tmp_path, monkeypatch):
    g = run_lesson("lesson_02", tmp_path, monkeypatch)
    # against the exact solution sin(3 pi xi / 2): L2 orders k + 1, derivative k
    for k, (p_l2, p_h1) in g["linear_orders"].items():
        assert p_l2 == pytest.approx(k + 1, abs=0.1)
        assert p_h1 == pytest.approx(k, abs=0.1)
    # the lesson's forty lines and fempipe are two implementations of one discrete problem
    assert g["ours"] == pytest.approx(g["theirs"], abs=1e-12)
    # the natural condition theta'(1) = 0 is reached as h^k for P2
    assert g["slope_order"] == pytest.approx(2.0, abs=0.2)


def test_lesson_03_nested_integrals(tmp_path, monkeypatch):
    g = run_lesson("lesson_03", tmp_path, monkeypatch)
    assert g["exact_deg2"] < 1e-14  # C x^2 = x^3/3 exactly with 3 Gauss points
    assert g["inexact_deg4"] > 1e-6  # but not x^4 (degree above n_g - 1)
    d = g["defects"]
    assert d["Gauss-Legendre"] < 1e-14
    assert min(d["Gauss-Lobatto"], d["equispaced interior"]) > 1e-4
    assert g["asymmetry"] < 1e-14 and g["eigs"][0] > 0
    # the kernel form's brute-force quadrature converges to the Gram form as h^2
    assert g["kernel_ratio"] == pytest.approx(4.0, abs=0.3)


def test_lesson_04_newton_continuation(tmp_path, monkeypatch):
    g = run_lesson("lesson_04", tmp_path, monkeypatch)
    c = g["newton_constants"]
    # quadratic convergence: e_(k+1) / e_k^2 settles to a constant
    assert c[-1] == pytest.approx(c[-2], rel=0.25)
    assert g["errors"][-1] < 1e-13
    greenhill = brentq(lambda s: jv(-1.0 / 3.0, 2.0 / 3.0 * math.sqrt(s)), 5.0, 10.0, xtol=1e-14)
    assert g["pitchfork"].value == pytest.approx(greenhill, abs=1e-6)  # P3:8
    assert g["fold_singularity"] < 1e-8  # dR/dq is singular at the fold
    # natural continuation cannot follow the branch round the fold: Newton fails on the
    # first step past it (having solved every step before it), or lands on another branch
    if g["natural_failed"]:
        assert g["reached"] < g["fold"].value < g["reached"] + 0.1
    else:
        assert abs(g["jumped"] - g["fold_tip"]) > 0.5


def test_lesson_05_eigenproblems_flutter(tmp_path, monkeypatch):
    g = run_lesson("lesson_05", tmp_path, monkeypatch)
    x = brentq(lambda x: 1.0 + math.cos(x) * math.cosh(x), 1.0, 3.0, xtol=1e-15)
    assert x == pytest.approx(1.8751040687, abs=1e-10)  # the textbook beta_1 L
    assert g["omega_errors"][-1] == pytest.approx(abs(3.5160157284 - x**2), rel=1e-3)
    assert g["omega_errors"][-1] < 1e-6
    assert g["eigen_order"] == pytest.approx(4.0, abs=0.2)  # 2k for P2
    from fempipe.validation.classical import StraightPipe, critical_velocity

    ref = critical_velocity(
        StraightPipe(beta=0.2, gamma=0.0, mu=1e-3), v_max=8.0, method="legendre"
    ).v_cr
    assert g["v_bisect"] == pytest.approx(ref, abs=1e-5)
    assert g["v_bisect"] == pytest.approx(g["v_fempipe"], abs=1e-7)


def test_lesson_06_time_integration(tmp_path, monkeypatch):
    g = run_lesson("lesson_06", tmp_path, monkeypatch)
    assert g["stiffness_growth"] == pytest.approx(4.0, abs=0.2)  # mu omega^2 ~ h^-4
    assert g["radau_orders"][-1] == pytest.approx(5.0, abs=0.3)  # 2s - 1, s = 3
    # energy is conserved by the equations; the integrator's error follows the tolerance
    assert g["drifts"][1e-6] < 1e-7
    assert g["drifts"][1e-4] > 30 * g["drifts"][1e-6]


def test_lesson_07_modal_vs_fe(tmp_path, monkeypatch):
    g = run_lesson("lesson_07", tmp_path, monkeypatch)
    hand = g["hand_orders"]
    assert [hand["P1"], hand["P2"], hand["P3"]] == pytest.approx([2, 4, 6], abs=0.2)
    assert hand["sine modes N (the paper's)"] == pytest.approx(3.0, abs=0.2)
    assert g["api_orders"]["modal-beam"] == pytest.approx(4.0, abs=0.3)
    # the study's reference, formed without the answer, against solve_bvp
    assert np.isclose(g["study"].reference.value, g["reference"], rtol=0, atol=1e-9)

"""The fast paths of the stability analysis agree with the general ones; the classical baseline.

* The straight branch (alpha = 0, pi without a branch point): no
  continuation, K^d, C^d from fixed matrices, spectra every
  ``STRAIGHT_STEP * ds_max`` -- its events against the general
  continuation forced on the same pipe, to the 1e-10 both locate them to.
* :class:`StraightPencil` against the assembled Jacobians, the straight
  sample values against the continuation's own points.
* The vectorized pre-filter of the narrow-window check never drops an
  eigenvalue the exact per-eigenvalue test would take.
* The classical baseline script (``fempipe/validation/classical_baseline.py``,
  the timing reference of ``fempipe bench``): its closed-form Paidoussis
  coefficients against quadrature of the beam modes, its eigenvalues against
  fempipe's straight-pipe spectrum, its v_cr against the Legendre reference.
"""

import importlib.util
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

import fempipe.analyses.stability.chunked_branch as chunked_branch
import fempipe.analyses.stability.classified as classified
import fempipe.analyses.stability.hysteretic as hysteretic
import fempipe.analyses.stability.tracking as tracking
from fempipe import FiniteElement, Modal, Params, PipeModel
from fempipe.analyses.stability import (
    STABILITY_TOL,
    analyse_stability,
    compute_spectrum,
    linearized_matrices,
)
from fempipe.analyses.stability.branch_analysis import peak_candidates
from fempipe.analyses.stability.linear import StraightPencil
from fempipe.analyses.statics import continue_static
from fempipe.validation import classical

BASELINE = Path(classical.__file__).resolve().with_name("classical_baseline.py")
PAPER = {"beta": 0.142, "gamma": 18.9, "mu": 5e-3}


def _baseline():
    spec = importlib.util.spec_from_file_location("classical_baseline", BASELINE)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _events(res):
    return [(e.branch, e.type, e.mode, e.v, e.frequency) for e in res.events]


def _assert_same_events(fast, general, **tol):
    """The same events (branch, type, mode) in order, at least one, v and frequency
    within ``tol`` (pytest.approx keywords)."""
    a, b = _events(fast), _events(general)
    assert len(a) == len(b) >= 1
    for x, y in zip(a, b, strict=True):
        assert x[:3] == y[:3]
        assert x[3] == pytest.approx(y[3], **tol)
        assert x[4] == pytest.approx(y[4], **tol)


def _analyse(model, forced_general: bool, monkeypatch, v_max: float):
    """analyse_stability, with the straight fast path allowed or switched off (then also
    the StraightPencil: every spectrum from the assembled Jacobians); and whether the fast
    path built the primary branch."""
    taken = []
    real_piece = chunked_branch._straight_piece

    def spy(*args, **kwargs):
        taken.append(True)
        return real_piece(*args, **kwargs)

    class Assembled:
        """K^d, C^d, M^d assembled at theta = 0 instead of the StraightPencil."""

        def __init__(self, m):
            self.m = m

        def matrices(self, v):
            m = self.m.with_params(replace(self.m.params, v=v))
            return linearized_matrices(m, np.zeros(m.n))

    with monkeypatch.context() as mp:
        mp.setattr(chunked_branch, "_straight_piece", spy)
        if forced_general:
            mp.setattr(chunked_branch, "_straight_without_branch_points", lambda *a, **k: False)
            mp.setattr(tracking, "straight_pencil", Assembled)
        res = analyse_stability(model, v_max, 0.0)
    return res, bool(taken)


@pytest.mark.parametrize(
    "params",
    [
        Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.0),
        Params(alpha=0.0, end_mass=0.3, springs=((5.0, 0.5),), **PAPER),
        Params(alpha=math.pi, beta=0.142, gamma=5.0, mu=5e-3),  # standing, below buckling
    ],
    ids=["hanging", "variants", "standing"],
)
def test_straight_fast_path_agrees_with_the_general_continuation(params, monkeypatch):
    model = PipeModel(FiniteElement(4, 3), params)
    fast, taken = _analyse(model, False, monkeypatch, 9.0)
    general, taken_general = _analyse(model, True, monkeypatch, 9.0)
    assert taken and not taken_general
    assert fast.v_cr is not None
    _assert_same_events(fast, general, abs=1e-9)
    assert fast.v_cr == pytest.approx(general.v_cr, abs=1e-9)


@pytest.mark.parametrize(
    ("disc", "params"),
    [
        (FiniteElement(4, 3), Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.0)),
        (FiniteElement(4, 3), Params(alpha=0.0, beta=0.9, gamma=0.0, mu=0.05)),
        (FiniteElement(4, 3), Params(alpha=0.0, end_mass=0.3, **PAPER)),
        (Modal(5), Params(alpha=0.0, beta=0.5, gamma=0.0, mu=0.0)),
    ],
    ids=["hanging", "heavy-damping", "end-mass", "modal"],
)
def test_inherited_classification_is_that_of_the_eigenvectors(disc, params, monkeypatch):
    """Spectra of the straight branch solved without eigenvectors take their resolved
    classification from the nearest sample (classified.classify_inherited): each is compared
    with the full solve at the same v (every light root's class, the largest resolved real
    part, the unstable count), and the events with the full solve everywhere.  With
    Modal(5) the class of the nearest old root, taken without the safeguards, is wrong for
    light roots (measured: in 36 spectra up to v = 16); with beta = 0.9, mu = 0.05 the crowded
    heavy roots near -1/mu are exempt."""
    real = tracking.classify_inherited
    inherited = []

    def check(model, q, res, method, matrices, ref):
        e = real(model, q, res, method, matrices, ref)
        if e.X is None:
            full = classified.classify_spectrum(model, q, res, method, matrices)
            j = np.argmin(np.abs(e.lam[:, None] - full.lam[None, :]), axis=1)
            light = -e.lam.real < hysteretic.HYSTERETIC_HEAVY * np.abs(e.lam)
            inherited.append(
                (
                    np.array_equal(e.resolved[light], full.resolved[j][light]),
                    e.max_real == pytest.approx(full.max_real, rel=1e-12, abs=1e-12),
                    int(e.unstable.sum()) == int(full.unstable.sum()),
                )
            )
        return e

    model = PipeModel(disc, params)
    with monkeypatch.context() as mp:
        mp.setattr(tracking, "classify_inherited", check)
        fast = analyse_stability(model, 16.0, 0.0)
    with monkeypatch.context() as mp:
        mp.setattr(
            tracking,
            "classify_inherited",
            lambda m, q, r, meth, mat, ref: classified.classify_spectrum(m, q, r, meth, mat),
        )
        general = analyse_stability(model, 16.0, 0.0)
    assert len(inherited) >= 10
    assert all(all(x) for x in inherited)
    _assert_same_events(fast, general, rel=1e-10)
    assert np.array_equal(fast.branches[0].n_unstable, general.branches[0].n_unstable)
    assert fast.branches[0].max_real == pytest.approx(general.branches[0].max_real, rel=1e-10)


def test_a_branch_point_on_the_straight_branch_takes_the_general_path(monkeypatch):
    """The standing pipe above the heavy column's buckling load (gamma = 7.837): det K^d
    changes sign on the straight branch, which is then continued (branch points found,
    branches followed)."""
    model = PipeModel(FiniteElement(4, 3), Params(alpha=math.pi, **PAPER))
    res, taken = _analyse(model, False, monkeypatch, 4.0)
    assert not taken
    assert res.branches[0].bifurcations
    assert len(res.branches) > 1


@pytest.mark.parametrize("gamma", [2.0, 7.5, 7.9, 12.0])
def test_branch_point_test_is_the_sign_of_the_assembled_determinant(gamma):
    """chunked_branch._straight_without_branch_points (one batched determinant of the pencil)
    against det K^d of the assembled Jacobians at each point the continuation visits: the
    standing pipe below and above the heavy column's buckling load (gamma = 7.837)."""
    model = PipeModel(FiniteElement(4, 3), Params(alpha=math.pi, beta=0.142, gamma=gamma, mu=0.0))
    kw = {"ds": 0.05, "ds_max": 0.1, "max_steps": 2000}
    for lo, hi in ((0.0, 3.0), (0.0, 9.0), (2.0, 2.5)):
        signs = set()
        for v in chunked_branch._straight_values(lo, hi, kw["ds"], kw["ds_max"]):
            m = model.with_params(replace(model.params, v=v))
            signs.add(float(np.sign(np.linalg.det(linearized_matrices(m, np.zeros(m.n))[0]))))
        want = len(signs) == 1 and 0.0 not in signs
        assert chunked_branch._straight_without_branch_points(model, lo, hi, kw) == want


def test_straight_pencil_is_the_assembled_linearization():
    p = Params(
        alpha=math.pi,
        beta=0.3,
        gamma=7.0,
        mu=0.01,
        end_mass=0.2,
        external_damping=0.4,
        springs=((20.0, 0.4), (3.0, 1.0)),
    )
    for disc in (FiniteElement(4, 3), Modal(5)):
        model = PipeModel(disc, p)
        pencil = StraightPencil(model)
        for v in (0.0, 1.7, 6.3):
            want = linearized_matrices(model.with_params(replace(p, v=v)), np.zeros(disc.n))
            for got, ref in zip(pencil.matrices(v), want, strict=True):
                assert np.abs(got - ref).max() <= 1e-12 * np.abs(ref).max()


def test_static_jacobians_are_the_jacobians_at_rest():
    """PipeModel.static_jacobians (what the spectra use) against jacobians(q, 0, 0), at a
    curved state with every variant."""
    p = Params(
        alpha=1.1,
        beta=0.3,
        gamma=7.0,
        mu=0.01,
        v=4.2,
        end_mass=0.2,
        external_damping=0.4,
        springs=((20.0, 0.4), (3.0, 1.0)),
    )
    for disc in (FiniteElement(4, 3), Modal(5)):
        model = PipeModel(disc, p)
        q = 0.4 * np.sin(np.arange(disc.n) + 1.0)
        zero = np.zeros(disc.n)
        for got, ref in zip(model.static_jacobians(q), model.jacobians(q, zero, zero), strict=True):
            assert np.abs(got - ref).max() <= 1e-13 * np.abs(ref).max()


def test_straight_values_are_the_points_of_the_continuation():
    """The values of v the fast path uses with the continuation's ds_max are the ones the
    continuation itself visits on the straight branch, bit for bit."""
    model = PipeModel(Modal(3), Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.0, v=0.0))
    for lo, hi, ds_max in ((0.0, 3.0, 0.1), (0.4, 2.0, 0.3)):
        m = model.with_params(replace(model.params, v=lo))
        br = continue_static(m, "v", stop=hi, ds=min(0.05, ds_max), ds_max=ds_max)
        assert br.values.tolist() == chunked_branch._straight_values(
            lo, hi, min(0.05, ds_max), ds_max
        )


def _exact_peak_test(x, lam):
    """The per-eigenvalue narrow-window test of BranchAnalysis._peak, up to the
    minimization: np.polyfit on the three samples."""
    out = []
    for j in range(lam.shape[1]):
        r = lam[:, j].real
        tol = STABILITY_TOL * np.maximum(1.0, np.abs(lam[:, j]))
        states = np.where(r > tol, 1, np.where(r < -tol, -1, 0))
        if len(set(states > 0)) != 1:
            continue
        unstable = states[0] > 0
        if not unstable and -1 not in states:
            continue
        h = 0.5 * (x.max() - x.min())
        c = np.polyfit((x - x[1]) / h, r, 2)
        if c[0] == 0 or (c[0] < 0) == unstable:
            continue
        tx = -c[1] / (2 * c[0])
        if not x.min() < x[1] + h * tx < x.max():
            continue
        ext, spread = np.polyval(c, tx), abs(r[1] - r[0]) + abs(r[2] - r[1])
        if (not unstable and ext < -0.5 * spread) or (unstable and ext > 0.5 * spread):
            continue
        out.append(j)
    return out


def test_peak_prefilter_keeps_every_eigenvalue_the_exact_test_takes():
    rng = np.random.default_rng(7)
    taken = 0
    for trial in range(150):
        x = np.sort(rng.uniform(0.0, 2.0, 3))
        if trial % 2:
            x = x[::-1]
        k = 30
        scale = 10.0 ** rng.uniform(-9, 1, k)
        c2, c1, c0 = (rng.normal(size=k) * scale for _ in range(3))
        r = 0.3 * c0 + c1 * x[:, None] + c2 * x[:, None] ** 2
        lam = r + 1j * rng.uniform(0.0, 20.0, k)
        exact = set(_exact_peak_test(x, lam))
        taken += len(exact)
        assert exact <= set(peak_candidates(x, lam).tolist())
    assert taken > 40  # the synthetic cases do exercise the test


# --------------------------------------------------------- the baseline --
def test_baseline_coefficients_are_the_integrals_of_the_beam_modes():
    """Paidoussis' closed forms against Gauss quadrature of the modes (classical.BeamGalerkin)."""
    lam, b, c, d = _baseline().beam_coefficients(8)
    ref = classical.BeamGalerkin(8)
    x, w = ref._x, ref._w
    phi = classical.beam_mode_values(8, x)
    d2 = classical.beam_mode_values(8, x, 2)
    assert lam == pytest.approx(classical.cantilever_roots(8), rel=1e-13)
    scale = np.abs(ref.c).max()
    assert np.abs(b - ref.b).max() <= 1e-10 * scale
    assert np.abs(c - ref.c).max() <= 1e-10 * scale
    assert np.abs(d - (phi.T * (w * x)) @ d2).max() <= 1e-10 * scale


def test_baseline_eigenvalues_match_the_straight_pipe_spectrum():
    """The hanging pipe at v = 3: the four lowest modes of the baseline (40 beam modes)
    and of fempipe P3:16 agree to 1e-6 (both converged to ~1e-7 there)."""
    lam_b = _baseline().make_eigenvalues(40, 0.2, 10.0)(3.0)
    model = PipeModel(FiniteElement(16, 3), Params(alpha=0.0, beta=0.2, gamma=10.0, mu=0.0, v=3.0))
    spec = compute_spectrum(model, np.zeros(model.n))
    for mode in range(1, 5):
        k = np.flatnonzero((spec.mode == mode) & (spec.lam.imag > 0))
        assert k.size == 1
        lam = spec.lam[k[0]]
        j = np.argmin(np.abs(lam_b - lam))
        assert abs(lam_b[j] - lam) <= 1e-6 * abs(lam)


def test_baseline_critical_velocity_against_the_legendre_reference():
    """20 beam modes: error ~5e-6 relative (N^-4, measured 3e-5 absolute); the reference is
    the classical theory on Legendre spectral elements (converged to ~1e-12)."""
    base = _baseline()
    v_cr, freq = base.critical_velocity(base.make_eigenvalues(20, 0.2, 10.0), v_max=10.0)
    ref = classical.critical_velocity(
        classical.StraightPipe(beta=0.2, gamma=10.0), v_max=10.0, method="legendre", n=16
    )
    assert v_cr == pytest.approx(ref.v_cr, rel=2e-5)
    assert abs(v_cr - ref.v_cr) > 1e-8  # a 20-mode Galerkin is not exact: the check can see
    assert freq == pytest.approx(ref.frequency, rel=2e-5)


@pytest.mark.slow
def test_bench_critical_vs_classical_quick_run():
    """The benchmark's smoke run: fresh processes, errors against the references, the ratio.

    fempipe's default P3:16 is within 1e-6 of the converged v_cr (measured 7e-10), the
    40-mode baseline too (3e-7), the 20-mode one less accurate than the 40-mode one.
    """
    from fempipe.bench.stability import bench_critical_vs_classical

    out = bench_critical_vs_classical(quick=True)
    fem, b40, b20 = out["table"][0], out["table"][1], out["table"][2]
    assert fem["rel_error"] < 1e-6 and b40["rel_error"] < 1e-6
    assert b20["rel_error"] > b40["rel_error"]
    assert out["table"][3]["rel_error"] < 1e-6
    assert out["ratio_fempipe_over_baseline40"] > 0
    assert len(out["ratio_by_round"]) == out["runs"] == 1
    # The baseline once more with one BLAS thread: the same v_cr, a ratio of its own.
    one = out["table"][4]
    assert one["v_cr"] == b40["v_cr"]
    assert out["ratio_one_thread"] > 0 and len(out["ratio_by_round_one_thread"]) == 1

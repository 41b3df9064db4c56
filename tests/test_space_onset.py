"""The onset of the non-planar oscillation of the horizontal pipe: the Hopf normal form of
the 3-D model (fempipe.analyses.three_d.onset) against independent computations.

* v_cr of the 3-D Jacobian against the linear out-of-plane model's (another model of the
  same linear problem: the two differ by their discretization errors, which fall with the
  mesh);
* the normal form's cycle against the cycle shot on the full 3-D model near the onset
  (its Y_tip amplitude, period and stability);
* the transversality from the adjoint formula against the difference quotient of the
  eigenvalue along the re-solved static branch;
* the mirror symmetry Y -> -Y: the critical mode is out of the plane, the cycle's Y_tip
  swings symmetrically.
"""

from __future__ import annotations

import functools
import math
from dataclasses import replace

import numpy as np
import pytest

from fempipe.analyses.limit_cycle import shoot
from fempipe.model.three_d.dynamics import PipeDynamics3D
from fempipe.model.three_d.model import PipeModel3D
from fempipe.validation import space_runs

ALPHA = math.pi / 2


@functools.cache
def onset(elements: int):
    return space_runs.onset(elements, ALPHA)


@functools.cache
def near_onset_cycle(delta: float):
    """The 3-D cycle at v_cr + delta on P3:3, loose tolerances (a few seconds)."""
    on = onset(3)
    nf = on.normal_form
    v = nf.v + delta
    model = PipeModel3D(on.planar.disc, replace(on.planar.params, v=v))
    U0, Ud0, T = nf.initial_state(v)
    return shoot(PipeDynamics3D(model), U0, Ud0, T, rtol=1e-6, tol=1e-5)


def test_v_cr_of_the_3d_jacobian_is_the_out_of_plane_models():
    """Two discretizations of one linear problem: they agree to their discretization error,
    which falls fast under refinement (measured 3.4e-5 on P3:3, 1.1e-5 on P3:4, 8.5e-7 on
    P3:6, 1.5e-7 on P3:8: order ~6 from P3:4 on, as P3 eigenvalues; 5.3 from P3:3 to P3:6).
    Required: order above 4 between P3:3 and P3:6."""
    d3 = abs(onset(3).normal_form.v - onset(3).normal_form.checks.v_out_of_plane)
    d6 = abs(onset(6).normal_form.v - onset(6).normal_form.checks.v_out_of_plane)
    assert d3 < 2e-4
    assert d6 < d3 / 2**4


def test_normal_form_diagnostics():
    nf = onset(3).normal_form
    assert nf.criticality == "supercritical"
    assert abs(nf.eigenvalue.real) < 1e-9 * nf.omega
    # The critical mode is out of the plane (mirror-odd): no theta part.
    assert nf.checks.in_plane_fraction < 1e-9
    # The gauge (about -50, -100) and the rest of the spectrum are far from critical.
    assert nf.checks.largest_real_eigenvalue < -40.0
    assert nf.checks.next_real_part < -0.5
    # l1 is flat on the ladder of steps.
    assert nf.uncertainty < 1e-5 * abs(nf.l1)
    # The adjoint formula for lambda'(v) against the eigenvalue re-solved at v +- 1e-4
    # (its rounding ~1e-9 / 1e-4).
    assert nf.transversality == pytest.approx(nf.checks.transversality_check, rel=1e-6)
    assert nf.transversality > 0


def test_shot_cycle_near_onset_is_the_normal_forms():
    """At v_cr + 1e-3 the shot cycle's Y_tip amplitude is c sqrt(delta) (1 + k delta / 2),
    k ~ -0.37 (measured on P3:4): A^2 / (c^2 delta) = 1 - 4e-4, within the integration
    tolerance 1e-6's ~3e-4; a wrong term of l1 changes it at O(1)."""
    delta = 1e-3
    nf = onset(3).normal_form
    cyc = near_onset_cycle(delta)
    lo, hi = cyc.tip["Y_tip"]
    assert lo == pytest.approx(-hi, abs=1e-6)  # the mirror: Y_tip swings symmetrically
    ratio = (0.5 * (hi - lo)) ** 2 / (nf.amplitude_coefficients["Y_tip"] ** 2 * delta)
    assert abs(ratio - 1.0) < 2e-3
    # Period 2 pi / omega to O(delta); the born cycle is stable (supercritical).
    assert cyc.period == pytest.approx(2.0 * math.pi / nf.omega, rel=1e-3)
    assert cyc.stable


@pytest.mark.slow
def test_amplitude_slope_at_onset_to_1e4():
    """The slope of A^2 in v - v_cr at the onset equals c^2 of the normal form to 1e-4
    (P3:4: four cycles shot at delta = 1e-3 ... 1e-2, A^2 / delta = c^2 (1 + k delta +
    k2 delta^2) fitted; measured 1.1e-6)."""
    on = space_runs.onset(4, ALPHA)
    c2 = on.normal_form.amplitude_coefficients["Y_tip"] ** 2
    deltas = np.array([1e-3, 2e-3, 5e-3, 1e-2])
    ratios = np.array(
        [space_runs.amplitude(space_runs.space_cycle_near_onset(on, d)) ** 2 / d for d in deltas]
    )
    r0, k = space_runs.fit_slope(deltas, ratios / c2)
    assert abs(r0 - 1.0) < 1e-4
    assert k < 0  # the amplitude grows slower than sqrt(delta) (measured k = -0.37)


def test_local_order_recovers_a_known_order():
    """The local order of three non-uniform meshes recovers p of Q0 + C N^-p exactly, and a
    sequence whose error changes sign is flagged (no order observed)."""
    from fempipe.validation.space_convergence import local_order, orders

    ns = [2, 3, 4, 6, 8]
    for p in (2.0, 4.0, 6.0, 7.5):
        vals = [1.0 + 0.3 * n**-p for n in ns]
        assert local_order(ns[-3:], vals[-3:]) == pytest.approx(p, abs=1e-8)
    table = {n: {"q": 1.0 + 0.3 * n**-6.0, "bent": 1.0 + n**-6.0 - 0.24 * n**-4.0} for n in ns}
    out = orders(ns, table)
    assert out["q"]["monotone"] and out["q"]["slope"] == pytest.approx(6.0, abs=0.1)
    assert not out["bent"]["monotone"]


def test_critical_reports_the_out_of_plane_criticality_of_the_shot_cycles(capsys):
    """``fempipe critical``'s flutter out of the plane carries the 3-D normal form: supercritical,
    the cycles above v_cr, the tip's swing out of the plane c sqrt(v - v_cr), checked here
    against the 3-D cycle shot at v_cr + 1e-3 on the same mesh (A^2 / (c^2 delta) within 2e-3 of
    1, as the library's normal form)."""
    import json

    from fempipe.cli import main

    assert (
        main(["critical", "--alpha", "pi/2", "--v", "0,7", "--fe", "P3:3", "--json", "--quiet"])
        == 0
    )
    res = json.loads(capsys.readouterr().out)
    (ev,) = [e for e in res["events"] if e.get("plane") == "out" and e["type"] == "flutter"]
    assert ev["criticality"] == "supercritical" and ev["cycle_side"] == "above"
    assert ev["hopf_note"] is None and ev["first_lyapunov_coefficient"] < 0
    c = ev["Y_tip_amplitude_coefficient"]
    assert ev["theta_tip_amplitude_coefficient"] is None
    (inp,) = [e for e in res["events"] if e.get("plane") == "in" and e["type"] == "flutter"]
    assert inp["Y_tip_amplitude_coefficient"] is None and inp["criticality"] == "supercritical"
    delta = 1e-3
    cyc = near_onset_cycle(delta)
    lo, hi = cyc.tip["Y_tip"]
    assert abs((0.5 * (hi - lo)) ** 2 / (c * c * delta) - 1.0) < 2e-3
    assert cyc.stable  # supercritical: the born cycle is stable

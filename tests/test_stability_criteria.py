"""One stability criterion, intrinsic mode numbers, whole-system events, cheap stability flag.

References come from outside the code under test where they can: the dense
eigenvalue criterion of :func:`fempipe.analyses.stability.compute_spectrum` checks the sparse
one, a second mesh and the modal discretization check the mode numbers, a
spectrum just below and above an event checks its stable_before/stable_after.
"""

import time
from dataclasses import replace

import numpy as np
import pytest

from fempipe import FiniteElement, Modal, Params, PipeModel, solve_static
from fempipe.analyses.stability import (
    STABILITY_TOL,
    analyse_stability,
    compute_spectrum,
    trace_root_locus,
)
from fempipe.analyses.statics import solve_sagged

P3_16 = FiniteElement(16, 3)


def _unstable(lam):
    return lam.real > STABILITY_TOL * np.maximum(1.0, np.abs(lam))


def _unstable_modes(locus, i):
    lam = locus.lam[i]
    return sorted(
        {
            int(m)
            for m, x, r in zip(locus.modes, lam, locus.resolved[i], strict=True)
            if r and _unstable(x)
        }
    )


# --------------------------------------------- every unstable root listed --
def test_single_v_spectrum_lists_the_unstable_eigenvalue():
    """beta = 0.65, gamma = 10, mu = 0, alpha = 0 flutters before v = 12.88.

    At that one v, with modes 1..4 asked, the eigenvalue that makes the state
    unstable must be listed (its real part is the reported max_real).
    """
    model = PipeModel(P3_16, Params(alpha=0.0, beta=0.65, gamma=10.0, mu=0.0, v=12.88))
    locus = trace_root_locus(model, [12.88], n_modes=4)
    assert not locus.stable[0] and locus.max_real[0] > 0
    listed = locus.lam[0][locus.resolved[0]]
    assert np.isclose(listed.real.max(), locus.max_real[0], rtol=1e-12, atol=0)
    d = locus.to_dict()["points"][0]
    assert max(e["re"] for e in d["eigenvalues"]) == pytest.approx(d["max_real"], rel=1e-12)


def test_spectrum_cli_single_v_lists_the_unstable_eigenvalue(capsys):
    import json

    from fempipe.cli import main

    argv = ["spectrum", "--alpha", "0", "--beta", "0.65", "--gamma", "10", "--mu", "0"]
    assert main([*argv, "--v", "12.88", "--json", "--quiet"]) == 0
    pt = json.loads(capsys.readouterr().out)["points"][0]
    assert pt["stable"] is False
    assert any(e["re"] > 0 for e in pt["eigenvalues"])
    assert max(e["re"] for e in pt["eigenvalues"]) == pytest.approx(pt["max_real"], rel=1e-12)


# ------------------------------------------------------ intrinsic numbers --
@pytest.mark.parametrize(
    ("beta", "v"),
    [(0.65, 13.0), (0.295, 12.6)],
    ids=["beta0.65", "beta0.295"],
)
def test_mode_number_does_not_depend_on_range_start_or_mesh(beta, v):
    """The unstable mode has one number from v = 0 or from v alone, on two meshes and with sine modes."""
    labels = []
    for disc in (P3_16, FiniteElement(40, 3), Modal(10)):
        model = PipeModel(disc, Params(alpha=0.0, beta=beta, gamma=10.0, mu=0.0, v=0.0))
        path = trace_root_locus(model, np.linspace(0.0, v, 5), n_modes=2)
        alone = trace_root_locus(model, [v], n_modes=2)
        spec = compute_spectrum(model.with_params(model.params.with_flow(v)))
        got = [_unstable_modes(path, -1), _unstable_modes(alone, 0)]
        got.append(sorted({int(m) for m in spec.mode[spec.unstable]}))
        assert got[0] and got[0] == got[1] == got[2], (disc.name, got)
        labels.append(got[0])
    assert labels[0] == labels[1] == labels[2]


@pytest.mark.parametrize(
    ("params", "v_min", "v_max"),
    [
        (Params(alpha=0.0, beta=0.295, gamma=10.0, mu=0.0), 7.0, 13.0),
        (Params(alpha=np.pi, beta=0.2, gamma=40.0, mu=0.0), 1.0, 4.0),
    ],
    ids=["hanging", "standing"],
)
def test_events_from_v0_equal_events_from_vmin(params, v_min, v_max):
    """Events above v_min, with their mode numbers, do not depend on where the range starts."""
    model = PipeModel(P3_16, params)

    def events(lo):
        res = analyse_stability(model, v_max, lo, follow_bifurcations=False)
        return [
            (e.type, e.mode, round(e.v, 8), e.stable_before, e.stable_after)
            for e in res.events
            if not e.at_start and e.v > v_min
        ]

    full, late = events(0.0), events(v_min)
    assert full and late == full


# ------------------------------------------------- whole-system events --
@pytest.mark.parametrize(
    ("mu", "back"),
    [(0.0, "mode_restabilization"), (5e-3, "restabilization")],
    ids=["undamped", "damped"],
)
def test_events_state_whole_system_stability(mu, back):
    """Standing pipe beta = 0.2, gamma = 40: each event says what the system does.

    Mode 1 (diverged from v = 0) returns at v = 2.647.  Undamped, mode 2
    flutters from v = 2.552 and the system stays unstable: the return is a
    per-mode event.  With mu = 5e-3 the flutter comes at 2.712, after it, and
    the system is stable in between: a restabilization.  stable_before and
    stable_after are checked with the dense criterion just below and above
    each event on the straight primary branch.
    """
    model = PipeModel(P3_16, Params(alpha=np.pi, beta=0.2, gamma=40.0, mu=mu))
    res = analyse_stability(model, 4.0, 0.0, follow_bifurcations=False)
    prim = [e for e in res.events if e.branch == "primary" and not e.at_start]
    assert [(e.type, e.mode) for e in prim if e.mode == 1] == [(back, 1)]
    q = np.zeros(P3_16.n)  # the straight column is the primary branch at alpha = pi
    for ev in prim:
        d = ev.to_dict()
        for dv, key in ((-1e-6, "stable_before"), (1e-6, "stable_after")):
            m = model.with_params(model.params.with_flow(ev.v + dv))
            assert compute_spectrum(m, q).stable is d[key], (ev, key)
    for ev in res.events:
        assert {"stable_before", "stable_after"} <= set(ev.to_dict())


# ----------------------------------------------- the cheap stability flag --
def _states():
    """Stable, fluttering, diverging and buckled static states (P3:80, n = 240)."""
    disc = FiniteElement(80, 3)
    out = []
    for v in (1.0, 6.0, 6.5):
        m = PipeModel(disc, Params(alpha=np.pi / 2, beta=0.142, gamma=18.9, mu=5e-3, v=v))
        out.append((m, solve_sagged(m).q))
    for v in (12.0, 12.88):
        m = PipeModel(disc, Params(alpha=0.0, beta=0.65, gamma=10.0, mu=0.0, v=v))
        out.append((m, np.zeros(disc.n)))
    for v in (0.0, 2.6, 3.5):
        m = PipeModel(disc, Params(alpha=np.pi, beta=0.2, gamma=40.0, mu=5e-3, v=v))
        out.append((m, np.zeros(disc.n)))  # the straight column
        # A buckled state: Newton from the state loaded slightly off the vertical.
        lean = solve_sagged(m.with_params(replace(m.params, alpha=np.pi - 0.05))).q
        out.append((m, solve_static(m, q0=lean).q))
    return out


def test_sparse_criterion_decides_as_the_dense_one():
    from fempipe.analyses.stability import linearly_stable

    decisions = []
    for model, q in _states():
        dense = linearly_stable(model, q, sparse=False)
        cheap = linearly_stable(model, q, sparse=True)
        assert cheap is dense, model.params
        decisions.append(dense)
    assert True in decisions and False in decisions


def test_stable_flag_of_a_3000_dof_state_takes_seconds():
    """P3:1000 (n = 3000): the dense criterion would solve a 6000 x 6000 eigenproblem."""
    from fempipe.analyses.stability import linearly_stable

    disc = FiniteElement(1000, 3)
    model = PipeModel(disc, Params(alpha=np.pi / 2, beta=0.142, gamma=18.9, mu=5e-3, v=1.0))
    q = solve_sagged(model).q
    linearly_stable(model, q)  # the canonical modes, once per discretization
    t = time.process_time()
    assert linearly_stable(model, q) is True
    assert time.process_time() - t < 10.0


# ------------------------------------------------------- one criterion --
@pytest.mark.parametrize(
    "params",
    [
        Params(alpha=0.0, beta=0.2, gamma=0.0, mu=0.0, v=0.0),  # conservative: Re = 0 to round-off
        Params(alpha=0.0, beta=0.65, gamma=10.0, mu=0.0, v=12.88),  # flutter
        Params(alpha=np.pi, beta=0.2, gamma=40.0, mu=5e-3, v=1.0),  # divergence
        Params(alpha=np.pi / 2, beta=0.142, gamma=18.9, mu=5e-3, v=3.0),  # stable, deformed
    ],
    ids=["conservative", "flutter", "divergence", "deformed"],
)
def test_linearly_stable_is_the_spectrum_criterion(params):
    """linearly_stable and growth_rate decide and measure as Spectrum.stable and max_real."""
    from fempipe.analyses.stability import growth_rate, linearly_stable

    model = PipeModel(P3_16, params)
    q = solve_sagged(model).q
    spec = compute_spectrum(model, q)
    assert linearly_stable(model, q) is spec.stable
    assert growth_rate(model, q) == pytest.approx(spec.max_real, rel=1e-9, abs=1e-12)

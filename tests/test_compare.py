"""``fempipe compare``: a user's values against fempipe's, with fempipe's error estimate.

Everything runs in-process through ``fempipe.cli.main``, on cheap
discretizations (three sine modes, P2 on 4 elements); the expected numbers
come from independent computations: the second v_cr implementation of
:mod:`fempipe.validation.onset`, the collocation solution of the strong form
(:func:`fempipe.validation.bvp.solve_static_bvp`), a finer mesh, and
``fempipe convergence`` for "the same numbers as the convergence study".
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from fempipe.cli import main
from fempipe.io import read_csv

#: The keys of an output row fixed by the users' request.
CONTRACT = (
    "row",
    "quantity",
    "user",
    "fempipe",
    "difference",
    "relative_difference",
    "error_estimate",
    "resolved",
)
TD_PIPE = {"length": 0.094, "EI": 1.8e-5, "m": 0.0159, "M": 0.0058, "g": 9.8}


def write(tmp_path, *lines, name="user.csv"):
    path = tmp_path / name
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
    return str(path)


def run_json(argv, capsys):
    code = main([*argv, "--json", "--quiet"])
    out = capsys.readouterr()
    return code, json.loads(out.out), out.err


def rows_of(result, quantity):
    return [r for r in result["rows"] if r["quantity"] == quantity]


def gci(coarse, fine, p, r=2.0):
    """Roache's estimate of the coarse value's error, written out here (factor 3, ratio r)."""
    return 3.0 * abs(coarse - fine) * r**p / (r**p - 1.0)


# ---------------------------------------------------------------------------
# The table


def test_table_against_independent_solutions(tmp_path, capsys):
    """Three sine modes: v_cr from the second implementation, tip values from collocation."""
    from fempipe.model.discretization import Modal
    from fempipe.validation.bvp import solve_static_bvp
    from fempipe.validation.onset import critical_velocity

    path = write(
        tmp_path,
        "# a modal code's results",
        "label,alpha [rad],gamma,v,v_cr [1],X_tip [L],theta_tip",
        "hanging,0,,,6.4,,",
        "",
        "# the next row is at 60 degrees",
        "inclined,pi/3,18.9,2,6.4,0.9,-0.8",
    )
    out = tmp_path / "out"
    code, res, err = run_json(["compare", path, "--modal", "3", "--out", str(out)], capsys)
    rows = res["rows"]
    # as diff: 0 only when every value agrees within fempipe's error estimate
    assert code == (0 if all(r["verdict"] == "agrees" for r in rows) else 1), err
    assert [r["verdict"] for r in rows] == [
        {True: "differs", False: "agrees"}[r["resolved"]] for r in rows
    ]
    assert [(r["row"], r["quantity"]) for r in rows] == [
        (1, "v_cr"),
        (2, "v_cr"),
        (2, "X_tip"),
        (2, "theta_tip"),
    ]
    assert [r["line"] for r in rows] == [3, 6, 6, 6]
    assert [r["label"] for r in rows] == ["hanging", "inclined", "inclined", "inclined"]
    for r in rows:
        assert set(CONTRACT) <= set(r), r
    assert res["discretization"]["name"] == "modal:3"
    assert res["error_estimate"]["refined"] == "modal:7"
    assert res["error_estimate"]["order"] == 3

    # v_cr: the value and the refined value from the independent implementation.
    vcr, vcr2 = rows_of(res, "v_cr")
    q3 = critical_velocity(Modal(3), alpha=0.0, v_max=15.0).v_cr
    # Three modes are refined to seven (odd N -> 2N + 1, ratio 7/3).
    q6 = critical_velocity(Modal(7), alpha=0.0, v_max=15.0).v_cr
    assert abs(vcr["fempipe"] - q3) < 1e-8
    assert abs(vcr["refined"] - q6) < 1e-8
    assert vcr["error_estimate"] == pytest.approx(gci(q3, q6, 3, 7 / 3), rel=1e-6)
    assert vcr["difference"] == pytest.approx(6.4 - q3, abs=1e-8)
    assert vcr["relative_difference"] == pytest.approx((6.4 - q3) / q3, abs=1e-8)
    assert vcr["resolved"] is (abs(6.4 - q3) > vcr["error_estimate"])
    # Parameters not given: the paper's case, listed; the flow range 0..15.
    assert (vcr["beta"], vcr["gamma"], vcr["mu"]) == (0.142, 18.9, 0.005)
    assert (vcr["v"], vcr["v_min"], vcr["v_max"]) == (None, 0.0, 15.0)
    assert vcr["defaults"] == {
        "beta": 0.142,
        "gamma": 18.9,
        "mu": 0.005,
        "v_min": 0.0,
        "v_max": 15.0,
    }
    # Each entry gives the flow its quantity uses: the range for v_cr, v for the tip values.
    assert (vcr2["v"], vcr2["v_min"], vcr2["v_max"]) == (None, 0.0, 15.0)
    assert vcr2["defaults"] == {"beta": 0.142, "mu": 0.005, "v_min": 0.0, "v_max": 15.0}

    # Static tip values: the collocation solution lies within fempipe's estimate.
    bvp = solve_static_bvp(math.pi / 3, 18.9, 2.0, tol=1e-10)
    for name, exact in (("X_tip", bvp.X_tip), ("theta_tip", bvp.theta_tip)):
        (r,) = rows_of(res, name)
        assert r["alpha"] == pytest.approx(math.pi / 3, abs=1e-15)
        assert r["v"] == 2.0 and r["v_min"] is None and r["v_max"] is None
        assert r["defaults"] == {"beta": 0.142, "mu": 0.005}
        true_error = abs(r["fempipe"] - exact)
        assert 1e-4 < true_error < r["error_estimate"], (name, true_error, r["error_estimate"])
        assert abs(r["refined"] - exact) < true_error  # six modes are closer
        assert r["difference"] == r["user"] - r["fempipe"]
        assert r["resolved"] is (abs(r["difference"]) > r["error_estimate"])
    assert res["summary"]["comparisons"] == 4 and res["summary"]["failed"] == 0

    # The files: compare.csv holds the JSON's rows, the figure's texts fit.
    assert sorted(p.name for p in out.iterdir()) == ["compare.csv", "compare.json", "compare.png"]
    assert json.loads((out / "compare.json").read_text()) == res
    cols = read_csv(out / "compare.csv")
    assert cols["row"].tolist() == [1, 2, 2, 2]
    assert cols["unit"].tolist() == ["1", "1", "L", "rad"]
    for key in ("user", "fempipe", "difference", "relative_difference", "error_estimate"):
        assert cols[key].tolist() == [r[key] for r in rows], key
    assert cols["resolved"].tolist() == [r["resolved"] for r in rows]
    assert cols["verdict"].tolist() == [r["verdict"] for r in rows]
    header = (out / "compare.csv").read_text().splitlines()[0]
    assert header.startswith("row [-],label [-],quantity [-],unit [-],user [-],fempipe [-]")
    assert "relative_difference [1]" in header and "v_max [1]" in header


def test_text_table(tmp_path, capsys):
    path = write(tmp_path, "alpha,v,X_tip", "pi/2,1,0.5")
    # X_tip = 0.5 against fempipe's 0.81: a difference, exit 1 as diff's
    assert main(["compare", path, "--modal", "3", "--quiet"]) == 1
    cap = capsys.readouterr()
    out = cap.out
    assert "1 of 1 values differ from fempipe's by more than its error estimate" in cap.err
    lines = out.splitlines()
    assert "1 comparison on modal:3" in lines[0] and "modal:7" in lines[0]
    assert lines[1].split() == [
        "row",
        "quantity",
        "user",
        "fempipe",
        "difference",
        "rel.",
        "diff.",
        "error",
        "est.",
        "verdict",
    ]
    assert lines[2].split()[:3] == ["1", "X_tip", "0.5"]
    assert lines[2].split()[-1] == "differs"
    assert "not given in row 1: beta = 0.142 (the paper's case)" in out
    assert "0 agree within fempipe's error estimate, 1 differ by more than it" in out


def test_same_numbers_as_fempipe_convergence(tmp_path, capsys):
    """The value and the refined value are those of the convergence study's members."""
    path = write(tmp_path, "alpha,gamma,v,Z_tip", "1.2,30,3,0.5")
    code, res, err = run_json(["compare", path, "--modal", "3"], capsys)
    assert code == 1 and res["rows"][0]["verdict"] == "differs", err
    code, study, err = run_json(
        ["convergence", "--quantity", "Z_tip", "--alpha", "1.2", "--gamma", "30", "--v", "3"]
        + ["--modal", "3,7"],
        capsys,
    )
    assert code == 0, err
    (series,) = study["series"]
    assert series["n"] == [3, 7]
    (r,) = res["rows"]
    assert [r["fempipe"], r["refined"]] == series["values"]


def test_resolved_separates_a_finer_mesh_from_a_wrong_value(tmp_path, capsys):
    """P2:4: the P2:16 value is within the estimate, 1 % off is resolved."""
    from fempipe.model.discretization import FiniteElement
    from fempipe.model.params import Params
    from fempipe.studies.convergence import Quantity
    from fempipe.validation.onset import critical_velocity

    fine = FiniteElement(16, 2)
    x_tip = Quantity("X_tip", Params(alpha=math.pi / 2, v=2.0))(fine)
    v_cr = critical_velocity(fine, alpha=0.0, v_max=15.0).v_cr
    path = write(
        tmp_path,
        "alpha_deg,v,X_tip,v_cr",
        f"90,2,{x_tip!r},",
        f"90,2,{1.01 * x_tip!r},",
        f"0,,,{v_cr!r}",
        f"0,,,{1.01 * v_cr!r}",
    )
    code, res, err = run_json(["compare", path, "--fe", "P2:4"], capsys)
    assert code == 1, err  # two of the values differ
    assert [r["resolved"] for r in res["rows"]] == [False, True, False, True]
    assert [r["verdict"] for r in res["rows"]] == ["agrees", "differs"] * 2
    for r in res["rows"]:
        assert r["error_estimate"] > 0
    # The finer mesh's value is within the estimate, but not trivially (not the floor).
    for r in res["rows"][::2]:
        assert 1e-6 < abs(r["difference"]) < r["error_estimate"]
    s = res["summary"]
    assert (s["resolved"], s["not_resolved"], s["failed"]) == (2, 2, 0)
    assert (s["differ"], s["agree"]) == (2, 2)


def test_parametric_thresholds(tmp_path, capsys):
    """sigma_threshold and omega_threshold at the mean flow v, searched in the row's band:
    fempipe on three sine modes against a user's values from other discretizations (P4:2,
    P2:3) of the convergence study's Quantity; the P4:2 value, 1e-3 off the converged one, lies
    within fempipe's estimate and the refined modal:7 is closer to it."""
    from fempipe.model.discretization import FiniteElement, Modal
    from fempipe.model.params import Params
    from fempipe.studies.convergence import Quantity

    p = Params(beta=0.2, gamma=10.0, mu=0.005, v=6.0)  # Paidoussis & Issid's hanging pipe
    band = {"omega_band": (24.0, 36.0), "sigma_max": 0.2}
    sigma = Quantity("sigma_threshold", p, **band)(FiniteElement(2, 4))
    omega = Quantity("omega_threshold", p, **band)(FiniteElement(3, 2))
    path = write(
        tmp_path,
        "beta,gamma,mu,v,omega_min [1/T],omega_max,sigma_max,sigma_threshold,omega_threshold",
        f"0.2,10,0.005,6,24,36,0.2,{sigma!r},",
        f"0.2,10,0.005,6,24,36,0.2,,{omega!r}",
    )
    out = tmp_path / "out"
    code, res, err = run_json(["compare", path, "--modal", "3", "--out", str(out)], capsys)
    s, w = res["rows"]
    assert (s["quantity"], w["quantity"]) == ("sigma_threshold", "omega_threshold")
    assert code == 0 and res["summary"]["agree"] == 2, err
    for r, user, q in ((s, sigma, "sigma_threshold"), (w, omega, "omega_threshold")):
        assert r["fempipe_quantity"] == q and r["unit"] == {"sigma_threshold": "1"}.get(q, "1/T")
        fempipe = Quantity(q, p, **band)(Modal(3))
        assert r["fempipe"] == fempipe
        assert r["difference"] == pytest.approx(user - fempipe, abs=1e-12)
        assert r["error_estimate"] == pytest.approx(gci(r["fempipe"], r["refined"], 3, 7 / 3))
        assert (r["omega_min"], r["omega_max"], r["sigma_max"], r["v"]) == (24, 36, 0.2, 6)
        assert r["v_min"] is None and r["defaults"] == {"alpha": 0.0}
    # three modes are 8 % off the converged threshold: within the estimate, modal:7 closer
    assert 0.05 < abs(s["relative_difference"]) < 0.1
    assert abs(s["difference"]) < s["error_estimate"]
    assert abs(s["refined"] - sigma) < abs(s["difference"])
    assert set(res["error_estimate"]["floors"]) == {"sigma_threshold", "omega_threshold"}
    header = (out / "compare.csv").read_text().splitlines()[0]
    assert "omega_min [1/T],omega_max [1/T],sigma_max [1]" in header


def test_reading_the_band_of_the_thresholds(tmp_path):
    """The band columns: sigma_max defaults to 0.5 (listed), a row's quantity carries the band,
    an SI row's mean flow is its U and its band stays dimensionless; the other quantities of
    the row do not report the band."""
    from fempipe.io.cases import read_cases
    from fempipe.model.params import PipeSI

    path = write(
        tmp_path,
        "v,omega_min,omega_max,sigma_max,sigma_threshold,X_tip",
        "6,24,36,,0.09,0.9",
        "6,,,0.3,,0.9",
    )
    thresholds, tip = read_cases(path)
    q = thresholds.quantity("sigma_threshold")
    assert (q.omega_band, q.sigma_max, q.params.v) == ((24.0, 36.0), 0.5, 6.0)
    assert "24 <= omega <= 36, sigma <= 0.5" in q.describe()
    d = thresholds.to_dict("sigma_threshold")
    assert (d["omega_min"], d["omega_max"], d["sigma_max"]) == (24.0, 36.0, 0.5)
    assert d["defaults"]["sigma_max"] == 0.5
    d = thresholds.to_dict("X_tip")
    assert (d["omega_min"], d["sigma_max"]) == (None, None) and "sigma_max" not in d["defaults"]
    assert tip.omega_range is None and "omega_min" not in tip.to_dict()
    si = write(
        tmp_path,
        "length,EI,m,M,U,omega_min,omega_max,omega_threshold",
        "0.094,1.8e-5,0.0159,0.0058,2,24,36,30",
        name="si.csv",
    )
    (case,) = read_cases(si)
    q = case.quantity("omega_threshold")
    pipe = PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058)
    assert q.params.v == pipe.v_of_U(2.0) and q.omega_band == (24.0, 36.0)


def test_si_rows(tmp_path, capsys):
    """Texier & Dorbolo's pipe in SI units: the groups of PipeSI, U in m/s, v_cr up to U_max."""
    from fempipe.model.params import PipeSI
    from fempipe.validation.bvp import solve_static_bvp

    pipe = PipeSI(L=0.094, EI=1.8e-5, m=0.0159, M=0.0058, g=9.8, alpha=math.pi / 2)
    path = write(
        tmp_path,
        "length [m],EI [N m^2],m [kg/m],M [kg/m],g [m/s^2],alpha_deg,U [m/s],U_max,X_tip,v_cr",
        "0.094,1.8e-5,0.0159,0.0058,9.8,90,2,,0.5,",
        "0.094,1.8e-5,0.0159,0.0058,9.8,90,,6,,6.5",
    )
    code, res, err = run_json(["compare", path, "--modal", "3"], capsys)
    assert code == (0 if all(r["verdict"] == "agrees" for r in res["rows"]) else 1), err
    x, vcr = res["rows"]
    p = pipe.params(2.0)
    assert (x["beta"], x["gamma"], x["mu"], x["v"]) == (p.beta, p.gamma, p.mu, p.v)
    assert x["U"] == 2.0 and x["pipe_SI"] == pipe.to_dict()
    assert x["defaults"] == {"a": 0.0}
    assert vcr["v_max"] == pipe.v_of_U(6.0) and vcr["U_max"] == 6.0
    assert vcr["v_min"] == 0.0 and vcr["U_min"] == 0.0
    assert vcr["defaults"] == {"a": 0.0, "U_min": 0.0}
    assert vcr["fempipe"] is not None and vcr["resolved"] is not None
    bvp = solve_static_bvp(math.pi / 2, p.gamma, p.v, tol=1e-10)
    assert abs(x["fempipe"] - bvp.X_tip) < x["error_estimate"]


def test_failed_row_is_reported_and_the_others_computed(tmp_path, capsys):
    """No v_cr below v_max: that row has no fempipe value and a message; exit 1, files written."""
    path = write(tmp_path, "alpha,v,v_max,v_cr,X_tip", "0,,1,6.3,", "0,1,,,0.99")
    out = tmp_path / "out"
    code = main(["compare", path, "--modal", "3", "--workers", "2", "--out", str(out), "--json"])
    cap = capsys.readouterr()
    assert code == 1
    res = json.loads(cap.out)
    failed, ok = res["rows"]
    assert failed["fempipe"] is None and failed["resolved"] is None
    assert failed["error_estimate"] is None and failed["difference"] is None
    assert "no v_cr in the range" in failed["failure"]
    assert ok["failure"] is None and ok["fempipe"] is not None
    assert res["summary"]["failed"] == 1
    assert "1 of 2 comparisons failed (row 1 v_cr)" in cap.err
    cols = read_csv(out / "compare.csv")
    assert "no v_cr in the range" in cols["failure"][0]
    assert math.isnan(cols["fempipe"][0]) and np.isfinite(cols["fempipe"][1])


def test_figure_text_fits(tmp_path):
    """compare.png: every quantity in its panels, no text clipped or overlapping."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from test_figures import text_faults

    from fempipe.plotting.compare import plot_comparison

    rows = []
    for i, (q, f, u) in enumerate(
        [("v_cr", 6.33, 6.37), ("v_cr", 4.48, 4.49), ("X_tip", 0.92, 0.917), ("Z_tip", 0.32, 0.322)]
        + [("theta_tip", -0.89, -0.905), ("eta_tip", 0.1, 0.2), ("frequency", 15.7, 15.0)],
        start=1,
    ):
        e = 1e-3 * abs(f)
        rows.append(
            {"row": i, "quantity": q, "user": u, "fempipe": f, "difference": u - f}
            | {"error_estimate": e, "resolved": abs(u - f) > e}
        )
    rows.append({"row": 8, "quantity": "lc_period", "user": 1.0, "fempipe": None})
    fig = plot_comparison(rows, caption="α per row, β = 0.142, γ = 18.9, μ = 0.005. " * 4)
    try:
        faults = text_faults(fig)
        titles = [ax.get_title() for ax in fig.axes if ax.get_visible() and ax.get_title()]
    finally:
        plt.close(fig)
    assert not faults, "\n".join(faults)
    assert titles == ["v_cr", "X_tip", "Z_tip", "theta_tip", "eta_tip", "frequency", "lc_period"]


# ---------------------------------------------------------------------------
# Bad files: one line naming the row and column, exit 2, nothing computed or written


class ComputeStartedError(Exception):
    """Raised by a stand-in solver: the command started computing."""


@pytest.fixture
def no_compute(monkeypatch):
    import fempipe.studies.compare

    def computed(*args, **kwargs):
        raise ComputeStartedError

    monkeypatch.setattr(fempipe.studies.compare, "evaluate", computed)
    monkeypatch.setattr(fempipe.studies.compare, "compare_values", computed)


SI_HEAD = "length,EI,m,M,U,X_tip"
BAD_FILES = {
    "empty": ([], "no header line"),
    "only comments": (["# nothing"], "no header line"),
    "header only": (["alpha,v,X_tip"], "no data rows"),
    "no quantity column": (["alpha,gamma,v", "0,18.9,1"], "header: no quantity column"),
    "unknown column": (["alpha,v,X_tip,speed", "0,1,0.9,2"], "header, column speed: unknown"),
    "duplicate column": (["v,X_tip,v", "1,0.9,1"], "header, column v: appears twice"),
    "wrong unit": (["alpha [deg],v,X_tip", "0,1,0.9"], "header, column alpha: unit [deg]"),
    "both alphas": (["alpha,alpha_deg,v,X_tip", "0,0,1,0.9"], "header, columns alpha, alpha_deg"),
    "non-numeric": (["gamma,v,X_tip", "18.9,1,0.9", "abc,1,0.9"], "row 2 (line 3), column gamma"),
    "non-finite": (["v,X_tip", "1,nan"], "row 1 (line 2), column X_tip: 'nan'"),
    "bad angle": (["alpha,v,X_tip", "pi/x,1,0.9"], "row 1 (line 2), column alpha"),
    "alpha range": (["alpha,v,X_tip", "7,1,0.9"], "row 1 (line 2), column alpha: alpha = 7"),
    "alpha_deg range": (["alpha_deg,v,X_tip", "400,1,0.9"], "column alpha_deg: alpha_deg = 400"),
    "beta range": (["beta,v,X_tip", "1.5,1,0.9"], "row 1 (line 2), column beta: beta must"),
    "gamma range": (["gamma,v,X_tip", "18.9,1,0.9", "3000,1,0.9"], "row 2 (line 3), column gamma"),
    "negative gamma": (["gamma,v,X_tip", "-1,1,0.9"], "row 1 (line 2), column gamma: gamma must"),
    "mu range": (["mu,v,X_tip", "11,1,0.9"], "row 1 (line 2), column mu: mu = 11"),
    "v range": (["v,X_tip", "60,0.9"], "row 1 (line 2), column v: v = 60"),
    "v_max range": (["v_max,v_cr", "60,6"], "row 1 (line 2), column v_max: v = 60"),
    "empty range": (["v_min,v_max,v_cr", "5,3,6"], "row 1 (line 2), columns v_min, v_max"),
    "no flow column": (["alpha,X_tip", "0,0.9"], "row 1 (line 2), column X_tip: needs the flow"),
    "empty flow cell": (["v,v_cr,X_tip", "1,6,", ",,0.9"], "row 2 (line 3), column v: empty"),
    "cell count": (["v,X_tip", "1,0.9,3"], "row 1 (line 2): 3 cells, the header has 2"),
    "no value": (
        ["v,X_tip,v_cr", "1,0.9,", "1,,"],
        "row 2 (line 3), columns X_tip, v_cr: no value",
    ),
    "mixed": (["gamma,EI,v,X_tip", "18.9,1,1,0.9"], "header, columns gamma, EI: mixes"),
    "SI incomplete": (["length,EI,m,U,X_tip", "0.1,1e-5,0.01,1,0.9"], "header, column M: missing"),
    "SI empty cell": ([SI_HEAD, "0.1,1e-5,0.01,,1,0.9"], "row 1 (line 2), column M: empty"),
    "SI bad EI": ([SI_HEAD, "0.1,-1e-5,0.01,0.01,1,0.9"], "row 1 (line 2), column EI: EI must"),
    "SI gamma": ([SI_HEAD, "10,1e-5,0.01,0.01,1,0.9"], "columns length, EI, m, M, g: the pipe has"),
    "SI damping": (
        ["length,EI,m,M,a,U,X_tip", "0.1,1e-5,0.01,0.01,1e4,1,0.9"],
        "row 1 (line 2), column a: the pipe has mu",
    ),
    "SI U range": ([SI_HEAD, "0.1,1e-5,0.01,0.01,100,0.9"], "row 1 (line 2), column U: U = 100"),
    "SI no U": (["length,EI,m,M,X_tip", "0.1,1e-5,0.01,0.01,0.9"], "column X_tip: needs the flow"),
    "comments shift lines": (
        ["# header next", "v,X_tip", "1,0.9", "# bad row next", "x,0.9"],
        "row 2 (line 5), column v: 'x'",
    ),
    "not CSV": (["v,X_tip", "1,0.9", '1,"0.9'], "row 2 (line 3): not CSV"),
    "no band": (
        ["v,X_tip,sigma_threshold", "6,1,", "6,,0.09"],
        "row 2 (line 3), column sigma_threshold: sigma_threshold is searched in the band "
        "omega_min < omega < omega_max [1/T]: add the columns omega_min, omega_max",
    ),
    "empty band cell": (
        ["v,omega_min,omega_max,omega_threshold", "6,24,,30"],
        "row 1 (line 2), column omega_max: empty, but omega_threshold is searched in the band",
    ),
    "empty band": (
        ["v,omega_min,omega_max,sigma_threshold", "6,36,24,0.1"],
        "row 1 (line 2), columns omega_min, omega_max: the band of sigma_threshold needs",
    ),
    "omega range": (
        ["v,omega_min,omega_max,sigma_threshold", "6,0,24,0.1"],
        "column omega_min: omega_min = 0 is outside 0 < omega_min <= 10000",
    ),
    "sigma_max range": (
        ["v,omega_min,omega_max,sigma_max,sigma_threshold", "6,1,24,1.5,0.1"],
        "row 1 (line 2), column sigma_max: sigma_max = 1.5 is outside 0 < sigma_max <= 1",
    ),
    "band unit": (
        ["v,omega_min [1],omega_max,sigma_threshold", "6,1,24,0.1"],
        "header, column omega_min: unit [1] is not the unit of omega_min, [1/T]",
    ),
}


@pytest.mark.parametrize("case", list(BAD_FILES))
def test_bad_file_is_refused_before_computing(case, tmp_path, capsys, no_compute):
    lines, expected = BAD_FILES[case]
    path = tmp_path / "user.csv"
    path.write_text("".join(line + "\n" for line in lines), encoding="utf-8")
    out = tmp_path / "out"
    code = main(["compare", str(path), "--modal", "3", "--out", str(out)])
    cap = capsys.readouterr()
    assert code == 2, cap.err
    assert cap.out == ""
    err = cap.err.strip().splitlines()
    assert len(err) == 1, cap.err
    assert err[0].startswith(f"fempipe compare: error: {path}: "), err[0]
    assert expected in err[0], err[0]
    assert not out.exists() or not any(out.iterdir())


def test_missing_file_and_directory(tmp_path, capsys, no_compute):
    for target, expected in ((tmp_path / "nope.csv", "no such file"), (tmp_path, "a directory")):
        assert main(["compare", str(target), "--out", str(tmp_path / "out")]) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith(f"fempipe compare: error: {target}: ") and "\n" not in err
        assert expected in err
    assert not (tmp_path / "out").exists()


def test_too_many_comparisons_need_allow_large(tmp_path, capsys, no_compute):
    path = write(tmp_path, "v,X_tip,Z_tip", *(["1,0.9,0.1"] * 501))
    assert main(["compare", path]) == 2
    err = capsys.readouterr().err
    assert "1002 comparisons is more than the limit 1000" in err and "--allow-large" in err


# ---------------------------------------------------------------------------
# Acceptance: the paper's N = 3 values


@pytest.mark.slow
def test_paper_n3_values_are_resolved(tmp_path, capsys):
    """validation/compare_paper_N3.csv: N = 3 overestimates v_cr by 0.2-0.7 %, resolved at P3:16."""
    from pathlib import Path

    path = Path(__file__).resolve().parents[1] / "validation" / "compare_paper_N3.csv"
    code, res, err = run_json(["compare", str(path), "--workers", "2", "--planar"], capsys)
    assert code == 1, err  # every N = 3 value differs from the converged one
    vcr = rows_of(res, "v_cr")
    assert [r["row"] for r in vcr] == list(range(1, 13))
    rel = [r["relative_difference"] for r in vcr]
    assert all(0.0015 < x < 0.007 for x in rel), rel
    assert max(rel) > 0.006 and min(rel) < 0.002  # the spread the report shows
    for r in res["rows"]:
        assert r["resolved"] is True and r["verdict"] == "differs", r
        assert r["error_estimate"] < 1e-6
    tips = [r for r in res["rows"] if r["row"] > 12]
    assert len(tips) == 12
    assert all(1e-3 < abs(r["difference"]) < 0.02 for r in tips), tips


def test_v_cr_means_what_critical_means_and_planar_the_plane(tmp_path, capsys):
    """An inclined pipe (alpha = 60 deg, beta = 0.3, gamma = 10) first loses stability out of
    its plane: ``v_cr`` is that first loss, as ``fempipe critical``'s (one meaning in every
    command); ``--planar`` compares the in-plane value, as ``critical --planar``.  Each row
    names the fempipe quantity it used."""
    from test_cli_stability import run_json as critical_json

    args = ["--alpha", "60deg", "--beta", "0.3", "--gamma", "10", "--fe", "P3:4"]
    crit = critical_json(capsys, ["critical", *args, "--v", "0,10", "--json", "--quiet"])
    planar = critical_json(
        capsys, ["critical", *args, "--v", "0,10", "--planar", "--json", "--quiet"]
    )
    assert crit["v_cr"] < planar["v_cr"]  # out of the plane first
    path = write(tmp_path, "alpha_deg,beta,gamma,v_max,v_cr", "60,0.3,10,10,7.9")
    _, res, _ = run_json(["compare", path, "--fe", "P3:4"], capsys)
    (row,) = res["rows"]
    assert row["fempipe_quantity"] == "v_cr" and res["planar"] is False
    assert row["fempipe"] == pytest.approx(crit["v_cr"], abs=1e-9)
    _, res, _ = run_json(["compare", path, "--fe", "P3:4", "--planar"], capsys)
    (row,) = res["rows"]
    assert row["fempipe_quantity"] == "v_cr_in_plane" and res["planar"] is True
    assert row["fempipe"] == pytest.approx(planar["v_cr"], abs=1e-9)
    assert main(["compare", path, "--fe", "P3:4", "--planar", "--quiet"]) in (0, 1)
    out = capsys.readouterr().out
    assert (
        "v_cr: compared with fempipe's v_cr_in_plane, the first loss of stability in the plane"
        in out
    )

"""The convergence-study engine and ``fempipe convergence``."""

from __future__ import annotations

import contextlib
import io
import json
from dataclasses import dataclass

import numpy as np
import pytest

from fempipe.cli import main
from fempipe.core.errors import SolverError
from fempipe.model.params import Params
from fempipe.studies.convergence import (
    Family,
    Quantity,
    doubling,
    estimate_order,
    extrapolate_richardson,
    local_orders,
    run_study,
)


def run_cli(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@dataclass(frozen=True)
class Synthetic:
    """Q(n) = exact + C n^-p (+ a failure below n_fail): a study with a known answer."""

    exact: float = 1.25
    C: float = 0.7
    tolerance: float = 1e-13
    n_fail: int = 0

    def __call__(self, disc) -> float:
        n = disc.n_elements if hasattr(disc, "n_elements") else disc.n_modes
        if n < self.n_fail:
            raise SolverError(f"too coarse: n = {n}")
        p = 2.0 * disc.degree if hasattr(disc, "degree") else 3.0
        return self.exact + self.C * float(n) ** -p


def test_doubling():
    assert doubling(2, 64) == [2, 4, 8, 16, 32, 64]
    assert doubling(3, 20) == [3, 6, 12]
    with pytest.raises(ValueError):
        doubling(4, 2)


def test_richardson_and_orders_recover_a_power_law():
    n = np.array([4.0, 8.0, 16.0])
    q = 2.0 + 5.0 * n**-4
    val, err = extrapolate_richardson(q[1], q[2], 4.0)
    assert val == pytest.approx(2.0, abs=1e-14)
    assert err == pytest.approx(5.0 * 16.0**-4, rel=1e-12)
    assert local_orders(n, q) == pytest.approx([4.0])
    order, idx = estimate_order(n, np.abs(q - 2.0), floor=0.0)
    assert order == pytest.approx(4.0) and idx == (0, 1, 2)
    # Points at or below the floor are not fitted.
    order, idx = estimate_order(n, np.abs(q - 2.0), floor=1e-4)
    assert idx == (0, 1)


def test_study_of_a_known_power_law():
    """Reference = the exact value within its estimate; orders = the built-in ones."""
    fams = [
        Family("fe", (2, 4, 8, 16), degree=1),
        Family("fe", (2, 4, 8), degree=2),
        Family("modal", (2, 4, 8, 16)),
    ]
    q = Synthetic()
    st = run_study(q, fams, tolerance=q.tolerance)
    # P2 has the smallest correction (0.7 (8^-4 - 4^-4) / 15): it is the reference.
    assert st.reference.family == "fe-P2"
    assert abs(st.reference.value - q.exact) <= 1e-12
    orders = {s.family: s.observed_order for s in st.series}
    assert orders["fe-P1"] == pytest.approx(2.0, abs=1e-6)
    assert orders["fe-P2"] == pytest.approx(4.0, abs=1e-6)
    assert orders["modal-sine"] == pytest.approx(3.0, abs=1e-6)
    # Each other family's extrapolation is listed as an independent value.
    methods = [d["method"] for d in st.reference.independent]
    assert methods == ["Richardson of fe-P1", "Richardson of modal-sine"]


def test_failed_members_are_recorded_and_left_out():
    fams = [Family("fe", (2, 4, 8, 16, 32), degree=1)]
    st = run_study(Synthetic(n_fail=4), fams, tolerance=1e-13)
    s = st.series[0]
    assert np.isnan(s.values[0]) and "too coarse" in s.failures[0]
    assert s.observed_order == pytest.approx(2.0, abs=1e-6)
    assert 0 not in s.fit
    d = st.to_dict()["series"][0]
    assert d["values"][0] is None and d["failures"] == {"2": "too coarse: n = 2"}


def test_static_study_orders_and_collocation():
    """X_tip of the horizontal pipe at v = 3: P2 converges as h^4, P1 as h^2."""
    from fempipe.validation.bvp import solve_static_bvp

    p = Params(alpha=np.pi / 2, beta=0.142, gamma=18.9, mu=5e-3, v=3.0)
    q = Quantity("X_tip", p)
    st = run_study(
        q, [Family("fe", (4, 8, 16, 32), degree=1), Family("fe", (2, 4, 8, 16), degree=2)]
    )
    orders = {s.family: s.observed_order for s in st.series}
    assert orders["fe-P1"] == pytest.approx(2.0, abs=0.1)
    assert orders["fe-P2"] == pytest.approx(4.0, abs=0.3)
    bvp = solve_static_bvp(p.alpha, p.gamma, p.v, tol=1e-11)
    # The reference (Richardson of P2:8, P2:16) agrees with collocation within its estimate.
    assert abs(st.reference.value - bvp.X_tip) <= st.reference.error_estimate + 1e-10


def test_eigenvalue_study_is_complex_and_converges():
    p = Params(alpha=0.0, beta=0.142, gamma=18.9, mu=5e-3, v=2.0)
    st = run_study(Quantity("eigenvalue", p, mode=2), [Family("fe", (4, 8, 16), degree=2)])
    s = st.series[0]
    assert np.iscomplexobj(s.values) and s.values[-1].imag > 0
    assert s.errors[0] > s.errors[1] > 0
    d = st.to_dict()
    assert isinstance(d["reference"]["value"], list) and len(d["reference"]["value"]) == 2


def test_quantity_rejects_bad_input():
    with pytest.raises(ValueError, match="quantity must be one of"):
        Quantity("tip", Params())
    with pytest.raises(ValueError, match="v_cr needs a flow range"):
        Quantity("v_cr", Params())


def test_cli_json_contract_and_files(tmp_path):
    code, out, err = run_cli(
        [
            "convergence",
            "--quantity",
            "theta_tip",
            "--alpha",
            "pi/3",
            "--v",
            "2",
            "--fe",
            "P1,P2",
            "--elements",
            "2:16",
            "--modal",
            "2:8",
            "--basis",
            "sine,beam",
            "--json",
            "--out",
            str(tmp_path),
        ]
    )
    assert code == 0, err
    d = json.loads(out)
    assert d["quantity"] == "theta_tip"
    assert set(d["reference"]) >= {"value", "error_estimate", "method"}
    assert [s["family"] for s in d["series"]] == ["fe-P1", "fe-P2", "modal-sine", "modal-beam"]
    for s in d["series"]:
        assert set(s) >= {
            "family",
            "n",
            "dofs",
            "values",
            "errors",
            "observed_order",
            "expected_order",
        }
    assert d["series"][1]["dofs"] == [4, 8, 16, 32]
    assert d["series"][0]["expected_order"] == 2.0
    # The collocation solution is among the independent values and agrees.
    bvp = [x for x in d["reference"]["independent"] if x["method"].startswith("solve_bvp")]
    assert bvp and bvp[0]["difference"] < 1e-6
    assert d["params"]["alpha"] == pytest.approx(np.pi / 3)
    for name in ("convergence.json", "convergence.csv", "convergence.png"):
        assert (tmp_path / name).is_file()
    from fempipe.io import read_csv

    rows = read_csv(tmp_path / "convergence.csv")
    assert list(rows["family"][:1]) == ["fe-P1"]
    assert rows["theta_tip"][0] == pytest.approx(d["series"][0]["values"][0])


@pytest.mark.parametrize(
    "argv, option",
    [
        (["--quantity", "v_cr", "--v", "3"], "--v"),
        (["--quantity", "theta_tip", "--v", "0,3"], "--v"),
        (["--quantity", "theta_tip"], "--v"),
        (["--quantity", "theta_tip", "--v", "1", "--elements", "8:4"], "--elements"),
        (["--quantity", "theta_tip", "--v", "1", "--elements", "4,4"], "--elements"),
        (["--quantity", "theta_tip", "--v", "1", "--fe", "P0"], "--fe"),
        (["--quantity", "theta_tip", "--v", "1", "--fe", "P2,P2"], "--fe"),
        (["--quantity", "theta_tip", "--v", "1", "--fe", "P2", "--basis", "beam"], "--basis"),
        (["--quantity", "theta_tip", "--v", "1", "--modal", "2:8", "--basis", "cos"], "--basis"),
        (
            ["--quantity", "theta_tip", "--v", "1", "--fe", "P3", "--elements", "2:512"],
            "--elements",
        ),
        (["--quantity", "omega", "--v", "1"], "--quantity"),
        (["--quantity", "eigenvalue", "--v", "1", "--mode", "0"], "--mode"),
    ],
)
def test_cli_bad_input_exits_2_naming_the_option(argv, option, tmp_path):
    out_dir = tmp_path / "out"
    code, out, err = run_cli(["convergence", *argv, "--out", str(out_dir)])
    assert code == 2
    assert out == ""
    lines = err.strip().splitlines()
    assert len(lines) == 1 and option in lines[0], err
    assert not out_dir.exists() or not any(out_dir.iterdir())


def test_bench_convergence_vcr_quick_measures_the_orders():
    """The benchmark's study (quick: up to 8 elements) forms a reference that P3:32 confirms."""
    code, out, err = run_cli(["bench", "--quick", "--only", "convergence_vcr", "--json"])
    assert code == 0, err
    d = json.loads(out)["benchmarks"]["convergence_vcr"]
    rows = {r["family"]: r for r in d["table"]}
    assert set(rows) == {"fe-P1", "fe-P2", "fe-P3", "modal-sine", "modal-beam"}
    assert rows["fe-P3"]["finest_error"] < rows["fe-P2"]["finest_error"]
    assert d["cpu_seconds"] > 0
    # v_cr of the paper's horizontal pipe: the Richardson reference of P3:4, P3:8
    # against P3:16 computed directly (1e-9 bounds P3:16's own error, 2.5e-10).
    from fempipe.analyses.stability import find_critical_velocity
    from fempipe.model.discretization import FiniteElement
    from fempipe.model.plane.operators import PipeModel

    fine = find_critical_velocity(
        PipeModel(FiniteElement(16, 3), Params(alpha=np.pi / 2, beta=0.142, gamma=18.9, mu=5e-3)),
        10.0,
    ).v_cr
    assert abs(d["v_cr_reference"] - fine) <= d["reference_error_estimate"] + 1e-9


def test_cli_study_of_a_variant_pipe(capsys):
    """v_cr of the hanging pipe with an end mass and a spring at a node: P2 still as h^4."""
    code, out, err = run_cli(
        ["convergence", "--quantity", "v_cr", "--v", "0,12", "--end-mass", "0.2"]
        + ["--spring", "20@0.5", "--fe", "P2", "--elements", "2:32", "--json"]
    )
    assert code == 0, err
    d = json.loads(out)
    assert d["params"]["end_mass"] == 0.2 and d["params"]["springs"] == [[20.0, 0.5]]
    (s,) = d["series"]
    assert s["expected_order"] == 4.0
    assert s["observed_order"] == pytest.approx(4.0, abs=0.3)


def test_cli_refuses_hysteretic_damping_for_a_limit_cycle():
    code, out, err = run_cli(
        ["convergence", "--quantity", "lc_period", "--v", "10", "--hysteretic-damping", "0.01"]
    )
    assert code == 2 and "--hysteretic-damping" in err and "time-domain" in err


@pytest.mark.parametrize(
    "observed, expected, verdict",
    [(5.95, 6.0, "asymptotic"), (5.28, 6.0, "pre-asymptotic"), (5.34, 4.0, "super-convergent"),
     (3.0, None, None), (float("nan"), 6.0, None)],
)  # fmt: skip
def test_order_verdict_flags_orders_outside_the_theory_band(observed, expected, verdict):
    """The observed orders the text once printed without a word (v_cr on P3: 5.28 against 6;
    beam modes: 5.34 against 4) are flagged, with the band +-ORDER_BAND about the theory."""
    import numpy as np

    from fempipe.studies.convergence.study import ORDER_BAND, Series

    assert ORDER_BAND == 0.5
    s = Series("fe-P3", np.array([2, 4]), np.array([6, 12]), np.ones(2), np.ones(2),
               observed, (0, 1), expected)  # fmt: skip
    assert s.order_verdict == verdict
    assert s.to_dict()["order_verdict"] == verdict

"""The CSV files of the CLI: a unit in every header cell, values equal to the JSON.

Every CSV a subcommand writes with ``--out`` (static.csv, spectrum.csv,
events.csv, stability_map.csv, tip.csv) is read back with
:func:`fempipe.io.read_csv` and compared, column by column, with the JSON of
the same run (tip.csv, whose series is not in the JSON, with the trajectory's
VTU frames).  Small cases (three sine modes, few v) keep this to seconds.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest

from fempipe.cli import main
from fempipe.io import read_csv

TD_ARGS = ["--length", "0.094", "--EI", "1.8e-5", "--m", "0.0159", "--M", "0.0058", "--g", "9.8"]
CELL = re.compile(r"([A-Za-z_][A-Za-z0-9_]*) \[([^\[\]]+)\]")
#: The units of the convention (fempipe.io module docstring).
UNITS = {"1", "-", "L", "T", "rad", "1/T", "L/T", "rad/T", "m", "mm", "m/s"}


def _run(tmp_path, capsys, argv, csv_name):
    out = tmp_path / "out"
    assert main([*argv, "--quiet", "--out", str(out)]) == 0
    capsys.readouterr()
    header = (out / csv_name).read_text().splitlines()[0].split(",")
    return out, header


def _units(header):
    """name -> unit of every header cell; each cell must be ``name [unit]``."""
    units = {}
    for cell in header:
        m = CELL.fullmatch(cell)
        assert m is not None, f"header cell {cell!r} has no unit"
        assert m[2] in UNITS, cell
        units[m[1]] = m[2]
    return units


def _same(csv_value, json_value):
    if json_value is None:  # an empty cell: NaN in a numeric column
        return csv_value == "" or (isinstance(csv_value, float) and math.isnan(csv_value))
    return csv_value == json_value and type(json_value)(csv_value) == json_value


def _assert_rows(cols, rows):
    """Every CSV column equals the JSON rows' value of the same key, exactly."""
    assert {len(c) for c in cols.values()} == {len(rows)}
    for name, col in cols.items():
        for i, row in enumerate(rows):
            assert _same(col[i].item(), row[name]), (name, i, col[i], row[name])


def test_static_csv_si_pipe(tmp_path, capsys):
    argv = ["static", "--modal", "3", *TD_ARGS, "--alpha", "90deg", "--U", "0,1,2"]
    out, header = _run(tmp_path, capsys, argv, "static.csv")
    units = _units(header)
    assert units["theta_tip"] == "rad" and units["X_tip"] == "L" and units["U"] == "m/s"
    cols = read_csv(out / "static.csv")
    assert list(cols) == list(units)
    points = json.loads((out / "static.json").read_text())["points"]
    _assert_rows(cols, points)
    # The SI columns are the [L] columns times L = 0.094 m (1e3 L for mm): the
    # units in the header say so.
    for name, unit in units.items():
        if unit in ("m", "mm"):
            base = name.rsplit("_", 1)[0]
            assert units[base] == "L"
            scale = 0.094 * (1e3 if unit == "mm" else 1.0)
            np.testing.assert_allclose(cols[name], scale * cols[base], rtol=1e-14, atol=1e-15)


def test_static_csv_alpha_continuation(tmp_path, capsys):
    argv = ["static", "--modal", "3", "--continuation", "alpha", "--values", "0,1", "--v", "1"]
    out, header = _run(tmp_path, capsys, argv, "static.csv")
    assert _units(header)["alpha"] == "rad"
    points = json.loads((out / "static.json").read_text())["points"]
    _assert_rows(read_csv(out / "static.csv"), points)


def test_spectrum_csv(tmp_path, capsys):
    argv = ["spectrum", "--modal", "3", "--alpha", "pi", "--v", "0,3"]
    out, header = _run(tmp_path, capsys, argv, "spectrum.csv")
    units = _units(header)
    assert units["lambda_re"] == units["Omega_im"] == "1/T"
    rows = []
    for pt in json.loads((out / "spectrum.json").read_text())["points"]:
        seen: dict = {}
        for i, e in enumerate(pt["eigenvalues"]):
            seen[e["mode"]] = seen.get(e["mode"], 0) + 1
            rows.append(
                {
                    "v": pt["v"],
                    "mode": e["mode"],
                    "lambda_re": e["re"],
                    "lambda_im": e["im"],
                    "Omega_re": e["Omega_re"],
                    "Omega_im": e["Omega_im"],
                    "stable": pt["stable"],
                    "system_stable": pt["stable"],
                    "eigenvalue_index": i,
                    "pair_member": seen[e["mode"]],
                }
            )
    cols = read_csv(out / "spectrum.csv")
    assert set(cols) == set(rows[0])
    _assert_rows(cols, rows)


def test_events_csv(tmp_path, capsys):
    argv = ["critical", "--modal", "3", "--alpha", "pi", "--v", "0,6"]
    out, header = _run(tmp_path, capsys, argv, "events.csv")
    units = _units(header)
    assert units["v"] == "1" and units["frequency"] == "1/T" and units["type"] == "-"
    d = json.loads((out / "critical.json").read_text())
    cols = read_csv(out / "events.csv")
    events = sorted(d["events"], key=lambda e: e["v"])
    _assert_rows({k: cols[k] for k in events[0]}, events)
    # The extra columns: the critical event's eigenvalue and at_start.
    i = next(
        i
        for i, e in enumerate(events)
        if (e["v"], e["type"], e["branch"])
        == (d["critical"]["v"], d["critical"]["type"], d["critical"]["branch"])
    )
    assert cols["eigenvalue_re"][i] == d["critical"]["eigenvalue"][0]
    assert cols["eigenvalue_im"][i] == d["critical"]["eigenvalue"][1]
    assert cols["at_start"][i] == d["critical"]["at_start"]


def test_stability_map_csv_si_pipe(tmp_path, capsys):
    argv = ["stability-map", "--modal", "3", "--alphas", "0,pi", *TD_ARGS]
    out, header = _run(tmp_path, capsys, argv, "stability_map.csv")
    units = _units(header)
    assert units["alpha"] == "rad" and units["v_cr"] == "1" and units["U_cr"] == "m/s"
    cols = read_csv(out / "stability_map.csv")
    _assert_rows(cols, json.loads((out / "stability_map.json").read_text())["points"])


def test_tip_csv(tmp_path, capsys):
    """tip.csv against the trajectory's VTU frames (one per accepted step here) and the
    step count of the JSON: the frames' tip point is the same state at the same tau."""
    from fempipe.io.trajectory import read_trajectory

    argv = ["simulate", "--modal", "3", "--v", "3", "--alpha", "pi/2", "--t-max", "1"]
    out, header = _run(tmp_path, capsys, [*argv, "--no-shooting"], "tip.csv")
    units = _units(header)
    assert units["tau"] == "T" and units["X_tip"] == "L" and units["X_tip_rate"] == "L/T"
    tip = read_csv(out / "tip.csv")
    d = json.loads((out / "simulate.json").read_text())
    assert tip["tau"].size == d["steps"] + 1
    times, meshes = read_trajectory(out / "trajectory.pvd")
    assert times.size == tip["tau"].size
    np.testing.assert_array_equal(tip["tau"], times)
    for col, field in (("theta_tip", "theta"), ("X_tip", "X_g"), ("Z_tip", "Z_g")):
        frames = np.array([m.point_data[field][-1] for m in meshes])
        np.testing.assert_allclose(tip[col], frames, rtol=0, atol=1e-12, err_msg=col)
    rate = np.array([m.point_data["theta_dot"][-1] for m in meshes])
    np.testing.assert_allclose(tip["theta_tip_rate"], rate, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["no_unit", "v [1],v [1]"])
def test_read_csv_refuses_a_header_without_units(tmp_path, name):
    path = tmp_path / "x.csv"
    path.write_text(f"{name}\n")
    with pytest.raises(ValueError, match="unit|twice"):
        read_csv(path)

"""Atomic writers and the meshio shape file (fempipe.io)."""

from __future__ import annotations

import json

import numpy as np
import pytest

from fempipe import FiniteElement, Params, PipeModel, solve_static
from fempipe.io import (
    CSV_UNITS,
    SHAPE_FIELDS,
    atomic_path,
    json_dumps,
    read_csv,
    read_shapes,
    write_csv,
    write_json,
    write_shapes,
)
from fempipe.model.kinematics import compute_shape


def test_json_is_numpy_safe_and_strict(tmp_path):
    obj = {
        "a": np.float64(1.5),
        "b": np.arange(3),
        "c": np.int64(2),
        "d": float("nan"),
        "e": (1, 2),
    }
    path = write_json(tmp_path / "x.json", obj)
    back = json.loads(path.read_text())
    assert back == {"a": 1.5, "b": [0, 1, 2], "c": 2, "d": None, "e": [1, 2]}
    # Strict JSON: NaN must not leak as a bare literal.
    assert "NaN" not in json_dumps({"x": float("nan")})


def test_csv_round_trips_full_precision(tmp_path):
    x = 1.0 / 3.0
    path = write_csv(tmp_path / "x.csv", [{"v": 0.0, "theta_tip": x}, {"v": 1.0}])
    lines = path.read_text().splitlines()
    assert lines[0] == "v [1],theta_tip [rad]"
    assert float(lines[1].split(",")[1]) == x  # repr keeps all digits
    assert lines[2] == "1.0,"
    cols = read_csv(path)
    assert list(cols) == ["v", "theta_tip"]
    assert cols["v"].tolist() == [0.0, 1.0]
    assert cols["theta_tip"][0] == x and np.isnan(cols["theta_tip"][1])


def test_csv_column_types_read_back(tmp_path):
    rows = [
        {"mode": 1, "stable": True, "type": "flutter", "U": 0.5},
        {"mode": 2, "stable": False, "type": "fold", "U": None},
    ]
    cols = read_csv(write_csv(tmp_path / "x.csv", rows))
    assert cols["mode"].dtype == int and cols["mode"].tolist() == [1, 2]
    assert cols["stable"].dtype == bool and cols["stable"].tolist() == [True, False]
    assert cols["type"].tolist() == ["flutter", "fold"]
    assert cols["U"][0] == 0.5 and np.isnan(cols["U"][1])


def test_every_csv_unit_is_documented():
    """Each unit of the table is explained in the io module docstring and the docs
    (docs/cli/options.md, "Files and units")."""
    from pathlib import Path

    import fempipe.io

    root = Path(__file__).resolve().parents[1]
    docs = (root / "docs" / "cli" / "options.md").read_text(encoding="utf-8")
    for unit in set(CSV_UNITS.values()):
        assert f"``[{unit}]``" in fempipe.io.__doc__, unit
        assert f"`[{unit}]`" in docs, unit


def test_csv_column_without_a_unit_is_an_error(tmp_path):
    with pytest.raises(ValueError, match="no unit.*CSV_UNITS"):
        write_csv(tmp_path / "x.csv", [{"v": 1.0, "speed": 2.0}])
    assert not (tmp_path / "x.csv").exists()


def test_atomic_path_leaves_old_file_on_failure(tmp_path):
    target = tmp_path / "keep.txt"
    target.write_text("old")
    with pytest.raises(RuntimeError), atomic_path(target) as tmp:
        tmp.write_text("half")
        raise RuntimeError("crash while writing")
    assert target.read_text() == "old"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["keep.txt"]  # no temp left


@pytest.fixture(scope="module")
def two_shapes():
    disc = FiniteElement(8, 2)
    out = []
    for v in (0.0, 3.0):
        p = Params(alpha=np.pi / 2, v=v)
        sol = solve_static(PipeModel(disc, p))
        out.append(compute_shape(disc, sol.q, p.alpha))
    return out


@pytest.mark.parametrize("length", [None, 0.094])
def test_shapes_vtu_reads_back_with_meshio(tmp_path, two_shapes, length):
    import meshio

    path = write_shapes(tmp_path / "shapes.vtu", two_shapes, [0.0, 3.0], length=length)
    mesh = meshio.read(path)
    assert [c.type for c in mesh.cells] == ["line"]
    m = two_shapes[0].xi.size
    assert mesh.points.shape == (2 * m, 3)
    assert mesh.cells[0].data.shape == (2 * (m - 1), 2)
    back = read_shapes(path)
    assert len(back) == 2
    scale = 1.0 if length is None else length
    for s, d, v in zip(two_shapes, back, (0.0, 3.0), strict=True):
        for f in SHAPE_FIELDS:
            np.testing.assert_array_equal(d[f], getattr(s, f))
        np.testing.assert_array_equal(d["v"], v)
        # Points: the centerline with gravity along -y, (Z_g, -X_g, 0), Eq. (28).
        np.testing.assert_allclose(d["points"][:, 0], s.Z_g * scale, rtol=0, atol=1e-15)
        np.testing.assert_allclose(d["points"][:, 1], -s.X_g * scale, rtol=0, atol=1e-15)
        assert np.all(d["points"][:, 2] == 0)


def test_to_jsonable_converts_every_numpy_scalar_and_container():
    """The one sanitiser: numpy scalars of every kind, arrays, tuples, keys, NaN/inf, paths."""
    from pathlib import Path

    from fempipe.io import to_jsonable

    got = to_jsonable(
        {
            1: (np.int64(3), np.bool_(True)),
            "f": [np.float32(0.5), np.float64("nan"), -np.inf],
            "a": np.array([[1.5, np.inf]]),
            "s": np.str_("x"),
            "p": Path("out/x.json"),
        }
    )
    assert got == {
        "1": [3, True],
        "f": [0.5, None, None],
        "a": [[1.5, None]],
        "s": "x",
        "p": "out/x.json",
    }
    assert type(got["1"][0]) is int and type(got["1"][1]) is bool
    assert type(got["f"][0]) is float and type(got["s"]) is str

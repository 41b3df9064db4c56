"""shapes.vtu and trajectory.pvd read back by VTK's own XML reader, in one frame.

VTK (the library under ParaView) reads the files; VTK itself has no reader
for the .pvd collection (that one is ParaView's), so the collection's XML is
parsed here and each frame is read with ``vtkXMLUnstructuredGridReader``.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from fempipe.cli import main

vtk_xml = pytest.importorskip("vtkmodules.vtkIOXML")
from vtkmodules.util.numpy_support import vtk_to_numpy  # noqa: E402

ARRAYS = {"xi", "theta", "varsigma", "eta", "X_g", "Z_g"}
CASE = ["--alpha", "pi/2", "--gamma", "10", "--fe", "P2:6"]


def read_vtu(path):
    reader = vtk_xml.vtkXMLUnstructuredGridReader()
    reader.SetFileName(str(path))
    reader.Update()
    grid = reader.GetOutput()
    assert grid.GetNumberOfPoints() > 0, path
    pd, fd = grid.GetPointData(), grid.GetFieldData()
    point = {
        pd.GetArrayName(i): vtk_to_numpy(pd.GetArray(i)) for i in range(pd.GetNumberOfArrays())
    }
    field = {
        fd.GetArrayName(i): vtk_to_numpy(fd.GetArray(i)) for i in range(fd.GetNumberOfArrays())
    }
    return vtk_to_numpy(grid.GetPoints().GetData()), point, field


def test_static_shapes_and_trajectory_frames_share_one_frame(tmp_path, capsys):
    v = 3.0
    assert main(["static", *CASE, "--v", f"{v}", "--out", str(tmp_path / "s"), "--quiet"]) == 0
    argv = ["simulate", *CASE, "--v", f"{v}", "--amplitude", "0", "--t-max", "1"]
    assert main([*argv, "--no-shooting", "--out", str(tmp_path / "d"), "--quiet"]) == 0
    capsys.readouterr()

    pts_s, point_s, field_s = read_vtu(tmp_path / "s" / "shapes.vtu")
    root = ET.parse(tmp_path / "d" / "trajectory.pvd").getroot()
    first = next(root.iter("DataSet"))
    pts_d, point_d, field_d = read_vtu(tmp_path / "d" / first.get("file"))

    # The same point arrays (theta_dot only where there is a velocity) ...
    assert ARRAYS <= set(point_s) and ARRAYS | {"theta_dot"} <= set(point_d)
    # ... time, v and the parameters as field data ...
    assert field_s["time"][0] == 0.0 and field_s["v_values"][0] == v
    assert float(first.get("timestep")) == field_d["time"][0] == 0.0
    assert field_d["v"][0] == v
    for name, value in (("alpha", math.pi / 2), ("gamma", 10.0)):
        assert field_s[name][0] == pytest.approx(value, rel=1e-15)
        assert field_d[name][0] == pytest.approx(value, rel=1e-15)
    # ... and gravity along -y in both: points (Z_g, -X_g, 0).
    for pts, point in ((pts_s, point_s), (pts_d, point_d)):
        np.testing.assert_array_equal(pts[:, 0], point["Z_g"])
        np.testing.assert_array_equal(pts[:, 1], -point["X_g"])
        assert np.all(pts[:, 2] == 0)
    # The first frame of an unperturbed start is the static state at v: the
    # same tip.  The pipe at alpha = pi/2 sags under gravity, so the tip lies
    # below the clamp (y < 0) and short of the undeformed tip (x < 1).
    np.testing.assert_allclose(pts_d[-1], pts_s[-1], rtol=0, atol=1e-9)
    assert pts_s[-1, 1] < -0.05 and 0 < pts_s[-1, 0] < 1

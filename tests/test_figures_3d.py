"""The figures of the 3-D commands and of the convergence study, read from their Figure objects.

``fempipe simulate --3d`` (tip_orbit.png, snapshots_3d.png) on a synthetic motion about the
static state (no integration), ``fempipe critical`` (branches.png) on 4-element analyses, and
``fempipe convergence`` (convergence.png) on a synthetic study.  Each test checks what a
reader would object to: the motion lost in an empty frame, a colour without a key, events
hidden under others, no v_cr, radians in a title, the reference's own member drawn as a
measured error, text cut or overlapping, text under 9 pt.
"""

from __future__ import annotations

import functools
import math
import re

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from test_figures import small_texts, text_faults  # noqa: E402

from fempipe.model.discretization import discretization_from_name  # noqa: E402
from fempipe.model.params import Params  # noqa: E402
from fempipe.model.plane.operators import PipeModel  # noqa: E402

#: The inclination in radians, as "alpha = 1.571" or "$\alpha$ = 1.047" (not followed by °).
RADIANS = re.compile(r"(alpha|α)\$?\s*=\s*-?\d+(\.\d+)?(?![\d.°])")
CASE = {"alpha": math.radians(60), "beta": 0.3, "gamma": 10.0, "mu": 0.005}


def _titles(fig) -> list[str]:
    texts = [fig.get_suptitle()] + [ax.get_title() for ax in fig.axes]
    return [t for t in texts if t]


def _check_titles(fig) -> None:
    """Every title and caption gives the angle in degrees, as ``α = 60°``."""
    titles = _titles(fig)
    assert titles
    assert any("α = 60°" in t for t in titles), titles
    assert not any(RADIANS.search(t) for t in titles), titles


def _check_text(fig) -> None:
    """No text cut or overlapping, none under 9 pt.

    A 3-D axis label is text along the axis, whose box on the renderer is
    larger than its glyphs: it is checked against the canvas, not for
    overlaps.
    """
    rotated = [
        axis.label.get_text()
        for ax in fig.axes
        if hasattr(ax, "zaxis")
        for axis in (ax.xaxis, ax.yaxis, ax.zaxis)
    ]
    faults = [
        f
        for f in text_faults(fig)
        if not (f.startswith("overlap") and any(repr(lab) in f for lab in rotated))
    ]
    faults += [f"too small: {s}" for s in small_texts(fig)]
    assert not faults, "\n".join(faults)


@functools.cache
def _motion():
    """A swing in and out of the plane about the (unstable) static state at v = 8.2, one
    period per unit tau, with the Motion3D fields the figures read."""
    from fempipe.analyses.dynamics import make_initial_state
    from fempipe.analyses.statics import solve_static
    from fempipe.analyses.three_d.motion import Motion3D, out_of_plane_perturbation
    from fempipe.model.three_d.model import PipeModel3D, planar_state

    model = PipeModel(discretization_from_name("P2:4"), Params(v=8.2, **CASE))
    space = PipeModel3D(model.disc, model.params)
    q_s = solve_static(model).q
    q1, _ = make_initial_state(model, 1, 0.08, q_static=q_s)
    a, b = out_of_plane_perturbation(space, q_s, 1, 0.12)
    n = model.disc.n
    t = np.linspace(0.0, 10.0, 1001)
    U = np.tile(planar_state(q_s), (t.size, 1))
    U[:, :n] += np.sin(2 * np.pi * t)[:, None] * (q1 - q_s)
    U[:, n : 2 * n] += np.cos(2 * np.pi * t)[:, None] * a
    U[:, 2 * n :] += np.cos(2 * np.pi * t)[:, None] * b
    motion = Motion3D(
        kind="non-periodic", motion="nonplanar", period=None, period_n=None, whirl_rate=None,
        tip={}, planarity=1.0, frequencies=(1.0,), t=t, U=U,
    )  # fmt: skip
    return space, motion, (planar_state(q_s), False)


def test_tip_orbit_views_are_framed_on_the_motion():
    """tip_orbit.png: each view has equal scales, encloses the tip's path and is at least
    half filled by it in both directions (the clamp at the origin left it 18 % of the width);
    X_g points down the page; the unstable static state is open and grey."""
    from fempipe.plotting.static import UNSTABLE_COLOR
    from fempipe.plotting.three_d import plot_tip_orbit

    space, motion, static = _motion()
    fig = plot_tip_orbit(space, motion, static=static)
    try:
        assert len(fig.axes) == 3
        for ax in fig.axes:
            (path,) = [ln for ln in ax.get_lines() if ln.get_label().startswith("tip path")]
            (fixed,) = [ln for ln in ax.get_lines() if ln.get_label().startswith("static")]
            xy = np.vstack([path.get_xydata(), fixed.get_xydata()])
            assert ax.get_aspect() == 1.0
            for k, lim in enumerate((ax.get_xlim(), ax.get_ylim())):
                lo, hi = sorted(lim)
                assert lo < xy[:, k].min() and xy[:, k].max() < hi
                assert np.ptp(xy[:, k]) >= 0.5 * (hi - lo), (ax.get_title(), k)
            xlabel, ylabel = ax.get_xlabel(), ax.get_ylabel()
            assert all(re.search(r"\$[XYZ]_g\$", lab) for lab in (xlabel, ylabel))
            if "X_g" in ylabel:
                assert ax.yaxis_inverted()  # along gravity: down the page
            assert fixed.get_label() == "static state (unstable)"
            assert fixed.get_markerfacecolor() == "none"
            assert matplotlib.colors.same_color(fixed.get_color(), UNSTABLE_COLOR)
        legend = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
        assert "static state (unstable)" in legend and "tip path" in legend
        _check_titles(fig)
        _check_text(fig)
    finally:
        plt.close(fig)


def test_snapshots_are_framed_on_the_pipe_with_a_tau_colorbar():
    """snapshots_3d.png: the 3-D box fits the pipe (the fixed +-1 cube left it small), equal
    scales, X_g down, a colour bar labelled tau for the snapshots' colours."""
    from fempipe.plotting.three_d import plot_snapshots_3d

    space, motion, static = _motion()
    fig = plot_snapshots_3d(space, motion, static=static)
    try:
        ax = fig.axes[0]
        pts = np.vstack([np.column_stack(ln.get_data_3d()) for ln in ax.get_lines()])
        longest = np.ptp(pts, axis=0).max()
        limits = (ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d())
        for k, lim in enumerate(limits):
            lo, hi = sorted(lim)
            assert lo <= pts[:, k].min() and pts[:, k].max() <= hi
            assert hi - lo <= max(1.25 * np.ptp(pts[:, k]), 0.3 * longest), (k, lim)
        spans = [abs(hi - lo) for lo, hi in limits]
        assert np.allclose(np.array(ax.get_box_aspect()) / ax.get_box_aspect()[0],
                           np.array(spans) / spans[0], rtol=1e-6)  # fmt: skip
        assert ax.get_zlim3d()[0] > ax.get_zlim3d()[1]  # X_g down
        bars = [a for a in fig.axes[1:] if r"\tau" in a.get_ylabel()]
        assert len(bars) == 1
        snaps = [ln for ln in ax.get_lines() if not ln.get_label().startswith(("_", "tip"))]
        assert any(ln.get_label() == "static state (unstable)" for ln in snaps)
        assert all(ln.get_linestyle() == "--" for ln in snaps if "unstable" in ln.get_label())
        _check_titles(fig)
        _check_text(fig)
    finally:
        plt.close(fig)


@functools.cache
def _spatial(alpha: float, **kw):
    from fempipe.analyses.stability import analyse_stability

    params = Params(alpha=alpha, **kw)
    model = PipeModel(discretization_from_name("P3:4"), params)
    v_max = 6.0 if alpha > 3 else 10.0
    return analyse_stability(model, v_max=v_max, ds_max=0.3, planes=("in", "out"))


def _event_marks(ax) -> list:
    from fempipe.plotting.style import EVENT_MARKERS

    shapes = set(EVENT_MARKERS.values())
    return [ln for ln in ax.get_lines() if ln.get_marker() in shapes and len(ln.get_xdata()) == 1]


@pytest.mark.parametrize(
    "case", [{"alpha": math.pi}, {"alpha": math.radians(60), "beta": 0.3, "gamma": 10.0}]
)
def test_spatial_branches_show_every_event_and_v_cr(case):
    """branches.png of ``critical``: one mark per event of both planes, none hidden under
    another (marks at one place differ in size, the smaller on top), a vertical line at
    v_cr with its value in the legend; the two planes' close first losses (alpha = 60°)
    in an inset where the dash-dot piece between them shows."""
    from fempipe.plotting.planes import plot_branches_in_planes

    result = _spatial(**case)
    ax = plot_branches_in_planes(result)
    fig = ax.figure
    try:
        marks = _event_marks(ax)
        assert len(marks) == len(result.events)
        xmin, xmax = ax.get_xlim()
        for m in marks:
            assert xmin < m.get_xdata()[0] < xmax
        for a, b in ((a, b) for i, a in enumerate(marks) for b in marks[i + 1 :]):
            pa = ax.transData.transform(a.get_xydata()[0])
            pb = ax.transData.transform(b.get_xydata()[0])
            if np.hypot(*(pa - pb)) < max(a.get_markersize(), b.get_markersize()):
                top, under = (a, b) if a.get_zorder() > b.get_zorder() else (b, a)
                assert top.get_zorder() > under.get_zorder()
                assert top.get_markersize() < 0.6 * under.get_markersize()
        v_cr = result.v_cr
        lines = [ln for ln in ax.get_lines() if np.allclose(ln.get_xdata(), v_cr)]
        assert any(f"{v_cr:.5g}" in ln.get_label() for ln in lines)
        legend = [t.get_text() for leg in fig.legends for t in leg.get_texts()]
        assert any("v_{cr}" in t and f"{v_cr:.5g}" in t for t in legend), legend
        vi, vo = result.in_plane.v_cr, result.out_of_plane.v_cr
        if vi != vo:
            (inset,) = ax.child_axes
            lo, hi = inset.get_xlim()
            assert lo < min(vi, vo) < max(vi, vo) < hi
            assert len(_event_marks(inset)) >= 2
            dash_dot = [ln for ln in inset.get_lines() if ln.get_linestyle() == "-."]
            assert dash_dot and np.allclose(
                [dash_dot[0].get_xdata()[0], dash_dot[0].get_xdata()[-1]], sorted([vo, vi])
            )
        else:
            assert not ax.child_axes
        assert f"α = {math.degrees(case['alpha']):.4g}°" in ax.get_title()
        assert not RADIANS.search(ax.get_title())
        _check_text(fig)
    finally:
        plt.close(fig)


def test_convergence_reference_member_is_not_a_measured_error():
    """convergence.png: the finest member of the reference's family (its error is the
    Richardson correction itself) is not on its family's error line; it is an open marker
    at the reference's error estimate, named in the legend."""
    from fempipe.plotting.convergence import plot_convergence
    from fempipe.studies.convergence import ConvergenceStudy, Quantity, Reference, Series

    dofs = np.array([6, 12, 24, 48])
    errors = 1e-2 * (dofs / 6.0) ** -6.0
    errors[-1] = 2e-13  # the finest member against its own extrapolation
    p3 = Series("fe-P3", np.array([2, 4, 8, 16]), dofs, 5.8 + errors, errors, 6.0, (1, 2), 6.0)
    dofs2 = np.array([4, 8, 16, 32])
    errors2 = 1e-2 * (dofs2 / 4.0) ** -4.0
    p2 = Series("fe-P2", np.array([2, 4, 8, 16]), dofs2, 5.8 + errors2, errors2, 4.0, (1, 2), 4.0)
    study = ConvergenceStudy(
        Quantity("v_cr", Params(v=0.0, **CASE), v_max=10.0),
        Reference(5.8, 3e-8, "synthetic", "fe-P3"),
        (p2, p3),
        3e-7,
        0.0,
    )
    ax = plot_convergence(study)
    try:
        for ln in ax.get_lines():
            on_it = np.isclose(ln.get_xdata(), 48) & np.isclose(ln.get_ydata(), 2e-13)
            assert not on_it.any(), ln.get_label()
        (own,) = [ln for ln in ax.get_lines() if "defines the reference" in ln.get_label()]
        assert list(own.get_xdata()) == [48] and list(own.get_ydata()) == [3e-8]
        assert own.get_markerfacecolor() == "none"
        assert len(ax.get_lines()[0].get_xdata()) == 4  # fe-P2 keeps its finest member
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any("defines the reference" in t for t in legend)
        assert "°" in ax.get_title() and not RADIANS.search(ax.get_title())
        _check_text(ax.figure)
    finally:
        plt.close(ax.figure)

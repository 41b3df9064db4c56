"""Every figure the package draws: no text outside the canvas, no two texts overlapping.

Each figure of the command-line tools is drawn by its plotting function on
small, quick data (a 4-mode Galerkin model), and each validation figure from
the quick validation results (computed once per session, shared with
``tests/test_validation.py``).  A figure fails when a visible text artist
(title, axis label, tick label, legend entry, annotation) extends outside the
canvas or overlaps another one, measured on the renderer's window extents.
This is a layout test, not a pixel baseline: it reads where matplotlib put the
texts, so it fails on the faults a reader sees (cut labels, "N = 8N = 4").
"""

from __future__ import annotations

import functools
import itertools
import math
from dataclasses import replace

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
import pytest  # noqa: E402
from matplotlib.text import Annotation, Text  # noqa: E402
from mpl_toolkits.mplot3d.axis3d import Axis as Axis3D  # noqa: E402

from fempipe.model.discretization import Modal  # noqa: E402
from fempipe.model.params import PAPER_CASE, Params  # noqa: E402
from fempipe.model.plane.operators import PipeModel  # noqa: E402

#: Overlap below this many square pixels is anti-aliasing, not a collision.
_MIN_OVERLAP_PX2 = 2.0


def _axis_texts(axis) -> list[Text]:
    # Only the tick labels matplotlib draws (ticks inside the view); the
    # others keep stale positions.  A 3-D axis places its ticks as it draws.
    if isinstance(axis, Axis3D):
        lo, hi = sorted(axis.get_view_interval())
        ticks = [t for t in axis.get_major_ticks() if lo <= t.get_loc() <= hi]
    else:
        ticks = axis._update_ticks()
    out = []
    for t in ticks:
        out += [lab for lab in (t.label1, t.label2) if lab.get_visible()]
    return out + [axis.label, axis.get_offset_text()]


def drawn_texts(fig) -> list[Text]:
    """The visible, non-empty text artists of a figure that a draw puts on the canvas."""
    # Twice: equal-aspect axes change their limits after the layout engine
    # has run, so the second draw (as when saving) is the one a reader sees.
    fig.canvas.draw()
    fig.canvas.draw()
    renderer = fig.canvas.get_renderer()
    texts: list[Text] = list(fig.texts)
    if fig._suptitle is not None:
        texts.append(fig._suptitle)
    for leg in fig.legends:
        texts += [*leg.get_texts(), leg.get_title()]
    for ax in fig.axes:
        if not ax.get_visible():
            continue
        texts += [ax.title, ax._left_title, ax._right_title, *ax.texts]
        texts += _axis_texts(ax.xaxis) + _axis_texts(ax.yaxis)
        if hasattr(ax, "zaxis"):
            texts += _axis_texts(ax.zaxis)
        leg = ax.get_legend()
        if leg is not None and leg.get_visible():
            texts += [*leg.get_texts(), leg.get_title()]
    unique = list({id(t): t for t in texts}.values())  # the suptitle is also in fig.texts
    # An annotation whose point is outside its axes is not drawn (annotation_clip).
    return [
        t
        for t in unique
        if t.get_visible()
        and t.get_text().strip()
        and not (isinstance(t, Annotation) and not t._check_xy(renderer))
    ]


def text_faults(fig) -> list[str]:
    """Texts outside the canvas and pairs of overlapping texts, as readable lines."""
    texts = drawn_texts(fig)
    renderer = fig.canvas.get_renderer()
    width, height = fig.bbox.width, fig.bbox.height
    boxes = [(t, t.get_window_extent(renderer)) for t in texts]
    faults = []
    for t, b in boxes:
        if b.x0 < -0.5 or b.y0 < -0.5 or b.x1 > width + 0.5 or b.y1 > height + 0.5:
            faults.append(
                f"outside the canvas ({width:.0f} x {height:.0f} px): {t.get_text()!r} at "
                f"x {b.x0:.0f}..{b.x1:.0f}, y {b.y0:.0f}..{b.y1:.0f}"
            )
    for (s, a), (t, b) in itertools.combinations(boxes, 2):
        w = min(a.x1, b.x1) - max(a.x0, b.x0)
        h = min(a.y1, b.y1) - max(a.y0, b.y0)
        if w > 0 and h > 0 and w * h > _MIN_OVERLAP_PX2:
            faults.append(f"overlap: {s.get_text()!r} and {t.get_text()!r} ({w:.0f} x {h:.0f} px)")
    return faults


def small_texts(fig, minimum: float = 9.0) -> list[str]:
    """Texts set below ``minimum`` points."""
    return [
        f"{t.get_fontsize():.1f} pt: {t.get_text()!r}"
        for t in drawn_texts(fig)
        if t.get_fontsize() < minimum - 1e-9
    ]


# ---------------------------------------------------------------------------
# The checker itself can fail.


def test_checker_sees_overlap_and_clipping():
    fig, ax = plt.subplots(figsize=(3, 2))
    ax.text(0.5, 0.5, "N = 8", transform=ax.transAxes)
    ax.text(0.52, 0.5, "N = 4", transform=ax.transAxes)
    ax.set_ylabel("a label that the canvas cuts", fontsize=20)
    faults = text_faults(fig)
    plt.close(fig)
    assert any("overlap: 'N = 8' and 'N = 4'" in f for f in faults), faults
    assert any("outside the canvas" in f for f in faults), faults


def test_checker_passes_a_clean_figure():
    fig, ax = plt.subplots(figsize=(4, 3), layout="constrained")
    ax.plot([0, 1], [0, 1], label="a line")
    ax.set_xlabel("x")
    ax.set_ylabel("y")
    ax.legend()
    faults = text_faults(fig)
    plt.close(fig)
    assert not faults, faults


# ---------------------------------------------------------------------------
# The figures of the command-line tools, on quick data (4 sine modes).


@functools.cache
def _model(alpha: float, v: float = 0.0) -> PipeModel:
    p = Params(
        alpha=alpha, beta=PAPER_CASE["beta"], gamma=PAPER_CASE["gamma"], mu=PAPER_CASE["mu"], v=v
    )
    return PipeModel(Modal(4), p)


def _shapes_figure():
    from fempipe.analyses.stability import linearly_stable
    from fempipe.analyses.statics import solve_path
    from fempipe.model.kinematics import compute_shape
    from fempipe.plotting.static import plot_shapes

    model = _model(math.pi / 2)
    values = np.linspace(0.0, 10.0, 11)
    sols = solve_path(model, values, parameter="v")
    shapes = [compute_shape(model.disc, s.q, model.params.alpha) for s in sols]
    stable = [
        linearly_stable(model.with_params(replace(model.params, v=v)), s.q)
        for v, s in zip(values, sols, strict=True)
    ]
    assert not all(stable)  # the figure must show both kinds
    ax = plot_shapes(
        shapes,
        [f"v = {v:g}" for v in values],
        alpha=math.pi / 2,
        stable=stable,
        title="α = 90°, β = 0.142, γ = 18.9",
    )
    return ax.figure


def _argand_figure():
    from fempipe.analyses.stability import trace_root_locus
    from fempipe.plotting.stability import plot_argand

    locus = trace_root_locus(_model(math.pi), np.linspace(0.0, 6.0, 31), n_modes=3)
    return plot_argand(locus).figure


def _branches_figure():
    from fempipe.analyses.stability import analyse_stability
    from fempipe.plotting.stability import plot_branches

    res = analyse_stability(_model(math.pi), v_max=6.0, ds_max=0.3, max_depth=1)
    return plot_branches(res).figure


@functools.cache
def _trajectory():
    from fempipe.analyses.dynamics import make_initial_state, simulate
    from fempipe.analyses.statics import solve_sagged

    model = _model(0.0, v=10.0)
    q0, qd0 = make_initial_state(model, q_static=solve_sagged(model).q)
    traj = simulate(model, q0, qd0, 2.0, n_out=400)
    return model, traj


def _time_traces_figure():
    from fempipe.plotting.dynamics import plot_time_traces

    model, tr = _trajectory()
    title = "α = 0°, β = 0.142, γ = 18.9, v = 10"
    return plot_time_traces(model.disc, tr.t, tr.q, 0.0, title=title).figure


def _phase_portrait_figure():
    from fempipe.plotting.dynamics import plot_phase_portrait

    model, tr = _trajectory()
    ax = plot_phase_portrait(model.disc, tr.q, tr.qdot, 0.0)
    ax.set_title("α = 0°, β = 0.142, γ = 18.9, v = 10", fontsize="small")
    return ax.figure


def _oscillating_shapes_figure():
    from fempipe.plotting.dynamics import plot_oscillating_shapes

    model, tr = _trajectory()
    half = tr.t >= 0.5 * tr.t[-1]
    return plot_oscillating_shapes(
        model.disc, tr.q[half], 0.0, title="α = 0°, β = 0.142, γ = 18.9, v = 10"
    ).figure


def _animation_frame_figure():
    from fempipe.plotting.dynamics import animation_figure

    model, tr = _trajectory()
    fig, draw, n = animation_figure(
        model.disc, tr.t[-50:], tr.q[-50:], 0.0, title="α = 0°, β = 0.142, γ = 18.9, v = 10"
    )
    draw(n - 1)
    return fig


def _bifurcation_figure():
    from fempipe.plotting.dynamics import plot_bifurcation

    pts = [
        {"v": v, "direction": d, "attractor": "cycle", "eta_tip": [-a, a]}
        for d in ("up", "down")
        for v, a in zip(np.linspace(4, 9, 11), np.sqrt(np.linspace(0, 1, 11)), strict=True)
    ]
    return plot_bifurcation(pts, title="α = 0°, β = 0.142, γ = 18.9").figure


def _stability_map_figure():
    from fempipe.analyses.stability.maps import map_stability
    from fempipe.plotting.stability import plot_stability_map

    smap = map_stability(Modal(2), np.linspace(0, np.pi, 5), [(0.142, 18.9)], workers=1)
    ax = plot_stability_map(smap)
    # The title's key: open circles for the flutter velocity, open squares for
    # an earlier loss of stability (here alpha = pi: the straight pipe buckles).
    assert "○" in ax.get_title() and "□" in ax.get_title()
    marks = [ln for ln in ax.get_lines() if ln.get_marker() in ("o", "s")]
    assert {ln.get_marker() for ln in marks} == {"o", "s"}
    assert all(ln.get_markerfacecolor() == "none" for ln in marks)
    return ax.figure


CLI_FIGURES = {
    "shapes.png": _shapes_figure,
    "argand.png": _argand_figure,
    "branches.png": _branches_figure,
    "time_traces.png": _time_traces_figure,
    "phase_portrait.png": _phase_portrait_figure,
    "oscillating_shapes.png": _oscillating_shapes_figure,
    "pipe.gif frame": _animation_frame_figure,
    "bifurcation.png": _bifurcation_figure,
    "stability_map.png": _stability_map_figure,
}


@pytest.mark.parametrize("name", list(CLI_FIGURES))
def test_cli_figure_text_fits(name):
    fig = CLI_FIGURES[name]()
    try:
        faults = text_faults(fig)
    finally:
        plt.close(fig)
    assert not faults, "\n".join(faults)


def test_unstable_static_states_look_different():
    """shapes.png: the states flagged unstable are grey, dashed and named in the legend."""
    from fempipe.plotting.static import UNSTABLE_COLOR

    fig = _shapes_figure()
    ax = fig.axes[0]
    lines = [ln for ln in ax.get_lines() if ln.get_label().startswith("v = ")]
    try:
        unstable = [ln for ln in lines if "unstable" in ln.get_label()]
        assert unstable and len(unstable) < len(lines)
        for ln in unstable:
            assert ln.get_linestyle() == "--"
            assert matplotlib.colors.same_color(ln.get_color(), UNSTABLE_COLOR)
        for ln in set(lines) - set(unstable):
            assert ln.get_linestyle() == "-"
        legend = [t.get_text() for t in ax.get_legend().get_texts()]
        assert any("unstable" in t for t in legend), legend
    finally:
        plt.close(fig)


def test_a_hopf_point_below_the_requested_v_is_marked_where_its_branch_starts():
    """bifurcation diagrams: a Hopf point below the requested v (alpha = pi, where
    the straight pipe flutters at 4.15 and --v starts at 5) is marked at its
    equilibrium from the JSON, and its branch of orbits is drawn from there."""
    from fempipe.plotting.dynamics import plot_bifurcation

    def point(v, direction, lo, hi, **kw):
        return {"v": v, "direction": direction, "alpha": math.pi, "attractor": "periodic",
                "eta_tip": [lo, hi], "X_tip": [lo, hi], "Z_tip": [lo, hi], "period": 0.5,
                "stable": True, **kw}  # fmt: skip

    pts = [point(v, "static", 0.0, 0.0, requested=True, stable=False) for v in (5.0, 6.0)]
    pts += [point(v, "continuation", -a, a, branch="H1", requested=req)
            for v, a, req in ((4.2, 0.1, False), (5.0, 0.5, True), (6.0, 0.6, True))]  # fmt: skip
    hopf = {"v": 4.15, "branch": "H1", "eta_tip": [0.0, 0.0], "X_tip": [0.0, 0.0],
            "Z_tip": [0.0, 0.0]}  # fmt: skip
    fig, ax = plt.subplots()
    try:
        plot_bifurcation(pts, "eta_tip", ax=ax, hopf_points=[hopf])
        marks = [ln for ln in ax.get_lines() if ln.get_marker() == "D"]
        assert [list(ln.get_xdata()) for ln in marks] == [[4.15]]
        starts = [ln.get_xdata()[0] for ln in ax.get_lines() if len(ln.get_xdata()) > 1]
        assert 4.15 in starts  # the branch is joined to the Hopf point
    finally:
        plt.close(fig)


@pytest.mark.parametrize("method", ["continuation", "sweep"])
def test_bifurcation_command_figures_have_one_legend_below_the_panels(method, capsys):
    """eta_tip.png, X_tip.png, Z_tip.png of ``fempipe bifurcation``: one legend for
    all panels, under them (inside the axes it covered the diagram), each entry
    once, text >= 9 pt, nothing cut or overlapping."""
    from clirun import run_json

    from fempipe.plotting.dynamics import diagram_figure

    argv = [
        "bifurcation",
        "--modal",
        "2",
        "--alphas",
        "0,pi/2",
        "--v",
        "6,7.5",
        "--json",
        "--planar",
    ]
    result = run_json(capsys, [*argv, "--method", method, "--quiet"])
    for key in ("eta_tip", "X_tip", "Z_tip"):
        fig = diagram_figure(result, key)
        try:
            assert len(fig.axes) == 2 and all(ax.get_legend() is None for ax in fig.axes)
            (legend,) = fig.legends
            labels = [t.get_text() for t in legend.get_texts()]
            assert len(labels) == len(set(labels)) >= 2, labels
            assert not text_faults(fig), text_faults(fig)
            assert not small_texts(fig), small_texts(fig)
        finally:
            plt.close(fig)


def test_animation_loops_without_a_repeated_frame():
    """A closed orbit (last state = first) is animated without drawing its start twice."""
    from fempipe.plotting.dynamics import animation_figure

    model, tr = _trajectory()
    q = np.concatenate([tr.q[-20:], tr.q[-20:][:1]])  # closed: last = first
    t = np.concatenate([tr.t[-20:], [tr.t[-1] + (tr.t[1] - tr.t[0])]])
    fig, _, n = animation_figure(model.disc, t, q, 0.0)
    plt.close(fig)
    assert n == len(q) - 1


# ---------------------------------------------------------------------------
# The validation figures, from the quick results of tests/test_validation.py.


def _validation_cases():
    from test_validation import CHEAP

    from fempipe.validation import CASES

    # The quick Figs. 7 and 8-10 take about 10 s each: with the slow tests.
    slow = [pytest.param(n, marks=pytest.mark.slow) for n in CASES if n not in CHEAP]
    return [*CHEAP, *slow]


@pytest.mark.parametrize("name", _validation_cases())
def test_validation_figure_text_fits(name):
    """Every figure of a case (Figs. 8-10: three), text >= 9 pt, nothing cut or overlapping."""
    from test_validation import quick_result

    from fempipe.validation import load_case

    case = load_case(name)
    result = quick_result(name)
    figs = case.plots(result) if hasattr(case, "plots") else {name: case.plot(result)}
    faults = []
    try:
        for stem, fig in figs.items():
            faults += [f"{stem}: {f}" for f in text_faults(fig)]
            faults += [f"{stem}: too small: {s}" for s in small_texts(fig)]
    finally:
        for fig in figs.values():
            plt.close(fig)
    assert not faults, "\n".join(faults)


@pytest.mark.parametrize(
    "name",
    [
        "fig05",
        "fig11",
        "fig12",
        *(pytest.param(n, marks=pytest.mark.slow) for n in ("fig07", "fig08_10")),
    ],
)
def test_dynamic_figures_carry_the_parameters(name):
    """The figures of the paper's reference case say beta, gamma and mu on the
    figure itself (under the title), not only in the report's caption."""
    from test_validation import quick_result

    from fempipe.validation import load_case

    line = f"β = {PAPER_CASE['beta']:g}, γ = {PAPER_CASE['gamma']:g}, μ = {PAPER_CASE['mu']:g}"
    case = load_case(name)
    result = quick_result(name)
    figs = case.plots(result) if hasattr(case, "plots") else {name: case.plot(result)}
    try:
        titles = {stem: fig.get_suptitle() for stem, fig in figs.items()}
    finally:
        for fig in figs.values():
            plt.close(fig)
    assert line == "β = 0.142, γ = 18.9, μ = 0.005"
    for stem, title in titles.items():
        assert title.splitlines()[-1] == line, (stem, title)


def test_convergence_labels_of_close_truncations_do_not_overlap():
    """convergence.png: N = 3 and N = 4 lie one dof apart with nearly equal errors."""
    from fempipe.validation.convergence import Series, Study, draw_study

    dofs = np.array([8.0, 32.0, 128.0, 512.0, 2048.0])
    errors = 0.3 * dofs**-4.0
    modal_dofs = np.array([2.0, 3.0, 4.0, 6.0, 8.0, 16.0, 32.0])
    modal_errors = 0.06 * modal_dofs**-1.0
    series = {
        "FE P3": Series("FE P3", dofs, 1.0 + errors, errors, 4.0, (2, 3, 4), 6.0),
        "modal": Series("modal", modal_dofs, 1.0 + modal_errors, modal_errors, 1.0, (4, 5, 6)),
    }
    study = Study("v_cr, α = 0°", 1.0, 1e-12, series, {3: 1.0 + 0.021, 4: 1.0 + 0.019})
    fig, ax = plt.subplots(figsize=(4.5, 4.5), layout="constrained")
    draw_study(study, ax=ax)
    try:
        faults = text_faults(fig)
    finally:
        plt.close(fig)
    assert not faults, "\n".join(faults)

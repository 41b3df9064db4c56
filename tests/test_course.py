"""The course "FEM for slender structures, on this pipe": every lesson runs and shows what it says.

Each ``docs/course/lesson_*.py`` is run as sphinx-gallery runs it (a fresh ``__main__``
without ``__file__``, Agg backend, an empty temporary working directory that must stay
empty); its key numbers, read from the lesson's globals, are checked against values from
elsewhere: closed forms (an exact solution, Greenhill's and the Euler-Bernoulli cantilever's
characteristic equations, exact integrals of polynomials), the theoretical orders (k + 1,
2k, 5, N^-3), and independent solvers (scipy's ``solve_bvp``, the classical straight-pipe
theory).  Every exercise's solution, collapsed in the lesson's text, is run too: the numbers
its text states must be the ones its code computes, and ``fempipe.course.check`` must accept
its answer and reject a wrong one.  Run as a script, a lesson writes its figures.  The
lessons, their solutions and two script runs take about 40 CPU-s in the default test run
(lesson 8's Floquet multipliers 28 of them); the notebook tests need the docs extra and are
slow-marked (CI runs them after installing it).
"""

from __future__ import annotations

import contextlib
import functools
import io
import math
import os
import re
import tempfile
import textwrap
from pathlib import Path

import numpy as np
import pytest
from gallery_exec import run_as_script, run_like_sphinx_gallery
from scipy.optimize import brentq
from scipy.special import jv

ROOT = Path(__file__).resolve().parents[1]
LESSONS = sorted((ROOT / "docs" / "course").glob("lesson_*.py"))
EXAMPLES = sorted((ROOT / "examples").glob("plot_*.py"))
NUMBER = r"-?\d+(?:\.\d+)?(?:e-?\d+)?"


@functools.cache
def lesson_globals(stem: str) -> dict:
    """Run ``docs/course/<stem>*.py`` as sphinx-gallery does, in an empty cwd that must stay
    empty; its globals (one run per test process, shared by the lesson's tests)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    (path,) = [p for p in LESSONS if p.name.startswith(stem)]
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory() as tmp:
        os.chdir(tmp)
        try:
            g = run_like_sphinx_gallery(path)
            assert plt.get_fignums(), f"{path.name} drew no figure"
            assert os.listdir(tmp) == [], "a lesson wrote into the working directory"
        finally:
            plt.close("all")
            os.chdir(cwd)
    return g


def run_lesson(stem: str) -> dict:
    return dict(lesson_globals(stem))


def solutions(path: Path) -> list[dict]:
    """The collapsed solutions of a lesson's exercises: their text, code and exercise key."""
    last = path.read_text(encoding="utf-8").split("# %%")[-1]
    text = "\n".join(
        line[2:] if line.startswith("# ") else line.lstrip("#") for line in last.splitlines()
    )
    found = []
    for block in text.split("<details><summary>Solution</summary>")[1:]:
        block = block.split("</details>")[0]
        prose, code = block.split(".. code-block:: python\n", 1)
        code = textwrap.dedent(code.rsplit(".. raw:: html", 1)[0])
        (key,) = re.findall(r'check\("(\d\.\d)", answer\)', code)
        found.append({"text": " ".join(prose.split()), "code": code, "key": key})
    return found


def stated(text: str) -> dict[str, str]:
    """The numbers a solution states: ``name`` = value, in its "Expected:" sentence(s)."""
    expected = text.split("Expected:", 1)[1]
    return dict(re.findall(rf"``(\w+)`` = ({NUMBER})", expected))


def half_unit(number: str) -> float:
    """Half a unit in the last stated digit: 0.0885417 -> 5e-8, 3.0e-06 -> 5e-8."""
    mantissa, _, exponent = number.lower().partition("e")
    decimals = len(mantissa.split(".")[1]) if "." in mantissa else 0
    return 0.5 * 10.0 ** (int(exponent or 0) - decimals)


def test_the_lessons_are_lessons():
    """5 to 8 lessons, each a sphinx-gallery script that says what to see and ends with
    exercises, and each readable as a percent-format notebook."""
    assert 5 <= len(LESSONS) <= 8
    header = (ROOT / "docs" / "course" / "GALLERY_HEADER.rst").read_text()
    assert header.splitlines()[1].startswith("====")
    for path in LESSONS:
        text = path.read_text()
        assert "What you should see" in text, path.name
        assert "# Exercises" in text.split("# %%")[-1], path.name
    for path in LESSONS:
        found = solutions(path)
        assert len(found) >= 2, path.name
        exercises = re.findall(r"^# \d\. ", path.read_text().split("# %%")[-1], re.MULTILINE)
        assert len(found) == len(exercises), path.name  # every exercise has one
        lesson = path.name.split("_")[1].lstrip("0")
        assert [f["key"] for f in found] == [f"{lesson}.{k}" for k in range(1, len(found) + 1)]
    jupytext = pytest.importorskip("jupytext")
    for path in LESSONS:
        nb = jupytext.read(path, fmt="py:percent")
        assert sum(c.cell_type == "code" for c in nb.cells) >= 3, path.name


def test_lesson_01_weak_form():
    g = run_lesson("lesson_01")
    # Eq. (19) by hand for the SI pipe
    m, M, L, EI, grav = 0.0159, 0.0058, 0.094, 1.8e-5, 9.8
    assert g["params"].beta == pytest.approx(M / (m + M), rel=1e-12)
    assert g["params"].gamma == pytest.approx((m + M) * grav * L**3 / EI, rel=1e-12)
    # the sine-mode Galerkin tip against the closed form -gamma/6, and its order N^-3
    assert g["tip_errors"][-1] < 1e-6
    assert g["galerkin_order"] == pytest.approx(3.0, abs=0.15)
    # fempipe P2:16 against solve_bvp: the P2 discretization error, 3.6e-7
    assert abs(g["X_fe"] - g["X_bvp"]) < 1e-6


def test_lesson_02_lagrange_elements():
    g = run_lesson("lesson_02")
    # against the exact solution sin(3 pi xi / 2): L2 orders k + 1, derivative k
    for k, (p_l2, p_h1) in g["linear_orders"].items():
        assert p_l2 == pytest.approx(k + 1, abs=0.1)
        assert p_h1 == pytest.approx(k, abs=0.1)
    # the lesson's forty lines and fempipe are two implementations of one discrete problem
    assert g["ours"] == pytest.approx(g["theirs"], abs=1e-12)
    # and solve_bvp on the strong form differs by P2:16's discretization error, 3.6e-7
    assert 1e-8 < abs(g["ours"] - g["X_bvp"]) < 1e-6
    # the natural condition theta'(1) = 0 is reached as h^k for P2
    assert g["slope_order"] == pytest.approx(2.0, abs=0.2)


def test_lesson_03_nested_integrals():
    g = run_lesson("lesson_03")
    assert g["exact_deg2"] < 1e-14  # C x^2 = x^3/3 exactly with 3 Gauss points
    assert g["inexact_deg4"] > 1e-6  # but not x^4 (degree above n_g - 1)
    d = g["defects"]
    assert d["Gauss-Legendre"] < 1e-14
    assert min(d["Gauss-Lobatto"], d["equispaced interior"]) > 1e-4
    assert g["asymmetry"] < 1e-14 and g["eigs"][0] > 0
    # the kernel form's brute-force quadrature converges to the Gram form as h^2
    assert g["kernel_ratio"] == pytest.approx(4.0, abs=0.3)


def test_lesson_04_newton_continuation():
    g = run_lesson("lesson_04")
    c = g["newton_constants"]
    # quadratic convergence: e_(k+1) / e_k^2 settles to a constant
    assert c[-1] == pytest.approx(c[-2], rel=0.25)
    assert g["errors"][-1] < 1e-13
    greenhill = brentq(lambda s: jv(-1.0 / 3.0, 2.0 / 3.0 * math.sqrt(s)), 5.0, 10.0, xtol=1e-14)
    assert g["pitchfork"].value == pytest.approx(greenhill, abs=1e-6)  # P3:8
    assert g["greenhill"] == pytest.approx(greenhill, abs=1e-12)  # the lesson shows it
    assert g["fold_singularity"] < 1e-8  # dR/dq is singular at the fold
    # natural continuation cannot follow the branch round the fold: Newton fails on the
    # first step past it (having solved every step before it), or lands on another branch
    if g["natural_failed"]:
        assert g["reached"] < g["fold"].value < g["reached"] + 0.1
    else:
        assert abs(g["jumped"] - g["fold_tip"]) > 0.5


def test_lesson_05_eigenproblems_flutter():
    g = run_lesson("lesson_05")
    x = brentq(lambda x: 1.0 + math.cos(x) * math.cosh(x), 1.0, 3.0, xtol=1e-15)
    assert x == pytest.approx(1.8751040687, abs=1e-10)  # the textbook beta_1 L
    assert g["omega_errors"][-1] == pytest.approx(abs(3.5160157284 - x**2), rel=1e-3)
    assert g["omega_errors"][-1] < 1e-6
    assert g["eigen_order"] == pytest.approx(4.0, abs=0.2)  # 2k for P2
    from fempipe.validation.classical import StraightPipe, critical_velocity

    ref = critical_velocity(
        StraightPipe(beta=0.2, gamma=0.0, mu=1e-3), v_max=8.0, method="legendre"
    ).v_cr
    assert g["v_bisect"] == pytest.approx(ref, abs=1e-5)
    assert g["v_classical"] == pytest.approx(ref, abs=1e-12)  # the lesson shows it
    assert g["v_bisect"] == pytest.approx(g["v_fempipe"], abs=1e-7)


def test_lesson_06_time_integration():
    g = run_lesson("lesson_06")
    assert g["stiffness_growth"] == pytest.approx(4.0, abs=0.2)  # mu omega^2 ~ h^-4
    assert g["radau_orders"][-1] == pytest.approx(5.0, abs=0.3)  # 2s - 1, s = 3
    # energy is conserved by the equations; the integrator's error follows the tolerance
    assert g["drifts"][1e-6] < 1e-7
    assert g["drifts"][1e-4] > 30 * g["drifts"][1e-6]


def test_lesson_07_modal_vs_fe():
    g = run_lesson("lesson_07")
    hand = g["hand_orders"]
    assert [hand["P1"], hand["P2"], hand["P3"]] == pytest.approx([2, 4, 6], abs=0.2)
    assert hand["sine modes N (the paper's)"] == pytest.approx(3.0, abs=0.2)
    assert g["api_orders"]["modal-beam"] == pytest.approx(4.0, abs=0.3)
    # the study's reference, formed without the answer, against solve_bvp
    assert np.isclose(g["study"].reference.value, g["reference"], rtol=0, atol=1e-9)


def test_lesson_08_floquet():
    g = run_lesson("lesson_08")
    # Mathieu: Liouville's det Phi = exp(-c T); the tongue opens near eps = c (averaging)
    assert g["liouville"] < 1e-9
    assert g["eps_threshold"] == pytest.approx(g["c"], abs=0.01)
    # the pipe at sigma = 0: exp(lambda T) to Radau's error; the region is mode 2's
    # principal one near 2 omega_2, its multiplier -1 at the edges and the threshold
    assert g["rest_error"] < 1e-8
    region = g["region"]
    assert region.candidate.mode == (2,) and region.candidate.kind == "principal"
    assert region.omega_threshold == pytest.approx(2 * g["omega_2"], rel=0.01)
    assert region.multiplier == pytest.approx(-1.0, abs=1e-6)
    assert [r.real for r in g["edge_rho"]] == pytest.approx([-1.0, -1.0], abs=1e-6)
    # the edges of the sweep are the chart's at sigma = 0.2 (docs/theory/parametric.md's
    # P3:16 threshold 0.0883031 is 1.3e-6 below P3:6's)
    (row,) = [r for r in region.boundary if r[0] == 0.2]
    assert g["edges"] == pytest.approx(row[1:], abs=1e-6)
    assert region.sigma_threshold == pytest.approx(0.0883031386, abs=3e-6)
    # Hill's method converges to the monodromy's multiplier, exponentially in the harmonics
    errors = g["hill_errors"]
    assert errors[8] < 1e-10 and errors[1] > 1e-3
    assert errors[4] < 1e-3 * errors[2]
    # Eq. (20) with the pulsating flow grows by the largest multiplier per period inside
    assert g["sim_ratio"] == pytest.approx(g["rho_in"].real, abs=1e-4)
    assert g["decay"] < 0.02


@pytest.mark.parametrize("path", LESSONS, ids=lambda p: p.stem[:9])
def test_every_solution_computes_what_it_states(path, capsys):
    """Each exercise's solution runs in its lesson; the numbers its text states are the ones
    its code computes (to the last stated digit), and ``check`` accepts its answer, which it
    compares with a reference computed otherwise, and rejects a wrong one."""
    from fempipe.course import check, reference

    g = lesson_globals(path.name[:9])
    for solution in solutions(path):
        ns = dict(g)
        exec(compile(solution["code"], f"{path.name}: solution {solution['key']}", "exec"), ns)
        out = capsys.readouterr().out
        assert f"exercise {solution['key']}: correct" in out, out
        numbers = stated(solution["text"])
        assert "answer" in numbers, solution["key"]
        for name, number in numbers.items():
            value = float(np.real(ns[name]))
            assert abs(value - float(number)) <= half_unit(number) * (1 + 1e-9), (
                f"exercise {solution['key']}: {name} = {value!r}, the text says {number}"
            )
        _, tol, _ = reference(solution["key"])
        with contextlib.redirect_stdout(io.StringIO()):
            assert check(solution["key"], ns["answer"])
            assert not check(solution["key"], float(ns["answer"]) + (3 * tol if tol else 1.0))


def test_check_knows_every_exercise_and_no_other():
    from fempipe.course import check, exercises

    keys = [s["key"] for path in LESSONS for s in solutions(path)]
    assert exercises() == keys
    with pytest.raises(ValueError, match="no exercise"):
        check("9.9", 0.0)


def test_no_stale_links_and_no_placeholders():
    """The variants live in docs/theory/variants.md, not in a README section; every
    :doc: target of a lesson or an example exists; no '...' stands for a missing value."""
    for path in [*LESSONS, *EXAMPLES]:
        text = path.read_text(encoding="utf-8")
        assert not re.search(r"README[,'’]", text), path.name
        for target in re.findall(r":doc:`[^`<]*<(/[^>]+)>`", text):
            assert (ROOT / "docs" / f"{target[1:]}.md").is_file(), (path.name, target)
        assert "..." not in text.replace(".. ", ""), path.name
        assert not re.search(r"\b(TODO|XXX|FIXME)\b", text), path.name


def test_show_or_save(tmp_path, monkeypatch, capsys):
    """No script: nothing (sphinx-gallery, a notebook); an interactive backend: plt.show();
    Agg: one PNG per figure, into FEMPIPE_FIGURES when it is set."""
    import matplotlib
    import matplotlib.pyplot as plt

    from fempipe.plotting.scripts import show_or_save

    monkeypatch.chdir(tmp_path)
    monkeypatch.delenv("FEMPIPE_FIGURES", raising=False)
    shown = []
    monkeypatch.setattr(plt, "show", lambda: shown.append(True))
    try:
        plt.figure()
        plt.figure()
        exec("show_or_save()", {"show_or_save": show_or_save})  # a caller without __file__
        assert os.listdir(tmp_path) == [] and not shown
        monkeypatch.setattr(matplotlib, "get_backend", lambda: "tkagg")
        show_or_save("lesson_x.py")
        assert shown == [True] and os.listdir(tmp_path) == []
        monkeypatch.undo()
        monkeypatch.chdir(tmp_path)
        monkeypatch.setenv("FEMPIPE_FIGURES", str(tmp_path / "figs"))
        show_or_save("docs/lesson_x.py")
        assert sorted(os.listdir(tmp_path / "figs")) == ["lesson_x_1.png", "lesson_x_2.png"]
        assert "wrote 2 figures" in capsys.readouterr().out
    finally:
        plt.close("all")


@pytest.mark.parametrize(
    "path, env",
    [(LESSONS[1], {}), (ROOT / "examples" / "plot_si_pipe_static.py", {"FEMPIPE_FIGURES": "out"})],
    ids=["lesson_02", "plot_si_pipe_static"],
)
def test_run_as_a_script_it_writes_its_figures(path, env, tmp_path):
    """``python lesson.py`` without a display writes PNG files (run the sphinx-gallery way,
    the same script writes nothing: the lesson and gallery tests keep their cwd empty)."""
    proc = run_as_script(path, tmp_path, **env)
    assert proc.returncode == 0, proc.stderr
    folder = tmp_path / env.get("FEMPIPE_FIGURES", f"{path.stem}-figures")
    pngs = sorted(folder.glob("*.png"))
    assert [p.name for p in pngs] == [f"{path.stem}_{k}.png" for k in range(1, len(pngs) + 1)]
    assert pngs and all(p.stat().st_size > 10_000 for p in pngs)
    assert f"wrote {len(pngs)} figure" in proc.stdout
    assert sorted(os.listdir(tmp_path)) == [folder.name]


def _notebook_markdown(path: Path, gallery_conf: dict, tmp_path: Path) -> str:
    from sphinx_gallery.notebook import jupyter_notebook
    from sphinx_gallery.py_source_parser import split_code_and_text_blocks

    _, blocks = split_code_and_text_blocks(str(path))
    nb = jupyter_notebook(blocks, gallery_conf, tmp_path)
    return "".join("".join(c["source"]) for c in nb["cells"] if c["cell_type"] == "markdown")


@pytest.mark.slow
def test_downloaded_notebooks_are_markdown(tmp_path, caplog):
    """The notebooks sphinx-gallery offers (its own conversion with docs/conf.py's settings:
    pandoc and the role filter) carry no raw RST; maths and collapsed solutions survive, and
    pandoc reads every text without a warning (an RST reference or substitution it cannot
    resolve, such as e_(k+1) or |x|, would be one)."""
    pytest.importorskip("sphinx_gallery", reason="the docs extra: pip install -e '.[docs]'")
    pytest.importorskip("pypandoc", reason="the docs extra: pip install -e '.[docs]'")
    import runpy

    from sphinx_gallery.gen_gallery import _fill_gallery_conf_defaults

    conf = runpy.run_path(str(ROOT / "docs" / "conf.py"))["sphinx_gallery_conf"]
    gallery_conf = _fill_gallery_conf_defaults(conf)
    assert gallery_conf["pypandoc"], "pandoc is not used: the notebooks would keep raw RST"
    for path in [*LESSONS, *EXAMPLES]:
        with caplog.at_level("WARNING", logger="pypandoc"):
            md = _notebook_markdown(path, gallery_conf, tmp_path)
        assert not [r.getMessage() for r in caplog.records if r.name == "pypandoc"], path.name
        for raw in (
            ":class:",
            ":func:",
            ":mod:",
            ":meth:",
            ":doc:",
            ":math:",
            ".. math::",
            ".. raw::",
            ".. code-block::",
            "interpreted-text",
        ):
            assert raw not in md, (path.name, raw)
        if path in LESSONS:
            assert md.count("<details><summary>Solution</summary>") == len(solutions(path))
            assert "```python" in md or "``` python" in md
    assert "$$" in _notebook_markdown(LESSONS[0], gallery_conf, tmp_path)  # its .. math::


@pytest.mark.slow
def test_the_documented_notebook_command_runs(tmp_path):
    """GALLERY_HEADER.rst's jupytext command, verbatim, makes an executed notebook with its
    figures (the docs extra has jupytext, nbconvert and ipykernel)."""
    import shlex
    import subprocess

    nbformat = pytest.importorskip("nbformat")
    pytest.importorskip("nbconvert", reason="the docs extra: pip install -e '.[docs]'")
    header = (ROOT / "docs" / "course" / "GALLERY_HEADER.rst").read_text(encoding="utf-8")
    (command,) = [
        line.strip() for line in header.splitlines() if line.strip().startswith("jupytext ")
    ]
    (tmp_path / "docs").symlink_to(ROOT / "docs")  # the command's relative path, from tmp_path
    argv = shlex.split(command)
    proc = subprocess.run(
        [str(Path(os.sys.executable).parent / argv[0]), *argv[1:]],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,
        check=False,
        env={**os.environ, "MPLBACKEND": "module://matplotlib_inline.backend_inline"},
    )
    assert proc.returncode == 0, proc.stderr[-3000:]
    nb = nbformat.read(tmp_path / argv[argv.index("-o") + 1], as_version=4)
    outputs = [o for c in nb.cells if c.cell_type == "code" for o in c.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    assert any("image/png" in o.get("data", {}) for o in outputs)
    assert sorted(os.listdir(tmp_path)) == ["docs", "lesson_02.ipynb"]  # no figure files

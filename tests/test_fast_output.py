"""The fast writers of ``simulate --out``: the same files as the plain ones, and atomic.

* :func:`fempipe.plotting.dynamics.render_frames` blits the moving pipe on a
  figure laid out once; its frames are compared with matplotlib's own
  ``FuncAnimation(..., blit=False)`` + ``PillowWriter`` frames (a full redraw of
  the figure, layout included, at every frame);
* :func:`fempipe.io.write_gif` shares one palette over the frames; its error
  is compared with Pillow's own per-frame palette;
* :class:`fempipe.io.trajectory.CenterlineSampler` and
  :func:`fempipe.io.meshes.write_vtu_frames` must give the numbers and bytes of
  :func:`fempipe.model.kinematics.compute_shape` and meshio, bit for bit;
* a writer that fails leaves no file, half or whole, behind.
"""

from __future__ import annotations

import os

import matplotlib

matplotlib.use("Agg")

import matplotlib.pyplot as plt
import numpy as np
import pytest
from PIL import Image

from fempipe.model.discretization import FiniteElement, Modal


def _orbit(disc, n: int = 8, alpha: float = 0.3):
    """n states of a made-up oscillation (a first-mode swing plus a second mode),
    closed (last = first) as a limit cycle is stored; t over one period."""
    t = np.linspace(0.0, 0.4, n + 1)
    phase = 2 * np.pi * t / t[-1]
    q1 = _mode_coefficients(disc, 1)
    q2 = _mode_coefficients(disc, 2)
    q = np.outer(0.9 * np.sin(phase), q1) + np.outer(0.3 * np.cos(2 * phase), q2)
    q[-1] = q[0]
    qdot = np.gradient(q, t, axis=0)
    return t, q, qdot, alpha


def _mode_coefficients(disc, r: int) -> np.ndarray:
    """Coefficients of theta(xi) = sin((r - 1/2) pi xi), by L2 projection."""
    xq = disc.quad.x
    f = np.sin((r - 0.5) * np.pi * xq)
    phi = disc.Phi.toarray() if hasattr(disc.Phi, "toarray") else np.asarray(disc.Phi)
    w = disc.quad.w
    return np.linalg.solve(phi.T @ (w[:, None] * phi), phi.T @ (w * f))


def _pixels(im) -> np.ndarray:
    return np.asarray(im.convert("RGB"), dtype=int)


@pytest.fixture(scope="module")
def frames():
    """The animation's frames drawn both ways: (fast, full redraw)."""
    from fempipe.plotting.dynamics import animation_figure, render_frames

    disc = FiniteElement(degree=2, n_elements=6)
    t, q, _, alpha = _orbit(disc, n=5)
    out = []
    for full in (False, True):
        fig, draw, n = animation_figure(disc, t, q, alpha, title="α = 17.2°, v = 10")
        try:
            out.append(render_frames(fig, draw, n, full_redraw=full))
        finally:
            plt.close(fig)
    return out


def test_blitted_frames_are_the_full_redraw(frames):
    """Same number of frames and the same pixels as FuncAnimation's full redraws.

    Tolerance zero: the moving artists (pipe, tip, time label) are the last
    ones of their axes in matplotlib's drawing order, clear of the spines,
    and the background is drawn with the layout a running animation has
    (the second constrained layout), so blitting draws the same pixels.
    """
    fast, full = frames
    assert len(fast) == len(full) == 5  # a closed orbit of 6 states: 5 frames
    for k in (0, len(fast) - 1, len(fast) // 2):
        assert fast[k].size == full[k].size
        np.testing.assert_array_equal(np.asarray(fast[k]), np.asarray(full[k]), err_msg=f"{k}")
    # The frames differ from each other: the pipe moves.
    assert np.any(np.asarray(fast[0]) != np.asarray(fast[len(fast) // 2]))


def test_gif_frames_within_the_palette_error(frames, tmp_path):
    """The GIF holds every frame; its colors are as close to the rendered frames
    as Pillow's per-frame adaptive palettes (PillowWriter's encoding) get.

    A GIF frame has at most 256 colors and an antialiased frame about 500, so
    both encodings move some edge pixels to a near color.  The shared palette
    must not do worse than 1.5 times the per-frame palette's mean error (plus
    0.01 of 255), nor change more than 2 % of the pixels.
    """
    from fempipe.io import write_gif

    fast, full = frames
    path = write_gif(tmp_path / "pipe.gif", fast, fps=16)
    reference = tmp_path / "reference.gif"
    rgb = [im.convert("RGB") for im in full]
    rgb[0].save(reference, save_all=True, append_images=rgb[1:], duration=62, loop=0)
    with Image.open(path) as gif, Image.open(reference) as ref:
        assert gif.n_frames == len(full)
        # 62 ms, stored in the GIF's hundredths of a second.
        assert gif.info["duration"] == 60 and gif.info["loop"] == 0
        for k in (0, len(full) - 1):
            gif.seek(k)
            ref.seek(k)
            truth = _pixels(full[k])
            ours, theirs = np.abs(_pixels(gif) - truth), np.abs(_pixels(ref) - truth)
            assert ours.mean() <= 1.5 * theirs.mean() + 0.01, (k, ours.mean(), theirs.mean())
            assert np.any(ours > 0, axis=2).mean() < 0.02


@pytest.mark.parametrize(
    "disc",
    [FiniteElement(degree=3, n_elements=5), Modal(4), Modal(3, basis="beam")],
    ids=["P3:5", "modal:4", "modal-beam:3"],
)
def test_sampler_is_shape_bit_for_bit(disc):
    """CenterlineSampler gives the arrays of kinematics.compute_shape and disc.evaluate exactly."""
    from fempipe.io.trajectory import CenterlineSampler, frame_data
    from fempipe.model.kinematics import compute_shape

    _, q, qdot, alpha = _orbit(disc, n=5)
    sampler = CenterlineSampler(disc, alpha, points_per_cell=4)
    for k in range(q.shape[0]):
        ref, got = compute_shape(disc, q[k], alpha, points_per_cell=4), sampler.shape(q[k], qdot[k])
        for f in ("xi", "theta", "varsigma", "eta", "X_g", "Z_g"):
            np.testing.assert_array_equal(getattr(got, f), getattr(ref, f), err_msg=f)
        np.testing.assert_array_equal(sampler.evaluate(qdot[k]), disc.evaluate(qdot[k], ref.xi))
        pts, data = frame_data(disc, q[k], qdot[k], alpha, 4, sampler)
        pts0, data0 = frame_data(disc, q[k], qdot[k], alpha, 4)
        np.testing.assert_array_equal(pts, pts0)
        for name in data0:
            np.testing.assert_array_equal(data[name], data0[name], err_msg=name)
    assert sampler._basis is not None  # the fast path was taken


def test_vtu_frames_are_meshio_files_byte_for_byte(tmp_path):
    """write_vtu_frames writes the bytes write_vtu (meshio) writes, frame by frame."""
    from fempipe.io.meshes import write_vtu, write_vtu_frames
    from fempipe.io.trajectory import frame_data

    disc = FiniteElement(degree=2, n_elements=4)
    t, q, qdot, alpha = _orbit(disc, n=4)
    frames = []
    for k in range(t.size):
        pts, data = frame_data(disc, q[k], qdot[k], alpha)
        frames.append((pts, data, {"time": float(t[k]), "v": 10.0}))
    m = frames[0][0].shape[0]
    cells = np.stack([np.arange(m - 1), np.arange(1, m)], axis=1)
    names = [f"frame_{k}.vtu" for k in range(t.size)]
    fast = write_vtu_frames(tmp_path / "fast", names, frames, cells)
    assert fast == [tmp_path / "fast" / name for name in names]
    for k, (pts, data, field) in enumerate(frames):
        ref = write_vtu(tmp_path / f"ref_{k}.vtu", pts, cells, data, field)
        assert fast[k].read_bytes() == ref.read_bytes(), k
    # A frame of another layout (one more array) is written by meshio, correctly,
    # into the existing directory, beside the files already there.
    pts, data, field = frames[0]
    odd = [(pts, {**data, "extra": data["xi"] * 2}, field)]
    (path,) = write_vtu_frames(tmp_path / "fast", ["odd.vtu"], odd, cells)
    assert (
        path.read_bytes()
        == write_vtu(tmp_path / "odd_ref.vtu", pts, cells, *odd[0][1:]).read_bytes()
    )
    assert len(list((tmp_path / "fast").iterdir())) == t.size + 1
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]


def _leftovers(directory) -> list[str]:
    """Every file below ``directory`` (the temporary files of the atomic writers start with '.')."""
    return sorted(
        os.path.relpath(os.path.join(root, f), directory)
        for root, _, files in os.walk(directory)
        for f in files
    )


def test_gif_of_transparent_frames_keeps_their_alpha(tmp_path):
    """Frames with transparent pixels are not forced onto the opaque shared palette:
    they are written as PillowWriter writes them (Pillow gives the GIF a
    transparent color)."""
    from fempipe.io import write_gif

    frames = []
    for k in range(3):
        a = np.zeros((20, 30, 4), dtype=np.uint8)
        a[..., 0] = 40 * k
        a[5:15, 5 + 5 * k : 15 + 5 * k] = (0, 0, 255, 255)  # an opaque square moving right
        frames.append(Image.fromarray(a, mode="RGBA"))  # the rest fully transparent
    path = write_gif(tmp_path / "t.gif", frames, fps=10)
    with Image.open(path) as gif:
        assert gif.n_frames == 3 and "transparency" in gif.info
        # The first frame: transparent exactly where it was (later frames are
        # composed over the earlier ones, as GIF players show them).
        alpha = np.asarray(gif.convert("RGBA"))[..., 3]
        np.testing.assert_array_equal(alpha > 0, np.asarray(frames[0])[..., 3] > 0)


def test_failed_gif_writes_no_file(tmp_path, monkeypatch, frames):
    """An encoder that fails half-way leaves neither pipe.gif nor its temporary file."""
    from fempipe.io import write_gif

    def broken_save(self, fp, *args, **kwargs):
        with open(fp, "wb") as f:
            f.write(b"GIF89a half")
        raise OSError("disk full")

    monkeypatch.setattr(Image.Image, "save", broken_save)
    with pytest.raises(OSError, match="disk full"):
        write_gif(tmp_path / "pipe.gif", frames[0], fps=16)
    assert _leftovers(tmp_path) == []


def test_failed_trajectory_writes_nothing(tmp_path, monkeypatch):
    """A trajectory that fails at its fourth frame leaves no frame (the frames are
    moved into place all at once), no temporary file or directory and no .pvd index;
    a trajectory written over an older one replaces its frames."""
    import fempipe.io.trajectory as trajectory
    from fempipe.io import read_field_data

    disc = FiniteElement(degree=2, n_elements=4)
    t, q, qdot, alpha = _orbit(disc, n=6)
    real = trajectory.frame_data
    calls = []

    def failing(*args, **kwargs):
        calls.append(1)
        if len(calls) == 4:
            raise RuntimeError("interrupted")
        return real(*args, **kwargs)

    monkeypatch.setattr(trajectory, "frame_data", failing)
    with pytest.raises(RuntimeError, match="interrupted"):
        trajectory.write_trajectory(tmp_path / "trajectory.pvd", disc, t, q, qdot, alpha)
    assert len(calls) == 4 and list(tmp_path.iterdir()) == []
    monkeypatch.setattr(trajectory, "frame_data", real)
    trajectory.write_trajectory(tmp_path / "trajectory.pvd", disc, t, q, qdot, alpha)
    trajectory.write_trajectory(tmp_path / "trajectory.pvd", disc, t + 1.0, q, qdot, alpha)
    files = _leftovers(tmp_path)
    assert files == ["trajectory.pvd"] + [f"trajectory/frame_{k:05d}.vtu" for k in range(7)]
    assert read_field_data(tmp_path / files[-1])["time"][0] == t[-1] + 1.0


def test_bench_simulate_output_reports_the_ratio(monkeypatch):
    """The benchmark alternates the two commands, gives --out a fresh directory that it
    removes, and reports the median ratio (the CPU seconds faked here)."""
    import fempipe.bench.output as bench_output
    from fempipe.bench import available

    assert available()["simulate_output"] is bench_output.bench_simulate_output
    calls, dirs = [], []

    def fake(argv, env=None):
        assert argv[:3] == ["-m", "fempipe", "simulate"] and env == {"MPLBACKEND": "Agg"}
        calls.append("--out" in argv)
        if "--out" in argv:
            dirs.append(argv[argv.index("--out") + 1])
            assert os.path.isdir(dirs[-1])
            return 3.5, ""
        return 1.25, ""

    monkeypatch.setattr(bench_output, "child_cpu_seconds", fake)
    res = bench_output.bench_simulate_output(quick=True)
    assert calls == [False, True, False, True]  # one untimed pair, then the timed pair
    assert res["ratio"] == 2.8 and res["meets_target"] and res["files_seconds"] == 2.25
    assert [r["cpu_seconds"] for r in res["table"]] == [1.25, 3.5]
    assert not any(os.path.exists(d) for d in dirs)

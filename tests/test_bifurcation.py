"""Bifurcation sweeps: ordering, resume after a kill, atomic point store, executors."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np
import pytest
from processes import alive, children, needs_proc

import fempipe.analyses.bifurcation as bif
from fempipe import Modal, Params, PipeModel
from fempipe.analyses.bifurcation import PointStore, compute_bifurcation_diagram, sweep
from fempipe.core.errors import PointStoreMismatchError

# Two sine modes on a coarse quadrature: the cheapest model that flutters
# (v_cr ~ 6 at alpha = 0), so sweeps take seconds.
VALUES = [5.0, 7.0, 9.0]
OPTIONS = {"rtol": 1e-5, "shoot_rtol": 1e-6}


def _model(alpha=0.0):
    return PipeModel(Modal(2, n_cells=8), Params(alpha=alpha))


def _strip(points):
    return [{k: v for k, v in p.items() if k not in ("wall_time",)} for p in points]


@pytest.fixture(scope="module")
def reference():
    """An uninterrupted serial run (up and down)."""
    return compute_bifurcation_diagram(_model(), VALUES, **OPTIONS)


def test_sweep_orders_values_and_finds_flutter(reference):
    pts = reference.points
    assert [p["v"] for p in pts if p["direction"] == "up"] == VALUES
    assert [p["v"] for p in pts if p["direction"] == "down"] == VALUES[::-1]
    kinds = {(p["direction"], p["v"]): p["attractor"] for p in pts}
    assert kinds[("up", 5.0)] == kinds[("down", 5.0)] == "equilibrium"
    assert kinds[("up", 9.0)] == kinds[("down", 9.0)] == "periodic"
    # No hysteresis in this supercritical case: up and down agree.
    up = {p["v"]: p for p in pts if p["direction"] == "up"}
    for p in pts:
        if p["direction"] == "down":
            np.testing.assert_allclose(p["eta_tip"], up[p["v"]]["eta_tip"], atol=1e-5)


@needs_proc
@pytest.mark.parametrize(
    "sig, workers", [(signal.SIGKILL, 1), (signal.SIGKILL, 2), (signal.SIGTERM, 2)]
)
def test_resume_after_kill_gives_same_points_without_recomputation(
    tmp_path, reference, monkeypatch, sig, workers
):
    """Kill a run in a subprocess once its first point is on disk, rerun, compare.

    The killed run's workers must be gone within seconds; the rerun must load
    the finished points (compute and write only the others) and give the same
    points as the uninterrupted run: each stored point holds the exact
    (repr-round-tripped) state the next point starts from.
    """
    store = tmp_path / "points"
    directions = ["up"] if workers == 1 else ["up", "down"]  # one sweep per worker
    script = textwrap.dedent(
        f"""
        import sys
        from fempipe import Modal, Params, PipeModel
        from fempipe.analyses.bifurcation import compute_bifurcation_diagram
        from fempipe.core.parallel import Interrupted, interruptible
        m = PipeModel(Modal(2, n_cells=8), Params(alpha=0.0))
        try:
            with interruptible():
                compute_bifurcation_diagram(
                    m,
                    {VALUES!r},
                    {directions!r},
                    store_dir={str(store)!r},
                    workers={workers},
                    **{OPTIONS!r},
                )
        except Interrupted as exc:
            sys.exit(exc.exit_code)
        """
    )
    env = dict(os.environ, PYTHONPATH=str(Path(bif.__file__).parents[2]))
    proc = subprocess.Popen([sys.executable, "-c", script], env=env)
    workers_seen: set[int] = set()
    try:
        deadline = time.time() + 120
        while time.time() < deadline and not list(store.glob("a00-*-000.json")):
            workers_seen.update(children(proc.pid))
            time.sleep(0.05)
        workers_seen.update(children(proc.pid))
        proc.send_signal(sig)
        killed = time.time()
        proc.wait(timeout=30)
        while any(map(alive, workers_seen)) and time.time() - killed < 10:
            time.sleep(0.05)
        survivors = [p for p in workers_seen if alive(p)]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for p in workers_seen:
            if alive(p):
                os.kill(p, signal.SIGKILL)
    assert len(workers_seen) == (workers if workers > 1 else 0)
    assert not survivors
    assert proc.returncode == (-sig if sig == signal.SIGKILL else 128 + sig)
    total = len(directions) * len(VALUES)
    done = sorted(p.name for p in store.glob("a00-*.json"))
    assert 1 <= len(done) < total, done  # killed midway
    for name in done:  # finished points are complete JSON
        json.loads((store / name).read_text())
    mtimes = {n: (store / n).stat().st_mtime_ns for n in done}

    saved, computed = [], []
    real_save, real_find, real_continue = PointStore.save, bif.find_attractor, bif._continue_cycle

    def save(self, sweep_name, point):
        saved.append(f"{sweep_name}-{point.direction}-{point.index:03d}.json")
        real_save(self, sweep_name, point)

    def find(model, *a, **k):
        computed.append(model.params.v)
        return real_find(model, *a, **k)

    def cont(model, *a, **k):
        computed.append(model.params.v)
        return real_continue(model, *a, **k)

    monkeypatch.setattr(PointStore, "save", save)
    monkeypatch.setattr(bif, "find_attractor", find)
    monkeypatch.setattr(bif, "_continue_cycle", cont)
    d = compute_bifurcation_diagram(_model(), VALUES, directions, store_dir=store, **OPTIONS)
    # only the missing points were computed and written, the others loaded
    assert sorted(saved) == sorted(set(saved)) and not set(saved) & set(done)
    assert len(saved) == total - len(done)
    assert set(computed) <= {json.loads((store / n).read_text())["v"] for n in saved}
    assert all((store / n).stat().st_mtime_ns == mtimes[n] for n in done)
    ref = [p for p in reference.points if p["direction"] in directions]
    assert _strip(d.points) == _strip(ref)


def test_store_refuses_a_different_run(tmp_path):
    compute_bifurcation_diagram(_model(), [5.0], ["up"], store_dir=tmp_path, **OPTIONS)
    with pytest.raises(PointStoreMismatchError, match="different run") as err:
        compute_bifurcation_diagram(_model(), [5.0], ["up"], store_dir=tmp_path, rtol=1e-4)
    assert isinstance(err.value, ValueError) and err.value.field == "store_dir"
    assert err.value.differences == ["options.rtol", "options.shoot_rtol"]
    assert "options.rtol, options.shoot_rtol" in str(err.value)


def test_point_store_writes_atomically(tmp_path):
    store = PointStore(tmp_path, {"run": 1})
    pts = sweep(_model(), [5.0], "up", store=store, **OPTIONS)
    files = sorted(os.listdir(tmp_path))
    assert files == ["a00-up-000.json", "run.json"]  # no temporary files left
    back = store.load("a00", "up", 0, 5.0)
    assert back.to_dict(state=True) == pts[0].to_dict(state=True)


def test_process_pool_gives_the_serial_result(reference):
    with ProcessPoolExecutor(max_workers=2) as ex:
        d = compute_bifurcation_diagram(_model(), VALUES, executor=ex, **OPTIONS)
    assert _strip(d.points) == _strip(reference.points)


def test_progress_callback_counts_points():
    seen = []
    compute_bifurcation_diagram(
        _model(), [5.0, 5.5], ["up", "down"], progress=lambda d, t: seen.append((d, t)), **OPTIONS
    )
    assert seen[-1] == (4, 4)
    assert [d for d, _ in seen] == sorted(d for d, _ in seen)


def test_several_alphas_are_independent_sweeps():
    d = compute_bifurcation_diagram(_model(), [5.0], ["up"], alphas=[0.0, 0.5], **OPTIONS)
    assert [p["alpha"] for p in d.points] == [0.0, 0.5]
    # alpha = 0.5: the static tip leaves the vertical
    assert abs(d.points[1]["Z_tip"][0]) > 0.1 > abs(d.points[0]["Z_tip"][0])


def test_a_failed_sweep_does_not_stop_the_others(tmp_path, monkeypatch):
    """The failure is raised once the other sweeps have ended and stored their points."""
    real = bif.find_attractor

    def fails_at_half(model, *a, **k):
        if model.params.alpha == 0.5:
            raise RuntimeError("injected failure")
        return real(model, *a, **k)

    monkeypatch.setattr(bif, "find_attractor", fails_at_half)
    with pytest.raises(RuntimeError, match="injected failure"):
        compute_bifurcation_diagram(
            _model(), [5.0], ["up"], alphas=[0.5, 0.0], store_dir=tmp_path, **OPTIONS
        )
    assert sorted(p.name for p in tmp_path.glob("a*.json")) == ["a01-up-000.json"]


@pytest.mark.parametrize(
    "kwargs, word",
    [({"directions": ["sideways"]}, "direction"), ({"workers": 0}, "workers")],
)
def test_bad_arguments(kwargs, word):
    with pytest.raises(ValueError, match=word):
        compute_bifurcation_diagram(_model(), [5.0], **kwargs)


def test_dask_local_cluster(reference):
    # dask[distributed] is in the test extra: a missing dask fails, never skips.
    from dask import distributed

    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None
        ) as cluster,
        distributed.Client(cluster) as client,
    ):
        d = compute_bifurcation_diagram(_model(), VALUES, executor=client.get_executor(), **OPTIONS)
    assert _strip(d.points) == _strip(reference.points)


def test_no_spurious_cycle_below_v_cr_when_sweeping_down():
    """Regression: continuing the v = 6.5 cycle to v = 6.2 < v_cr = 6.334 (P3:4,
    supercritical Hopf) once let Newton stop on its way to the equilibrium and
    report a 'cycle' of amplitude 7e-6.  Below v_cr the attractor is the
    equilibrium; there is no hysteresis here."""
    from fempipe import FiniteElement

    m = PipeModel(FiniteElement(4, 3), Params(alpha=0.0))
    pts = sweep(m, [6.2, 6.5], "down", shoot_rtol=1e-6)
    assert [p.attractor for p in pts] == ["periodic", "equilibrium"]

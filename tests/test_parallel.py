"""The task runner: order, error policy, callbacks, BLAS limit, and no orphan workers.

The orphan tests run a parent process whose pool workers sleep, signal the
parent, and watch the workers' pids: they must be gone within seconds,
whether the parent could clean up (SIGTERM, SIGINT) or not (SIGKILL).
"""

from __future__ import annotations

import contextlib
import json
import math
import multiprocessing
import os
import signal
import subprocess
import sys
import textwrap
import time
import traceback
from pathlib import Path

import pytest
from processes import alive, needs_proc
from threadpoolctl import threadpool_info

import fempipe
from fempipe.core.parallel import (
    Interrupted,
    interruptible,
    process_pool,
    run_tasks,
    single_blas_thread,
)

LINUX = sys.platform.startswith("linux")
#: How long orphaned workers may live after their parent is gone.
GRACE = 10.0


def _fails_on_negative(x):
    if x < 0:
        raise ValueError(f"negative input {x}")
    return math.sqrt(x)


def _blas_threads() -> list[int]:
    import numpy  # noqa: F401 - its BLAS is what the limit is about; fempipe loads it lazily

    return [lib["num_threads"] for lib in threadpool_info() if lib["user_api"] == "blas"]


def _worker_state(_i):
    """What the pool's initializer set up, seen from inside a worker."""
    import ctypes

    pdeathsig = None
    if LINUX:
        sig = ctypes.c_int(0)
        ctypes.CDLL(None).prctl(2, ctypes.byref(sig), 0, 0, 0)  # PR_GET_PDEATHSIG
        pdeathsig = sig.value
    return {
        "blas": _blas_threads(),
        "sigint": signal.getsignal(signal.SIGINT),
        "sigterm": signal.getsignal(signal.SIGTERM),
        "pdeathsig": pdeathsig,
    }


@pytest.mark.parametrize("workers", [None, 1, 2])
def test_results_in_task_order_and_failures_in_their_slot(workers):
    tasks = [(4.0,), (-1.0,), (9.0,), (-2.0,), (16.0,)]
    seen, slots = [], {}
    out = run_tasks(
        _fails_on_negative,
        tasks,
        workers=workers,
        callback=lambda done, total, r: seen.append((done, total)),
        on_result=slots.__setitem__,
    )
    assert out[0] == 2.0 and out[2] == 3.0 and out[4] == 4.0
    for i in (1, 3):
        assert isinstance(out[i], ValueError)
        # where it failed is kept (the worker's traceback for a pool)
        text = "".join(traceback.format_exception(out[i]))
        assert "_fails_on_negative" in text and f"negative input {tasks[i][0]}" in text
    assert seen == [(k, 5) for k in range(1, 6)]
    assert slots == dict(enumerate(out))


def test_a_given_executor_is_used_and_left_open():
    with process_pool(2) as pool:
        assert run_tasks(_fails_on_negative, [(1.0,), (4.0,)], executor=pool) == [1.0, 2.0]
        assert pool.submit(_fails_on_negative, 9.0).result() == 3.0  # not shut down


def test_heartbeat_is_called_while_tasks_run():
    beats = []
    run_tasks(time.sleep, [(0.6,), (0.6,)], workers=2, heartbeat=lambda: beats.append(1))
    assert len(beats) >= 2


def test_workers_must_be_positive():
    with pytest.raises(ValueError, match="workers"):
        run_tasks(_fails_on_negative, [(1.0,)], workers=0)
    with pytest.raises(ValueError, match="workers"):
        process_pool(0)


def test_single_blas_thread_limits_and_restores():
    before = _blas_threads()
    assert before, "numpy's BLAS is not visible to threadpoolctl"
    with single_blas_thread():
        assert set(_blas_threads()) == {1}
    assert _blas_threads() == before


def test_single_blas_thread_sees_a_blas_loaded_after_its_first_use():
    """The cached controller is rescanned once scipy.linalg (its own OpenBLAS) is loaded."""
    code = (
        "import json, numpy\n"
        "from threadpoolctl import threadpool_info\n"
        "from fempipe.core.parallel import single_blas_thread\n"
        "with single_blas_thread():\n"
        "    pass\n"
        "import scipy.linalg\n"
        "with single_blas_thread():\n"
        "    inside = [d['num_threads'] for d in threadpool_info() if d['user_api'] == 'blas']\n"
        "print(json.dumps(inside))\n"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    inside = json.loads(res.stdout)
    assert len(inside) >= 2 and set(inside) == {1}


@pytest.mark.parametrize("method", multiprocessing.get_all_start_methods())
def test_pool_workers_are_set_up_by_the_initializer(method):
    with process_pool(1, multiprocessing.get_context(method)) as pool:
        state = pool.submit(_worker_state, 0).result()
    assert set(state["blas"]) == {1}
    assert state["sigint"] == signal.SIG_IGN
    assert state["sigterm"] == signal.SIG_DFL
    if LINUX:
        assert state["pdeathsig"] == signal.SIGKILL


def test_a_failing_callback_stops_the_workers_at_once():
    """A callback error propagates without waiting for the running slow tasks."""

    def boom(done, total, result):
        raise RuntimeError("callback failed")

    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="callback failed"):
        run_tasks(time.sleep, [(0.0,), (30.0,), (30.0,)], workers=2, callback=boom)
    assert time.perf_counter() - t0 < 10


def test_interrupted_is_a_keyboard_interrupt_with_the_shell_exit_code():
    assert issubclass(Interrupted, KeyboardInterrupt)  # never caught as a task failure
    assert Interrupted(signal.SIGINT).exit_code == 130
    assert Interrupted(signal.SIGTERM).exit_code == 143
    previous = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Interrupted) as info, interruptible():
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(5)
    assert info.value.signum == signal.SIGTERM
    assert signal.getsignal(signal.SIGTERM) is previous  # restored


# -- orphans ---------------------------------------------------------------

PARENT = textwrap.dedent(
    """
    import contextlib, ctypes, multiprocessing, os, sys, time
    from pathlib import Path

    from fempipe.core.parallel import Interrupted, interruptible, run_tasks

    OUT = Path(sys.argv[1])
    HANDLE = sys.argv[2] == "handle"
    DISARM = sys.argv[3] == "disarm"
    METHOD = sys.argv[4]


    def slow(i):
        if DISARM:  # leave only the portable watchdog
            ctypes.CDLL(None).prctl(1, 0, 0, 0, 0)  # PR_SET_PDEATHSIG, 0
        (OUT / f"worker-{os.getpid()}").write_text("")
        time.sleep(120)
        return i


    if __name__ == "__main__":
        multiprocessing.set_start_method(METHOD)
        try:
            with interruptible() if HANDLE else contextlib.nullcontext():
                run_tasks(slow, [(i,) for i in range(4)], workers=2)
        except Interrupted as exc:
            print(f"stopped: {exc}", file=sys.stderr)
            sys.exit(exc.exit_code)
    """
)


def _signal_parent(tmp_path, sig, *, handle=False, disarm=False, method="fork"):
    """Start the parent, wait for its two busy workers, send ``sig``.

    Returns the parent's exit status (None if it still runs after ``GRACE``
    seconds), its stderr, and the seconds until the last worker was gone
    (None if some survived ``GRACE`` seconds).
    """
    script = tmp_path / "parent.py"
    script.write_text(PARENT)
    env = dict(os.environ, PYTHONPATH=str(Path(fempipe.__file__).parents[1]))
    args = [str(tmp_path), "handle" if handle else "-", "disarm" if disarm else "-", method]
    log = tmp_path / "stderr.txt"
    with log.open("w") as err:
        proc = subprocess.Popen(  # Ctrl-C not ignored, as from a terminal
            [sys.executable, str(script), *args],
            env=env,
            stderr=err,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
    pids: list[int] = []
    try:
        deadline = time.monotonic() + 60
        while len(pids) < 2 and time.monotonic() < deadline:
            time.sleep(0.05)
            pids = [int(p.name.split("-")[1]) for p in tmp_path.glob("worker-*")]
        assert len(pids) == 2, "the workers did not start"
        t0 = time.monotonic()
        proc.send_signal(sig)
        with contextlib.suppress(subprocess.TimeoutExpired):  # None: still running
            proc.wait(timeout=GRACE)
        while any(alive(p) for p in pids) and time.monotonic() - t0 < GRACE:
            time.sleep(0.02)
        gone = time.monotonic() - t0
        survivors = [p for p in pids if alive(p)]
        return proc.poll(), log.read_text(), (None if survivors else gone)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
        for p in pids:
            if alive(p):
                os.kill(p, signal.SIGKILL)


@needs_proc
@pytest.mark.parametrize("method", multiprocessing.get_all_start_methods())
def test_workers_die_with_a_killed_parent(tmp_path, method):
    """SIGKILL: the parent cannot clean up; its workers must notice and exit.

    With "forkserver" the workers' parent is the fork server, which exits
    when the pool's creator does.
    """
    rc, _, gone = _signal_parent(tmp_path, signal.SIGKILL, method=method)
    assert gone is not None and gone < GRACE
    assert rc == -signal.SIGKILL


@needs_proc
@pytest.mark.skipif(not LINUX, reason="disarms the Linux parent-death signal")
def test_the_watchdog_alone_ends_orphaned_workers(tmp_path):
    """Without the parent-death signal (other platforms), the watchdog thread does it."""
    rc, _, gone = _signal_parent(tmp_path, signal.SIGKILL, disarm=True)
    assert gone is not None and gone < GRACE
    assert rc == -signal.SIGKILL


@needs_proc
@pytest.mark.parametrize("sig, code", [(signal.SIGTERM, 143), (signal.SIGINT, 130)])
def test_an_interrupted_parent_stops_its_workers_and_exits(tmp_path, sig, code):
    rc, err, gone = _signal_parent(tmp_path, sig, handle=True)
    assert gone is not None and gone < GRACE
    assert rc == code
    assert f"stopped: interrupted by {signal.Signals(sig).name}" in err


@needs_proc
def test_plain_sigterm_leaves_no_workers(tmp_path):
    """SIGTERM's default action ends the parent at once; the workers follow."""
    rc, _, gone = _signal_parent(tmp_path, signal.SIGTERM)
    assert gone is not None and gone < GRACE
    assert rc == -signal.SIGTERM


def test_an_inherited_ignored_sigint_stays_ignored():
    """A background job started from a script inherits SIGINT as SIG_IGN; keep it so."""
    script = textwrap.dedent(
        """
        import os, signal, time
        from fempipe.core.parallel import interruptible
        signal.signal(signal.SIGINT, signal.SIG_IGN)
        with interruptible():
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.2)
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
        print("survived")
        """
    )
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "survived"

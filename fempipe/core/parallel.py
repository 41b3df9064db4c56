"""Independent tasks in worker processes: one runner, one BLAS limiter, clean exits.

Every parallel sweep (stability maps, root loci, bifurcation sweeps, validation cases) runs
through :func:`run_tasks`, on a :func:`process_pool` or any ``concurrent.futures.Executor``:
results in task order, a failing task's exception in its slot, interrupts stop everything
(:func:`interruptible`), no orphaned workers, and one BLAS thread per process
(:func:`single_blas_thread`, :func:`single_blas`, :func:`one_blas_thread`).

Policy: docs/development.md, "Worker processes".
"""

from __future__ import annotations

import contextlib
import functools
import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    import multiprocessing.context
    from concurrent.futures import Executor, ProcessPoolExecutor

__all__ = [
    "BLAS_SET_BY_FEMPIPE",
    "BLAS_THREAD_VARIABLES",
    "one_blas_thread",
    "Interrupted",
    "interruptible",
    "process_pool",
    "run_tasks",
    "single_blas_thread",
    "single_blas",
    "HEARTBEAT",
    "PARENT_POLL",
]

#: Seconds between calls of ``run_tasks(heartbeat=...)`` while tasks run.
HEARTBEAT = 0.2
#: Seconds between a worker's checks that its parent process is still alive.
PARENT_POLL = 0.5
#: Seconds a terminated worker is given to exit before it is killed.
_TERMINATE_GRACE = 5.0
#: From <linux/prctl.h>.
_PR_SET_PDEATHSIG = 1


class Interrupted(KeyboardInterrupt):
    """SIGINT or SIGTERM (``signum``; ``exit_code`` 128 + ``signum``) arrived: a
    ``KeyboardInterrupt``, so that :func:`run_tasks`'s ``except Exception`` never swallows it."""

    def __init__(self, signum: int) -> None:
        self.signum = int(signum)
        super().__init__(f"interrupted by {signal.Signals(self.signum).name}")

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


@contextlib.contextmanager
def interruptible() -> Iterator[None]:
    """Raise :class:`Interrupted` in the main thread on SIGINT or SIGTERM: SIGTERM unwinds like
    Ctrl-C (``finally`` blocks run); a second signal and an inherited ``SIG_IGN`` are ignored."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    fired = False

    def handler(signum, _frame):
        nonlocal fired
        if fired:
            return
        fired = True
        raise Interrupted(signum)

    # A signal the process inherited as ignored (SIGINT of a job started with
    # `&` from a non-interactive shell, nohup) stays ignored.
    previous = {
        s: signal.signal(s, handler)
        for s in (signal.SIGINT, signal.SIGTERM)
        if signal.getsignal(s) is not signal.SIG_IGN
    }
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)


def single_blas_thread() -> contextlib.AbstractContextManager:
    """One BLAS thread in this process while active (small dense solves: start-up > arithmetic)."""
    return _blas_controller().limit(limits=1, user_api="blas")


def single_blas(fn: Callable) -> Callable:
    """Decorator: run ``fn`` under :func:`single_blas_thread`."""

    @functools.wraps(fn)
    def wrapper(*args, **kwargs):
        with single_blas_thread():
            return fn(*args, **kwargs)

    return wrapper


#: threadpoolctl controllers by which of numpy and scipy.linalg are loaded: a controller scans
#: the shared libraries once, ``threadpool_limits`` on every call.
_CONTROLLERS: dict = {}


def _blas_controller():
    key = tuple(name in sys.modules for name in ("numpy", "scipy.linalg"))
    ctl = _CONTROLLERS.get(key)
    if ctl is None:
        from threadpoolctl import ThreadpoolController

        ctl = _CONTROLLERS[key] = ThreadpoolController()
    return ctl


def _running(pid: int) -> bool:
    """True while process ``pid`` runs (on Linux a zombie awaiting its reaper is not)."""
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, PermissionError):  # gone, or the pid was reused by another user
        return False
    if sys.platform.startswith("linux"):
        try:
            stat = Path(f"/proc/{pid}/stat").read_text()
        except FileNotFoundError:
            return False
        return stat.rsplit(")", 1)[1].split()[0] != "Z"
    return True


def _watch_parent(parent: int, ppid: int) -> None:
    # Two checks: a worker whose parent died is re-parented (its ppid changes);
    # a worker of the "forkserver" start method has the fork server as parent,
    # which lives on while any worker does, so the pool's creator is watched too.
    while True:
        time.sleep(PARENT_POLL)
        if os.getppid() != ppid or not _running(parent):
            os._exit(1)


def _init_worker(parent: int) -> None:
    """Initializer of the workers of :func:`process_pool`; ``parent`` is the pool creator's pid."""
    # The parent handles Ctrl-C (the terminal sends SIGINT to the whole process
    # group) and stops the workers with SIGTERM; a forked worker would
    # otherwise inherit the parent's Python-level handlers.
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    # A worker started by "spawn" or "forkserver" has not loaded numpy's and
    # scipy's BLAS yet: load them, or the limit would miss them.
    import scipy.linalg  # noqa: F401
    from threadpoolctl import threadpool_limits

    threadpool_limits(limits=1, user_api="blas")
    if sys.platform.startswith("linux"):
        import ctypes

        libc = ctypes.CDLL(None, use_errno=True)
        if libc.prctl(_PR_SET_PDEATHSIG, int(signal.SIGKILL), 0, 0, 0) != 0:
            err = ctypes.get_errno()
            raise OSError(err, f"prctl(PR_SET_PDEATHSIG): {os.strerror(err)}")
    # The parent may have died before the death signal was armed.
    ppid = os.getppid()
    if not _running(parent):
        os._exit(1)
    threading.Thread(
        target=_watch_parent, args=(parent, ppid), name="parent-watchdog", daemon=True
    ).start()


def process_pool(
    workers: int, mp_context: multiprocessing.context.BaseContext | None = None
) -> ProcessPoolExecutor:
    """A ``ProcessPoolExecutor`` of ``workers`` processes that never outlive this process.

    Each worker uses one BLAS thread, ignores SIGINT, dies on SIGTERM and exits within
    :data:`PARENT_POLL` seconds of this process's death (on Linux at once, by a parent-death
    signal sent when the creating *thread* exits: use the pool from that thread).
    ``mp_context`` chooses how workers start.
    """
    # concurrent.futures and multiprocessing are imported here: a serial run does
    # not pay for them at start-up.
    from concurrent.futures import ProcessPoolExecutor

    if int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    return ProcessPoolExecutor(
        max_workers=int(workers),
        mp_context=mp_context,
        initializer=_init_worker,
        initargs=(os.getpid(),),
    )


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Cancel what has not started and terminate the workers (no waiting for tasks)."""
    terminate = getattr(pool, "terminate_workers", None)  # Python >= 3.14
    if terminate is not None:
        terminate()
        return
    processes = list((pool._processes or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for p in processes:
        p.terminate()
    for p in processes:
        p.join(_TERMINATE_GRACE)
        if p.is_alive():
            p.kill()
            p.join()
    # Let the executor's manager thread finish now (it sees the dead workers and
    # closes its wakeup pipe): before Python 3.12 the interpreter's exit handler
    # may otherwise write to that pipe while the thread closes it, and print
    # "Exception ignored ... Bad file descriptor" after an interrupted run's one line.
    manager = getattr(pool, "_executor_manager_thread", None)
    if manager is not None:
        manager.join(_TERMINATE_GRACE)


def run_tasks(
    fn: Callable,
    tasks: Sequence[tuple],
    *,
    workers: int | None = None,
    executor: Executor | None = None,
    callback: Callable[[int, int, object], None] | None = None,
    on_result: Callable[[int, object], None] | None = None,
    heartbeat: Callable[[], None] | None = None,
) -> list:
    """Run ``fn(*task)`` for every task, in parallel if asked; per task its result or exception.

    A task's ``Exception`` stays in its slot; an interrupt, ``SystemExit`` or a callback's
    exception cancels what has not started, terminates a pool started here, and propagates.

    Parameters
    ----------
    fn : callable
        A module-level function (pickled for process pools).
    tasks : sequence of tuple
        Positional arguments of each call.
    workers : int, optional
        > 1 starts a :func:`process_pool` (without ``executor``); None or 1 runs here.
    executor : concurrent.futures.Executor, optional
        Any executor; not shut down.
    callback, on_result : callable, optional
        ``callback(done, total, result)``, ``on_result(index, result)`` as each task finishes.
    heartbeat : callable, optional
        Called every :data:`HEARTBEAT` seconds while parallel tasks run.
    """
    tasks = [tuple(t) for t in tasks]
    total = len(tasks)
    if workers is not None and int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    out: list = [None] * total

    def finish(i: int, result: object, done: int) -> None:
        out[i] = result
        if on_result is not None:
            on_result(i, result)
        if callback is not None:
            callback(done, total, result)

    if executor is None and (workers is None or int(workers) == 1 or total <= 1):
        for i, t in enumerate(tasks):
            try:
                result = fn(*t)
            except Exception as exc:  # noqa: BLE001 - the per-task error policy
                result = exc
            finish(i, result, i + 1)
        return out

    from concurrent.futures import FIRST_COMPLETED, wait

    own = None
    if executor is None:
        own = executor = process_pool(min(int(workers), total))
    futures: dict = {}
    try:
        for i, t in enumerate(tasks):
            futures[executor.submit(fn, *t)] = i
        pending = set(futures)
        done = 0
        while pending:
            finished, pending = wait(
                pending, timeout=HEARTBEAT if heartbeat else None, return_when=FIRST_COMPLETED
            )
            for fut in sorted(finished, key=futures.__getitem__):
                try:
                    result = fut.result()
                except Exception as exc:  # noqa: BLE001 - the per-task error policy
                    result = exc
                done += 1
                finish(futures[fut], result, done)
            if heartbeat is not None:
                heartbeat()
    except BaseException:
        for fut in futures:
            fut.cancel()
        if own is not None:
            _stop_pool(own)
            own = None
        raise
    finally:
        if own is not None:
            own.shutdown()
    return out


#: The thread-count variables of the BLAS libraries numpy and scipy load
#: (OpenBLAS in the PyPI wheels, MKL, BLIS).
BLAS_THREAD_VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "BLIS_NUM_THREADS")
#: Those of them :func:`one_blas_thread` set (the user had not); ``fempipe bench`` unsets them
#: for its "as written" baseline.
BLAS_SET_BY_FEMPIPE: tuple[str, ...] = ()


def one_blas_thread() -> tuple[str, ...]:
    """Set the BLAS thread variables to 1 before numpy loads, unless the user set them
    (docs/cli/commands.md, "One BLAS thread"); the names set, also in :data:`BLAS_SET_BY_FEMPIPE`."""
    global BLAS_SET_BY_FEMPIPE
    if "numpy" in sys.modules:
        return ()
    unset = tuple(name for name in BLAS_THREAD_VARIABLES if name not in os.environ)
    for name in unset:
        os.environ[name] = "1"
    BLAS_SET_BY_FEMPIPE = unset
    return unset

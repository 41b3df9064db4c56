"""Run the validation cases (in parallel, :func:`fempipe.core.parallel.run_tasks`), draw their
figures (Agg) and collect a :class:`SuiteResult`; a case that raises is recorded with its
error and the suite goes on.  The report: :mod:`fempipe.validation.report`.
"""

from __future__ import annotations

import logging
import os
import time
import traceback
from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass, field, replace
from pathlib import Path

from fempipe.core.parallel import run_tasks

from ..core.version import __version__
from ..io import write_figure
from . import CASES, load_case
from .checks import CaseResult, merge_results

__all__ = ["CaseOutcome", "SuiteResult", "run_case", "run_suite"]

log = logging.getLogger(__name__)

#: Rough relative cost of the full cases, to start the longest first.
_COST = {"space_convergence": 150, "space_onset": 110, "fig08_10": 100, "convergence": 90,
         "fig07": 80, "fig06": 70, "out_of_plane": 60, "fig11": 40, "fig12": 39, "fig05": 20}  # fmt: skip


#: Cases that share cached computations run one after the other in one worker.
_GROUPS = (("fig11", "fig12"),)


def _case_groups(order: list[str]) -> list[tuple[str, ...]]:
    """Group the cases of ``order`` into worker tasks, keeping the order."""
    tasks, seen = [], set()
    for n in order:
        if n in seen:
            continue
        group = next((g for g in _GROUPS if n in g), (n,))
        task = tuple(m for m in group if m in order)
        seen.update(task)
        tasks.append(task)
    return tasks


def _run_task(names: tuple[str, ...], quick: bool, out, part):
    """One task of :func:`run_suite`: a group of cases, or one part of a split case."""
    if part is None:
        return [run_case(n, quick, out) for n in names]  # one process: shared caches
    return run_part(names[0], quick, part)


def _format(exc: BaseException) -> str:
    """The traceback of an exception a task returned (a worker's is chained as its cause)."""
    return "".join(traceback.format_exception(exc))


@dataclass(frozen=True)
class CaseOutcome:
    """One case of a run: ``status`` ``"ok"`` (see ``result``) or ``"error"`` (``error``: the
    traceback); ``figures`` its PNG files, ``figure`` the first.
    """

    name: str
    status: str
    result: CaseResult | None = None
    figure: str | None = None
    error: str = ""
    wall_time: float = 0.0
    figures: tuple[str, ...] = ()

    @property
    def ok(self) -> bool:
        """Ran and every numerics check passed."""
        return self.status == "ok" and self.result is not None and self.result.numerics_passed

    def to_dict(self) -> dict:
        return {
            "name": self.name,
            "status": self.status,
            "figure": self.figure,
            "figures": list(self.figures),
            "error": self.error,
            "wall_time": self.wall_time,
            "result": self.result.to_dict() if self.result is not None else None,
        }


@dataclass(frozen=True)
class SuiteResult:
    """All outcomes of a run, with how it was run."""

    outcomes: tuple[CaseOutcome, ...]
    quick: bool
    workers: int
    wall_time: float
    started: str
    environment: dict = field(default_factory=dict)

    @property
    def ok(self) -> bool:
        """No case errored and every numerics check of every case passed."""
        return all(o.ok for o in self.outcomes)

    def checks(self, category: str | None = None):
        for o in self.outcomes:
            if o.result is None:
                continue
            for c in o.result.checks:
                if category is None or c.category == category:
                    yield o.name, c

    def to_dict(self) -> dict:
        n_num = [c.passed for _, c in self.checks("numerics")]
        n_pap = [c.passed for _, c in self.checks("paper")]
        return {
            "quick": self.quick,
            "workers": self.workers,
            "wall_time": self.wall_time,
            "started": self.started,
            "ok": self.ok,
            "numerics_checks": {"passed": sum(n_num), "total": len(n_num)},
            "paper_checks": {"passed": sum(n_pap), "total": len(n_pap)},
            "environment": self.environment,
            "cases": [o.to_dict() for o in self.outcomes],
        }


def _draw(name: str, module, result: CaseResult, out) -> tuple[str, ...]:
    """Draw a case's figures (``module.plots`` or ``module.plot``) into ``out``; their file names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plots = getattr(module, "plots", None)
    figs = plots(result) if plots is not None else {name: module.plot(result)}
    files = []
    try:
        for stem, fig in figs.items():
            files.append(f"{stem}.png")
            write_figure(Path(out) / files[-1], fig, dpi=110)
    finally:
        for fig in figs.values():
            plt.close(fig)
    return tuple(files)


def _kept(result: CaseResult) -> dict:
    """What of a case's data the report needs: its headline sentence, if it has one."""
    return {"headline": result.data["headline"]} if "headline" in result.data else {}


def _finish(name: str, module, result: CaseResult, out, t0: float) -> CaseOutcome:
    """Draw the figure (if ``out``) and wrap the result without its arrays."""
    figures: tuple[str, ...] = ()
    error = ""
    if out is not None:
        try:
            figures = _draw(name, module, result, out)
        except Exception:
            log.exception("figure of validation case %s failed", name)
            error = "figure: " + traceback.format_exc()
    return CaseOutcome(
        name,
        "error" if error else "ok",
        result=replace(result, data=_kept(result)),
        error=error,
        figure=figures[0] if figures else None,
        figures=figures,
        wall_time=time.perf_counter() - t0,
    )


def _timed(run: Callable[..., CaseResult], quick: bool, **kwargs) -> CaseResult:
    """``run(quick=quick, **kwargs)`` with its wall time as the result's ``runtime``."""
    t0 = time.perf_counter()
    result = run(quick=quick, **kwargs)
    return replace(result, runtime=time.perf_counter() - t0)


def run_case(name: str, quick: bool = False, out: str | os.PathLike | None = None) -> CaseOutcome:
    """Run one case and draw its figures into ``out`` (if given); never raises."""
    t0 = time.perf_counter()
    try:
        module = load_case(name)
        result = _timed(module.run, quick)
    except Exception:  # a failing case must not stop the suite
        log.exception("validation case %s failed", name)
        return CaseOutcome(
            name, "error", error=traceback.format_exc(), wall_time=time.perf_counter() - t0
        )
    return _finish(name, module, result, out, t0)


def run_part(name: str, quick: bool, part) -> tuple[str, object]:
    """One part of a split case: ``("ok", CaseResult)`` or ``("error", traceback)``."""
    try:
        return "ok", _timed(load_case(name).run, quick, part=part)
    except Exception:
        log.exception("validation case %s, part %s failed", name, part)
        return "error", traceback.format_exc()


def _parts(name: str, quick: bool) -> list | None:
    """The parts of a case that defines ``parts(quick)`` (run in parallel), else None."""
    fn = getattr(load_case(name), "parts", None)
    return list(fn(quick)) if fn is not None else None


def _merge_parts(name: str, quick: bool, out, pieces: list, wall: float) -> CaseOutcome:
    """Merge the parts of a split case and draw its figure here."""
    errors = [p for status, p in pieces if status != "ok"]
    if errors:
        return CaseOutcome(name, "error", error="\n".join(errors), wall_time=wall)
    t0 = time.perf_counter()
    result = merge_results([p for _, p in pieces])
    outcome = _finish(name, load_case(name), result, out, t0)
    return replace(outcome, wall_time=wall + outcome.wall_time)


def _environment(workers: int) -> dict:
    import platform
    import subprocess

    import numpy
    import scipy
    import skfem

    commit = None
    root = Path(__file__).resolve().parents[2]
    git = ["git", "-C", str(root), "rev-parse", "--short", "HEAD"]
    try:
        if (root / ".git").exists():
            run = subprocess.run(git, capture_output=True, text=True, check=False, timeout=10)
            commit = run.stdout.strip() or None
    except (OSError, subprocess.SubprocessError):
        commit = None
    return {
        "fempipe": __version__,
        "git_commit": commit,
        "python": platform.python_version(),
        "numpy": numpy.__version__,
        "scipy": scipy.__version__,
        "scikit-fem": getattr(skfem, "__version__", "?"),
        "platform": platform.platform(),
        "cpu_count": os.cpu_count(),
        "workers": workers,
    }


def run_suite(
    quick: bool = False,
    out: str | os.PathLike | None = None,
    workers: int = 1,
    cases: Sequence[str] | None = None,
    executor: Executor | None = None,
    callback: Callable[[CaseOutcome], None] | None = None,
) -> SuiteResult:
    """Run validation cases and return their outcomes.

    Parameters
    ----------
    quick : bool
        The quick versions (coarser sweeps).
    out : path, optional
        Directory for the figures (PNG); nothing is written without it.
    workers : int
        Worker processes (1: this process); the most expensive cases start first, a case with
        ``parts(quick)`` runs part by part and is merged here.
    cases : sequence of str, optional
        Subset of case names (default: all).
    executor : concurrent.futures.Executor, optional
        Use this instead of a new process pool.
    callback : callable, optional
        Called with each finished :class:`CaseOutcome`.
    """
    names = list(CASES) if cases is None else list(cases)
    for n in names:
        if n not in CASES:
            raise ValueError(f"unknown validation case {n!r}; choose from {', '.join(CASES)}")
    if int(workers) < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    if out is not None:
        Path(out).mkdir(parents=True, exist_ok=True)
    started = time.strftime("%Y-%m-%d %H:%M:%S %Z")
    t0 = time.perf_counter()
    order = sorted(names, key=lambda n: -_COST.get(n, 1))
    done: dict[str, CaseOutcome] = {}
    split = {n: _parts(n, quick) for n in order}
    split = {n: p for n, p in split.items() if p}

    def finished(outcome: CaseOutcome) -> None:
        done[outcome.name] = outcome
        if callback:
            callback(outcome)

    # The parts of the split (longest) cases first, then the rest by cost.
    tasks = [((n,), quick, out, k) for n, parts in split.items() for k in parts]
    tasks += [
        (group, quick, out, None) for group in _case_groups([n for n in order if n not in split])
    ]
    pieces: dict[str, dict] = {n: {} for n in split}

    def task_done(i: int, result) -> None:
        group, _, _, part = tasks[i]
        if part is not None:
            name = group[0]
            if isinstance(result, BaseException):  # the worker itself failed
                result = ("error", _format(result))
            pieces[name][part] = result
            if len(pieces[name]) == len(split[name]):
                ordered = [pieces[name][k] for k in split[name]]
                finished(_merge_parts(name, quick, out, ordered, time.perf_counter() - t0))
            return
        if isinstance(result, BaseException):
            result = [CaseOutcome(n, "error", error=_format(result)) for n in group]
        for outcome in result:
            finished(outcome)

    run_tasks(
        _run_task,
        tasks,
        workers=None if executor is not None else int(workers),
        executor=executor,
        on_result=task_done,
    )
    return SuiteResult(
        outcomes=tuple(done[n] for n in names),
        quick=quick,
        workers=int(workers) if executor is None else -1,
        wall_time=time.perf_counter() - t0,
        started=started,
        environment=_environment(int(workers)),
    )

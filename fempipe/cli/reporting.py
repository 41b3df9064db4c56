"""What a ``fempipe`` command shows and writes: progress, result files, tables, error estimates.

``--out DIR`` is checked before any computation (:func:`check_out_dir`); a run's files are staged
inside DIR and moved in together at the end (:class:`Output`): a failed run leaves DIR as it was.
Conventions: docs/cli/options.md.
"""

from __future__ import annotations

import argparse
import contextlib
import os
import shutil
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Mapping, Sequence
from pathlib import Path

from fempipe.studies.error_estimate import ERROR, REFINED

from .parsing import CLIError

__all__ = [
    "ERROR",
    "LOG_INTERVAL",
    "Output",
    "agg",
    "check_out_dir",
    "cpu_seconds",
    "deliver",
    "describe",
    "discard_pending",
    "error_columns",
    "pm",
    "print_footer",
    "print_table",
    "value",
    "progress",
    "time_progress",
]

#: Seconds between two progress lines when stderr is not a terminal.
LOG_INTERVAL = 20.0


def check_out_dir(text: str, option: str = "--out") -> Path:
    """``text`` as a writable directory (created, or probed and left as it was), else CLIError."""
    if not text or not text.strip():
        raise CLIError(option, "empty directory name; give a directory, e.g. --out results/")
    path = Path(text)
    if path.exists() and not path.is_dir():
        raise CLIError(option, f"{text} exists and is not a directory")
    created: list[Path] = []
    probe = path
    while not probe.exists():
        created.append(probe)
        probe = probe.parent
    if not probe.is_dir():
        raise CLIError(option, f"cannot create {text}: {probe} is not a directory")
    try:
        for d in reversed(created):
            try:
                d.mkdir()
            except OSError as exc:
                raise CLIError(option, f"cannot create {text}: {exc.strerror or exc}") from None
        fd, tmp = tempfile.mkstemp(prefix=".fempipe-probe-", dir=path)
        os.close(fd)
        os.unlink(tmp)
    except OSError as exc:
        raise CLIError(option, f"cannot write into {text}: {exc.strerror or exc}") from None
    finally:
        for d in created:
            with contextlib.suppress(OSError):
                d.rmdir()
    return path


def progress(args: argparse.Namespace, total: int | None, desc: str):
    """tqdm's bar with ``--progress`` or on a terminal, nothing with ``--quiet``, else a line
    such as ``fempipe: simulate: 12/40 (30 %), 61 s`` every :data:`LOG_INTERVAL` s."""
    show = getattr(args, "progress", None)
    if show is None and not sys.stderr.isatty():
        return _LogProgress(total, desc, LOG_INTERVAL)
    from tqdm import tqdm  # only for a bar: log lines do not need it

    return tqdm(
        total=total,
        desc=desc,
        file=sys.stderr,
        leave=False,
        dynamic_ncols=True,
        disable=show is False,
    )


def time_progress(bar, t_end: float):
    """A ``callback(t)`` advancing ``bar`` by 100 over t in [0, t_end] (``.done`` so far)."""

    def on_time(t: float) -> None:
        k = min(100, int(100 * t / t_end))
        if k > on_time.done:
            bar.update(k - on_time.done)
            on_time.done = k

    on_time.done = 0
    return on_time


class _LogProgress:
    """tqdm's ``update`` / ``set_postfix_str`` as a line on stderr every ``interval`` s."""

    def __init__(self, total: int | None, desc: str, interval: float) -> None:
        self.total, self.desc, self.interval = total, desc, float(interval)
        self.n = 0
        self.postfix = ""
        self.start = self.last = time.monotonic()

    def __enter__(self) -> _LogProgress:
        return self

    def __exit__(self, *exc) -> None:
        return None

    def set_postfix_str(self, text: str, refresh: bool = True) -> None:
        self.postfix = str(text)
        self._maybe_print()

    def update(self, n: float = 1) -> None:
        self.n += n
        self._maybe_print()

    def _maybe_print(self) -> None:
        now = time.monotonic()
        if now - self.last < self.interval:
            return
        self.last = now
        elapsed = now - self.start
        done = f"{self.n:g}"
        if self.total:
            done += f"/{self.total:g} ({100.0 * self.n / self.total:.0f} %)"
        extra = f", {self.postfix}" if self.postfix else ""
        eta = ""
        if self.total and 0 < self.n < self.total:
            eta = f", about {elapsed * (self.total - self.n) / self.n:.0f} s left"
        print(f"fempipe: {self.desc}: {done}{extra}, {elapsed:.0f} s{eta}", file=sys.stderr)


#: Outputs created and not yet committed; :func:`discard_pending` removes
#: their staging directories when a command fails or is interrupted.
_PENDING: list[Output] = []


def discard_pending() -> None:
    """Remove the staging directory of every uncommitted :class:`Output`."""
    while _PENDING:
        _PENDING.pop().discard()


class Output:
    """The result files of one command in ``--out DIR``, all or none.

    Files go into a staging directory inside DIR (by the methods, or by another writer at
    :meth:`path` followed by :meth:`record`); :meth:`commit` moves them into DIR together,
    :func:`discard_pending` removes them if the command fails first.
    """

    def __init__(self, directory) -> None:
        self.directory = Path(directory)
        self.written: list[Path] = []
        self._staged: list[str] = []
        self._stage: Path | None = None
        _PENDING.append(self)

    @property
    def stage(self) -> Path:
        """The staging directory (created on first use)."""
        if self._stage is None:
            self.directory.mkdir(parents=True, exist_ok=True)
            self._stage = Path(tempfile.mkdtemp(prefix=".fempipe-staging-", dir=self.directory))
        return self._stage

    def path(self, name: str) -> Path:
        """Where to write ``name`` now; call :meth:`record` once it is written."""
        return self.stage / name

    def record(self, path) -> Path:
        """Record a file or directory written at ``path`` (from :meth:`path`, or outside the
        staging directory: written in place); returns its destination."""
        path = Path(path)
        if not path.is_relative_to(self.stage):
            # in place on purpose: bifurcation's resumable point store
            self.written.append(path)
            return path
        name = path.relative_to(self.stage).parts[0]
        if name not in self._staged:
            self._staged.append(name)
        return self.directory / name

    def commit(self) -> None:
        """Move every staged file into DIR (replacing files of an earlier run)."""
        if self in _PENDING:
            _PENDING.remove(self)
        if self._stage is None:
            return
        # Check every destination first, so that a clash moves nothing.
        for name in self._staged:
            src, dst = self._stage / name, self.directory / name
            if dst.exists() and dst.is_dir() != src.is_dir():
                kind = "a directory" if dst.is_dir() else "a file"
                self.discard()
                raise CLIError(
                    "--out", f"{dst} is {kind} in the way; no file of this run was written"
                )
        for name in self._staged:
            src, dst = self._stage / name, self.directory / name
            if src.is_dir() and dst.is_dir():
                shutil.rmtree(dst)
            os.replace(src, dst)
            self.written.append(dst)
        shutil.rmtree(self._stage, ignore_errors=True)
        self._stage = None

    def discard(self) -> None:
        """Remove the staging directory and everything in it."""
        if self in _PENDING:
            _PENDING.remove(self)
        if self._stage is not None:
            shutil.rmtree(self._stage, ignore_errors=True)
            self._stage = None

    def json(self, name: str, obj) -> Path:
        from fempipe.io import write_json

        return self.record(write_json(self.path(name), obj))

    def csv(self, name: str, rows, columns=None) -> Path:
        from fempipe.io import write_csv

        return self.record(write_csv(self.path(name), rows, columns))

    def figure(self, name: str, fig, **savefig_kwargs) -> Path:
        """Write ``fig`` (dpi 150 unless given) and close it."""
        import matplotlib.pyplot as plt

        from fempipe.io import write_figure

        try:
            path = write_figure(self.path(name), fig, **({"dpi": 150} | savefig_kwargs))
        finally:
            plt.close(fig)
        return self.record(path)

    def report(self, args: argparse.Namespace) -> None:
        """:meth:`commit`, then ``wrote PATH`` on stderr per file (not with --json or --quiet)."""
        self.commit()
        if getattr(args, "json", False) or getattr(args, "progress", None) is False:
            return
        for path in self.written:
            print(f"wrote {path}", file=sys.stderr)


def describe(result: dict, keys: Sequence[str] = ("alpha", "beta", "gamma", "mu")) -> tuple:
    """``(discretization label, "alpha = ..., beta = ...")`` of a result's heading."""
    p, d = result["params"], result["discretization"]
    if d["kind"] == "fe":
        disc = f"P{d['degree']}:{d['n_elements']}"
    else:
        basis = d.get("basis", "sine")
        disc = f"modal{'' if basis == 'sine' else '-' + basis}:{d['n_modes']}"
    head = ", ".join(f"{k} = {p[k]:.6g}" for k in keys if k in p)
    return disc, head


def cpu_seconds(t0: float) -> float:
    """CPU seconds since ``t0`` (``time.process_time()``), finished worker processes included."""
    t = os.times()
    return time.process_time() - t0 + t.children_user + t.children_system


def deliver(
    args: argparse.Namespace,
    result: dict,
    output: Output | None = None,
    write: Callable[[Output], None] | None = None,
    text: Callable[[], None] | None = None,
) -> None:
    """The end of a command: its files (``write(output)``), JSON or ``text()`` on stdout,
    then the files moved into ``--out`` (:meth:`Output.report`)."""
    from fempipe.io import json_dumps

    if output is None and write is not None and getattr(args, "out", None) is not None:
        output = Output(args.out)
    if output is not None and write is not None:
        write(output)
    if args.json:
        print(json_dumps(result))
    elif text is not None:
        text()
    if output is not None:
        output.report(args)


def agg() -> None:
    """matplotlib without a display (before fempipe.plotting imports pyplot)."""
    import matplotlib

    matplotlib.use("Agg")


def error_columns(rows: Iterable[Mapping]) -> list[str]:
    """CSV columns with ``--error-estimate``: no ``*_refined``, ``error_note``; ``*_error`` last."""
    keys = list(dict.fromkeys(k for row in rows for k in row))
    errors = [k for k in keys if k.endswith(ERROR)]
    return [k for k in keys if not k.endswith((ERROR, REFINED)) and k != "error_note"] + errors


def print_footer(est: Mapping, where: str = "") -> None:
    """How the error estimates were formed, then their notes."""
    print(
        f"± error estimate: {est['method']} to {est['refined']}{where}, {est['formula']} "
        f"(floor: {est['floor']})"
    )
    for note in est["notes"]:
        print(f"note: {note}")


def pm(value, error, spec: str = "{:+.6f}") -> str:
    """``"value ± error"`` (two digits; ``± ?`` without an error)."""
    return f"{spec.format(value)} ± {'?' if error is None else f'{error:.1e}'}"


def value(d: Mapping, key: str, spec: str, with_errors: bool = False) -> str:
    """``d[key]`` formatted by ``spec``, as :func:`pm` with its error estimate when there is one."""
    if with_errors and key + ERROR in d:
        return pm(d[key], d[key + ERROR], spec)
    return spec.format(d[key])


def print_table(columns: Sequence[tuple], rows: Iterable, indent: str = "") -> None:
    """Rows under their headers, each column as wide as its widest cell, two spaces apart.

    ``columns``: ``(header, cell)`` with ``cell(row) -> str``, right-aligned, or
    ``(header, cell, "<")`` left-aligned.
    """
    cells = [[col[1](row) for col in columns] for row in rows]
    widths = [max([len(c[0])] + [len(r[i]) for r in cells]) for i, c in enumerate(columns)]
    aligns = [c[2] if len(c) > 2 else ">" for c in columns]

    def line(texts) -> str:
        parts = [f"{t:{a}{w}}" for t, a, w in zip(texts, aligns, widths, strict=True)]
        return (indent + "  ".join(parts)).rstrip()

    print(line([c[0] for c in columns]))
    for r in cells:
        print(line(r))

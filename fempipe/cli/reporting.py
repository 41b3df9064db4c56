"""What a ``fempipe`` command shows and writes: progress bar, result files, headings."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence
from pathlib import Path

__all__ = ["Output", "describe", "progress"]


def progress(args: argparse.Namespace, total: int | None, desc: str):
    """A tqdm bar on stderr if ``--progress`` (or a terminal without ``--quiet``).

    Use as a context manager; call ``bar.update()`` from the library's
    progress callback.  A disabled bar does nothing.
    """
    from tqdm import tqdm

    show = getattr(args, "progress", None)
    if show is None:
        show = sys.stderr.isatty()
    return tqdm(
        total=total,
        desc=desc,
        file=sys.stderr,
        leave=False,
        dynamic_ncols=True,
        disable=not show,
    )


class Output:
    """The result files of one command in ``--out DIR``, recorded as they are written.

    Every file goes through one of the methods, which write atomically
    (:mod:`fempipe.io`) and record the path, so the "wrote ..." lines of
    :meth:`report` are exactly the files written.

    Parameters
    ----------
    directory : path-like
        The ``--out`` directory.
    """

    def __init__(self, directory) -> None:
        self.directory = Path(directory)
        self.written: list[Path] = []

    def path(self, name: str) -> Path:
        """The destination of ``name``; call :meth:`record` once it is written."""
        return self.directory / name

    def record(self, path) -> Path:
        """Record a path written by another writer (e.g. a GIF, a point store)."""
        path = Path(path)
        self.written.append(path)
        return path

    def json(self, name: str, obj) -> Path:
        from fempipe.io import write_json

        return self.record(write_json(self.path(name), obj))

    def csv(self, name: str, rows, columns=None) -> Path:
        from fempipe.io import write_csv

        return self.record(write_csv(self.path(name), rows, columns))

    def figure(self, name: str, fig, **savefig_kwargs) -> Path:
        from fempipe.io import write_figure

        return self.record(write_figure(self.path(name), fig, **savefig_kwargs))

    def report(self, args: argparse.Namespace) -> None:
        """``wrote PATH`` on stderr for each file, unless ``--json`` or ``--quiet``."""
        if getattr(args, "json", False) or getattr(args, "progress", None) is False:
            return
        for path in self.written:
            print(f"wrote {path}", file=sys.stderr)


def describe(result: dict, keys: Sequence[str] = ("alpha", "beta", "gamma", "mu")) -> tuple:
    """``(discretisation label, "alpha = ..., beta = ...")`` for a table heading.

    ``result`` is a subcommand's JSON dict with ``params`` and ``discretization``.
    """
    p, d = result["params"], result["discretization"]
    disc = f"P{d['degree']}:{d['n_elements']}" if d["kind"] == "fe" else f"modal:{d['n_modes']}"
    head = ", ".join(f"{k} = {p[k]:.6g}" for k in keys if k in p)
    return disc, head

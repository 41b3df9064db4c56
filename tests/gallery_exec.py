"""Run a gallery example or a course lesson the way sphinx-gallery runs it, and as a script.

sphinx-gallery executes a script's code in a fresh module named ``__main__`` that it puts in
``sys.modules`` for the time of the run, with the Agg backend and without ``__file__``
(sphinx_gallery.gen_rst: "Don't ever support __file__"), so the scripts' final
``show_or_save()`` leaves the figures to the gallery.  Run by ``python``, the same script
has ``__file__`` and writes them.
"""

from __future__ import annotations

import importlib.util
import os
import subprocess
import sys
from pathlib import Path


def run_like_sphinx_gallery(path: Path) -> dict:
    """Execute ``path`` as sphinx-gallery does; its globals.  The caller sets the backend
    and the working directory."""
    spec = importlib.util.spec_from_loader("__main__", None)
    main = importlib.util.module_from_spec(spec)
    main.__dict__["__doc__"] = ""
    code = compile(path.read_text(encoding="utf-8"), str(path), "exec")
    saved_main, saved_argv = sys.modules["__main__"], sys.argv[:]
    sys.modules["__main__"], sys.argv = main, [str(path)]
    try:
        exec(code, main.__dict__)
    finally:
        sys.modules["__main__"], sys.argv = saved_main, saved_argv
    return main.__dict__


def run_as_script(path: Path, cwd: Path, **env: str) -> subprocess.CompletedProcess:
    """``python path`` in ``cwd`` on the Agg backend (no display), with ``env`` added."""
    environ = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "FEMPIPE_FIGURES")}
    environ.update(MPLBACKEND="Agg", **env)
    return subprocess.run(
        [sys.executable, str(path)],
        cwd=cwd,
        env=environ,
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )

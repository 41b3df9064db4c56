"""The figures of a gallery example or a course lesson run as a script.

Every ``examples/plot_*.py`` and ``docs/course/lesson_*.py`` ends with :func:`show_or_save`:
from a terminal it shows the figures, without a display it writes PNG files, and under
sphinx-gallery or in a notebook (no ``__file__``) it does nothing.
"""

from __future__ import annotations

import os
import sys
from pathlib import Path

__all__ = ["NON_INTERACTIVE", "show_or_save"]

#: matplotlib's backends that draw into files only (``backend_registry``'s non-interactive list)
NON_INTERACTIVE = frozenset({"agg", "cairo", "pdf", "pgf", "ps", "svg", "template"})


def show_or_save(script: str | os.PathLike | None = None, *, dpi: int = 100) -> None:
    """Show the open figures, or save them as PNG files.

    Parameters
    ----------
    script : str or path-like, optional
        The running script; by default the caller's ``__file__`` (none: nothing happens).
    dpi : int
        Resolution of the saved files.

    Figure k goes to ``<stem>-figures/<stem>_<k>.png`` (or ``$FEMPIPE_FIGURES``).  Nothing is
    returned, which Jupyter would display.
    """
    if script is None:
        script = sys._getframe(1).f_globals.get("__file__")
    if script is None:
        return
    import matplotlib
    import matplotlib.pyplot as plt

    numbers = plt.get_fignums()
    if not numbers:
        return
    if matplotlib.get_backend().lower() not in NON_INTERACTIVE:
        plt.show()  # a window, or inline in IPython's %run
        return
    stem = Path(script).stem
    out = Path(os.environ.get("FEMPIPE_FIGURES") or f"{stem}-figures")
    out.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, number in enumerate(numbers, start=1):
        path = out / f"{stem}_{k}.png"
        plt.figure(number).savefig(path, dpi=dpi)
        paths.append(path)
    print(f"wrote {len(paths)} figure{'s' * (len(paths) > 1)}: {', '.join(map(str, paths))}")

"""The figures of a gallery example or a course lesson run as a script.

Every ``examples/plot_*.py`` and ``docs/course/lesson_*.py`` ends with
:func:`show_or_save`: run from a terminal (``python docs/course/lesson_02_...py``) the
script opens its figures in a window, or, without a display (the Agg backend), writes them
as PNG files and says where.  Under sphinx-gallery, which captures the figures itself, and
in a notebook, which shows them inline, it does nothing: neither defines ``__file__``
(sphinx-gallery runs the code in a module of its own without it), and a script run by
``python`` always does.
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
        The running script; by default the caller's ``__file__``.  Without one (under
        sphinx-gallery, in a notebook) nothing happens.
    dpi : int
        Resolution of the saved files.

    Notes
    -----
    The k-th open figure is written as ``<stem>-figures/<stem>_<k>.png`` in the working
    directory (``<stem>`` the script's name without ``.py``), or into the directory named by
    the environment variable ``FEMPIPE_FIGURES`` if it is set, and the files are printed.
    Nothing is returned: the call ends the scripts, where sphinx-gallery and Jupyter would
    display a returned value.
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

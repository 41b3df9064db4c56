"""The literate finite-element tutorial now lives in the course: ``docs/course/``.

"FEM for slender structures, on this pipe" (``docs/course/GALLERY_HEADER.rst``): the weak
form (lesson 1), Lagrange elements in scikit-fem and a static solver in forty lines
(lesson 2), the integration operators on Gauss points, their adjointness and the mass matrix
as a Gram matrix (lesson 3), Newton and continuation (4), eigenproblems and flutter (5),
implicit time integration (6), and the convergence of finite elements against modes (7).
Each lesson is a percent-format script (``# %%`` cells) that runs on its own.

This script runs lesson 7 and writes its convergence plot, as the tutorial did:

    python validation/tutorial.py [--out DIR]

(default DIR: ``validation/``, where git ignores ``tutorial_convergence.png``).
"""

from __future__ import annotations

import argparse
from pathlib import Path

LESSON = Path(__file__).resolve().parents[1] / "docs" / "course" / "lesson_07_modal_vs_fe.py"


def main() -> None:
    """Run lesson 7 (it prints its study) and save its figure into ``--out``."""
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).parent), help="directory for the PNG")
    args = parser.parse_args()
    import matplotlib

    matplotlib.use("Agg")
    # as sphinx-gallery runs it, without __file__: the lesson's show_or_save() then leaves
    # the figure to this script instead of writing it into the working directory
    lesson = {"__name__": "__main__"}
    exec(compile(LESSON.read_text(encoding="utf-8"), str(LESSON), "exec"), lesson)
    out = Path(args.out) / "tutorial_convergence.png"
    out.parent.mkdir(parents=True, exist_ok=True)
    lesson["fig"].savefig(out, dpi=120)
    print(f"\nwrote {out}")


if __name__ == "__main__":
    main()

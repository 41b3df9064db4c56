"""Regenerate the images of the figure review (validation/figure-review/README.md).

The images are not kept in git; this script draws them:

* the "after" set, ``after_*.png`` and ``after_pipe.gif``: the command-line
  figures drawn by the code of this working tree;
* with ``--before REV``, the "before" set, ``before_*``: the same command-line
  figures drawn by the code of git revision REV (checked out in a temporary
  ``git worktree``, removed afterwards), and the report figures committed at
  REV (``validation/report/*.png``), copied as they are.

The command-line figures come from

    fempipe static   --alpha pi/2 --v 0:10:11             shapes.png
    fempipe spectrum --alpha pi --v 0:6:31 --modal 4      argand.png
    fempipe simulate --alpha 0 --v 10 --modal 4           time_traces.png, phase_portrait.png,
                                                          oscillating_shapes.png, pipe.gif

each run with ``--out`` in a temporary directory, in a fresh python with the
tree on ``PYTHONPATH`` (nothing of fempipe is imported here).  The first and
last frames of each animation are saved as ``*_pipe_gif_frame0.png`` and
``*_pipe_gif_last.png``.  About a minute per set on one core.

Examples
--------
    python validation/figure_review.py                     # after_* from this tree
    python validation/figure_review.py --before f17f72a    # and before_* from the review's base
    python validation/figure_review.py --only before --before f17f72a --out /tmp/review
"""

from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
REPO = HERE.parent
#: The revision the review started from (the README's "before").
REVIEW_BASE = "f17f72a"

#: (arguments of ``fempipe``, the figures it writes into --out).
COMMANDS: tuple[tuple[list[str], tuple[str, ...]], ...] = (
    (["static", "--alpha", "pi/2", "--v", "0:10:11"], ("shapes.png",)),
    (["spectrum", "--alpha", "pi", "--v", "0:6:31", "--modal", "4"], ("argand.png",)),
    (
        ["simulate", "--alpha", "0", "--v", "10", "--modal", "4"],
        ("time_traces.png", "phase_portrait.png", "oscillating_shapes.png", "pipe.gif"),
    ),
)

#: Runs ``fempipe.cli.main`` of whichever tree is first on PYTHONPATH.
_MAIN = "import sys; from fempipe.cli import main; sys.exit(main(sys.argv[1:]))"


def command_figures(tree: Path, prefix: str, out: Path) -> list[Path]:
    """Run :data:`COMMANDS` with the code of ``tree``; copy their figures as ``out/prefix_NAME``."""
    written = []
    with tempfile.TemporaryDirectory(prefix="fempipe-figure-review-") as tmp:
        for args, names in COMMANDS:
            dest = Path(tmp) / args[0]
            cmd = [sys.executable, "-c", _MAIN, *args, "--out", str(dest)]
            env = {**os.environ, "PYTHONPATH": str(tree), "MPLBACKEND": "Agg"}
            print(f"{prefix}: fempipe {' '.join(args)}", flush=True)
            res = subprocess.run(cmd, cwd=tmp, env=env, capture_output=True, text=True)
            if res.returncode != 0:
                sys.exit(f"fempipe {' '.join(args)} failed:\n{res.stderr}")
            for name in names:
                target = out / f"{prefix}_{name}"
                shutil.copyfile(dest / name, target)
                written.append(target)
                if name.endswith(".gif"):
                    written += gif_frames(target, out / f"{prefix}_{name.replace('.', '_')}")
    return written


def gif_frames(gif: Path, stem: Path) -> list[Path]:
    """The first and the last frame of ``gif`` as ``{stem}_frame0.png``, ``{stem}_last.png``."""
    from PIL import Image

    out = []
    with Image.open(gif) as im:
        for index, suffix in ((0, "frame0"), (im.n_frames - 1, "last")):
            im.seek(index)
            path = Path(f"{stem}_{suffix}.png")
            im.convert("RGB").save(path)
            out.append(path)
    return out


def report_figures(rev: str, out: Path) -> list[Path]:
    """The report figures committed at ``rev`` (``validation/report/*.png``) as ``before_NAME``."""
    names = _git("ls-tree", "--name-only", rev, "validation/report/").split()
    written = []
    for name in (n for n in names if n.endswith(".png")):
        target = out / f"before_{Path(name).name}"
        target.write_bytes(_git_bytes("show", f"{rev}:{name}"))
        written.append(target)
    return written


def before_set(rev: str, out: Path) -> list[Path]:
    """The command-line figures of ``rev`` (in a temporary git worktree) and its report figures."""
    with tempfile.TemporaryDirectory(prefix="fempipe-review-tree-") as tmp:
        tree = Path(tmp) / "tree"
        _git("worktree", "add", "--detach", str(tree), rev)
        try:
            written = command_figures(tree, "before", out)
        finally:
            _git("worktree", "remove", "--force", str(tree))
    return written + report_figures(rev, out)


def _git(*args: str) -> str:
    return _git_bytes(*args).decode()


def _git_bytes(*args: str) -> bytes:
    return subprocess.run(["git", "-C", str(REPO), *args], check=True, capture_output=True).stdout


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=HERE / "figure-review",
        help="destination (default: %(default)s)",
    )
    parser.add_argument(
        "--before",
        metavar="REV",
        help=f"also draw the before set from this git revision (the review's: {REVIEW_BASE})",
    )
    parser.add_argument(
        "--only", choices=("after", "before"), help="draw one set only (before needs --before)"
    )
    args = parser.parse_args(argv)
    if args.only == "before" and not args.before:
        parser.error("--only before needs --before REV")
    args.out.mkdir(parents=True, exist_ok=True)
    written = []
    if args.only != "before":
        written += command_figures(REPO, "after", args.out)
    if args.before and args.only != "after":
        written += before_set(args.before, args.out)
    for path in written:
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())

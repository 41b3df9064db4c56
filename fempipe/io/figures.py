"""Figures and animations written atomically."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from fempipe.core.files import atomic_path

__all__ = ["write_figure", "write_gif"]


def write_figure(path: str | os.PathLike, fig, **savefig_kwargs) -> Path:
    """``fig.savefig`` atomically; the format follows the suffix of ``path``."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_kwargs)
    return Path(path)


def write_gif(path: str | os.PathLike, frames: Sequence, fps: float = 20) -> Path:
    """An animated GIF of RGBA frames (PIL images), looping, atomically.

    Encoded as matplotlib's ``PillowWriter`` encodes the frames it grabs:
    an opaque frame is converted to RGB (Pillow then quantizes it to an
    adaptive palette of its own), a frame with transparency is kept as RGBA,
    every frame lasts ``int(1000 / fps)`` ms and the GIF loops forever.  The
    same frames therefore give the same file as
    ``FuncAnimation.save(path, writer=PillowWriter(fps=fps))``.

    Raises
    ------
    ValueError
        Without frames (nothing is written).
    """
    if not frames:
        raise ValueError("an animation needs at least one frame")
    images = []
    for im in frames:
        if im.mode == "RGBA" and im.getextrema()[3][0] == 255:
            im = im.convert("RGB")
        images.append(im)
    with atomic_path(path) as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(1000 / fps),
            loop=0,
        )
    return Path(path)

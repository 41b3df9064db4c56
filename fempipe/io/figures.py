"""Figures and animations written atomically."""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from fempipe.core.files import atomic_path

__all__ = ["write_figure", "write_gif", "quantize_frames"]


def write_figure(path: str | os.PathLike, fig, **savefig_kwargs) -> Path:
    """``fig.savefig`` atomically; the format follows the suffix of ``path``."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_kwargs)
    return Path(path)


def write_gif(path: str | os.PathLike, frames: Sequence, fps: float = 20) -> Path:
    """An animated GIF of RGBA frames (PIL images), looping, ``int(1000 / fps)`` ms a frame,
    atomically; ValueError without frames.

    Opaque frames share one palette (:func:`quantize_frames`): a palette per frame is most of
    the cost.  Frames with transparency are encoded as matplotlib's ``PillowWriter`` does.
    """
    if not frames:
        raise ValueError("an animation needs at least one frame")
    images = quantize_frames(frames)
    options = {"optimize": False}
    if images is None:
        # PillowWriter: a frame with transparency as it is, an opaque one as RGB.
        images = [im if im.getextrema()[3][0] < 255 else im.convert("RGB") for im in frames]
        options = {}
    with atomic_path(path) as tmp:
        images[0].save(
            tmp,
            format="GIF",
            save_all=True,
            append_images=images[1:],
            duration=int(1000 / fps),
            loop=0,
            **options,
        )
    return Path(path)


def quantize_frames(frames: Sequence) -> list | None:
    """Opaque frames (PIL) on the first frame's adaptive palette; None if one is transparent."""
    import numpy as np
    from PIL import Image

    first = frames[0].convert("RGB").convert("P", palette=Image.Palette.ADAPTIVE)
    raw_palette = first.getpalette()
    palette = np.array(raw_palette, dtype=np.int64).reshape(-1, 3)
    # A color as the 24-bit integer R + 256 G + 65536 B (the RGBA bytes read as
    # one little-endian word, alpha masked); the table maps it to its palette index.
    table = np.zeros(1 << 24, dtype=np.uint8)
    known = np.zeros(1 << 24, dtype=bool)
    out = []
    for im in frames:
        rgba = np.ascontiguousarray(np.asarray(im if im.mode == "RGBA" else im.convert("RGBA")))
        word = rgba.view("<u4")[..., 0]
        if word.min() < 0xFF000000:  # alpha < 255 somewhere
            return None
        color = word & 0xFFFFFF
        new = color[~known[color]]
        if new.size:
            new = np.unique(new)
            rgb = np.stack([new & 255, (new >> 8) & 255, new >> 16], axis=1).astype(np.int64)
            dist = ((rgb[:, None, :] - palette[None, :, :]) ** 2).sum(axis=2)
            table[new] = dist.argmin(axis=1)
            known[new] = True
        p = Image.fromarray(table[color], mode="P")
        p.putpalette(raw_palette)
        out.append(p)
    return out

"""Figures written atomically."""

from __future__ import annotations

import os
from pathlib import Path

from fempipe.core.files import atomic_path

__all__ = ["write_figure"]


def write_figure(path: str | os.PathLike, fig, **savefig_kwargs) -> Path:
    """``fig.savefig`` atomically; the format follows the suffix of ``path``."""
    fmt = Path(path).suffix.lstrip(".") or "png"
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format=fmt, **savefig_kwargs)
    return Path(path)

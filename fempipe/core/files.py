"""Writing files atomically, and strict JSON.

Every writer writes a temporary file in the destination directory and moves it into place
(:func:`os.replace`), so no reader sees a half-written file.  JSON is strict: numpy types
converted, NaN/inf as ``null``.  In the core because the analyses persist resumable point
stores with them; :mod:`fempipe.io` re-exports them.
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import tempfile
from collections.abc import Iterator, Mapping
from pathlib import Path

import numpy as np

__all__ = ["atomic_path", "to_jsonable", "json_dumps", "write_text", "write_json"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path`` (same suffix); move it onto ``path`` on success,
    remove it on an exception.

    Examples
    --------
    >>> with atomic_path("out/fig.png") as tmp:   # doctest: +SKIP
    ...     fig.savefig(tmp)
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        # mkstemp makes the file private (0600); give it the usual permissions.
        os.chmod(tmp_path, 0o666 & ~_umask())
        os.replace(tmp_path, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            tmp_path.unlink()
        raise


def _umask() -> int:
    """The process's file-creation mask (read by setting it and setting it back)."""
    mask = os.umask(0)
    os.umask(mask)
    return mask


def to_jsonable(obj):
    """Recursively convert for strict JSON: mappings to dicts with string keys, tuples and arrays
    to lists, numpy scalars to Python, NaN and +-inf to ``None``, paths to ``str``, objects with
    ``to_dict()`` to that dict.  The package's one JSON sanitiser.
    """
    if isinstance(obj, Mapping):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if isinstance(obj, (bool, np.bool_)):
        return bool(obj)
    if isinstance(obj, (int, np.integer)):
        return int(obj)
    if isinstance(obj, (float, np.floating)):
        x = float(obj)
        return x if math.isfinite(x) else None
    if isinstance(obj, np.generic):  # other numpy scalars (str_, complex, ...)
        return to_jsonable(obj.item())
    if isinstance(obj, Path):
        return str(obj)
    if hasattr(obj, "to_dict"):
        return to_jsonable(obj.to_dict())
    return obj


def json_dumps(obj, indent: int | None = 2) -> str:
    """``json.dumps`` of :func:`to_jsonable` (strict: no NaN literals)."""
    return json.dumps(to_jsonable(obj), indent=indent, allow_nan=False)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` atomically (UTF-8)."""
    with atomic_path(path) as tmp:
        tmp.write_text(text, encoding="utf-8")
    return Path(path)


def write_json(path: str | os.PathLike, obj) -> Path:
    """Write ``obj`` as indented strict JSON, atomically."""
    return write_text(path, json_dumps(obj) + "\n")

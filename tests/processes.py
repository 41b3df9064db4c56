"""Process helpers of the signal and orphan tests (Linux /proc)."""

from __future__ import annotations

from pathlib import Path

import pytest

needs_proc = pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="needs /proc")


def _state_and_parent(stat: Path) -> tuple[str, int]:
    # The command name in parentheses may hold spaces: split after its ")".
    fields = stat.read_text().rsplit(")", 1)[1].split()
    return fields[0], int(fields[1])


def alive(pid: int) -> bool:
    """True while ``pid`` runs (a zombie awaiting its reaper counts as gone)."""
    try:
        return _state_and_parent(Path(f"/proc/{pid}/stat"))[0] != "Z"
    except FileNotFoundError:
        return False


def children(pid: int) -> list[int]:
    """Pids of the running child processes of ``pid``."""
    out = []
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            state, parent = _state_and_parent(stat)
        except (FileNotFoundError, ProcessLookupError):
            continue
        if parent == pid and state != "Z":
            out.append(int(stat.parent.name))
    return out

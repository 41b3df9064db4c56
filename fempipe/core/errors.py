"""Exception types shared by the solvers and the command line.

Every numerical failure (Newton, time integration, shooting) derives from
:class:`SolverError`, so the ``fempipe`` command catches them once; bad input derives from
:class:`ValueError`, and :class:`ParamError` names the wrong parameter.
"""

from __future__ import annotations

__all__ = ["ParamError", "PointStoreMismatchError", "SolverError"]


class SolverError(RuntimeError):
    """A solver failed to produce a result it could vouch for; ``str()`` says which solver,
    where (the parameters) and why, the subclasses carry the details as attributes."""


class ParamError(ValueError):
    """A physical parameter outside its allowed range; ``field`` names it (``"gamma"``, ``"v"``,
    ...) so that a caller can point at the input without parsing ``message``."""

    def __init__(self, field: str, message: str) -> None:
        super().__init__(message)
        self.field = field


class PointStoreMismatchError(ParamError):
    """A point store (a resumable run's directory) of another run: ``field`` is ``"store_dir"``,
    ``differences`` the keys of ``run.json`` that differ (``["options.rtol"]``) or a point."""

    def __init__(self, directory, differences: list[str]) -> None:
        super().__init__(
            "store_dir",
            f"point store {directory} holds a different run (differs in: "
            f"{', '.join(differences)}); use another directory or delete it",
        )
        self.differences = list(differences)

"""What the pseudo-arclength engine asks of a problem and of its policies.

A one-parameter problem is a curve of zeros of F: R^(m+1) -> R^m in y = (x, lambda).  The
engine (:func:`fempipe.solvers.continuation.continue_curve`) needs two protocols:
:class:`ContinuationProblem` (F, its derivatives, the bordered solve of Keller's method, the
inner product of arclength) and :class:`ContinuationPolicy` (the algorithmic choices of one
kind of branch; :class:`fempipe.solvers.continuation.KellerPolicy` is the textbook one).

The bordered system: docs/theory/numerics.md; the protocol: docs/development.md, "The
continuation engine's protocol".
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable

import numpy as np

from fempipe.core.errors import SolverError


class CorrectorError(Exception):
    """A step failed (no convergence, or a failed integration); the engine asks for a shorter one."""


class SharpTurnError(CorrectorError):
    """The corrected point was refused because the curve turned too sharply
    from the last tangent: the corrector may have jumped to another branch."""


class ContinuationError(SolverError):
    """A curve could not be continued: the step fell below its minimum."""


@dataclass(frozen=True)
class BorderedSolution:
    """The solution z (shape (m + 1,)) of a bordered system and, if asked, ``det_sign`` (flips at
    a simple branch point, not at a fold) and ``log_abs_det`` of the bordered matrix.
    """

    z: np.ndarray
    det_sign: int | None = None
    log_abs_det: float | None = None


@runtime_checkable
class ContinuationProblem(Protocol):
    """A curve F(y) = 0 in R^(m+1), y = (x, lambda), lambda last, as the engine sees it."""

    def residual(self, y: np.ndarray) -> np.ndarray:
        """F(y), shape (m,)."""

    def derivatives(self, y: np.ndarray) -> Any:
        """F_x and F_lambda at y, in whatever form :meth:`solve_bordered` takes
        (dense or sparse matrices, a monodromy matrix and its companions ...)."""

    def solve_bordered(
        self, lin: Any, row: np.ndarray | None, rhs: np.ndarray, *, determinant: bool = False
    ) -> BorderedSolution:
        """Solve ``[[F_x, F_lambda], [row]] z = rhs`` (``row`` None: ``F_x z = rhs``); with
        ``determinant``, also sign and log|det| of the bordered matrix."""

    def inner(self, a: np.ndarray, b: np.ndarray) -> float:
        """The inner product of arclength, <a, b>."""

    def dual(self, t: np.ndarray) -> np.ndarray:
        """The row vector of the linear form ``z -> <t, z>``."""


class ContinuationPolicy(Protocol):
    """The algorithmic choices of one kind of branch; the engine hands back the *step* of
    :meth:`predict` and the *point* of :meth:`correct`, :meth:`land`; the policy keeps the branch."""

    def stop_before(self) -> str | None:
        """Why the branch ends before the next step (e.g. ``max_steps``), or None."""

    def predict(self, h: float) -> Any:
        """The predictor for a step of arclength ``h``."""

    def correct(self, step: Any) -> Any:
        """The corrected point of ``step``; raises :class:`CorrectorError`."""

    def accept(self, step: Any, point: Any) -> None:
        """Refuse ``point`` by raising :class:`SharpTurnError` (or :class:`CorrectorError`)."""

    def reject(self, step: Any, h: float, failure: CorrectorError) -> float:
        """The shorter step after a failure; raises when it falls below the minimum."""

    def land(self, step: Any, point: Any) -> Any:
        """The point to keep: ``point``, or the point landed on a requested
        parameter value that the step passed."""

    def detect(self, step: Any, point: Any) -> None:
        """Locate special points between the last point and ``point``."""

    def append(self, point: Any) -> None:
        """Add ``point`` to the branch."""

    def next_step(self, step: Any, point: Any, h: float) -> float:
        """The step length after an accepted step."""

    def notify(self, point: Any, h: float) -> None:
        """Report progress (callbacks, logging, a resumable state)."""

    def stop_after(self, step: Any, point: Any) -> str | None:
        """Why the branch ends after ``point``, or None."""

    def finish(self, reason: str, h: float) -> Any:
        """The result of the run, the branch ended for ``reason``."""

"""A user's numbers against fempipe: each value beside fempipe's and fempipe's error estimate.

A user's value of a :class:`~fempipe.studies.convergence.Quantity` is set beside fempipe's on
one discretization, with fempipe's error estimated from one refinement
(:mod:`fempipe.studies.error_estimate`).  The difference is **resolved** when it exceeds that
estimate: fempipe's discretization error cannot explain it.  A comparison whose computation
fails keeps its message.  docs/cli/commands.md, "fempipe compare".
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from fempipe.core.errors import SolverError
from fempipe.core.parallel import run_tasks
from fempipe.model.params import Params

from .convergence import CRITICAL_QUANTITIES, CYCLE_QUANTITIES, PARAMETRIC_QUANTITIES, Quantity
from .error_estimate import describe, estimate, expected_order, refine, refinement_ratio

__all__ = [
    "COMPARABLE",
    "Comparison",
    "Evaluation",
    "compare_values",
    "estimate_description",
    "evaluate",
]

#: The real quantities a user's value can be compared for (``fempipe compare`` compares
#: ``v_cr`` and ``frequency`` with the planar model's, ``Quantity(planar=True)``).
COMPARABLE = (
    "v_cr",
    "frequency",
    "theta_tip",
    "X_tip",
    "Z_tip",
    "eta_tip",
    "lc_amplitude",
    "lc_period",
    "v_cr_in_plane",
    "v_cr_out_of_plane",
    "frequency_in_plane",
    "frequency_out_of_plane",
    *PARAMETRIC_QUANTITIES,
)


@dataclass(frozen=True)
class Evaluation:
    """fempipe's ``value`` of a quantity, its ``refined`` value (None if that failed), the
    ``error_estimate`` (floor ``Quantity.tolerance * max(1, |value|)``), a ``note`` on a
    missing estimate and the ``cpu_time`` of both."""

    value: float
    refined: float | None
    error_estimate: float | None
    note: str | None = None
    cpu_time: float = 0.0


def evaluate(quantity: Quantity, disc) -> Evaluation:
    """The quantity on ``disc`` and on ``refine(disc)``, and the error estimate of the first.

    A limit cycle found on ``disc`` seeds the refined shooting.  Raises SolverError if the
    value on ``disc`` fails (a refined failure is the :attr:`Evaluation.note`).
    """
    t0 = time.process_time()
    if quantity.name in CYCLE_QUANTITIES:
        quantity = quantity.seeded(disc)
    value = float(quantity(disc))
    fine = refine(disc)
    try:
        refined: float | None = float(quantity(fine))
    except (SolverError, ValueError) as exc:
        refined, note = None, f"no error estimate: the refined run on {fine.name} failed: {exc}"
    else:
        note = None
    err = None
    if refined is not None:
        floor = quantity.tolerance * max(1.0, abs(value))
        order = expected_order(disc, quantity.params)
        err = float(estimate(value, refined, order, refinement_ratio(disc), floor=floor))
    return Evaluation(value, refined, err, note, time.process_time() - t0)


@dataclass(frozen=True)
class Comparison:
    """A user's value of ``quantity`` beside fempipe's ``evaluation`` (None, with the
    ``failure`` message, if the computation failed)."""

    quantity: Quantity
    user: float
    evaluation: Evaluation | None
    failure: str | None = None

    @property
    def fempipe(self) -> float | None:
        """fempipe's value on the reported discretization (None if it failed)."""
        return None if self.evaluation is None else self.evaluation.value

    @property
    def difference(self) -> float | None:
        """user - fempipe."""
        return None if self.fempipe is None else self.user - self.fempipe

    @property
    def relative_difference(self) -> float | None:
        """``(user - fempipe) / |fempipe|``; None where fempipe's value is 0 or missing."""
        if self.fempipe is None or self.fempipe == 0.0:
            return None
        return self.difference / abs(self.fempipe)

    @property
    def error_estimate(self) -> float | None:
        """fempipe's error estimate (None without a refined value)."""
        return None if self.evaluation is None else self.evaluation.error_estimate

    @property
    def resolved(self) -> bool | None:
        """``|user - fempipe|`` > fempipe's error estimate; None without an estimate."""
        if self.difference is None or self.error_estimate is None:
            return None
        return bool(abs(self.difference) > self.error_estimate)

    def to_dict(self) -> dict:
        """The JSON row of ``fempipe compare``."""
        ev = self.evaluation
        return {
            "quantity": self.quantity.name,
            "user": self.user,
            "fempipe": self.fempipe,
            "difference": self.difference,
            "relative_difference": self.relative_difference,
            "error_estimate": self.error_estimate,
            "resolved": self.resolved,
            "refined": None if ev is None else ev.refined,
            "failure": self.failure,
            "note": None if ev is None else ev.note,
            "cpu_time": None if ev is None else ev.cpu_time,
        }


def compare_values(
    pairs: Sequence[tuple[Quantity, float]],
    disc,
    *,
    workers: int | None = None,
    callback: Callable[[int, int], None] | None = None,
) -> list[Comparison]:
    """Compare each user's value with fempipe's (:func:`evaluate`), in order.

    A SolverError or ValueError of a computation is that comparison's ``failure``.

    Parameters
    ----------
    pairs : sequence of (Quantity, float)
        What to compute and the user's value of it.
    disc : FiniteElement or Modal
        The reported discretization.
    workers : int, optional
        Processes (:func:`fempipe.core.parallel.run_tasks`).
    callback : callable, optional
        ``callback(done, total)`` as each comparison finishes.
    """
    for q, _ in pairs:
        if q.name not in COMPARABLE:
            raise ValueError(f"{q.name} cannot be compared; the quantities are {COMPARABLE}")
    results = run_tasks(
        evaluate,
        [(q, disc) for q, _ in pairs],
        workers=workers,
        callback=None if callback is None else (lambda done, total, _r: callback(done, total)),
    )
    out = []
    for (q, user), r in zip(pairs, results, strict=True):
        if isinstance(r, SolverError | ValueError):
            out.append(Comparison(q, float(user), None, " ".join(str(r).split())))
        elif isinstance(r, BaseException):
            raise r
        else:
            out.append(Comparison(q, float(user), r))
    return out


def estimate_description(
    disc, quantities: Sequence[str] = COMPARABLE, shoot_rtol: float = 1e-9
) -> dict:
    """The top-level ``"error_estimate"`` of a comparison: the method of ``disc`` with the
    ``floors`` (:attr:`Quantity.tolerance` of each quantity) and the ``resolved`` criterion."""
    floors = {}
    for name in quantities:
        kw = {"v_max": 1.0} if name in CRITICAL_QUANTITIES else {}
        if name in PARAMETRIC_QUANTITIES:
            kw = {"omega_band": (1.0, 2.0)}
        floors[name] = Quantity(name, Params(), shoot_rtol=shoot_rtol, **kw).tolerance
    thresholds = set(quantities) & set(PARAMETRIC_QUANTITIES)
    text = (
        "the solver tolerance of the quantity times max(1, |Q|): "
        + ", ".join(f"{k} {v:.0e}" for k, v in floors.items())
        + " (Newton's 1e-12 on static states, events located to 1e-10 in v, 10 x the "
        "shooting tolerance of limit cycles"
        + (", parametric thresholds located to 1e-11 in sigma)" if thresholds else ")")
    )
    info = describe(disc, floor=text).to_dict()
    info["floors"] = floors
    info["resolved"] = (
        "|difference| > error_estimate: fempipe's discretization error cannot explain the "
        "difference"
    )
    return info

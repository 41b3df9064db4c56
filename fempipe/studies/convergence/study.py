"""The convergence study: every member of every family, the reference, the fitted orders.

:func:`run_study` and its result :class:`ConvergenceStudy` (the JSON of
``fempipe convergence``); how the reference is formed: docs/cli/commands.md, "fempipe
convergence".
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.core.parallel import run_tasks, single_blas_thread

from .orders import estimate_order, extrapolate, local_orders
from .quantities import Family, Quantity

__all__ = ["ORDER_BAND", "Series", "Reference", "ConvergenceStudy", "run_study"]

#: Half-width of the band about the theoretical order inside which an observed order counts as
#: asymptotic (:attr:`Series.order_verdict`): the spread of P3's observed orders about 6 on
#: the validation suite's meshes (its convergence cases' tolerance).
ORDER_BAND = 0.5


@dataclass(frozen=True)
class Series:
    """One family's members: sizes ``n``, ``dofs``, ``values`` (NaN where ``failures``
    holds the message), ``errors`` against the reference, the ``observed_order`` in dofs fitted
    on the points ``fit``, and the Richardson value of the finest two members."""

    family: str
    n: np.ndarray
    dofs: np.ndarray
    values: np.ndarray
    errors: np.ndarray
    observed_order: float
    fit: tuple[int, ...]
    expected_order: float | None
    extrapolated: complex | float | None = None
    extrapolation_error: float | None = None
    failures: dict = field(default_factory=dict)
    cpu_time: float = 0.0

    @property
    def order_verdict(self) -> str | None:
        """Where the observed order lies against the theory's band, expected_order +-
        :data:`ORDER_BAND`: ``"asymptotic"`` (inside), ``"pre-asymptotic"`` (below: the
        meshes are too coarse, or a reference error), ``"super-convergent"`` (above); None
        without a theory or an observed order."""
        if self.expected_order is None or not np.isfinite(self.observed_order):
            return None
        gap = self.observed_order - self.expected_order
        if abs(gap) <= ORDER_BAND:
            return "asymptotic"
        return "pre-asymptotic" if gap < 0 else "super-convergent"

    def to_dict(self) -> dict:
        return {
            "family": self.family,
            "n": [int(x) for x in self.n],
            "dofs": [int(x) for x in self.dofs],
            "values": [_number(x) for x in self.values],
            "errors": [_number(x) for x in self.errors],
            "observed_order": _number(self.observed_order),
            "expected_order": self.expected_order,
            "order_verdict": self.order_verdict,
            "fit_points": [int(self.n[i]) for i in self.fit],
            "local_orders": [_number(x) for x in local_orders(self.dofs, self.values)],
            "extrapolated": None if self.extrapolated is None else _number(self.extrapolated),
            "extrapolation_error": self.extrapolation_error,
            "failures": {str(int(self.n[i])): msg for i, msg in self.failures.items()},
            "cpu_time": self.cpu_time,
        }


@dataclass(frozen=True)
class Reference:
    """The reference value of a study and how it was formed."""

    value: complex | float
    error_estimate: float
    method: str
    family: str | None
    independent: tuple[dict, ...] = ()

    def to_dict(self) -> dict:
        return {
            "value": _number(self.value),
            "error_estimate": float(self.error_estimate),
            "method": self.method,
            "family": self.family,
            "independent": [dict(d, value=_number(d["value"])) for d in self.independent],
        }


@dataclass(frozen=True)
class ConvergenceStudy:
    """Result of :func:`run_study`."""

    quantity: Quantity | Callable
    reference: Reference
    series: tuple[Series, ...]
    fit_floor: float
    cpu_time: float

    def to_dict(self) -> dict:
        """The contract of ``fempipe convergence --json`` (see the docs)."""
        q = self.quantity
        out = {
            "quantity": getattr(q, "name", None),
            "quantity_details": q.to_dict() if isinstance(q, Quantity) else None,
            "reference": self.reference.to_dict(),
            "series": [s.to_dict() for s in self.series],
            "fit_floor": self.fit_floor,
            "params": None,
            "cpu_time": self.cpu_time,
        }
        if isinstance(q, Quantity):
            out["params"] = q.params.to_dict()
            out["params"].pop("v", None)
        return out


def _number(x):
    """JSON form: float, ``[re, im]`` for complex, None for NaN."""
    if isinstance(x, complex | np.complexfloating):
        if not np.isfinite(x):
            return None
        return [float(x.real), float(x.imag)]
    x = float(x)
    return x if math.isfinite(x) else None


def _member(quantity: Callable, family: Family, size: int) -> tuple[complex | float, float]:
    """Value of one member and its CPU seconds (a worker task)."""
    t0 = time.process_time()
    # The dense solves of a member are small: BLAS threads cost more than they
    # give (up to 50x on a loaded machine for N = 32 modes).
    with single_blas_thread():
        value = quantity(family.discretization(size))
    return value, time.process_time() - t0


def run_study(
    quantity: Quantity | Callable,
    families: Sequence[Family],
    *,
    tolerance: float | None = None,
    workers: int | None = None,
    callback: Callable[[int, int], None] | None = None,
    independent: Sequence[tuple[str, float]] = (),
    dtype: type = float,
) -> ConvergenceStudy:
    """Compute the quantity on every member of every family, form the reference, fit orders.

    Parameters
    ----------
    quantity : Quantity or callable
        ``quantity(disc) -> value``; picklable for ``workers > 1``.
    families : sequence of Family
    tolerance : float, optional
        Relative solver accuracy, the floor of the estimates (default ``quantity.tolerance``).
    workers : int, optional
        Processes computing members in parallel.
    callback : callable, optional
        ``callback(done, total)`` after each member.
    independent : sequence of (str, value)
        Further independent values listed with their distance to the reference.

    Returns
    -------
    ConvergenceStudy
        Failed members are NaN, left out of the reference and the fits.
    """
    t_start = time.process_time()
    families = list(families)
    if not families:
        raise ValueError("a study needs at least one family")
    tasks = [(quantity, f, n) for f in families for n in f.sizes]
    results = run_tasks(
        _member,
        tasks,
        workers=workers,
        callback=None if callback is None else (lambda i, total, _r: callback(i, total)),
    )
    tol = quantity.tolerance if tolerance is None else float(tolerance)
    params = getattr(quantity, "params", None)
    raw = _members(families, results)
    # Richardson per family from its two finest usable members
    extrap = {f.label: extrapolate(f, values, tol, f.order_for(params)) for f, values, *_ in raw}
    reference, ref_raw = _reference(extrap, raw, independent)
    scale = max(1.0, abs(reference.value))

    # Fit only errors well above the reference's own (before it was raised to the solver
    # tolerance) and above the solver tolerance: this leaves out the finest member of the
    # reference family, whose error is the correction itself.
    floor = max(10.0 * ref_raw, tol * scale)
    series = []
    for f, values, fails, cpu in raw:
        dofs = np.array([f.dofs(n) for n in f.sizes])
        errors = np.abs(values - reference.value).astype(float)
        order, fit = estimate_order(dofs, errors, floor)
        e = extrap[f.label]
        series.append(
            Series(
                family=f.label,
                n=np.array(f.sizes),
                dofs=dofs,
                values=values,
                errors=errors,
                observed_order=order,
                fit=fit,
                expected_order=f.order_for(params),
                extrapolated=None if e is None else e[0],
                extrapolation_error=None if e is None else e[1],
                failures=fails,
                cpu_time=cpu,
            )
        )
    cpu = time.process_time() - t_start
    if (workers or 1) > 1:
        cpu += sum(s.cpu_time for s in series)  # the members ran in worker processes
    return ConvergenceStudy(quantity, reference, tuple(series), floor, cpu)


def _members(families: list[Family], results: list) -> list[tuple]:
    """``(family, values, failures, cpu)`` per family from the members' results in order."""
    is_complex = any(isinstance(r, tuple) and isinstance(r[0], complex) for r in results)
    raw, members = [], iter(results)
    for f in families:
        vals, fails, cpu = [], {}, 0.0
        for i in range(len(f.sizes)):
            r = next(members)
            if isinstance(r, SolverError | ValueError):
                # A member too coarse for the quantity (no resolved mode,
                # Newton lost on P1:2, ...): recorded, left out of the fits.
                fails[i] = str(r)
                vals.append(np.nan)
            elif isinstance(r, BaseException):
                raise r
            else:
                vals.append(r[0])
                cpu += r[1]
        values = np.array(vals, dtype=complex if is_complex else float)
        raw.append((f, values, fails, cpu))
    return raw


def _reference(
    extrap: dict, raw: list[tuple], independent: Sequence[tuple[str, float]]
) -> tuple[Reference, float]:
    """The reference (the best family's extrapolation, the others listed beside it) and
    its error estimate before it was raised to the solver tolerance."""
    usable = {k: e for k, e in extrap.items() if e is not None}
    if not usable:
        raise SolverError(
            "no family has two successful members: the reference cannot be formed "
            f"(failures: {[(f.label, fl) for f, _, fl, _ in raw if fl]})"
        )
    # Smallest estimate; among estimates raised to the solver tolerance, the
    # smallest correction.
    best = min(usable, key=lambda k: (usable[k][1], usable[k][3]))
    ref, ref_err, how, ref_raw = usable[best]
    rows = [(f"Richardson of {k}", e[0], e[1]) for k, e in usable.items() if k != best]
    rows += [(name, val, None) for name, val in independent]
    indep = tuple(
        {"method": m, "value": val, "error_estimate": err, "difference": float(abs(val - ref))}
        for m, val, err in rows
    )
    method = f"Richardson extrapolation of {best}: {how}"
    return Reference(ref, ref_err, method, best, indep), ref_raw

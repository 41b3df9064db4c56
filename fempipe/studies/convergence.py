"""Convergence studies of one quantity of the user's case: error against degrees of freedom.

A study computes one scalar :class:`Quantity` (a static tip value, the
critical flow velocity or its frequency, an eigenvalue, a limit cycle's
amplitude or period) on a sequence of discretisations of each
:class:`Family` -- Lagrange elements P_k on meshes of doubling element
counts, sine or beam modes of doubling N -- and reports for each family the
values, the errors against a reference and the observed order.

How the reference is formed (:func:`run_study`, recorded in
``Reference.method`` so a reader can judge it):

* for every family with at least two usable members, the Richardson
  extrapolation of its two finest values,
  ``Q* = Q_f + (Q_f - Q_c) / (r^p - 1)`` (r the ratio of the sizes, p the
  family's theoretical order in that ratio, or the observed local order of
  its last three members where no theory is known), with error estimate the
  size of the correction (at least the solver's tolerance, below which
  differences mean nothing);
* the reference is the extrapolation of the *best* family, the one with the
  smallest error estimate;
* the other families' extrapolations, and for static tip values the
  collocation solution of the strong form (scipy ``solve_bvp``, Eq. (31a)),
  are listed as independent values with their distance to the reference.

The observed order is the least-squares slope of log(error) against
log(dofs) over the asymptotic range: the finest (at most three) consecutive
members whose error is above ten times the reference's error estimate and
the solver tolerance (so that the reference's own error does not bend the
fit).  Theory (README, "Conventions and derivations"): P_k converges as
h^(2k) in tip values, v_cr and eigenvalues (nodal superconvergence), the sine
modes as N^-3, the beam modes as given by ``Modal.expected_order``.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from fempipe.core.errors import SolverError
from fempipe.model.discretization import FiniteElement, Modal
from fempipe.model.params import Params

__all__ = [
    "QUANTITIES",
    "Quantity",
    "Family",
    "Series",
    "Reference",
    "ConvergenceStudy",
    "run_study",
    "observed_order",
    "richardson",
    "doubling",
]

#: quantity -> (description, unit).  The static tip values are those of
#: :func:`fempipe.model.kinematics.tip_values` (Eq. (5), (28)).
QUANTITIES: dict[str, tuple[str, str]] = {
    "theta_tip": ("static tip rotation theta(1)", "rad"),
    "X_tip": ("static tip position X_g(1), down the plumb line", "L"),
    "Z_tip": ("static tip position Z_g(1), horizontal", "L"),
    "eta_tip": ("static lateral tip displacement eta(1)", "L"),
    "v_cr": (
        "critical flow velocity (first loss of stability of the primary branch in three "
        "dimensions, in the plane of the static state or out of it)",
        "1",
    ),
    "frequency": ("frequency Im(lambda) of the critical event (in three dimensions)", "1"),
    "v_cr_in_plane": (
        "critical flow velocity in the plane of the static state (the paper's planar v_cr)",
        "1",
    ),
    "v_cr_out_of_plane": (
        "critical flow velocity of the motion out of the plane of the static state",
        "1",
    ),
    "frequency_in_plane": ("frequency Im(lambda) of the critical event in the plane", "1"),
    "frequency_out_of_plane": (
        "frequency Im(lambda) of the critical event out of the plane",
        "1",
    ),
    "eigenvalue": ("k-th resolved eigenvalue lambda at one v (complex)", "1"),
    "lc_amplitude": ("limit-cycle amplitude (max - min) / 2 of eta(1)", "L"),
    "lc_period": ("limit-cycle period", "1"),
}

STATIC_QUANTITIES = ("theta_tip", "X_tip", "Z_tip", "eta_tip")
CRITICAL_QUANTITIES = (
    "v_cr",
    "frequency",
    "v_cr_in_plane",
    "frequency_in_plane",
    "v_cr_out_of_plane",
    "frequency_out_of_plane",
)
CYCLE_QUANTITIES = ("lc_amplitude", "lc_period")

#: Tolerances the quantities are computed to, relative to max(1, |Q|): below
#: them a difference between two discretisations is solver noise.  Newton
#: (static, 1e-12 on the residual), Brent on v (1e-10, the events of
#: :mod:`fempipe.analyses.stability`), the shooting's integration (``shoot_rtol``).
STATIC_TOL = 1e-12
EVENT_TOL = 1e-10


def doubling(low: int, high: int) -> list[int]:
    """``[low, 2 low, 4 low, ...]`` up to ``high`` (the sizes of ``--elements 2:128``)."""
    low, high = int(low), int(high)
    if low < 1 or high < low:
        raise ValueError(f"need 1 <= low <= high, got {low}:{high}")
    out = [low]
    while out[-1] * 2 <= high:
        out.append(out[-1] * 2)
    return out


# ---------------------------------------------------------------------------
# Families of discretisations
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Family:
    """A sequence of discretisations of one kind.

    Parameters
    ----------
    kind : {'fe', 'modal'}
    sizes : tuple of int
        Element counts (fe) or numbers of modes (modal), each usually the
        double of the last.
    degree : int
        Element degree k of P_k (fe).
    basis : {'sine', 'beam'}
        Modal basis (modal).
    """

    kind: str
    sizes: tuple[int, ...]
    degree: int = 3
    basis: str = "sine"

    @property
    def label(self) -> str:
        """``fe-P1`` ... ``fe-P10``, ``modal-sine``, ``modal-beam`` (the JSON ``family``)."""
        return f"fe-P{self.degree}" if self.kind == "fe" else f"modal-{self.basis}"

    def discretization(self, size: int):
        if self.kind == "fe":
            return FiniteElement(int(size), self.degree)
        if self.basis == "sine":
            return Modal(int(size))
        return Modal(int(size), basis=self.basis)

    def dofs(self, size: int) -> int:
        return int(size) * self.degree if self.kind == "fe" else int(size)

    def order_for(self, params: Params | None) -> float | None:
        """Theoretical order for the case ``params`` (variants can lower it, see
        :func:`fempipe.studies.error_estimate.expected_order`), judged on the coarser of the two
        finest members (a spring is a mesh node there or not)."""
        from .error_estimate import expected_order

        size = self.sizes[-2] if len(self.sizes) > 1 else self.sizes[-1]
        return expected_order(self.discretization(size), params)


# ---------------------------------------------------------------------------
# Quantities
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Quantity:
    """One number of the user's case, as a function of the discretisation.

    Parameters
    ----------
    name : str
        A key of :data:`QUANTITIES`.
    params : Params
        alpha, beta, gamma, mu and v (the flow velocity of static, eigenvalue
        and limit-cycle quantities; the start of the range for v_cr and
        frequency).
    v_max : float, optional
        End of the flow range of v_cr and frequency.
    mode : int
        Mode number k of ``eigenvalue`` (1-based, carried by continuity from
        v = 0, see :mod:`fempipe.analyses.stability`).
    shoot_rtol : float
        Integration tolerance of the limit cycle's shooting (its accuracy).
    seed : tuple, optional
        ``(disc, q0, qdot0, period)``: a limit cycle on another
        discretisation to start the shooting from (see :meth:`seeded`).
    planar : bool
        ``v_cr`` and ``frequency`` of the paper's planar model (the same
        numbers as ``v_cr_in_plane`` and ``frequency_in_plane``) instead of
        those of three dimensions; ``fempipe compare`` sets it for a user's
        ``v_cr`` and ``frequency`` (its module docstring).

    The critical quantities (:data:`CRITICAL_QUANTITIES`): ``v_cr`` and
    ``frequency`` are those of the first loss of stability in three
    dimensions, the earlier of the motion in the plane of the static state
    and out of it (:func:`fempipe.analyses.stability.spatial_critical_velocity`);
    ``*_in_plane`` those of the plane alone
    (:func:`fempipe.analyses.stability.critical_velocity`), ``*_out_of_plane`` those
    of the motion out of it (:func:`~fempipe.analyses.stability.critical_velocity` of
    ``model.with_plane("out")``, the same static branch).

    Calling it on a discretisation returns the value (complex for
    ``eigenvalue``), or raises :class:`fempipe.core.errors.SolverError`.
    """

    name: str
    params: Params
    v_max: float | None = None
    mode: int = 1
    shoot_rtol: float = 1e-9
    seed: tuple | None = field(default=None, repr=False, compare=False)
    planar: bool = False

    def __post_init__(self) -> None:
        if self.name not in QUANTITIES:
            raise ValueError(f"quantity must be one of {', '.join(QUANTITIES)}, got {self.name!r}")
        if self.name in CRITICAL_QUANTITIES:
            if self.v_max is None or not self.v_max > self.params.v:
                raise ValueError(
                    f"{self.name} needs a flow range v_min < v_max, got "
                    f"{self.params.v:g}, {self.v_max}"
                )
        if int(self.mode) < 1:
            raise ValueError(f"mode must be >= 1, got {self.mode}")

    @property
    def tolerance(self) -> float:
        """Relative accuracy the solver delivers (the noise floor of the study)."""
        if self.name in STATIC_QUANTITIES:
            return 10 * STATIC_TOL
        if self.name in CRITICAL_QUANTITIES:
            return EVENT_TOL
        if self.name in CYCLE_QUANTITIES:
            return 10 * self.shoot_rtol
        return 1e-11

    def describe(self) -> str:
        """One line: what is computed, at which v."""
        text, unit = QUANTITIES[self.name]
        if self.planar and self.name in ("v_cr", "frequency"):
            text = QUANTITIES[self.name + "_in_plane"][0]
        p = self.params
        if self.name in CRITICAL_QUANTITIES:
            where = f"over {p.v:g} <= v <= {self.v_max:g}"
        elif self.name == "eigenvalue":
            where = f"mode {self.mode} at v = {p.v:g}"
        else:
            where = f"at v = {p.v:g}"
        return f"{text} {where} [{unit}]"

    def __call__(self, disc) -> float | complex:
        from fempipe.model.operators import PipeModel

        model = PipeModel(disc, self.params)
        if self.name in STATIC_QUANTITIES:
            return _static_tip(model, self.name)
        if self.name in CRITICAL_QUANTITIES:
            return self._critical(model)
        if self.name == "eigenvalue":
            return _eigenvalue(model, self.mode)
        cycle = self.cycle(disc)
        if self.name == "lc_period":
            return float(cycle.period)
        lo, hi = cycle.tip["eta_tip"]
        return 0.5 * float(hi - lo)

    def _critical(self, model) -> float:
        """v_cr or the frequency of the critical event, in 3-D or in one plane."""
        from fempipe.analyses.stability import critical_velocity, spatial_critical_velocity

        name, plane = self.name, "3-D"
        for suffix, which in (("_in_plane", "in"), ("_out_of_plane", "out")):
            if name.endswith(suffix):
                name, plane = name.removesuffix(suffix), which
        if self.planar:
            plane = "in"
        kw = {"v_max": self.v_max, "v_min": self.params.v}
        if plane == "3-D":
            res = spatial_critical_velocity(model, **kw)
        else:
            res = critical_velocity(model.with_plane(plane), **kw)
        if res.v_cr is None:
            where = {"3-D": "", "in": " in its plane", "out": " out of its plane"}[plane]
            raise SolverError(
                f"the primary branch is stable{where} over {self.params.v:g} <= v <= "
                f"{self.v_max:g} on {model.disc.name}: no v_cr in the range"
            )
        return float(res.v_cr if name == "v_cr" else res.critical.frequency)

    def cycle(self, disc):
        """The limit cycle of ``disc`` (from :attr:`seed` if given, else a transient)."""
        from fempipe.analyses.limit_cycle import ShootingError, find_attractor, shoot
        from fempipe.model.operators import PipeModel
        from fempipe.model.projection import project

        model = PipeModel(disc, self.params)
        if self.seed is not None:
            src, q0, p0, period = self.seed
            try:
                return shoot(
                    model,
                    project(src, q0, disc),
                    project(src, p0, disc),
                    period,
                    rtol=self.shoot_rtol,
                    tol=10 * self.shoot_rtol,
                )
            except ShootingError:
                pass  # too far from the seed: find the attractor from the static state
        att = find_attractor(model, shoot_rtol=self.shoot_rtol, shoot_tol=10 * self.shoot_rtol)
        if att.kind != "periodic" or att.cycle is None:
            raise SolverError(
                f"no limit cycle at v = {self.params.v:g} on {disc.name}: the attractor is "
                f"{att.kind}"
            )
        return att.cycle

    def seeded(self, disc) -> Quantity:
        """A copy whose limit cycles start from the cycle of ``disc`` (computed once)."""
        if self.name not in CYCLE_QUANTITIES:
            return self
        c = self.cycle(disc)
        return replace(self, seed=(disc, c.q0, c.qdot0, c.period))

    def to_dict(self) -> dict:
        out = {"name": self.name, "description": self.describe(), "unit": QUANTITIES[self.name][1]}
        if self.name in CRITICAL_QUANTITIES:
            out["v_range"] = [self.params.v, self.v_max]
        else:
            out["v"] = self.params.v
        if self.name == "eigenvalue":
            out["mode"] = int(self.mode)
        if self.name in CYCLE_QUANTITIES:
            out["shoot_rtol"] = self.shoot_rtol
        if self.planar and self.name in ("v_cr", "frequency"):
            out["planar"] = True
        return out


def _static_tip_state(disc, params: Params) -> np.ndarray:
    """Static state on the primary branch at ``params.v``, followed from v = 0."""
    from fempipe.analyses.statics import solve_path
    from fempipe.model.operators import PipeModel

    v = params.v
    # Steps of at most 0.5 in v keep the path on the branch the pipe follows
    # as the flow is turned up (the branch of `fempipe static`).
    values = np.linspace(0.0, v, max(2, math.ceil(v / 0.5) + 1)) if v > 0 else [0.0]
    model = PipeModel(disc, replace(params, v=0.0))
    return solve_path(model, values, tol=STATIC_TOL)[-1].q


def _static_tip(model, key: str) -> float:
    from fempipe.model.kinematics import tip_values

    q = _static_tip_state(model.disc, model.params)
    return float(tip_values(model.disc, q, model.params.alpha)[key])


def _eigenvalue(model, mode: int) -> complex:
    from fempipe.analyses.stability import spectrum

    q = _static_tip_state(model.disc, model.params)
    spec = spectrum(model, q)
    upper = [(m, lam) for m, lam in zip(spec.mode, spec.lam, strict=True) if lam.imag >= 0]
    for m, lam in upper:
        if int(m) == int(mode):
            return complex(lam)
    raise SolverError(
        f"mode {mode} is not among the resolved modes of {model.disc.name} at v = {model.params.v:g} "
        f"(resolved: {sorted({int(m) for m, _ in upper})})"
    )


# ---------------------------------------------------------------------------
# Orders and extrapolation
# ---------------------------------------------------------------------------


def observed_order(
    dofs: np.ndarray, errors: np.ndarray, floor: float, n_points: int = 3
) -> tuple[float, tuple[int, ...]]:
    """Slope of log(err) against log(dofs) over the finest ``n_points`` points with err > floor.

    Returns ``(order, indices)``; order is positive for a decaying error and
    NaN if fewer than two usable points exist.
    """
    dofs = np.asarray(dofs, dtype=float)
    errors = np.asarray(errors, dtype=float)
    ok = np.flatnonzero(np.isfinite(errors) & (errors > floor))
    # The finest usable points are consecutive refinements: the asymptotic range.
    idx = tuple(int(i) for i in ok[-n_points:])
    if len(idx) < 2:
        return float("nan"), idx
    slope = np.polyfit(np.log(dofs[list(idx)]), np.log(errors[list(idx)]), 1)[0]
    return float(-slope), idx


def richardson(
    coarse: complex, fine: complex, order: float, ratio: float = 2.0
) -> tuple[complex, float]:
    """Richardson extrapolation and its error estimate (the size of the correction)."""
    corr = (fine - coarse) / (ratio**order - 1.0)
    return fine + corr, float(abs(corr))


def local_orders(sizes: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Orders from three consecutive members: log(|d_1| / |d_2|) / log(r), d the differences."""
    sizes = np.asarray(sizes, dtype=float)
    values = np.asarray(values)
    out = np.full(max(0, sizes.size - 2), np.nan)
    for i in range(out.size):
        d1 = abs(values[i + 1] - values[i])
        d2 = abs(values[i + 2] - values[i + 1])
        r = sizes[i + 2] / sizes[i + 1]
        if d1 > 0 and d2 > 0 and np.isfinite(d1 + d2):
            out[i] = math.log(d1 / d2) / math.log(r)
    return out


# ---------------------------------------------------------------------------
# Results
# ---------------------------------------------------------------------------


@dataclass(frozen=True)
class Series:
    """One family's members: sizes, dofs, values, errors and the fitted order.

    Attributes
    ----------
    family : str
        ``fe-P1`` ..., ``modal-sine``, ``modal-beam``.
    n : ndarray of int
        Element counts (fe) or numbers of modes (modal).
    dofs : ndarray of int
    values : ndarray
        NaN where the computation failed (see ``failures``).
    errors : ndarray
        |value - reference|.
    observed_order : float
        In dofs (error ~ dofs^-order); NaN if fewer than two usable points.
    fit : tuple of int
        Indices of the points the fit used.
    expected_order : float or None
    extrapolated : complex or float or None
        Richardson value of the finest two members (None if not formed).
    extrapolation_error : float or None
    failures : dict
        index -> message of the solver failure.
    cpu_time : float
        CPU seconds of the members' computations.
    """

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

    def to_dict(self) -> dict:
        return {
            "family": self.family,
            "n": [int(x) for x in self.n],
            "dofs": [int(x) for x in self.dofs],
            "values": [_number(x) for x in self.values],
            "errors": [_number(x) for x in self.errors],
            "observed_order": _number(self.observed_order),
            "expected_order": self.expected_order,
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

    def series_of(self, family: str) -> Series:
        for s in self.series:
            if s.family == family:
                return s
        raise KeyError(family)

    def to_dict(self) -> dict:
        """The contract of ``fempipe convergence --json`` (see the README)."""
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


# ---------------------------------------------------------------------------
# The study
# ---------------------------------------------------------------------------


def _member(quantity: Callable, family: Family, size: int) -> tuple[complex | float, float]:
    """Value of one member and its CPU seconds (a worker task)."""
    from fempipe.core.parallel import single_blas_thread

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
        Relative accuracy of the solver (default ``quantity.tolerance``):
        the floor of the reference's error estimate and of the fits.
    workers : int, optional
        Processes computing members in parallel.
    callback : callable, optional
        ``callback(done, total)`` after each member.
    independent : sequence of (str, value)
        Further independent values (e.g. a strong-form solution) listed with
        their distance to the reference.

    Returns
    -------
    ConvergenceStudy
        Members whose solver failed have value NaN and their message in
        ``Series.failures``; they are left out of the reference and the fits.
    """
    from fempipe.core.parallel import run_tasks

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
    is_complex = any(isinstance(r, tuple) and isinstance(r[0], complex) for r in results)
    raw = []
    k = 0
    for f in families:
        vals, fails, cpu = [], {}, 0.0
        for i, _ in enumerate(f.sizes):
            r = results[k]
            k += 1
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

    # Richardson per family from its two finest usable members.
    extrap = {}
    for f, values, _fails, _cpu in raw:
        extrap[f.label] = _extrapolate(f, values, tol, f.order_for(params))
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
    scale = max(1.0, abs(ref))
    indep = []
    for label, (val, err, _how, _raw) in usable.items():
        if label != best:
            indep.append(
                {
                    "method": f"Richardson of {label}",
                    "value": val,
                    "error_estimate": err,
                    "difference": float(abs(val - ref)),
                }
            )
    for name, val in independent:
        indep.append(
            {
                "method": name,
                "value": val,
                "error_estimate": None,
                "difference": float(abs(val - ref)),
            }
        )
    method = f"Richardson extrapolation of {best}: {how}"
    reference = Reference(ref, ref_err, method, best, tuple(indep))

    # Fit only errors well above the reference's own (before it was raised to
    # the solver tolerance) and above the solver tolerance: this leaves out
    # the finest member of the reference family, whose error is the
    # correction itself.
    floor = max(10.0 * ref_raw, tol * scale)
    series = []
    for f, values, fails, cpu in raw:
        dofs = np.array([f.dofs(n) for n in f.sizes])
        errors = np.abs(values - ref).astype(float)
        order, fit = observed_order(dofs, errors, floor)
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
    return ConvergenceStudy(
        quantity=quantity,
        reference=reference,
        series=tuple(series),
        fit_floor=floor,
        cpu_time=cpu,
    )


def _extrapolate(f: Family, values: np.ndarray, tol: float, p: float | None):
    """``(value, error_estimate, how, raw)`` from the two finest usable members, or None.

    ``raw`` is the estimate before it is raised to the solver tolerance.
    """
    sizes = np.array(f.sizes, dtype=float)
    ok = np.flatnonzero(np.isfinite(values))
    if ok.size < 2 or ok[-1] != ok[-2] + 1:
        return None
    i, j = int(ok[-2]), int(ok[-1])
    r = sizes[j] / sizes[i]
    floor = tol * max(1.0, abs(values[j]))
    lo = local_orders(sizes[: j + 1], values[: j + 1])
    if p is None:
        if lo.size == 0 or not np.isfinite(lo[-1]) or lo[-1] <= 0:
            # No theory and no measured order: the last difference is the estimate.
            raw = float(abs(values[j] - values[i]))
            return (
                complex(values[j]) if np.iscomplexobj(values) else float(values[j]),
                max(raw, floor),
                (
                    f"finest member n = {f.sizes[j]}, estimate |Q(n={f.sizes[j]}) - "
                    f"Q(n={f.sizes[i]})| (no order known)"
                ),
                raw,
            )
        p = float(lo[-1])
        source = f"observed local order {p:.2f}"
    else:
        source = f"theoretical order {p:g}"
    val, corr = richardson(values[i], values[j], p, r)
    raw = corr
    err = max(corr, floor)
    how = (
        f"n = {f.sizes[i]}, {f.sizes[j]} with the {source} (ratio {r:g}); error estimate "
        f"|correction| = {corr:.2e}"
        + (f", raised to the solver tolerance {floor:.1e}" if floor > corr else "")
    )
    if lo.size and np.isfinite(lo[-1]) and abs(lo[-1] - p) > 0.5 * p and corr > floor:
        # Not yet asymptotic: the correction is no measure of the error; use
        # the last difference itself, a safer bound.
        raw = float(abs(values[j] - values[i]))
        err = max(raw, floor)
        how += (
            f"; the last local order {lo[-1]:.2f} is far from {p:g} (not asymptotic), so the "
            f"estimate is the last difference {err:.2e}"
        )
    return val, err, how, raw

"""The analysis driver: every stability event of the static branches over a v-range."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import (
    Branch,
    BranchPoint,
    NewtonError,
    continuation,
    sagged_state,
    solve_static,
    switch_branch,
)
from fempipe.model.operators import PipeModel

from .events import StabilityResult, _BranchAnalysis
from .linear import (
    RESOLUTION_TOL,
    resolution,
    single_blas,
    straight_is_static,
    straight_pencil,
)

log = logging.getLogger(__name__)


class _ChunkedBranch:
    """A static branch continued in v piece by piece, seen as one branch.

    With ``chunk`` set, the continuation advances ``chunk`` in v at a time and
    only as far as the analysis asks (``stop_at_first``: no continuation
    beyond the first loss of stability); otherwise in one piece.  Fold and
    branch-point indices are renumbered to the concatenated point list.
    """

    def __init__(self, branch: Branch | None = None) -> None:
        self.points: list = []
        self.special: list = []
        self.end_reason = "stop"
        self._next = None
        if branch is not None:
            self._add(branch)

    @classmethod
    def follow(
        cls,
        model: PipeModel,
        v_range: tuple[float, float],
        ds_max: float,
        q0: np.ndarray | None,
        max_steps: int,
        chunk: float | None = None,
    ) -> _ChunkedBranch:
        lo, hi = v_range
        self = cls()
        kw = {"ds": min(0.05, ds_max), "ds_max": ds_max, "max_steps": max_steps}
        if (q0 is None or not np.any(q0)) and _straight_without_branch_points(model, lo, hi, kw):
            q = np.zeros(model.n)

            def advance(piece_start, tangent):
                v_a = piece_start[0]
                stop = hi if chunk is None else min(hi, v_a + chunk)
                # Spectra every STRAIGHT_STEP * ds_max from the start (the
                # branch-point test above keeps the continuation's own points).
                step = STRAIGHT_STEP * ds_max
                return _straight_piece(model, v_a, stop, step, step, kw["max_steps"])

        else:
            m = model.with_params(replace(model.params, v=lo))
            q = sagged_state(m).q if q0 is None else solve_static(m, q0=q0).q

            def advance(piece_start, tangent):
                v_a, q_a = piece_start
                stop = hi if chunk is None else min(hi, v_a + chunk)
                ma = model.with_params(replace(model.params, v=v_a))
                return continuation(ma, "v", stop=stop, q0=q_a, tangent=tangent, **kw)

        self._next = lambda: advance((lo, q), None)
        self._hi = hi
        self._advance = advance
        return self

    def _add(self, branch: Branch) -> None:
        skip = 1 if self.points else 0
        offset = len(self.points) - skip
        self.points.extend(branch.points[skip:])
        self.special.extend(replace(s, index=s.index + offset) for s in branch.special)
        self.end_reason = branch.end_reason

    def more(self) -> bool:
        """Continue one more piece; False when the branch is finished."""
        if self._next is None:
            return False
        piece = self._next()
        self._add(piece)
        last = self.points[-1]
        if piece.end_reason != "stop" or last.value >= self._hi:
            self._next = None
        else:
            self._next = lambda: self._advance((last.value, last.q), last.tangent)
        return True

    def is_straight(self) -> bool:
        """Whether every point so far is the straight pipe theta = 0 (exactly)."""
        return bool(self.points) and not any(np.any(p.q) for p in self.points)

    @property
    def folds(self) -> list:
        return [s for s in self.special if s.kind == "fold"]

    @property
    def bifurcations(self) -> list:
        return [s for s in self.special if s.kind == "bifurcation"]

    def iter_points(self):
        """(q, v, is_fold) in arclength order, continuing lazily."""
        i = 0
        while True:
            while i < len(self.points):
                # The folds located in segment [i - 1, i] come before point i.
                for f in self.special:
                    if f.kind == "fold" and f.index == i - 1:
                        yield f.q, f.value, True
                p = self.points[i]
                yield p.q, p.value, False
                i += 1
            if not self.more():
                return


#: Step in v between the spectra of a straight branch, in units of ds_max
#: (Notes of :func:`stability_analysis`).  Measured at alpha = 0 (and pi
#: below buckling), P3:16, v in [0, 16] on 55 cases (beta 0.1-0.9, gamma
#: 0-40, mu 0-0.05, end mass, springs, external and hysteretic damping): the
#: events of factors 3, 4 and 5 (steps growing from 0.05) are those of
#: factor 1 to 2.5e-11, with 54 %, 50 % and 44 % of its spectra.  Beyond, the
#: tracker's halving can insert more spectra than the larger step saves (the
#: hanging pipe, beta = 0.2, gamma = 10: 42, 35, 31 spectra for 3, 4, 5 and 94
#: for 6); 4 keeps a margin.  Taking this step from v_min on, instead of
#: growing to it from 0.05, leaves the events of the 55 cases and of the
#: hanging pipe as they were (2.4e-11) with 7 % fewer spectra.
STRAIGHT_STEP = 4.0


#: Continuation points per out-of-plane sample when the in-plane analysis
#: runs on the same branch (:func:`analyse_planes`).  The events are located by
#: Brent's method between samples whatever their spacing, the tracker inserts
#: states where the match is unsure and the peak check catches a real part
#: that touches zero between samples; measured in tests/test_spatial.py:
#: the out-of-plane events of stride 3 are those of stride 1 to 1e-10.
OUT_OF_PLANE_STRIDE = 3


def _straight_values(v_a: float, stop: float, ds: float, ds_max: float) -> list[float]:
    """The v of the points :func:`fempipe.analyses.statics.continuation` visits on a straight branch.

    There the tangent is (0, 1), the corrector converges in one iteration,
    and the step grows by 1.5 from ``ds`` up to ``ds_max``; the last point
    lands on ``stop``.  The same floating-point operations, so the same values
    (with the continuation's ``ds`` and ``ds_max``; the spectra of the straight
    branch are taken with ``ds = ds_max = STRAIGHT_STEP`` times the
    continuation's, :data:`STRAIGHT_STEP`).
    """
    values, v, h = [v_a], v_a, ds
    while True:
        v = v + h
        if v >= stop:
            values.append(stop)
            return values
        values.append(v)
        h = min(ds_max, h * 1.5)


def _straight_without_branch_points(model: PipeModel, lo: float, hi: float, kw: dict) -> bool:
    """Whether the primary branch over [lo, hi] is the straight pipe with no branch point on it.

    True when theta = 0 is a static state at every v (alpha = 0 or pi,
    :func:`~fempipe.analyses.stability.linear.straight_is_static`), the continuation
    would reach ``hi`` within its step budget, and the static Jacobian K^d(v)
    (:class:`~fempipe.analyses.stability.linear.StraightPencil`) keeps the sign of its
    determinant at every point the continuation would visit: a sign change
    is a branch point (a pitchfork), where the general path locates it and
    switches branches.  The same test on the same points as
    :meth:`fempipe.solvers.continuation.KellerPolicy.detect`, whose bordered determinant is
    det K^d times the tangent's v component, 1, on this branch.
    """
    if not straight_is_static(model.params):
        return False
    values = _straight_values(lo, hi, kw["ds"], kw["ds_max"])
    if len(values) - 1 > kw["max_steps"]:
        return False
    pencil = straight_pencil(model)
    # K^d(v) = K0 + v^2 K2 at every point in one batched LU (the sign of the
    # determinant: product of the pivots' signs and of the row swaps').
    v = np.asarray(values, dtype=float)
    v2 = v * v  # as StraightPencil.matrices forms it
    signs = np.linalg.slogdet(pencil.K0[None, :, :] + v2[:, None, None] * pencil.K2[None])[0]
    return bool(np.all(signs == signs[0]) and signs[0] != 0)


def _straight_piece(
    model: PipeModel, v_a: float, stop: float, ds: float, ds_max: float, max_steps: int
) -> Branch:
    """The straight branch from v_a to stop as :func:`fempipe.analyses.statics.continuation` returns it.

    Only called after :func:`_straight_without_branch_points`: the points
    are theta = 0 at the values of :func:`_straight_values`, no folds, no
    branch points, no Newton iterations.
    """
    n = model.n
    tangent = np.zeros(n + 1)
    tangent[n] = 1.0
    q = np.zeros(n)
    branch = Branch(parameter="v", base=replace(model.params, v=v_a), end_reason="stop")
    for v in _straight_values(v_a, stop, ds, ds_max):
        branch.points.append(BranchPoint(q, float(v), tangent, 0, 0.0, 1))
    branch.steps = len(branch.points) - 1
    return branch


@single_blas
def stability_analysis(
    model: PipeModel,
    v_max: float = 10.0,
    v_min: float = 0.0,
    *,
    follow_bifurcations: bool = True,
    max_depth: int = 1,
    q0: np.ndarray | None = None,
    ds_max: float = 0.1,
    max_steps: int = 2000,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
    stop_at_first: bool = False,
    callback: Callable[[str, float], None] | None = None,
) -> StabilityResult:
    """Every stability event and fold of the static branches for v_min <= v <= v_max.

    Parameters
    ----------
    model : PipeModel
        alpha, beta, gamma, mu from ``model.params`` (its v is ignored).
    v_max, v_min : float
        The flow range, 0 <= v_min < v_max.
    follow_bifurcations : bool
        Follow the branches born at branch points (pitchforks at alpha = 0, pi)
        with :func:`fempipe.analyses.statics.switch_branch` and analyse them too.
    max_depth : int
        Generations of branches to follow (1: those born on the primary branch).
    q0 : ndarray, optional
        Initial guess of the primary state at v_min (default: gravity loading).
    ds_max : float
        Largest continuation step (arclength in (theta L2, v)); spectra are
        computed at every point, so it bounds the sampling of the eigenvalue
        paths; tracking inserts points where it is not clear and a peak check
        catches a real part that touches zero between samples.
    method : {'auto', 'qz', 'shift-invert'}
        Eigensolver of every spectrum.  ``auto`` is shift-invert here at
        every n: the analysis only uses the resolved eigenvalues, which it
        gives to ~1e-11 relative of QZ (measured on P3:16) at half the cost.
    stop_at_first : bool
        Stop analysing the primary branch after the first loss of stability
        (enough for v_cr; events beyond it are not listed).
    callback : callable, optional
        ``callback(branch_name, v)`` after every sample (progress).

    Returns
    -------
    StabilityResult

    Notes
    -----
    Where theta = 0 is the static state at every v (alpha = 0 or pi) and no
    branch point lies on it in the range, the primary branch is not
    continued: its points are the straight pipe, with steps in v of
    ``STRAIGHT_STEP * ds_max`` (:func:`_straight_values`; the tracker still
    halves a step wherever the match of the eigenvalues is
    ambiguous, and the peak check and Brent's method run as on any branch),
    and the spectra use K^d(v), C^d(v) formed from fixed matrices
    (:class:`~fempipe.analyses.stability.linear.StraightPencil`): no Newton
    iteration, no Jacobian assembly.  Most of these spectra are solved without
    eigenvectors, their resolved classification taken from the nearest sample
    where it is unambiguous (:func:`~fempipe.analyses.stability.linear._analyse_inherited`;
    a spectrum with eigenvectors at least every 2.0 in v).  The events agree with those of the
    general continuation to the 1e-10 to which both locate them
    (tests/test_stability_fast.py).  A sign change of det K^d on the points
    the continuation would visit (a branch point, where the general path
    locates it and switches branches) sends the branch through the general
    continuation, as does a step budget ``max_steps`` too small for the range.

    Raises
    ------
    NewtonError
        If the static state cannot be followed (naming v and the residual).
    """
    planes = analyse_planes(
        [model],
        v_min=v_min,
        v_max=v_max,
        follow_bifurcations=follow_bifurcations,
        max_depth=max_depth,
        q0=q0,
        ds_max=ds_max,
        max_steps=max_steps,
        method=method,
        tolerance=tolerance,
        stop_at_first=stop_at_first,
        callback=callback,
    )
    return planes[model.plane]


def analyse_planes(
    models: list[PipeModel],
    *,
    v_min: float,
    v_max: float,
    follow_bifurcations: bool,
    max_depth: int,
    q0: np.ndarray | None,
    ds_max: float,
    max_steps: int,
    method: str,
    tolerance: float,
    stop_at_first: bool,
    callback: Callable[[str, float], None] | None,
) -> dict[str, StabilityResult]:
    """:func:`stability_analysis` of one pipe in several planes, on shared static branches.

    ``models`` are the same pipe (discretisation and parameters) with the
    linearisations of their planes (``model.plane``); the static branches
    are continued and switched once, with the first model, and every plane's
    analysis runs along the same points (each inserts its own where its
    tracking asks).  Beside the in-plane analysis the out-of-plane one takes
    every :data:`OUT_OF_PLANE_STRIDE`-th point, and on a straight branch
    (theta = 0 at every point: alpha = 0, or pi below buckling) it takes the
    in-plane analysis as it is, the two pencils being the same matrices there.
    """
    model = models[0]
    v_min, v_max = float(v_min), float(v_max)
    if not (math.isfinite(v_min) and math.isfinite(v_max)) or v_min < 0 or v_max <= v_min:
        raise ValueError(f"need 0 <= v_min < v_max, got v_min={v_min}, v_max={v_max}")
    if ds_max <= 0:
        raise ValueError(f"ds_max must be > 0, got {ds_max}")
    res = resolution(model.disc, tolerance)
    if res.n_resolved == 0:
        raise ValueError(f"discretisation {model.disc.name} resolves no mode; refine it")
    if method == "auto":
        method = "shift-invert"
    # Piecewise continuation when only v_cr is wanted: nothing beyond it is computed.
    chunk = 1.0 if stop_at_first else None
    primary = _ChunkedBranch.follow(model, (v_min, v_max), ds_max, q0, max_steps, chunk)

    def analyse(m, branch, name, stop, parent, done):
        if m.plane != "in" and "in" in done and branch.is_straight():
            # On the straight pipe the out-of-plane problem is the in-plane one,
            # term by term (fempipe.model.out_of_plane): the same pencils, the same events.
            return done["in"].as_plane(m)
        stride = OUT_OF_PLANE_STRIDE if (m.plane != "in" and "in" in done) else 1
        ana = _BranchAnalysis(
            m, res, branch, name, (v_min, v_max), method, stop, callback, parent, stride
        )
        ana.run()
        return ana

    top: dict = {}
    for m in models:
        top[m.plane] = analyse(m, primary, "primary", stop_at_first, None, top)
    results = {p: [a.finish(None, None)] for p, a in top.items()}
    n_spectra = {p: a.path.n_spectra for p, a in top.items()}
    queue = [(primary, "primary", 1, top)] if follow_bifurcations and not stop_at_first else []
    while queue:
        br, name, depth, parents = queue.pop(0)
        for k, bp in enumerate(br.bifurcations, start=1):
            if not v_min <= bp.value <= v_max:
                continue
            try:
                kids = switch_branch(
                    model.with_params(replace(model.params, v=bp.value)),
                    bp,
                    "v",
                    v_max,
                    ds_max=ds_max,
                    max_steps=max_steps,
                )
            except (NewtonError, np.linalg.LinAlgError) as exc:
                log.warning("branch switching at v=%.8g on %s failed: %s", bp.value, name, exc)
                continue
            for sign, kid in zip("+-", kids, strict=True):
                kname = f"B{k}{sign}" if name == "primary" else f"{name}.B{k}{sign}"
                chunked = _ChunkedBranch(kid)
                born = parents[model.plane].refined_bifurcation(bp.value)
                anas: dict = {}
                for m in models:
                    anas[m.plane] = ka = analyse(m, chunked, kname, False, parents[m.plane], anas)
                    results[m.plane].append(ka.finish(name, born))
                    n_spectra[m.plane] += ka.path.n_spectra
                if depth < max_depth:
                    queue.append((kid, kname, depth + 1, anas))
    out = {}
    for m in models:
        ana = top[m.plane]
        first = ana.first_loss()
        branches = results[m.plane]
        out[m.plane] = StabilityResult(
            params=replace(model.params, v=v_min),
            discretization=model.disc.to_dict(),
            v_range=(v_min, v_max),
            v_cr=None if first is None else float(first.v),
            critical=first,
            v_flutter=next((ev.v for _, ev, _, _ in ana.events if ev.type == "flutter"), None),
            events=tuple(ev for b in branches for ev in b.events),
            branches=tuple(branches),
            n_spectra=n_spectra[m.plane],
            plane=m.plane,
        )
    return out


def critical_velocity(
    model: PipeModel,
    v_max: float = 10.0,
    v_min: float = 0.0,
    **kwargs,
) -> StabilityResult:
    """v_cr: the first loss of stability of the primary branch (no branch switching).

    A shortcut for :func:`stability_analysis` with ``follow_bifurcations=False``
    and ``stop_at_first=True``; its ``events`` stop at the critical one.
    """
    kwargs.setdefault("follow_bifurcations", False)
    kwargs.setdefault("stop_at_first", True)
    return stability_analysis(model, v_max, v_min, **kwargs)

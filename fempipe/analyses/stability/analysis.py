"""The analysis driver: every stability event of the static branches over a v-range."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import NewtonError, switch_branch
from fempipe.core.parallel import single_blas
from fempipe.model.operators import PipeModel

from .branch_analysis import BranchAnalysis
from .canonical import RESOLUTION_TOL, resolution
from .chunked_branch import ChunkedBranch
from .events import StabilityResult

log = logging.getLogger(__name__)

#: Continuation points per out-of-plane sample when the in-plane analysis
#: runs on the same branch (:func:`analyse_planes`).  The events are located by
#: Brent's method between samples whatever their spacing, the tracker inserts
#: states where the match is unsure and the peak check catches a real part
#: that touches zero between samples; measured in tests/test_spatial.py:
#: the out-of-plane events of stride 3 are those of stride 1 to 1e-10.
OUT_OF_PLANE_STRIDE = 3


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
    ``STRAIGHT_STEP * ds_max``
    (:data:`~fempipe.analyses.stability.chunked_branch.STRAIGHT_STEP`; the
    tracker still halves a step wherever the match of the eigenvalues is
    ambiguous, and the peak check and Brent's method run as on any branch),
    and the spectra use K^d(v), C^d(v) formed from fixed matrices
    (:class:`~fempipe.analyses.stability.linear.StraightPencil`): no Newton
    iteration, no Jacobian assembly.  Most of these spectra are solved without
    eigenvectors, their resolved classification taken from the nearest sample
    where it is unambiguous
    (:func:`~fempipe.analyses.stability.classified.classify_inherited`; a
    spectrum with eigenvectors at least every 2.0 in v).  The events agree with those of the
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

    ``models`` are the same pipe (discretization and parameters) with the
    linearizations of their planes (``model.plane``); the static branches
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
        raise ValueError(f"discretization {model.disc.name} resolves no mode; refine it")
    if method == "auto":
        method = "shift-invert"
    # Piecewise continuation when only v_cr is wanted: nothing beyond it is computed.
    chunk = 1.0 if stop_at_first else None
    primary = ChunkedBranch.follow(model, (v_min, v_max), ds_max, q0, max_steps, chunk)

    def analyse(m, branch, name, stop, parent, done):
        if m.plane != "in" and "in" in done and branch.is_straight():
            # On the straight pipe the out-of-plane problem is the in-plane one,
            # term by term (fempipe.model.out_of_plane): the same pencils, the same events.
            return done["in"].as_plane(m)
        stride = OUT_OF_PLANE_STRIDE if (m.plane != "in" and "in" in done) else 1
        ana = BranchAnalysis(
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
                chunked = ChunkedBranch(kid)
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

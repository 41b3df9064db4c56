"""The analysis driver: every stability event of the static branches over a v-range,
in the plane of the static states, out of it, or both (docs/theory/stability.md,
"Stability events" and "Both planes")."""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from dataclasses import replace

import numpy as np

from fempipe.analyses.statics import NewtonError, switch_branch
from fempipe.core.parallel import single_blas
from fempipe.model.plane.operators import PipeModel

from .branch_analysis import BranchAnalysis
from .canonical import RESOLUTION_TOL, resolution
from .chunked_branch import ChunkedBranch
from .events import StabilityInPlanes, StabilityResult
from .linear import plane_models

log = logging.getLogger(__name__)

#: Continuation points per out-of-plane sample when the in-plane analysis runs on the same
#: branch: Brent's method locates the events between samples whatever their spacing
#: (tests/test_spatial.py: the events of stride 3 are those of stride 1 to 1e-10).
OUT_OF_PLANE_STRIDE = 3


@single_blas
def analyse_stability(
    model: PipeModel,
    v_max: float = 10.0,
    v_min: float = 0.0,
    *,
    planes: tuple[str, ...] = ("in",),
    follow_bifurcations: bool = True,
    max_depth: int = 1,
    q0: np.ndarray | None = None,
    ds_max: float = 0.1,
    max_steps: int = 2000,
    method: str = "auto",
    tolerance: float = RESOLUTION_TOL,
    stop_at_first: bool = False,
    callback: Callable[[str, float], None] | None = None,
) -> StabilityResult | StabilityInPlanes:
    """Every stability event and fold of the static branches for v_min <= v <= v_max.

    Parameters
    ----------
    model : PipeModel
        alpha, beta, gamma, mu from ``model.params`` (its v is ignored).
    v_max, v_min : float
        The flow range, 0 <= v_min < v_max.
    planes : tuple of {'in', 'out'}
        The linear problems: in the plane (Eq. (32)) and/or out of it.
    follow_bifurcations, max_depth : bool, int
        Also analyse the branches born at branch points, to ``max_depth`` generations.
    q0 : ndarray, optional
        Primary state's guess at v_min (default: gravity loading).
    ds_max, max_steps : float, int
        Largest continuation step (arclength in (theta L2, v)) and step count.
    method : {'auto', 'qz', 'shift-invert'}
    tolerance : float
        :data:`RESOLUTION_TOL` of the resolved modes.
    stop_at_first : bool
        Stop each plane's primary branch at its first loss of stability.
    callback : callable, optional
        ``callback(branch_name, v)`` after every sample.

    Returns
    -------
    StabilityResult or StabilityInPlanes
        The latter for ``("in", "out")``.

    Notes
    -----
    The out-of-plane analysis runs every :data:`OUT_OF_PLANE_STRIDE`-th point of the same
    branches; the straight branch (alpha = 0, pi) is not continued (docs/theory/stability.md,
    "The straight branch").
    """
    models = plane_models(model, planes)
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
            # On the straight pipe the out-of-plane problem is the in-plane one, term by term.
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
    if len(out) == 2:
        return StabilityInPlanes(in_plane=out["in"], out_of_plane=out["out"])
    return out[models[0].plane]


def find_critical_velocity(
    model: PipeModel, v_max: float = 10.0, v_min: float = 0.0, **kwargs
) -> StabilityResult | StabilityInPlanes:
    """v_cr: the first loss of stability of the primary branch, in each of ``planes``.

    :func:`analyse_stability` (the same keywords) with ``follow_bifurcations=False`` and
    ``stop_at_first=True``; its ``events`` stop at the critical one.
    """
    kwargs.setdefault("follow_bifurcations", False)
    kwargs.setdefault("stop_at_first", True)
    return analyse_stability(model, v_max, v_min, **kwargs)
